//! Special functions: `erf` (from `libm`) and its inverse.

use std::f64::consts::PI;

/// The error function.
pub fn erf(x: f64) -> f64 {
    libm::erf(x)
}

/// Inverse error function on `(-1, 1)`: Giles (2010) single-precision approximation as a
/// start, refined by Newton steps on [`erf`] to double precision. Clamps to +-6 at +-1.
pub fn erf_inv(y: f64) -> f64 {
    if !(y > -1.0) {
        return -6.0;
    }
    if !(y < 1.0) {
        return 6.0;
    }
    let w = -((1.0 - y) * (1.0 + y)).ln();
    let mut x = if w < 5.0 {
        let w = w - 2.5;
        let mut p = 2.810_226_36e-08;
        p = 3.432_739_39e-07 + p * w;
        p = -3.523_387_7e-06 + p * w;
        p = -4.391_506_54e-06 + p * w;
        p = 0.000_218_580_87 + p * w;
        p = -0.001_253_725_03 + p * w;
        p = -0.004_177_681_64 + p * w;
        p = 0.246_640_727 + p * w;
        p = 1.501_409_41 + p * w;
        p * y
    } else {
        let w = w.sqrt() - 3.0;
        let mut p = -0.000_200_214_257;
        p = 0.000_100_950_558 + p * w;
        p = 0.001_349_343_22 + p * w;
        p = -0.003_673_428_44 + p * w;
        p = 0.005_739_507_73 + p * w;
        p = -0.007_622_461_3 + p * w;
        p = 0.009_438_870_47 + p * w;
        p = 1.001_674_06 + p * w;
        p = 2.832_976_82 + p * w;
        p * y
    };
    for _ in 0..3 {
        let d = 2.0 / PI.sqrt() * (-x * x).exp();
        if d <= 0.0 {
            break;
        }
        x -= (erf(x) - y) / d;
    }
    x.clamp(-6.0, 6.0)
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
