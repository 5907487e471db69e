//! The kernel's properties on the models the project ships (`models/*.dbsdf`, f32 and
//! f16): every step orientation preserving along sampled trajectories, the PDF of each
//! sample recovered by the exact inverse, nothing non-finite, and (disk) normalization.

mod support;

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::internals::Diagnostics;
use diffbsdf::spec::{PDF_CONSISTENCY_TOL, PDF_ROUNDING_SPAN};
use diffbsdf::{AnyModel, Domain, IncidentRange};
use std::path::PathBuf;
use support::{direction, rel, Rng};

/// Valid samples per model and precision; `DIFFBSDF_CONSISTENCY_SAMPLES` raises it (the
/// README's full check uses 1 000 000).
fn samples_per_model() -> usize {
    std::env::var("DIFFBSDF_CONSISTENCY_SAMPLES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(60_000)
}

/// Incident polar angles: normal incidence to grazing; below the surface too for models
/// declared for them.
fn incident_thetas(domain: Domain, below: bool) -> Vec<f32> {
    let mut deg = vec![0.0f32, 10.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.0, 89.9];
    if domain.is_spherical() && below {
        deg.extend([90.1, 100.0, 135.0, 170.0, 180.0]);
    }
    deg.into_iter().map(f32::to_radians).collect()
}

/// `u` for sample `k`: a third uniform, a third with `u1` and a third with `u0` in strips
/// of width 5e-4 at 0 and 1 (where the base quantile is steepest).
fn uniform_pair(rng: &mut Rng, k: usize) -> Vec2 {
    let (mut a, mut b) = (rng.uniform(), rng.uniform());
    let edge = |rng: &mut Rng| {
        let s = rng.uniform() * 5e-4;
        if rng.uniform() < 0.5 {
            s
        } else {
            1.0 - s
        }
    };
    match k % 3 {
        1 => b = edge(rng),
        2 => a = edge(rng),
        _ => {}
    }
    Vec2::new(a, b)
}

/// What one incident angle gave: valid samples, zero PDFs, samples past PDF_TOL, the
/// worst relative difference and the worst ratio to the rounding bound.
#[derive(Default)]
struct Consistency {
    valid: usize,
    zero: usize,
    past_tol: usize,
    worst: f32,
    worst_over_kappa: f32,
}

fn consistency(name: &str, m: &AnyModel, theta: f32, per_theta: usize, seed: u64) -> Consistency {
    let steps = m.def().default_steps as u32;
    let mut pts = vec![[0.0f32; 2]; steps as usize + 1];
    let mut rng = Rng::new(seed);
    let mut c = Consistency::default();
    let mut k = 0;
    while c.valid < per_theta && k < 4 * per_theta {
        let phi = std::f32::consts::TAU * rng.uniform();
        let wi = Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        );
        let u = uniform_pair(&mut rng, k);
        k += 1;
        let dir = m.sample_direction(wi, u);
        let Some(s) = m.sample(wi, u) else {
            assert!(dir.is_none(), "{name}: paths disagree on validity");
            continue;
        };
        assert_eq!(dir, Some(s.wo), "{name}");
        assert!(s.pdf.is_finite() && s.pdf > 0.0);
        let min_det = m.trajectory(wi, u, steps, &mut pts).unwrap();
        assert!(
            min_det > 0.0,
            "{name}: det {min_det} along a trajectory for wi {wi:?}"
        );
        c.valid += 1;
        let back = m.pdf(wi, s.wo);
        assert!(
            back > 0.0,
            "{name}: pdf() = {back} for a valid sample: wi {wi:?} u {u:?} (sampled {})",
            s.pdf
        );
        let r = rel(back, s.pdf, 0.0);
        c.worst = c.worst.max(r);
        if r > PDF_CONSISTENCY_TOL {
            c.past_tol += 1;
            let kappa = m.pdf_rounding(wi, s.wo, back, pts[0]);
            c.worst_over_kappa = c.worst_over_kappa.max(r / kappa);
            assert!(
                m.pdf_consistent(wi, s.wo, s.pdf, back, pts[0]),
                "{name}: wi {wi:?} u {u:?}: sampled {} vs pdf() {back} (rel {r:e}, density change per epsilon of wo {kappa:e})",
                s.pdf
            );
        }
    }
    assert!(
        c.valid * 4 > k,
        "{name}: most samples at theta {theta} should be valid"
    );
    c
}

/// Every shipped model, f32 and f16: forward and inverse agree on every valid sample
/// (never a zero PDF), incl. grazing and normal incidence and `u` at the edges of [0, 1].
#[test]
fn shipped_models_are_invertible_and_consistent() {
    let per_model = samples_per_model();
    for (name, bytes) in support::shipped_blobs() {
        let m = AnyModel::from_blob(&bytes).unwrap();
        let below = m.def().incident == IncidentRange::WholeSphere;
        let thetas = incident_thetas(m.def().domain, below);
        let per_theta = per_model.div_ceil(thetas.len());
        let results: Vec<Consistency> = std::thread::scope(|scope| {
            let jobs: Vec<_> = thetas
                .iter()
                .enumerate()
                .map(|(i, &t)| {
                    let (name, m) = (&name, &m);
                    scope.spawn(move || consistency(name, m, t, per_theta, i as u64 + 1))
                })
                .collect();
            jobs.into_iter().map(|j| j.join().unwrap()).collect()
        });
        let sum = |f: fn(&Consistency) -> usize| results.iter().map(f).sum::<usize>();
        let worst = results.iter().map(|c| c.worst).fold(0.0, f32::max);
        let over = results
            .iter()
            .map(|c| c.worst_over_kappa)
            .fold(0.0, f32::max);
        println!(
            "{name}: {} valid, pdf() = 0 on {}, rel > {PDF_CONSISTENCY_TOL:e} on {} (worst {worst:.2e}, at most {over:.1} x the rounding bound; allowed {PDF_ROUNDING_SPAN})",
            sum(|c| c.valid),
            sum(|c| c.zero),
            sum(|c| c.past_tol),
        );
    }
}

