//! The kernel's building blocks, for the project's code generator, trainer and tests, and
//! for anyone checking another implementation against the kernel piece by piece.
//!
//! Not needed to sample: a renderer uses the crate root ([`crate::Model`],
//! [`crate::AnyModel`], [`crate::Sample`]). Items here may change between minor versions.

/// The base distributions `p0(x0 | wi)`: the Gaussian quantile and the wrapped Cauchy.
pub mod base {
    pub use crate::base::*;
}

/// The weight blob: parsing, writing, the CRC-32 and the header constants.
pub mod blob {
    pub use crate::blob::*;
}

/// The disk and sphere maps between flow points and directions.
pub mod domain {
    pub use crate::domain::*;
}

/// The incident frame of isotropic models.
pub mod frame {
    pub use crate::frame::*;
}

/// Input checks (unit directions, `u` in `[0, 1]^2`).
pub mod input {
    pub use crate::input::*;
}

/// The exactness sweep: the samples on which `pdf()` is checked against `sample`.
pub mod exactness {
    pub use crate::exactness::*;
}

/// The polynomial `exp` of the activation.
pub mod math {
    pub use crate::math::exp_poly;
}

/// The two MLPs, their layers, the `wi` encoding and the Jacobian type.
pub mod net {
    pub use crate::net::*;
}

pub use crate::diagnostics::Diagnostics;

/// The batch forms' flow in lanes: `out[i]` as [`crate::Model::sample_direction_steps`]
/// bit for bit, [`crate::spec::BATCH_LANES`] samples per flow pass, in any build
/// ([`crate::Model::sample_direction_batch`] takes this path with the `fma` feature).
pub fn sample_direction_lanes<
    const BE: usize,
    const BW: usize,
    const BM: usize,
    const VE: usize,
    const VW: usize,
    const VM: usize,
>(
    model: &crate::Model<BE, BW, BM, VE, VW, VM>,
    wi: &[glam::Vec3],
    u: &[glam::Vec2],
    steps: u32,
    out: &mut [glam::Vec3],
) -> Result<(), crate::BatchError> {
    model.sample_direction_lanes(wi, u, steps, out)
}
