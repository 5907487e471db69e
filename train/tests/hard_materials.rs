//! Hard materials, trained: the cases the paper reports as failures — a near-specular
//! conductor (GGX alpha = 1e-3) and near-perfect transmission (Beckmann alpha = 1e-3,
//! eta = 1.01) — with f16 weights too. Tiny fits (seconds); every sample and PDF is
//! finite and non-negative, forward and inverse PDFs agree, and f16 samples stay close
//! to f32 ones, at grazing (cos theta_i in {0, 1e-6, 1e-3}), normal and oblique `wi` and
//! `u` at the corners of the unit square. Figures are printed (`--nocapture`).

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::{AnyModel, Domain, Precision};
use diffbsdf_materials::parse_spec;
use diffbsdf_train::{fit_material, FitConfig, ModelExt, Silent};

/// Relative forward/inverse PDF difference allowed (the kernel's contract is float
/// precision; sharp lobes condition the inverse, see docs/architecture.md).
const CONSISTENCY: f32 = 1e-3;
/// f16 vs f32: largest angle between the two samples of the same (wi, u), radians, for
/// the 99th percentile of pairs.
const F16_ANGLE_P99: f32 = 0.05;

fn incidences(sphere: bool) -> Vec<Vec3> {
    let mut v = Vec::new();
    for c in [0.0f32, 1e-6, 1e-3, 0.5, 1.0] {
        let s = (1.0 - c * c).sqrt();
        v.push(Vec3::new(s, 0.0, c));
        v.push(Vec3::new(0.6 * s, 0.8 * s, c));
        if sphere {
            v.push(Vec3::new(s, 0.0, -c));
        }
    }
    v
}

fn us() -> Vec<Vec2> {
    let edge = [0.0f32, 1e-7, 0.5, 1.0 - f32::EPSILON, 1.0];
    let mut v = Vec::new();
    for &a in &edge {
        for &b in &edge {
            v.push(Vec2::new(a, b));
        }
    }
    for k in 0..256 {
        let a = (k as f32 + 0.5) / 256.0;
        v.push(Vec2::new(a, (a * 97.0).fract()));
    }
    v
}

fn tiny(spec: &str, domain: Domain) -> AnyModel {
    let m = parse_spec(spec).unwrap();
    fit_material(m.as_ref(), "hard", &FitConfig::tiny(domain, 5), &Silent)
        .unwrap()
        .model
}

fn reload(m: &AnyModel, p: Precision) -> AnyModel {
    AnyModel::from_blob(&m.blob(p).unwrap()).unwrap()
}

fn check(spec: &str, domain: Domain) {
    let f32m = tiny(spec, domain);
    let f16m = reload(&f32m, Precision::F16);
    let sphere = domain == Domain::Sphere;
    for (label, m) in [("f32", &f32m), ("f16", &f16m)] {
        let (mut valid, mut unsolved, mut worst) = (0usize, 0usize, 0.0f32);
        for wi in incidences(sphere) {
            for u in us() {
                let Some(s) = m.sample(wi, u) else { continue };
                assert!(
                    s.wo.is_finite() && (s.wo.length() - 1.0).abs() < 1e-4,
                    "{spec} {label}: {s:?}"
                );
                assert!(
                    s.pdf.is_finite() && s.pdf > 0.0,
                    "{spec} {label}: pdf {}",
                    s.pdf
                );
                valid += 1;
                let q = m.pdf(wi, s.wo);
                assert!(q.is_finite() && q >= 0.0, "{spec} {label}: inverse pdf {q}");
                if q == 0.0 {
                    unsolved += 1;
                    eprintln!(
                        "{spec} {label} wi {wi:?} u {u:?}: pdf() = 0, sampled {}",
                        s.pdf
                    );
                    continue;
                }
                let r = (q - s.pdf).abs() / s.pdf;
                worst = worst.max(r);
                assert!(
                    r <= CONSISTENCY,
                    "{spec} {label} wi {wi:?} u {u:?}: sampled {}, inverse {q}",
                    s.pdf
                );
            }
        }
        let share = unsolved as f64 / valid.max(1) as f64;
        println!("{spec} ({domain:?}, {label}): {valid} valid samples, worst forward/inverse PDF difference {worst:.2e}, unsolved inversions {share:.4}");
        assert!(valid > 500, "{spec} {label}: only {valid} valid samples");
        assert_eq!(
            unsolved, 0,
            "{spec} {label}: {share} of inversions unsolved"
        );
    }
    let mut angles = Vec::new();
    for wi in incidences(sphere) {
        for u in us() {
            if let (Some(a), Some(b)) = (f32m.sample_direction(wi, u), f16m.sample_direction(wi, u))
            {
                angles.push(a.dot(b).clamp(-1.0, 1.0).acos());
            }
        }
    }
    angles.sort_by(f32::total_cmp);
    let p99 = angles[(angles.len() * 99 / 100).min(angles.len() - 1)];
    println!(
        "{spec}: f16 vs f32 sample angle p99 {p99:.2e} rad, max {:.2e} rad over {} pairs",
        angles.last().unwrap(),
        angles.len()
    );
    assert!(p99 <= F16_ANGLE_P99, "{spec}: f16 vs f32 p99 angle {p99}");
}

#[test]
fn near_specular_conductor_is_stable() {
    check("conductor:ggx,alpha=0.001,metal=Cu", Domain::Disk);
    check("conductor:ggx,alpha=0.001,metal=Cu", Domain::Sphere);
}

#[test]
fn near_perfect_transmission_is_stable() {
    check("dielectric:beckmann,alpha=0.001,eta=1.01", Domain::Sphere);
}