#[test]
fn shipped_disk_model_integrates_to_one_minus_lost_mass() {
    let bytes = std::fs::read(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("models/conductor-ggx-a0.3-cu-disk.dbsdf"),
    )
    .unwrap();
    let m = AnyModel::from_blob(&bytes).unwrap();
    for wi in [direction(0.9, 0.1, true), direction(0.4, 0.6, true)] {
        let (nr, nphi) = (600, 1200);
        let mut integral = 0.0f64;
        for i in 0..nr {
            let r = (i as f32 + 0.5) / nr as f32;
            for j in 0..nphi {
                let phi = (j as f32 + 0.5) / nphi as f32 * std::f32::consts::TAU;
                let wo = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - r * r).sqrt());
                integral += (m.pdf(wi, wo) / wo.z) as f64 * r as f64;
            }
        }
        integral *= std::f64::consts::TAU / (nr * nphi) as f64;
        let lost = lost_share(&m, wi, 1000);
        println!(
            "wi {wi:?}: integral {integral:.6} + lost {lost:.6} = {:.6}",
            integral + lost
        );
        assert!((integral + lost - 1.0).abs() <= 1e-3, "{integral} + {lost}");
    }
}

/// Each shipped model declares the incident range it was trained for (its report's
/// quality grid reaches below the surface exactly when it is declared for the whole
/// sphere), and answers nothing outside it.
#[test]
fn shipped_models_declare_their_incident_range() {
    for (name, bytes) in support::shipped_blobs() {
        let m = AnyModel::from_blob(&bytes).unwrap();
        let stem = name.trim_end_matches(".dbsdf").trim_end_matches(".f16");
        let report = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("models")
            .join(format!("{stem}.report.json"));
        let text = std::fs::read_to_string(&report).expect("every shipped model has its report");
        let trained_below = text.contains("\"theta_deg\": 100.0");
        assert_eq!(
            m.def().incident == IncidentRange::WholeSphere,
            trained_below,
            "{name}"
        );
        if !trained_below {
            let below = Vec3::new(0.3, 0.1, -0.9).normalize();
            assert!(m.sample(below, Vec2::new(0.3, 0.6)).is_none(), "{name}");
            assert_eq!(m.pdf(below, Vec3::Z), 0.0, "{name}");
            assert_eq!(m.pdf(below, -below), 0.0, "{name}");
        }
    }
}

/// `∫ pdf dω` over the sphere (midpoints of a grid uniform in `z = cos theta` and `phi`, so
/// every cell has the same solid angle), split over threads by rows.
fn sphere_integral(m: &AnyModel, wi: Vec3, nz: usize, nphi: usize) -> f64 {
    let rows: Vec<usize> = (0..nz).collect();
    let parts: Vec<f64> = std::thread::scope(|scope| {
        let jobs: Vec<_> = rows
            .chunks(nz.div_ceil(2))
            .map(|chunk| {
                scope.spawn(move || {
                    let mut sum = 0.0f64;
                    for &i in chunk {
                        let z = -1.0 + 2.0 * (i as f32 + 0.5) / nz as f32;
                        let r = (1.0 - z * z).max(0.0).sqrt();
                        for j in 0..nphi {
                            let phi = (j as f32 + 0.5) / nphi as f32 * std::f32::consts::TAU;
                            let wo = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                            sum += m.pdf(wi, wo) as f64;
                        }
                    }
                    sum
                })
            })
            .collect();
        jobs.into_iter().map(|j| j.join().unwrap()).collect()
    });
    parts.iter().sum::<f64>() * 4.0 * std::f64::consts::PI / (nz * nphi) as f64
}

/// The share of a stratified `u` grid whose sample is lost (leaves the domain).
fn lost_share(m: &AnyModel, wi: Vec3, grid: usize) -> f64 {
    let mut lost = 0usize;
    for i in 0..grid {
        for j in 0..grid {
            let u = Vec2::new(
                (i as f32 + 0.5) / grid as f32,
                (j as f32 + 0.5) / grid as f32,
            );
            lost += usize::from(m.sample_direction(wi, u).is_none());
        }
    }
    lost as f64 / (grid * grid) as f64
}

/// Every shipped sphere model's PDF integrates over the sphere to one minus the mass its
/// samples lose (the density is the true density of what is sampled, nothing renormalised).
#[test]
fn shipped_sphere_models_integrate_to_one_minus_lost_mass() {
    for (name, bytes) in support::shipped_blobs() {
        let m = AnyModel::from_blob(&bytes).unwrap();
        if !m.def().domain.is_spherical() || name.contains(".f16.") {
            continue;
        }
        let mut wis = vec![direction(0.45, 0.6, true)];
        if m.def().incident == IncidentRange::WholeSphere {
            wis.push(direction(0.2, 0.3, false));
        }
        for wi in wis {
            let integral = sphere_integral(&m, wi, 360, 720);
            let lost = lost_share(&m, wi, 500);
            println!(
                "{name} wi {wi:?}: integral {integral:.6} + lost {lost:.6} = {:.6}",
                integral + lost
            );
            assert!(
                (integral + lost - 1.0).abs() <= 2e-3,
                "{name} wi {wi:?}: {integral} + {lost}"
            );
        }
    }
}
