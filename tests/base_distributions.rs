//! The base distributions: the Gaussian quantile is accurate and finite everywhere, the
//! wrapped Cauchy sampling map is the inverse of its CDF, and both log-densities stay
//! accurate for the sharpest allowed lobes.

use diffbsdf::internals::base::{gaussian, wrapped_cauchy};
use diffbsdf::spec::LN_SCALE_MIN;

/// Tail mass down to which the quantile is accurate to 2e-5 (relative).
const ACCURATE_TAIL: f64 = 2e-8;

/// `Phi(z)` in f64.
fn normal_cdf(z: f64) -> f64 {
    0.5 * libm::erfc(-z / std::f64::consts::SQRT_2)
}

#[test]
fn gaussian_quantile_is_accurate_from_the_tails_to_the_centre() {
    let (mut worst, mut deep_worst) = (0.0f64, 0.0f64);
    // Tail probabilities from 1e-11 to 0.5, both sides.
    for k in 0..=220 {
        let q = 10f64.powf(-11.0 + k as f64 * (11.0 - 0.301) / 220.0);
        for u in [q, 1.0 - q] {
            let uf = u as f32;
            if uf >= 1.0 {
                continue; // 1 - q is not representable in f32 this close to 1
            }
            let z = gaussian::quantile(uf) as f64;
            // Error in probability, relative to the tail probability at that point.
            let tail = (uf as f64).min(1.0 - uf as f64);
            let err = (normal_cdf(z) - uf as f64).abs() / tail;
            if tail >= ACCURATE_TAIL {
                worst = worst.max(err);
            } else {
                deep_worst = deep_worst.max(err);
            }
        }
    }
    println!(
        "worst relative tail-probability error {worst:e}; beyond {ACCURATE_TAIL:e}: {deep_worst:e}"
    );
    assert!(worst < 2e-5, "worst relative error {worst}");
    // Giles' polynomial is extrapolated below ~2e-8 of tail mass (4e-8 of all mass).
    assert!(deep_worst < 0.1, "deep-tail relative error {deep_worst}");
}

/// The CDF the latent table reads a start point back with (docs/math.md, (75)): within
/// 3e-7 of the tail probability (relative) from `|z| = 0` to 7, increasing, and the inverse
/// of the quantile to 1e-5 of the tail probability wherever the quantile is accurate.
#[test]
fn normal_cdf_is_accurate_monotone_and_inverts_the_quantile() {
    let mut last = 0.0f32;
    for k in -7000..=7000 {
        let z = k as f32 * 1e-3;
        let p = gaussian::cdf(z);
        let want = normal_cdf(f64::from(z));
        let tail = want.min(1.0 - want);
        let err = (f64::from(p) - want).abs();
        assert!(err <= 3e-7 * tail + 6e-8, "z {z}: {p} vs {want}");
        assert!(p >= last, "not increasing at {z}");
        last = p;
    }
    for k in 1..2000 {
        let u = k as f32 / 2000.0;
        let back = f64::from(gaussian::cdf(gaussian::quantile(u)));
        let tail = f64::from(u.min(1.0 - u));
        assert!(
            (back - f64::from(u)).abs() <= 1e-5 * tail + 1e-7,
            "u {u}: {back}"
        );
    }
    assert_eq!(gaussian::cdf(f32::NEG_INFINITY), 0.0);
    assert_eq!(gaussian::cdf(f32::INFINITY), 1.0);
}

#[test]
fn gaussian_quantile_is_finite_and_monotone() {
    let mut prev = f32::NEG_INFINITY;
    let mut u = 0.0f32;
    let ends = [
        0.0f32,
        f32::MIN_POSITIVE,
        1e-30,
        1.0 - f32::EPSILON / 2.0,
        1.0,
    ];
    for e in ends {
        assert!(gaussian::quantile(e).is_finite(), "u = {e}");
    }
    assert!(gaussian::quantile(0.0) < -7.0 && gaussian::quantile(1.0) > 7.0);
    while u < 1.0 {
        let z = gaussian::quantile(u);
        assert!(z >= prev, "not monotone at u = {u}");
        prev = z;
        u += 1.0 / 65536.0;
    }
}

#[test]
fn wrapped_cauchy_sampling_inverts_its_cdf() {
    for gamma in [0.01f32, 0.1, 1.0, 5.0] {
        // CDF by f64 quadrature of the f32 density, compared with u at sampled points.
        let n = 400_000;
        let mut cdf = vec![0.0f64; n + 1];
        let dx = std::f64::consts::TAU / n as f64;
        for i in 0..n {
            let d = -std::f64::consts::PI + (i as f64 + 0.5) * dx;
            cdf[i + 1] = cdf[i] + (wrapped_cauchy::ln_pdf(d as f32, gamma) as f64).exp() * dx;
        }
        assert!(
            (cdf[n] - 1.0).abs() < 1e-4,
            "gamma {gamma}: integral {}",
            cdf[n]
        );
        for u in [0.01f32, 0.2, 0.5, 0.77, 0.99] {
            let d = wrapped_cauchy::sample(u, gamma) as f64;
            let i = (((d + std::f64::consts::PI) / dx) as usize).min(n);
            assert!(
                (cdf[i] - u as f64).abs() < 2e-4,
                "gamma {gamma}, u {u}: cdf {}",
                cdf[i]
            );
        }
        assert!((wrapped_cauchy::sample(0.0, gamma).abs() - std::f32::consts::PI).abs() < 1e-6);
    }
}

#[test]
fn log_densities_stay_accurate_for_the_sharpest_lobes() {
    let gamma = LN_SCALE_MIN.exp();
    for d in [0.0f32, 1e-5, 1e-4, 1e-2, 1.0, 3.0] {
        let g = gamma as f64;
        let dd = d as f64;
        let exact = (g.sinh() / (std::f64::consts::TAU * (g.cosh() - dd.cos()))).ln();
        let got = wrapped_cauchy::ln_pdf(d, gamma) as f64;
        assert!(
            (got - exact).abs() < 1e-4 * exact.abs().max(1.0),
            "d {d}: {got} vs {exact}"
        );
    }
    assert!(gaussian::ln_pdf(7.2).is_finite());
}
