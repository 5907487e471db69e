//! The standard normal: its quantile (the map from `u` to `z`) and its log-density.

use crate::math::{exp, ln, sqrt};
use crate::spec::{
    ERFC_POLY, ERFINV_BRANCH_W, ERFINV_CENTRAL, ERFINV_CENTRAL_SHIFT, ERFINV_TAIL,
    ERFINV_TAIL_SHIFT, GAUSSIAN_TAIL_MIN, LN_INV_SQRT_2PI,
};

/// `z = Phi^-1(u) = sqrt(2) erfinv(2u - 1)`, finite for every `u` in [0, 1].
///
/// erfinv by Giles' single-precision approximation ("Approximating the erfinv function",
/// GPU Computing Gems, 2011), with `w = -ln((1 - x)(1 + x)) = -ln(4 q (1 - q))` computed
/// from the tail probability `q = min(u, 1 - u)` so that no precision is lost near 0 or 1.
#[inline]
#[must_use]
pub fn quantile(u: f32) -> f32 {
    let q = if u < 0.5 { u } else { 1.0 - u };
    // `u` closer than GAUSSIAN_TAIL_MIN to 0 or 1 maps to |z| = 7.1: keeps `u = 0` finite;
    // the mass beyond (9.1e-13 per tail) is never sampled. The approximation's tail
    // probability is within 2e-5 (relative) of `u` down to tails of 2e-8, and within 10 %
    // below that (tests/base_distributions.rs).
    let q = q.clamp(GAUSSIAN_TAIL_MIN, 0.5);
    let x = 1.0 - 2.0 * q; // |2u - 1|
    let w = -ln(4.0 * q * (1.0 - q));
    let p = if w < ERFINV_BRANCH_W {
        horner(&ERFINV_CENTRAL, w - ERFINV_CENTRAL_SHIFT)
    } else {
        horner(&ERFINV_TAIL, sqrt(w) - ERFINV_TAIL_SHIFT)
    };
    let z = core::f32::consts::SQRT_2 * p * x;
    if u < 0.5 {
        -z
    } else {
        z
    }
}

/// `c[0] w^(n-1) + ... + c[n-1]` by Horner's rule, highest degree first.
#[inline(always)]
fn horner(c: &[f32], w: f32) -> f32 {
    let mut p = c.first().copied().unwrap_or(0.0);
    for &ck in c.iter().skip(1) {
        p = ck + p * w;
    }
    p
}

/// `Phi(z) = erfc(-z / sqrt 2) / 2`, for `z <= 0` as `t exp(-x^2 + P(t)) / 2` with `x =
/// |z| / sqrt 2`, `t = 1 / (1 + x / 2)` (docs/math.md, (73)), for `z > 0` as one minus
/// that: the tail probability keeps its relative precision on either side.
#[inline]
#[must_use]
pub fn cdf(z: f32) -> f32 {
    let x = z.abs() * core::f32::consts::FRAC_1_SQRT_2;
    let t = 1.0 / (1.0 + 0.5 * x);
    let tail = 0.5 * t * exp(horner(&ERFC_POLY, t) - x * x);
    if z > 0.0 {
        1.0 - tail
    } else {
        tail
    }
}

/// `ln N(z; 0, 1) = -z^2/2 - ln sqrt(2 pi)`.
#[inline(always)]
#[must_use]
pub fn ln_pdf(z: f32) -> f32 {
    -0.5 * z * z + LN_INV_SQRT_2PI
}
