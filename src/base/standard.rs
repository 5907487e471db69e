//! Standard coordinates of the disk's base distribution (docs/math.md, §6.3): a model with
//! [`crate::ModelDef::standardized`] runs its flow in `z = (x - mu) / sigma`, where the base
//! is the standard normal, and maps the flow's end point to the chart by `x = mu + sigma z`.
//! The velocity net then sees the target at the scale the base net fitted for this `wi`
//! (a near-mirror spike of radius 0.01 spans many units of `z`, not a hundredth of one).

use super::{gaussian, BaseDist};
use crate::math::exp;

impl BaseDist {
    /// `z0 = (Phi^-1(u_0), Phi^-1(u_1))` (docs/math.md, (59)).
    #[inline]
    #[must_use]
    pub fn standard_sample(u: [f32; 2]) -> [f32; 2] {
        [gaussian::quantile(u[0]), gaussian::quantile(u[1])]
    }

    /// The flow's start point for `u` in standard coordinates: `z0` (59), compressed by
    /// (63) when `warped` ([`crate::ModelDef::standard_warp`]).
    #[inline]
    #[must_use]
    pub fn standard_start(u: [f32; 2], warped: bool) -> [f32; 2] {
        let z0 = Self::standard_sample(u);
        if warped {
            super::warp::compress2(z0)
        } else {
            z0
        }
    }

    /// `ln p0` of the chart point `mu + sigma z0`, from `z0`:
    /// `((ln N(z0_0) + ln N(z0_1)) - ln sigma_0) - ln sigma_1` (docs/math.md, (60)).
    #[inline]
    #[must_use]
    pub fn standard_ln_pdf(&self, z0: [f32; 2]) -> f32 {
        let ln_sigma = self.disk_ln_sigma();
        gaussian::ln_pdf(z0[0]) + gaussian::ln_pdf(z0[1]) - ln_sigma[0] - ln_sigma[1]
    }

    /// The chart point of `z`: `x_j = mu_j + sigma_j z_j` (docs/math.md, (61)).
    #[inline]
    #[must_use]
    pub fn from_standard(&self, z: [f32; 2]) -> [f32; 2] {
        let (mu, ln_sigma) = (self.disk_mu(), self.disk_ln_sigma());
        [
            mu[0] + exp(ln_sigma[0]) * z[0],
            mu[1] + exp(ln_sigma[1]) * z[1],
        ]
    }

    /// The standard coordinates of the chart point `x`: `z_j = (x_j - mu_j) exp(-ln
    /// sigma_j)` (docs/math.md, (62)).
    #[inline]
    #[must_use]
    pub fn to_standard(&self, x: [f32; 2]) -> [f32; 2] {
        let (mu, ln_sigma) = (self.disk_mu(), self.disk_ln_sigma());
        [
            (x[0] - mu[0]) * exp(-ln_sigma[0]),
            (x[1] - mu[1]) * exp(-ln_sigma[1]),
        ]
    }

    /// The disk's locations (`(0, 0)` for the sphere, which has no standard coordinates).
    #[inline]
    fn disk_mu(&self) -> [f32; 2] {
        match *self {
            BaseDist::Disk { mu, .. } => mu,
            BaseDist::Sphere { .. } => [0.0, 0.0],
        }
    }

    /// The disk's log-scales (`(0, 0)` for the sphere).
    #[inline]
    fn disk_ln_sigma(&self) -> [f32; 2] {
        match *self {
            BaseDist::Disk { ln_sigma, .. } => ln_sigma,
            BaseDist::Sphere { .. } => [0.0, 0.0],
        }
    }
}
