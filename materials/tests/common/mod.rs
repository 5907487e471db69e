//! Shared statistics for the material and training-data tests: lobe-adapted spherical
//! binning, adaptive quadrature of a density over each bin, and Pearson's chi-square test
//! with pooling of small bins (as Mitsuba's `ChiSquareTest`).
#![allow(dead_code)]

use diffbsdf_materials::{from_spherical, DVec3};
use std::f64::consts::PI;

/// Significance of every chi-square test before the Bonferroni correction.
pub const ALPHA: f64 = 0.01;

/// Bins in `a = (theta'/pi)^(1/4)`.
pub const NA: usize = 24;
/// Bins in the azimuth around the axis.
pub const NP: usize = 48;

/// Spherical binning around an axis, with bins that shrink towards the axis:
/// `theta' = pi a^4`, so a lobe centred on the axis spans many bins at any width.
#[derive(Clone, Copy, Debug)]
pub struct Domain {
    /// Orthonormal frame `(s, t, axis)` (Duff et al. 2017, glam's `any_orthonormal_pair`).
    frame: [DVec3; 3],
}

impl Domain {
    /// Binning around the unit vector `axis`.
    pub fn new(axis: DVec3) -> Self {
        Self {
            frame: {
                let (s, t) = axis.any_orthonormal_pair();
                [s, t, axis]
            },
        }
    }

    /// Direction for domain coordinates `(a, phi)`.
    pub fn dir(&self, a: f64, phi: f64) -> DVec3 {
        let theta = PI * a.powi(4);
        let v = from_spherical(theta, phi);
        let [s, t, n] = self.frame;
        s * v.x + t * v.y + n * v.z
    }

    /// `|d omega / (da dphi)| = sin(theta') 4 pi a^3`.
    pub fn jacobian(a: f64) -> f64 {
        (PI * a.powi(4)).sin() * 4.0 * PI * a.powi(3)
    }

