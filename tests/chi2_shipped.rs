//! Pearson's chi-square test of every shipped f32 model: the directions `sample` draws are
//! distributed as `pdf()` says. The sphere is cut into cells of equal solid angle (uniform
//! in `cos theta` and `phi`); each cell's expected count is `n` times the quadrature of
//! `pdf()` over it, and the samples lost by the model (invalid) form one more cell with the
//! remaining mass. Cells expected to hold fewer than 5 samples are pooled. A sampler whose
//! PDF is not the density it samples (a wrong Jacobian, a mis-normalised base, a missing
//! branch) fails by a wide margin; rounding does not.

mod support;

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::AnyModel;
use std::f64::consts::TAU;
use support::Rng;

/// Cells in `cos theta` over [-1, 1] and in `phi`.
const CELLS_Z: usize = 32;
const CELLS_PHI: usize = 64;
/// Quadrature points per cell and axis (midpoint rule) to start with, and the most.
const QUAD: usize = 4;
const MAX_QUAD: usize = 64;
/// Samples per model and `wi`.
const SAMPLES: usize = 100_000;
/// Cells expected to hold fewer samples are pooled into one.
const MIN_EXPECTED: f64 = 5.0;
/// Largest allowed Wilson-Hilferty z of the statistic (one-sided p about 3e-7 per test;
/// some 40 tests run).
const MAX_Z: f64 = 5.0;

fn cell_of(wo: Vec3) -> usize {
    let z = (wo.z as f64).clamp(-1.0, 1.0);
    let iz = (((z + 1.0) * 0.5 * CELLS_Z as f64) as usize).min(CELLS_Z - 1);
    let phi = (wo.y as f64).atan2(wo.x as f64).rem_euclid(TAU);
    let ip = ((phi / TAU * CELLS_PHI as f64) as usize).min(CELLS_PHI - 1);
    iz * CELLS_PHI + ip
}

/// Midpoint quadrature of `pdf()` over cell `(iz, ip)` with `n x n` points.
fn cell_quadrature(m: &AnyModel, wi: Vec3, iz: usize, ip: usize, n: usize) -> f64 {
    let (dz, dphi) = (2.0 / CELLS_Z as f64, TAU / CELLS_PHI as f64);
    let mut sum = 0.0;
    for a in 0..n {
        let z = -1.0 + dz * (iz as f64 + (a as f64 + 0.5) / n as f64);
        let r = (1.0 - z * z).max(0.0).sqrt();
        for b in 0..n {
            let phi = dphi * (ip as f64 + (b as f64 + 0.5) / n as f64);
            let wo = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
            sum += m.pdf(wi, wo) as f64;
        }
    }
    sum * dz * dphi / (n * n) as f64
}

/// The probability `pdf()` gives each cell: midpoint quadrature, the points per axis
/// doubled from [`QUAD`] until two estimates agree to a tenth of the cell's sampling noise
/// (sharp measured lobes need far more points in the cells they peak in).
fn cell_masses(m: &AnyModel, wi: Vec3) -> Vec<f64> {
    let mut mass = vec![0.0; CELLS_Z * CELLS_PHI];
    for iz in 0..CELLS_Z {
        for ip in 0..CELLS_PHI {
            let mut n = QUAD;
            let mut coarse = cell_quadrature(m, wi, iz, ip, n);
            while n < MAX_QUAD {
                n *= 2;
                let fine = cell_quadrature(m, wi, iz, ip, n);
                let counts = fine * SAMPLES as f64;
                let change = (fine - coarse).abs() * SAMPLES as f64;
                coarse = fine;
                if change <= 0.1 * counts.sqrt().max(1.0) {
                    break;
                }
            }
            mass[iz * CELLS_PHI + ip] = coarse;
        }
    }
    mass
}

/// `(statistic, degrees of freedom)` of observed against expected counts, pooling the
/// cells expected to hold fewer than [`MIN_EXPECTED`].
fn pearson(observed: &[f64], expected: &[f64]) -> (f64, usize) {
    let (mut stat, mut cells) = (0.0, 0usize);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for (&o, &e) in observed.iter().zip(expected) {
        if e < MIN_EXPECTED {
            pool_o += o;
            pool_e += e;
        } else {
            stat += (o - e) * (o - e) / e;
            cells += 1;
        }
    }
    if pool_e >= MIN_EXPECTED {
        stat += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        cells += 1;
    } else if pool_o > 2.0 * MIN_EXPECTED {
        // Samples where pdf() says there is (almost) no mass: count them against a floor.
        stat += (pool_o - pool_e) * (pool_o - pool_e) / MIN_EXPECTED;
        cells += 1;
    }
    (stat, cells.saturating_sub(1).max(1))
}

