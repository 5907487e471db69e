//! The shipped models in `models/` load in the kernel, never return NaN, keep every Euler
//! step invertible on a grid of `wi` and `u`, and report the same PDF forward and inverse
//! (up to a small fraction of samples whose Newton inversion fails; printed).

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::internals::Diagnostics;
use diffbsdf::AnyModel;
use diffbsdf_train::ModelExt;
use std::path::Path;

fn shipped() -> Vec<(String, AnyModel)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models");
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let p = entry.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if name.ends_with(".dbsdf") {
            let bytes = std::fs::read(&p).unwrap();
            out.push((name, AnyModel::from_blob(&bytes).unwrap()));
        }
    }
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

#[test]
fn shipped_models_are_exact_and_invertible() {
    let models = shipped();
    assert!(!models.is_empty());
    for (name, m) in &models {
        let sphere = m.def().domain.is_spherical();
        let (mut n, mut bad, mut min_det) = (0usize, 0usize, f32::INFINITY);
        for ti in 0..12 {
            let theta = (ti as f32 + 0.5) / 12.0 * if sphere { 3.1 } else { 1.55 };
            for pi in 0..4 {
                let phi = pi as f32 * 1.3 - 2.0;
                let wi = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                for k in 0..256 {
                    let u = Vec2::new(
                        (k as f32 + 0.5) / 256.0,
                        ((k * 97) % 256) as f32 / 256.0 + 1e-3,
                    );
                    if let Some(d) = m.min_det(wi, u) {
                        min_det = min_det.min(d);
                    }
                    if let Some(s) = m.sample(wi, u) {
                        assert!(s.pdf.is_finite() && s.wo.is_finite(), "{name}: NaN sample");
                        let q = m.pdf(wi, s.wo);
                        assert!(q.is_finite(), "{name}: NaN pdf");
                        n += 1;
                        // The flow's start point (in standard coordinates where the
                        // model's flow runs in them).
                        let mut pts = vec![[0.0f32; 2]; m.default_steps() as usize + 1];
                        let x0 = m
                            .trajectory(wi, u, m.default_steps(), &mut pts)
                            .map_or([0.0, 0.0], |_| pts[0]);
                        if !m.pdf_consistent(wi, s.wo, s.pdf, q, x0) {
                            bad += 1;
                            if bad <= 3 {
                                eprintln!("{name}: wi theta {theta:.3} phi {phi:.2} u {u:?} wo {:?}: sampled {} inverse {q}", s.wo, s.pdf);
                            }
                        }
                    }
                }
            }
        }
        let frac = bad as f64 / n.max(1) as f64;
        eprintln!(
            "{name}: {n} samples, {:.4}% inconsistent, min det {min_det:.4}",
            100.0 * frac
        );
        assert!(
            min_det > 0.0,
            "{name}: a step is not invertible (det {min_det})"
        );
        assert_eq!(bad, 0, "{name}: {:.3}% of PDFs disagree", 100.0 * frac);
    }
}
