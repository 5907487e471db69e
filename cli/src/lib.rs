//! The `diffbsdf` command line ([`cli`]): fit, eval, demo, material, sample and pdf (of
//! a blob), codegen and the
//! step-count tradeoff report ([`tradeoff`]), over the reference materials
//! (`diffbsdf-materials`) and the trainer (`diffbsdf-train`).

#![forbid(unsafe_code)]
// `!(x > 0.0)` is deliberate throughout: it is true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cli;
pub mod tradeoff;
