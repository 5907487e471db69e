//! Training on the CPU, following the paper's §4.1: the base net by maximum likelihood,
//! a teacher velocity net by flow matching, reflow pairs from the teacher, the kernel-
//! shaped student on those straight pairs, and export as a kernel blob.
//!
//! Forward and backward passes are hand-written ([`mlp`]) and batched over both cores
//! ([`batch`]); the inputs are built with the kernel's own encoding and activation, so the
//! exported blob evaluates in the kernel as it did in training.

pub mod adam;
pub mod base_fit;
pub mod batch;
pub mod dataset;
pub mod error;
pub mod export;
pub mod features;
pub mod flow_fit;
pub mod mlp;
pub mod pipeline;
pub mod progress;
pub mod reflow;

pub use error::TrainError;
pub use export::LearnedModel;
pub use pipeline::{fit_data, fit_material, fit_source, FitConfig, Fitted, StageReport};
pub use progress::{Progress, Silent};
