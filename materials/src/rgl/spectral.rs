//! Spectral RGL files (`_spec`: a `spectra` table over `wavelengths` in place of `rgb`)
//! read as linear Rec. 709 RGB: every node's spectrum is projected once, at load, onto the
//! CIE 1931 colour-matching functions and the XYZ -> linear sRGB matrix.
//!
//! The projection is linear, so projecting the nodes and then interpolating them (what
//! [`super::RglMaterial`] does with an `rgb` table) is interpolating the spectra and
//! projecting the result. White is the equal-energy spectrum: a constant spectrum `s`
//! has luminance `Y = s` (the integrals are normalised by the `y` curve's integral over
//! the file's own wavelengths, by the trapezoid rule).
//!
//! The colour-matching functions are the multi-lobe fit of Wyman, Sloan and Shirley
//! (2013), "Simple Analytic Approximations to the CIE XYZ Color Matching Functions"
//! (JCGT 2(2)), eq. (2): within about 1 % of the tabulated CIE 1931 2-degree observer at
//! its peaks, finer than the measured spectra's own noise.

use super::RglError;

/// One piecewise Gaussian lobe: weight, centre (nm), width left and right of it (nm).
type Lobe = (f64, f64, f64, f64);

/// `x(lambda)`: three lobes.
const X_LOBES: [Lobe; 3] = [
    (1.056, 599.8, 37.9, 31.0),
    (0.362, 442.0, 16.0, 26.7),
    (-0.065, 501.1, 20.4, 26.2),
];
/// `y(lambda)`: two lobes.
const Y_LOBES: [Lobe; 2] = [(0.821, 568.8, 46.9, 40.5), (0.286, 530.9, 16.3, 31.1)];
/// `z(lambda)`: two lobes.
const Z_LOBES: [Lobe; 2] = [(1.217, 437.0, 11.8, 36.0), (0.681, 459.0, 26.0, 13.8)];

/// XYZ -> linear sRGB (Rec. 709 primaries, D65 white), rows R, G, B; its inverse's middle
/// row is the luminance weights of [`crate::Rgb::luminance`].
const XYZ_TO_RGB: [[f64; 3]; 3] = [
    [3.240_454_2, -1.537_138_5, -0.498_531_4],
    [-0.969_266_0, 1.876_010_8, 0.041_556_0],
    [0.055_643_4, -0.204_025_9, 1.057_225_2],
];

/// The sum of a curve's lobes at `lambda` (nm): `sum w exp(-(lambda - mu)^2 / (2
/// sigma^2))`, `sigma` the lobe's left width below `mu` and its right width above (Wyman
/// et al. 2013, eq. (2)).
fn lobes(lambda: f64, curve: &[Lobe]) -> f64 {
    curve
        .iter()
        .map(|&(w, mu, left, right)| {
            let t = (lambda - mu) / if lambda < mu { left } else { right };
            w * (-0.5 * t * t).exp()
        })
        .sum()
}

/// The CIE 1931 2-degree colour-matching functions `(x, y, z)` at `lambda` (nm).
pub fn cie_xyz(lambda: f64) -> [f64; 3] {
    [
        lobes(lambda, &X_LOBES),
        lobes(lambda, &Y_LOBES),
        lobes(lambda, &Z_LOBES),
    ]
}

/// Per wavelength, the weights that turn a spectrum sampled at `wavelengths` (nm,
/// increasing) into linear RGB: `rgb_c = sum_k weights[c][k] s_k`, the trapezoid rule
/// of `M (x, y, z) s` over the samples divided by that of `y` alone. An error when the
/// wavelengths are fewer than two, not finite and increasing, or see no visible light.
pub fn rgb_weights(wavelengths: &[f64]) -> Result<[Vec<f64>; 3], RglError> {
    let n = wavelengths.len();
    let increasing = wavelengths.windows(2).all(|w| w[1] > w[0]);
    if n < 2 || !increasing || wavelengths.iter().any(|l| !l.is_finite()) {
        return Err(RglError::BadWavelengths);
    }
    // Trapezoid rule on a non-uniform grid: half the neighbouring intervals.
    let step =
        |k: usize| 0.5 * (wavelengths[(k + 1).min(n - 1)] - wavelengths[k.saturating_sub(1)]);
    let cmf: Vec<[f64; 3]> = wavelengths.iter().map(|&l| cie_xyz(l)).collect();
    let y_integral: f64 = (0..n).map(|k| step(k) * cmf[k][1]).sum();
    if !(y_integral > 1e-6) {
        return Err(RglError::BadWavelengths);
    }
    let mut weights = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
    for (c, row) in weights.iter_mut().enumerate() {
        for (k, w) in row.iter_mut().enumerate() {
            let xyz = cmf[k];
            let m = XYZ_TO_RGB[c];
            *w = step(k) * (m[0] * xyz[0] + m[1] * xyz[1] + m[2] * xyz[2]) / y_integral;
        }
    }
    Ok(weights)
}

