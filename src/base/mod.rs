//! The base distribution `p0(x0 | wi)` and the deterministic map from the renderer's
//! `u in [0,1]^2` to `x0`.
//!
//! - Disk: a diagonal Gaussian, `x0_j = mu_j + sigma_j Phi^-1(u_j)`.
//! - Sphere: a Gaussian in `theta` times a wrapped Cauchy in `phi`.
//!
//! The base net's four outputs are the locations and the log-scales; log-scales are clamped
//! to [`LN_SCALE_MIN`, `LN_SCALE_MAX`] so every density stays finite.

pub mod gaussian;
mod standard;
pub mod table;
pub mod table_axes;
pub mod warp;
pub mod wrapped_cauchy;

use crate::def::Domain;
use crate::math::exp;
use crate::spec::{BASE_OUTPUTS, LN_SCALE_MAX, LN_SCALE_MIN};

/// `p0(x0 | wi)` for one `wi`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BaseDist {
    /// `N(mu_0, sigma_0^2) x N(mu_1, sigma_1^2)` on the plane.
    Disk {
        /// Means of `x0_0` and `x0_1`.
        mu: [f32; 2],
        /// Log standard deviations.
        ln_sigma: [f32; 2],
    },
    /// `N(mu_theta, sigma^2)` in theta times wrapped Cauchy `(mu_phi, gamma)` in phi.
    Sphere {
        /// Mean of theta.
        mu_theta: f32,
        /// Log standard deviation of theta.
        ln_sigma: f32,
        /// Centre of phi.
        mu_phi: f32,
        /// Log scale of the wrapped Cauchy.
        ln_gamma: f32,
    },
}

impl BaseDist {
    /// The distribution from the base net's raw outputs.
    #[inline]
    #[must_use]
    pub fn from_net(domain: Domain, out: [f32; BASE_OUTPUTS]) -> Self {
        let clamp = |s: f32| s.clamp(LN_SCALE_MIN, LN_SCALE_MAX);
        match domain {
            Domain::Disk | Domain::HalfVector => BaseDist::Disk {
                mu: [out[0], out[1]],
                ln_sigma: [clamp(out[2]), clamp(out[3])],
            },
            Domain::Sphere | Domain::Equatorial => BaseDist::Sphere {
                mu_theta: out[0],
                ln_sigma: clamp(out[1]),
                mu_phi: out[2],
                ln_gamma: clamp(out[3]),
            },
        }
    }

    /// `x0` for `u` (phi is not wrapped here; the flow wraps it).
    #[inline]
    #[must_use]
    pub fn sample(&self, u: [f32; 2]) -> [f32; 2] {
        match *self {
            BaseDist::Disk { mu, ln_sigma } => [
                mu[0] + exp(ln_sigma[0]) * gaussian::quantile(u[0]),
                mu[1] + exp(ln_sigma[1]) * gaussian::quantile(u[1]),
            ],
            BaseDist::Sphere {
                mu_theta,
                ln_sigma,
                mu_phi,
                ln_gamma,
            } => [
                mu_theta + exp(ln_sigma) * gaussian::quantile(u[0]),
                mu_phi + wrapped_cauchy::sample(u[1], exp(ln_gamma)),
            ],
        }
    }

    /// `ln p0(x0)` (density in the flow's coordinates).
    #[inline]
    #[must_use]
    pub fn ln_pdf(&self, x0: [f32; 2]) -> f32 {
        match *self {
            // (32): (60) at the standard coordinates of x0.
            BaseDist::Disk { .. } => self.standard_ln_pdf(self.to_standard(x0)),
            BaseDist::Sphere {
                mu_theta,
                ln_sigma,
                mu_phi,
                ln_gamma,
            } => {
                let z = (x0[0] - mu_theta) * exp(-ln_sigma);
                gaussian::ln_pdf(z) - ln_sigma
                    + wrapped_cauchy::ln_pdf(x0[1] - mu_phi, exp(ln_gamma))
            }
        }
    }
}
