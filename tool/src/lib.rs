//! Reference materials, training data, training and metrics for diffbsdf.
//!
//! - [`material`]: analytic reference BSDFs and RGL measured tables, each with its own
//!   sampler and PDF, and the one-string spec parser.
//! - [`data`]: training pairs `(wi, wo)` by MCMC (needs only `eval`) or by importance
//!   resampling of a material's own sampler.
//! - [`cli`]: the `diffbsdf` command line.

#![forbid(unsafe_code)]
// `!(x > 0.0)` is deliberate throughout: it is true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cli;
pub mod data;
pub mod material;
pub mod metrics;
pub mod tradeoff;
pub mod train;