/// A `[slices, W, ny, nx]` spectral table as the `[slices, 3, ny, nx]` RGB table of the
/// same nodes (`weights` from [`rgb_weights`], `W` long).
pub fn spectra_to_rgb(spectra: &[f64], weights: &[Vec<f64>; 3], node_count: usize) -> Vec<f64> {
    let w = weights[0].len();
    let slice_len = w * node_count;
    let slices = spectra.len().checked_div(slice_len).unwrap_or(0);
    let mut rgb = vec![0.0; slices * 3 * node_count];
    for s in 0..slices {
        let spectrum = &spectra[s * slice_len..(s + 1) * slice_len];
        for (c, weights_c) in weights.iter().enumerate() {
            let out = &mut rgb[(s * 3 + c) * node_count..(s * 3 + c + 1) * node_count];
            for (k, &wk) in weights_c.iter().enumerate() {
                let band = &spectrum[k * node_count..(k + 1) * node_count];
                for (o, &v) in out.iter_mut().zip(band) {
                    *o += wk * v;
                }
            }
        }
    }
    rgb
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rgb::luminance;

    /// The fit against the tabulated CIE 1931 2-degree observer at the curves' peaks
    /// (`y(555) = 1.0`, `x(600) = 1.0622`, `z(450) = 1.77211`) and their integrals over
    /// 360-830 nm (106.86, 106.86, 106.89 at 1 nm steps).
    #[test]
    fn colour_matching_functions_follow_the_cie_tables() {
        let close = |a: f64, b: f64, tol: f64| (a - b).abs() <= tol * b.abs();
        assert!(close(cie_xyz(555.0)[1], 1.0, 0.01), "{:?}", cie_xyz(555.0));
        assert!(
            close(cie_xyz(600.0)[0], 1.0622, 0.01),
            "{:?}",
            cie_xyz(600.0)
        );
        assert!(
            close(cie_xyz(450.0)[2], 1.77211, 0.01),
            "{:?}",
            cie_xyz(450.0)
        );
        let mut sums = [0.0; 3];
        for l in 360..=830 {
            let v = cie_xyz(l as f64);
            for c in 0..3 {
                sums[c] += v[c];
            }
        }
        for (s, cie) in sums.iter().zip([106.86, 106.86, 106.89]) {
            assert!(close(*s, cie, 0.02), "{sums:?}");
        }
    }

    /// A constant spectrum has luminance equal to its value on any grid that covers the
    /// visible range; a band at 610 nm is red, one at 460 nm blue.
    #[test]
    fn equal_energy_white_has_its_own_luminance_and_bands_have_their_hue() {
        let uniform: Vec<f64> = (0..=128).map(|k| 360.0 + 5.0 * k as f64).collect();
        let uneven: Vec<f64> = (0..=60).map(|k| 380.0 + 0.1 * (k * k) as f64).collect();
        for grid in [&uniform, &uneven] {
            let w = rgb_weights(grid).unwrap();
            let white = spectra_to_rgb(&vec![0.5; grid.len()], &w, 1);
            let y = luminance([white[0], white[1], white[2]]);
            assert!((y - 0.5).abs() < 1e-4 * 0.5, "{white:?} {y}");
            for (centre, channel) in [(610.0, 0), (460.0, 2)] {
                let band: Vec<f64> = grid
                    .iter()
                    .map(|l| (-0.5 * ((l - centre) / 15.0f64).powi(2)).exp())
                    .collect();
                let rgb = spectra_to_rgb(&band, &w, 1);
                let top = (0..3).max_by(|&a, &b| rgb[a].total_cmp(&rgb[b])).unwrap();
                assert_eq!(top, channel, "{centre} nm: {rgb:?}");
            }
        }
    }

    #[test]
    fn rejects_wavelengths_that_cannot_be_integrated() {
        for bad in [
            vec![],
            vec![550.0],
            vec![500.0, 500.0, 600.0],
            vec![600.0, 500.0],
            vec![400.0, f64::NAN],
            vec![1000.0, 1100.0, 1200.0],
        ] {
            assert_eq!(rgb_weights(&bad), Err(RglError::BadWavelengths), "{bad:?}");
        }
    }
}
