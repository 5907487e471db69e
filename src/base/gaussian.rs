//! The standard normal: its quantile (the map from `u` to `z`) and its log-density.

use crate::math::{ln, sqrt};

/// Smallest tail probability the quantile is evaluated at: `u` closer than this to 0 or 1
/// maps to `|z| = 7.1`. Keeps `u = 0` finite; the mass beyond (1.8e-12 per tail) is never
/// sampled. The approximation's tail probability is within 2e-5 (relative) of `u` down to
/// tails of 2e-8, and within 10 % below that (measured in `tests/base_distributions.rs`):
/// the sampled density departs from the reported one on at most 4e-8 of the mass.
pub const TAIL_MIN: f32 = 9.094_947e-13; // 2^-40

/// `ln(1/sqrt(2 pi))`.
const LN_INV_SQRT_2PI: f32 = -0.918_938_5;

/// `z = Phi^-1(u) = sqrt(2) erfinv(2u - 1)`, finite for every `u` in [0, 1].
///
/// erfinv by Giles' single-precision approximation ("Approximating the erfinv function",
/// GPU Computing Gems, 2011), with `w = -ln((1 - x)(1 + x)) = -ln(4 q (1 - q))` computed
/// from the tail probability `q = min(u, 1 - u)` so that no precision is lost near 0 or 1.
#[inline]
pub fn quantile(u: f32) -> f32 {
    let q = if u < 0.5 { u } else { 1.0 - u };
    let q = q.clamp(TAIL_MIN, 0.5);
    let x = 1.0 - 2.0 * q; // |2u - 1|
    let w = -ln(4.0 * q * (1.0 - q));
    let p = if w < 5.0 {
        let w = w - 2.5;
        let p = 2.810_226_4e-8;
        let p = 3.432_739_4e-7 + p * w;
        let p = -3.523_387_7e-6 + p * w;
        let p = -4.391_506_5e-6 + p * w;
        let p = 2.185_808_7e-4 + p * w;
        let p = -1.253_725e-3 + p * w;
        let p = -4.177_681_6e-3 + p * w;
        let p = 0.246_640_73 + p * w;
        1.501_409_4 + p * w
    } else {
        let w = sqrt(w) - 3.0;
        let p = -2.002_142_6e-4;
        let p = 1.009_505_6e-4 + p * w;
        let p = 1.349_343_2e-3 + p * w;
        let p = -3.673_428_4e-3 + p * w;
        let p = 5.739_507_7e-3 + p * w;
        let p = -7.622_461_3e-3 + p * w;
        let p = 9.438_870_5e-3 + p * w;
        let p = 1.001_674 + p * w;
        2.832_976_8 + p * w
    };
    let z = core::f32::consts::SQRT_2 * p * x;
    if u < 0.5 {
        -z
    } else {
        z
    }
}

/// `ln N(z; 0, 1) = -z^2/2 - ln sqrt(2 pi)`.
#[inline(always)]
pub fn ln_pdf(z: f32) -> f32 {
    -0.5 * z * z + LN_INV_SQRT_2PI
}
