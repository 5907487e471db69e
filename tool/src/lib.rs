//! Reference materials, training data, training and metrics for diffbsdf.
//!
//! - [`material`]: analytic reference BSDFs and RGL measured tables, each with its own
//!   sampler and PDF, and the one-string spec parser.
//! - [`data`]: training pairs `(wi, wo)` by MCMC (needs only `eval`) or by importance
//!   resampling of a material's own sampler.
//! - [`cli`]: the `diffbsdf` command line.

#![forbid(unsafe_code)]

pub mod cli;
pub mod data;
pub mod material;
