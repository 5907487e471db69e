//! Special functions: `erf` (from `libm`) and its inverse.

use diffbsdf::spec::{
    ERFINV_BRANCH_W, ERFINV_CENTRAL, ERFINV_CENTRAL_SHIFT, ERFINV_TAIL, ERFINV_TAIL_SHIFT,
};
use std::f64::consts::PI;

/// The error function.
pub fn erf(x: f64) -> f64 {
    libm::erf(x)
}

/// Inverse error function on `(-1, 1)`: the kernel's Giles (2010) single-precision
/// approximation (its coefficients, `diffbsdf::spec::ERFINV_*`, evaluated in f64) as a
/// start, refined by Newton steps on [`erf`] to double precision. Clamps to +-6 at +-1.
pub fn erf_inv(y: f64) -> f64 {
    if !(y > -1.0) {
        return -6.0;
    }
    if !(y < 1.0) {
        return 6.0;
    }
    let w = -((1.0 - y) * (1.0 + y)).ln();
    let p = if w < f64::from(ERFINV_BRANCH_W) {
        horner(&ERFINV_CENTRAL, w - f64::from(ERFINV_CENTRAL_SHIFT))
    } else {
        horner(&ERFINV_TAIL, w.sqrt() - f64::from(ERFINV_TAIL_SHIFT))
    };
    let mut x = p * y;
    for _ in 0..3 {
        let d = 2.0 / PI.sqrt() * (-x * x).exp();
        if d <= 0.0 {
            break;
        }
        x -= (erf(x) - y) / d;
    }
    x.clamp(-6.0, 6.0)
}

/// `c[0] w^(n-1) + ... + c[n-1]` by Horner's rule in f64, highest degree first.
fn horner(c: &[f32], w: f64) -> f64 {
    c.iter().fold(0.0, |p, &ck| f64::from(ck) + p * w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erf_inv_inverts_erf() {
        for i in 1..1000 {
            let y = -1.0 + 2.0 * i as f64 / 1000.0;
            assert!((erf(erf_inv(y)) - y).abs() < 1e-13, "{y}");
        }
    }
}
