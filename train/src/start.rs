//! The distribution every flow stage draws its start points from, in the flow's
//! coordinates: the base distribution of the pair's `wi` on the chart, or the standard
//! normal of the standard coordinates (compressed by the warp when the model has it), as
//! the kernel's `sample` draws them.

use diffbsdf::internals::base::BaseDist;

/// `p0` of one training pair, in the coordinates the flow runs in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StartDist {
    /// The base distribution of the pair's `wi`, in chart coordinates.
    Chart(BaseDist),
    /// The standard normal of standard coordinates (`ModelDef::standardized`), compressed
    /// by `K asinh(z / K)` when `warped` (`ModelDef::standard_warp`).
    Standard {
        /// The flow runs in the compressed coordinates.
        warped: bool,
    },
}

impl StartDist {
    /// The start point for the uniform pair `u`, as the kernel's `sample` computes it.
    #[must_use]
    pub fn sample(&self, u: [f32; 2]) -> [f32; 2] {
        match *self {
            StartDist::Chart(base) => base.sample(u),
            StartDist::Standard { warped } => BaseDist::standard_start(u, warped),
        }
    }
}