    /// Bin index of a direction.
    pub fn bin(&self, w: DVec3) -> usize {
        let [s, t, n] = self.frame;
        let l = DVec3::new(w.dot(s), w.dot(t), w.dot(n));
        let theta = l.z.clamp(-1.0, 1.0).acos();
        let a = (theta / PI).powf(0.25);
        let mut phi = l.y.atan2(l.x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let ia = ((a * NA as f64) as usize).min(NA - 1);
        let ip = ((phi / (2.0 * PI) * NP as f64) as usize).min(NP - 1);
        ia * NP + ip
    }

    /// Integral of a density (per solid angle) over every bin.
    pub fn integrate(&self, f: &dyn Fn(DVec3) -> f64) -> Vec<f64> {
        let g = |a: f64, p: f64| {
            let v = f(self.dir(a, p)) * Self::jacobian(a);
            if v.is_finite() {
                v
            } else {
                0.0
            }
        };
        let mut out = vec![0.0; NA * NP];
        let (da, dp) = (1.0 / NA as f64, 2.0 * PI / NP as f64);
        for ia in 0..NA {
            for ip in 0..NP {
                let (a0, p0) = (ia as f64 * da, ip as f64 * dp);
                let mut s = 0.0;
                // Pre-split each bin 3 x 3 so a narrow peak cannot hide between nodes.
                for i in 0..3 {
                    for j in 0..3 {
                        let (ca, cp) = (da / 3.0, dp / 3.0);
                        s += adaptive(
                            &g,
                            a0 + i as f64 * ca,
                            a0 + (i + 1) as f64 * ca,
                            p0 + j as f64 * cp,
                            p0 + (j + 1) as f64 * cp,
                            0,
                        );
                    }
                }
                out[ia * NP + ip] = s;
            }
        }
        out
    }
}

/// 3-point Gauss-Legendre nodes and weights on [-1, 1].
const GL: [(f64, f64); 3] = [
    (-0.774_596_669_241_483_4, 5.0 / 9.0),
    (0.0, 8.0 / 9.0),
    (0.774_596_669_241_483_4, 5.0 / 9.0),
];

fn gauss(g: &dyn Fn(f64, f64) -> f64, a0: f64, a1: f64, p0: f64, p1: f64) -> f64 {
    let (ca, ha) = (0.5 * (a0 + a1), 0.5 * (a1 - a0));
    let (cp, hp) = (0.5 * (p0 + p1), 0.5 * (p1 - p0));
    let mut s = 0.0;
    for (xa, wa) in GL {
        for (xp, wp) in GL {
            s += wa * wp * g(ca + ha * xa, cp + hp * xp);
        }
    }
    s * ha * hp
}

fn adaptive(g: &dyn Fn(f64, f64) -> f64, a0: f64, a1: f64, p0: f64, p1: f64, depth: u32) -> f64 {
    let whole = gauss(g, a0, a1, p0, p1);
    let (am, pm) = (0.5 * (a0 + a1), 0.5 * (p0 + p1));
    let parts = [
        (a0, am, p0, pm),
        (am, a1, p0, pm),
        (a0, am, pm, p1),
        (am, a1, pm, p1),
    ];
    let split: f64 = parts
        .iter()
        .map(|&(x0, x1, y0, y1)| gauss(g, x0, x1, y0, y1))
        .sum();
    if depth >= 8 || (split - whole).abs() <= 1e-9 + 1e-6 * split.abs() {
        return split;
    }
    parts
        .iter()
        .map(|&(x0, x1, y0, y1)| adaptive(g, x0, x1, y0, y1, depth + 1))
        .sum()
}

/// `ln Gamma(x)` (Lanczos, g = 7, n = 9).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Regularised upper incomplete gamma `Q(s, x)` (series / continued fraction).
pub fn gamma_q(s: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    if x < s + 1.0 {
        let mut sum = 1.0 / s;
        let mut term = sum;
        let mut n = s;
        for _ in 0..10_000 {
            n += 1.0;
            term *= x / n;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - (sum.ln() - x + s * x.ln() - ln_gamma(s)).exp()
    } else {
        // Lentz's continued fraction.
        let tiny = 1e-300;
        let mut b = x + 1.0 - s;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - s);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        (-x + s * x.ln() - ln_gamma(s)).exp() * h
    }
}

/// Outcome of a chi-square test.
#[derive(Debug, Clone, Copy)]
pub struct Chi2 {
    /// The statistic.
    pub stat: f64,
    /// Degrees of freedom.
    pub dof: usize,
    /// p-value.
    pub p: f64,
}

/// Pearson's test of the directions `samples`, `n` draws of which the rest were lost,
/// against `n` times the integrals `integral` of the density over `dom`'s bins; the lost
/// draws are one more bin, expected `n (1 - sum integral)`.
pub fn chi2_of_samples(dom: &Domain, samples: &[DVec3], n: usize, integral: &[f64]) -> Chi2 {
    let total: f64 = integral.iter().sum();
    let mut observed = vec![0.0; integral.len() + 1];
    for w in samples {
        observed[dom.bin(*w)] += 1.0;
    }
    observed[integral.len()] = (n - samples.len()) as f64;
    let mut expected: Vec<f64> = integral.iter().map(|p| p * n as f64).collect();
    expected.push((1.0 - total).max(0.0) * n as f64);
    chi2(&observed, &expected)
}

/// Pearson's test of observed against expected counts, pooling bins with expected < 5
/// into one bin (bins whose quadrature is zero, e.g. slivers at the horizon, go there too).
pub fn chi2(observed: &[f64], expected: &[f64]) -> Chi2 {
    let mut idx: Vec<usize> = (0..observed.len()).collect();
    idx.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    let (mut stat, mut bins) = (0.0, 0usize);
    for &i in &idx {
        if expected[i] < 5.0 {
            pool_o += observed[i];
            pool_e += expected[i];
        } else {
            let d = observed[i] - expected[i];
            stat += d * d / expected[i];
            bins += 1;
        }
    }
    if pool_e > 0.0 {
        let d = pool_o - pool_e;
        stat += d * d / pool_e;
        bins += 1;
    }
    let dof = bins.saturating_sub(1).max(1);
    Chi2 {
        stat,
        dof,
        p: gamma_q(dof as f64 / 2.0, stat / 2.0),
    }
}

/// A deterministic uniform generator for tests.
pub fn rng(seed: u64) -> rand_pcg::Pcg64 {
    use rand::SeedableRng;
    rand_pcg::Pcg64::seed_from_u64(seed)
}

/// Unit direction at polar angle `theta_deg` (degrees) and azimuth `phi`.
pub fn dir_deg(theta_deg: f64, phi: f64) -> DVec3 {
    from_spherical(theta_deg.to_radians(), phi)
}

#[test]
fn gamma_q_matches_known_values() {
    // chi-square with 10 dof: P(X > 23.209) = 0.01.
    assert!((gamma_q(5.0, 23.209 / 2.0) - 0.01).abs() < 1e-4);
    // 2 dof: Q = exp(-x/2).
    assert!((gamma_q(1.0, 3.0) - (-3.0f64).exp()).abs() < 1e-12);
    // 600 dof, statistic 600: about 0.49.
    let q = gamma_q(300.0, 300.0);
    assert!((q - 0.4923).abs() < 0.01, "{q}");
}
