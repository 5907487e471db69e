//! Training data, training and metrics for diffbsdf.
//!
//! - [`data`]: training pairs `(wi, wo)` by MCMC (needs only `eval`) or by importance
//!   resampling of a material's own sampler.
//! - Training on the CPU, following the paper's §4.1: the base net by maximum likelihood,
//!   a teacher velocity net by flow matching, reflow pairs from the teacher, the kernel-
//!   shaped student on those straight pairs, and export as a kernel blob. Every net is
//!   laid out by the kernel's `ModelDef`; forward and backward passes are hand-written
//!   ([`mlp`] one row at a time, the reference; [`block`] a chunk of rows layer by layer,
//!   the same bits, what training runs) and batched over both cores ([`batch`]); the inputs are built with the
//!   kernel's own encoding, domain maps and activation, so the exported blob evaluates in
//!   the kernel as it did in training.
//! - [`metrics`]: relative variance, fireflies, KL divergence, PDF consistency and cost of
//!   a model against its material.

#![deny(unsafe_code)]
// `!(x > 0.0)` is deliberate throughout: it is true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod adam;
pub mod assignment;
pub mod base_fit;
pub mod batch;
pub mod block;
pub mod data;
pub mod dataset;
pub mod error;
pub mod export;
pub mod features;
pub mod flow_fit;
mod lanes;
pub mod latent_table;
pub mod metrics;
pub mod mlp;
pub mod pipeline;
pub mod progress;
pub mod refine;
pub mod reflow;
pub mod start;
mod tiles;

pub use error::TrainError;
pub use export::{model_from_nets, ModelExt};
pub use pipeline::{fit_data, fit_material, fit_source, paper_def, FitConfig, Fitted, StageReport};
pub use progress::{Progress, Silent};