/// Wilson-Hilferty normal approximation of a chi-square statistic with `df` degrees.
fn wilson_hilferty_z(stat: f64, df: usize) -> f64 {
    let k = df as f64;
    let c = 2.0 / (9.0 * k);
    ((stat / k).powf(1.0 / 3.0) - (1.0 - c)) / c.sqrt()
}

/// The statistic and its degrees of freedom for [`SAMPLES`] samples drawn at `wi_sampled`
/// against the cell masses of `pdf()` at `wi_pdf`, and the lost fractions (sampled, by
/// `pdf()`).
fn statistic(m: &AnyModel, wi_sampled: Vec3, wi_pdf: Vec3, seed: u64) -> (f64, usize, f64, f64) {
    let mut rng = Rng::new(seed);
    let lost = CELLS_Z * CELLS_PHI;
    let mut observed = vec![0.0; lost + 1];
    for _ in 0..SAMPLES {
        let u = Vec2::new(rng.uniform(), rng.uniform());
        match m.sample(wi_sampled, u) {
            Some(s) => observed[cell_of(s.wo)] += 1.0,
            None => observed[lost] += 1.0,
        }
    }
    let mut expected: Vec<f64> = cell_masses(m, wi_pdf)
        .iter()
        .map(|p| p * SAMPLES as f64)
        .collect();
    let in_domain: f64 = expected.iter().sum();
    expected.push((SAMPLES as f64 - in_domain).max(0.0));
    let (stat, df) = pearson(&observed, &expected);
    let n = SAMPLES as f64;
    (stat, df, observed[lost] / n, expected[lost] / n)
}

fn check(name: &str, m: &AnyModel, wi: Vec3, seed: u64) -> f64 {
    let (stat, df, lost_sampled, lost_pdf) = statistic(m, wi, wi, seed);
    let z = wilson_hilferty_z(stat, df);
    println!(
        "{name} wi {wi:?}: chi2 {stat:.1} on {df} degrees, z {z:.2}; lost {lost_sampled:.4} sampled, {lost_pdf:.4} by pdf()"
    );
    z
}

#[test]
fn shipped_samplers_draw_the_density_their_pdf_reports() {
    let blobs = support::shipped_blobs();
    assert!(!blobs.is_empty(), "no shipped models found");
    let mut worst: (f64, String) = (f64::NEG_INFINITY, String::new());
    for (k, (name, bytes)) in blobs.iter().enumerate() {
        if name.contains(".f16.") {
            continue;
        }
        let m = AnyModel::from_blob(bytes).unwrap();
        let mut wis = vec![(0.6f64, 0.4f64), (1.35, 2.1)];
        if m.def().accepts_incident_z(-1.0) {
            wis.push((2.4, -1.0));
        }
        for (j, (theta, phi)) in wis.into_iter().enumerate() {
            let wi = Vec3::new(
                (theta.sin() * phi.cos()) as f32,
                (theta.sin() * phi.sin()) as f32,
                theta.cos() as f32,
            );
            let z = check(name, &m, wi, 1000 + (k * 10 + j) as u64);
            if z > worst.0 {
                worst = (z, format!("{name} at theta_i {theta}"));
            }
            assert!(
                z <= MAX_Z,
                "{name}: samples at theta_i {theta} do not follow pdf() (z {z:.2} > {MAX_Z})"
            );
        }
    }
    println!("worst: z {:.2} ({})", worst.0, worst.1);
}

/// The test has power: the samples of one `wi` against the `pdf()` of a `wi` 0.15 rad
/// away fail it by far.
#[test]
fn chi2_rejects_the_density_of_another_wi() {
    let blobs = support::shipped_blobs();
    let (name, bytes) = blobs
        .iter()
        .find(|(n, _)| n.starts_with("conductor-ggx-a0.3-cu-disk") && !n.contains(".f16."))
        .expect("the rough copper disk model is shipped");
    let m = AnyModel::from_blob(bytes).unwrap();
    let at = |theta: f32| Vec3::new(theta.sin(), 0.0, theta.cos());
    let (stat, df, _, _) = statistic(&m, at(0.6), at(0.75), 5);
    let z = wilson_hilferty_z(stat, df);
    println!("{name}: wrong wi: chi2 {stat:.1} on {df} degrees, z {z:.2}");
    assert!(z > 10.0 * MAX_Z, "a wrong density passed (z {z:.2})");
}
