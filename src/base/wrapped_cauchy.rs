//! The wrapped Cauchy distribution on the circle, the base law of `phi` on the sphere.
//!
//! With scale `gamma` (`rho = e^-gamma` the mean resultant length), centred at 0:
//!
//! `p(d) = sinh(gamma) / (2 pi (cosh gamma - cos d))
//!       = sinh(gamma) / (4 pi (sinh^2(gamma/2) + sin^2(d/2)))`
//!
//! The second form has no cancellation, so the log-density is accurate for lobes as sharp
//! as `gamma = 1e-4` and in f16. Its CDF inverts in closed form:
//! `tan(d/2) = tanh(gamma/2) tan(pi (u - 1/2))` — a deterministic, monotone map from `u`.
//! (The von Mises law has neither a closed-form inverse CDF nor a stable f16 density.)

use crate::math::{atan2, ln, sin, sin_cos, sinh, tanh};
use crate::spec::LN_4PI;
use core::f32::consts::PI;

/// The offset `d` in (-pi, pi] for `u` in [0, 1].
///
/// `tan(pi (u - 1/2)) = -cos(pi u) / sin(pi u)`, so `d / 2 = atan2(-tanh(gamma/2) cos(pi u),
/// sin(pi u))`: `sin(pi u) >= 0` on [0, 1) in f32, and `u = 0` gives `d = -pi` exactly.
#[inline]
#[must_use]
pub fn sample(u: f32, gamma: f32) -> f32 {
    let (s, c) = sin_cos(PI * u);
    2.0 * atan2(-tanh(0.5 * gamma) * c, s)
}

/// `ln p(d)` for an offset `d` (any real; the density is 2 pi periodic).
#[inline]
#[must_use]
pub fn ln_pdf(d: f32, gamma: f32) -> f32 {
    let sh = sinh(0.5 * gamma);
    let sd = sin(0.5 * d);
    ln(sinh(gamma)) - LN_4PI - ln(sh * sh + sd * sd)
}
