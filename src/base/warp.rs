//! The compressive warp of the standard coordinates (docs/math.md, §6.4): a model with
//! [`crate::ModelDef::standard_warp`] runs its flow in `y = K asinh(z / K)` per coordinate,
//! `K` = [`crate::spec::STANDARD_WARP_K`]. Near the lobe (`|z| << K`) `y = z`; far out, where a
//! measured target keeps mass many standard deviations from the base's centre (a grazing
//! tail, a second lobe), `y` grows like `K ln(2 |z| / K)`, so the velocity net sees the
//! whole target within a few units instead of dozens.
//!
//! Every formula is written with `exp`, `ln`, `sqrt` and `abs` only, as the generated
//! GLSL, WGSL and C write it, so all languages evaluate the same expressions.

use crate::math::{exp, ln, sqrt};
use crate::spec::STANDARD_WARP_K as K;

/// `y = K asinh(z / K) = sign(z) K ln(a + sqrt(a^2 + 1))`, `a = |z| / K` (docs/math.md, (63)).
#[inline]
#[must_use]
pub fn compress(z: f32) -> f32 {
    let a = z.abs() / K;
    let y = K * ln(a + sqrt(a * a + 1.0));
    if z < 0.0 {
        -y
    } else {
        y
    }
}

/// `z = K sinh(y / K) = K (e^(y/K) - e^(-y/K)) / 2` (docs/math.md, (64)).
#[inline]
#[must_use]
pub fn expand(y: f32) -> f32 {
    let s = y / K;
    K * (0.5 * (exp(s) - exp(-s)))
}

/// `ln |dz/dy| = ln cosh(y / K) = a + ln(1/2 + e^(-2a)/2)`, `a = |y| / K`, free of overflow
/// (docs/math.md, (65)).
#[inline]
#[must_use]
pub fn ln_expansion(y: f32) -> f32 {
    let a = y.abs() / K;
    a + ln(0.5 + 0.5 * exp(-2.0 * a))
}

/// [`compress`] of both coordinates.
#[inline]
#[must_use]
pub fn compress2(z: [f32; 2]) -> [f32; 2] {
    [compress(z[0]), compress(z[1])]
}

/// [`expand`] of both coordinates.
#[inline]
#[must_use]
pub fn expand2(y: [f32; 2]) -> [f32; 2] {
    [expand(y[0]), expand(y[1])]
}

/// `ln |det dz/dy|` of the warp at `y`: [`ln_expansion`] summed over both coordinates.
#[inline]
#[must_use]
pub fn ln_expansion2(y: [f32; 2]) -> f32 {
    ln_expansion(y[0]) + ln_expansion(y[1])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points from the lobe's centre to far beyond any standard coordinate a sample has.
    fn points() -> impl Iterator<Item = f32> {
        (-400..=400).map(|i| i as f32 * 0.05 * (1.0 + (i as f32 / 100.0).abs().powi(3)))
    }

    #[test]
    fn compress_and_expand_are_inverse_to_rounding() {
        for z in points() {
            let back = expand(compress(z));
            assert!((back - z).abs() <= 4e-6 * (1.0 + z.abs()), "z {z}: {back}");
        }
    }

    #[test]
    fn compress_is_odd_monotone_and_the_identity_near_zero() {
        let mut last = f32::NEG_INFINITY;
        for z in points() {
            let y = compress(z);
            assert!(y > last, "not increasing at {z}");
            assert_eq!(y, -compress(-z));
            last = y;
        }
        // Written with `ln`, not `ln_1p` (the shading languages have none): near 0 the
        // error is absolute, about K times one rounding of 1.
        assert!((compress(0.01) - 0.01).abs() < 1e-6);
        assert_eq!(compress(0.0), 0.0);
    }

    #[test]
    fn ln_expansion_is_ln_cosh_and_the_log_derivative_of_expand() {
        for y in points() {
            let want = (f64::from(y) / f64::from(K)).cosh().ln();
            let got = f64::from(ln_expansion(y));
            assert!(
                (got - want).abs() <= 2e-6 * (1.0 + want),
                "y {y}: {got} vs {want}"
            );
            // dz/dy by a central difference of expand, where it is finite.
            let h = 1e-2f32;
            let slope = (f64::from(expand(y + h)) - f64::from(expand(y - h))) / f64::from(2.0 * h);
            if slope.is_finite() && slope < 1e30 {
                assert!((slope.ln() - want).abs() < 1e-3, "y {y}: slope {slope}");
            }
        }
        assert!(ln_expansion(1e6).is_finite());
    }
}
