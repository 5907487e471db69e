//! # diffbsdf — BSDF importance sampling with a tiny learned rectified flow
//!
//! The kernel: load a few-kilobyte weight blob, then turn two uniform numbers into a
//! direction and its exact PDF, or a direction into its PDF.
//!
//! ```
//! use diffbsdf::{Model3x32, glam::{Vec2, Vec3}};
//! # fn demo(blob: &[u8]) -> Result<(), diffbsdf::BlobError> {
//! let model = Model3x32::from_blob(blob)?;
//! let wi = Vec3::new(0.3, 0.0, 0.9539392);
//! if let Some(s) = model.sample(wi, Vec2::new(0.25, 0.75)) {
//!     let pdf_again = model.pdf(wi, s.wo); // equals s.pdf to float precision
//! #   let _ = pdf_again;
//! }
//! # Ok(()) }
//! ```
//!
//! ## Contract
//! - `no_std`, no allocator; `unsafe` only for two CPU intrinsics on x86-64: the
//!   square-root instruction (`math::sqrt`, correctly rounded like libm's routine used
//!   elsewhere) and, with the optional `fma` feature, the fused multiply-add
//!   (`math::mul_add`).
//! - No panics on any input: a malformed blob is a [`BlobError`]; a NaN, infinite, zero or
//!   non-unit direction, `u` outside [0, 1], or zero steps give `None` / a PDF of 0.
//! - Exact: the PDF reported with a sample is the density of the discrete map that ran
//!   (`p0(x0) / prod det(I + h dv/dx)`), and [`Model::pdf`] inverts that same map step by
//!   step (Newton), so both agree to float precision.
//! - Pay for what you use: [`Model::sample_direction`] computes no Jacobians;
//!   [`Model::pdf`] alone runs the inverse.
//!
//! Frames: local shading frame, `z` the normal; `wi` points away from the surface.

#![no_std]
// `unsafe` is denied everywhere but the two intrinsic calls of `math` (see the contract).
#![deny(unsafe_code)]
#![warn(missing_docs)]
// `!(x > 0.0)` is how this crate rejects NaN together with the out-of-range values; the
// "clearer" `x <= 0.0` would let NaN through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod any_model;
mod base;
mod batch;
mod blob;
mod def;
mod diagnostics;
mod domain;
mod exactness;
mod flow;
mod frame;
mod input;
pub mod internals;
mod math;
mod model;
mod net;
mod sampler;
pub mod spec;

pub use any_model::AnyModel;
pub use batch::BatchError;
pub use blob::BlobError;
pub use def::{
    encoding_len, Activation, Domain, IncidentFold, IncidentRange, Layer, ModelDef, ModelName, Net,
    NetShape, Precision, TableGrid, NAME_CAPACITY,
};
pub use model::{Model, Model3x32, Model4x32};
pub use sampler::Sample;

pub use glam;

/// The README's Rust example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctest;
