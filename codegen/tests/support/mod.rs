//! Shared helpers of the codegen tests.
pub mod gpu;
pub mod shaders;
pub mod vectors;
