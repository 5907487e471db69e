//! Sampler tests for every analytic material: chi-square goodness of fit of the sampler's
//! histogram against its own PDF (significance 0.01, Bonferroni-corrected over all
//! configurations), quadrature normalisation of the PDF against the sampled-mass fraction,
//! PDF consistency of returned samples, reciprocity and a white furnace.

mod common;

use common::{chi2_of_samples, dir_deg, rng, Domain, ALPHA};
use diffbsdf_materials::{from_spherical, parse_spec, DVec3, Material, Spherical};
use rand::Rng;

/// (spec, incidence angles in degrees).
const CONFIGS: &[(&str, &[f64])] = &[
    ("lambertian:albedo=0.8/0.5/0.2", &[0.0, 60.0, 89.0]),
    ("conductor:ggx,alpha=0.01,metal=Au", &[30.0, 85.0]),
    ("conductor:ggx,alpha=0.3,metal=Cu", &[0.0, 45.0, 88.0]),
    ("conductor:ggx,alpha=1.0,metal=Al", &[10.0, 80.0]),
    (
        "conductor:ggx,alpha=0.05,alpha_y=0.3,metal=Cu",
        &[40.0, 80.0],
    ),
    ("conductor:beckmann,alpha=0.01,metal=Ag", &[30.0, 85.0]),
    ("conductor:beckmann,alpha=0.3,metal=Cu", &[0.0, 60.0, 88.0]),
    ("conductor:beckmann,alpha=1.0,metal=Au", &[20.0, 85.0]),
    ("conductor:beckmann,alpha=0.4,alpha_y=0.1,metal=Ag", &[50.0]),
    ("dielectric:ggx,alpha=0.01,eta=1.5", &[30.0, 80.0, 150.0]),
    (
        "dielectric:ggx,alpha=0.3,eta=1.5",
        &[0.0, 45.0, 88.0, 120.0, 170.0],
    ),
    ("dielectric:ggx,alpha=1.0,eta=1.33", &[30.0, 135.0]),
    ("dielectric:beckmann,alpha=0.01,eta=1.5", &[40.0, 140.0]),
    (
        "dielectric:beckmann,alpha=0.3,eta=1.5",
        &[20.0, 85.0, 160.0],
    ),
    ("dielectric:beckmann,alpha=1.0,eta=2.0", &[60.0, 100.0]),
    (
        "dielectric:ggx,alpha=0.2,alpha_y=0.6,eta=1.5",
        &[50.0, 130.0],
    ),
    ("plastic:ggx,alpha=0.01,eta=1.5,diffuse=0.5", &[30.0, 85.0]),
    (
        "plastic:beckmann,alpha=0.3,eta=1.5,diffuse=0.8/0.2/0.1",
        &[0.0, 70.0],
    ),
    ("plastic:ggx,alpha=1.0,eta=1.5,diffuse=0.3", &[45.0]),
    (
        "principled:base=0.8/0.3/0.2,roughness=0.5,sheen=0.5,clearcoat=0.5",
        &[20.0, 85.0],
    ),
    (
        "principled:base=0.9/0.6/0.2,metallic=1,roughness=0.2,anisotropic=0.8",
        &[45.0],
    ),
    (
        "principled:base=0.7,roughness=0.3,spec_trans=0.8,eta=1.5",
        &[30.0, 80.0, 140.0],
    ),
    (
        "principled:base=0.5,roughness=1,clearcoat=1,clearcoat_gloss=0.5",
        &[60.0],
    ),
];

const SAMPLES: usize = 200_000;

/// Binning axes: the mirror direction of `wi`, and the refracted direction as well for a
/// transmissive material.
fn axes(m: &dyn Material, wi: DVec3) -> Vec<DVec3> {
    let mut v = vec![DVec3::new(-wi.x, -wi.y, wi.z)];
    if m.is_transmissive() {
        // Smooth refraction about the normal (eta from the side index); fall back to -wi.
        let eta = m.index_of_side(DVec3::new(0.0, 0.0, -1.0)) / m.index_of_side(DVec3::Z);
        let (eta, n) = if wi.z > 0.0 {
            (eta, 1.0)
        } else {
            (1.0 / eta, -1.0)
        };
        let c = wi.z.abs();
        let s2 = (1.0 - c * c) / (eta * eta);
        if s2 < 1.0 {
            let t = DVec3::new(-wi.x / eta, -wi.y / eta, -n * (1.0 - s2).sqrt());
            v.push(t.try_normalize().unwrap_or(-wi));
        } else {
            v.push(-wi);
        }
    }
    v
}

fn configurations() -> Vec<(String, Box<dyn Material>, DVec3)> {
    let mut out = Vec::new();
    for (spec, angles) in CONFIGS {
        for &deg in *angles {
            let m = parse_spec(spec).unwrap();
            out.push((spec.to_string(), m, dir_deg(deg, 0.7)));
        }
    }
    out
}

#[test]
fn chi2_normalisation_and_pdf_consistency() {
    let configs = configurations();
    let tests: usize = configs
        .iter()
        .map(|(_, m, wi)| axes(m.as_ref(), *wi).len())
        .sum();
    let threshold = ALPHA / tests as f64;
    let mut failures = Vec::new();
    let mut report = String::new();
    for (k, (spec, m, wi)) in configs.iter().enumerate() {
        let m = m.as_ref();
        let mut r = rng(1000 + k as u64);
        let mut samples = Vec::with_capacity(SAMPLES);
        let mut worst_pdf_err: f64 = 0.0;
        for _ in 0..SAMPLES {
            let u = [r.gen::<f64>(), r.gen::<f64>(), r.gen::<f64>()];
            if let Some(s) = m.sample(*wi, u) {
                assert!(
                    s.pdf > 0.0 && s.pdf.is_finite() && s.weight.is_finite(),
                    "{spec}"
                );
                assert!((s.wo.length() - 1.0).abs() < 1e-9);
                let p = m.pdf(*wi, s.wo);
                worst_pdf_err = worst_pdf_err.max((p - s.pdf).abs() / s.pdf);
                // weight = f |cos| / pdf
                let w = m.eval(*wi, s.wo).luminance() * s.wo.z.abs() / s.pdf;
                assert!(
                    (w - s.weight.luminance()).abs() <= 1e-9 * (1.0 + w),
                    "{spec}"
                );
                samples.push(s.wo);
            }
        }
        assert!(
            worst_pdf_err < 1e-6,
            "{spec} wi={wi:?}: pdf mismatch {worst_pdf_err}"
        );
        let frac = samples.len() as f64 / SAMPLES as f64;
        for axis in axes(m, *wi) {
            let dom = Domain::new(axis);
            let pdf = |w: DVec3| m.pdf(*wi, w);
            let integral = dom.integrate(&pdf);
            let total: f64 = integral.iter().sum();
            let sigma = (frac * (1.0 - frac) / SAMPLES as f64).sqrt();
            let norm_ok = (total - frac).abs() <= 5.0 * sigma + 2e-3;
            let c = chi2_of_samples(&dom, &samples, SAMPLES, &integral);
            report.push_str(&format!(
                "{spec:<72} theta_i={:6.1} int={total:.5} frac={frac:.5} chi2={:9.1} dof={:4} p={:.4}\n",
                wi.theta().to_degrees(),
                c.stat,
                c.dof,
                c.p
            ));
            if !norm_ok || c.p < threshold {
                failures.push(format!(
                    "{spec} wi={:.1}: int={total:.5} frac={frac:.5} p={:.3e}",
                    wi.theta().to_degrees(),
                    c.p
                ));
            }
        }
    }
    println!("{report}");
    assert!(
        failures.is_empty(),
        "failures (threshold {threshold:.2e}):\n{}",
        failures.join("\n")
    );
}

#[test]
fn reciprocity() {
    let mut r = rng(7);
    for (spec, _) in CONFIGS {
        let m = parse_spec(spec).unwrap();
        for _ in 0..2000 {
            let a = from_spherical(r.gen::<f64>() * std::f64::consts::PI, r.gen::<f64>() * 6.3);
            let b = from_spherical(r.gen::<f64>() * std::f64::consts::PI, r.gen::<f64>() * 6.3);
            let (ea, eb) = (m.index_of_side(a), m.index_of_side(b));
            let f1 = m.eval(a, b);
            let f2 = m.eval(b, a);
            for c in 0..3 {
                let (x, y) = (f1.0[c] / (ea * ea), f2.0[c] / (eb * eb));
                assert!(
                    (x - y).abs() <= 1e-9 * (1.0 + x.abs().max(y.abs())),
                    "{spec}: {a:?} {b:?} {x} {y}"
                );
            }
        }
    }
}

/// `E(wi) = int f(wi, wo) |cos theta_o| (eta(wo) / eta(wi))^2 dwo <= 1`: the energy form
/// (for reflection the factor is 1; for transmission it undoes the radiance compression).
#[test]
fn white_furnace() {
    let specs = [
        "lambertian:albedo=1",
        "conductor:ggx,alpha=0.01,eta=1,k=1000",
        "conductor:ggx,alpha=0.5,eta=1,k=1000",
        "conductor:ggx,alpha=1.0,alpha_y=0.2,eta=1,k=1000",
        "conductor:beckmann,alpha=1.0,eta=1,k=1000",
        "dielectric:ggx,alpha=0.01,eta=1.5",
        "dielectric:ggx,alpha=0.5,eta=1.5",
        "dielectric:beckmann,alpha=1.0,eta=1.5",
        "plastic:ggx,alpha=0.1,eta=1.5,diffuse=1",
        "plastic:ggx,alpha=1.0,eta=1.5,diffuse=1",
        "principled:base=1,metallic=1,roughness=0.5",
        "principled:base=1,roughness=0.7,spec_trans=1",
    ];
    let mut report = String::new();
    let mut worst: f64 = 0.0;
    for spec in specs {
        let m = parse_spec(spec).unwrap();
        for deg in [0.0, 30.0, 60.0, 80.0, 89.0, 120.0, 170.0] {
            let wi = dir_deg(deg, 0.3);
            if wi.z < 0.0 && !m.is_transmissive() {
                continue;
            }
            let ei = m.index_of_side(wi);
            let mut e_max: f64 = 0.0;
            for axis in axes(m.as_ref(), wi) {
                let f = |wo: DVec3| {
                    let eo = m.index_of_side(wo);
                    m.eval(wi, wo).max_channel() * wo.z.abs() * (eo / ei).powi(2)
                };
                let e: f64 = Domain::new(axis).integrate(&f).iter().sum();
                e_max = e_max.max(e);
            }
            worst = worst.max(e_max);
            report.push_str(&format!("{spec:<50} theta_i={deg:5.1} E={e_max:.5}\n"));
            assert!(e_max <= 1.0 + 2e-3, "{spec} at {deg}: E = {e_max}");
        }
    }
    println!("{report}worst {worst:.5}");
}

/// Every material that declares a fold of its incident azimuths (`Material::azimuth_fold`)
/// has the symmetries it assumes: `f` and the PDF are unchanged when `wi` and `wo` are
/// folded together, at random pairs over the sphere; an isotropic one declares none.
#[test]
fn declared_folds_are_symmetries() {
    use diffbsdf_materials::symmetry::{apply_signs, fold_signs};
    use diffbsdf_materials::IncidentFold;
    let mut r = rng(77);
    let mut folded = 0;
    for (spec, _) in CONFIGS {
        let m = parse_spec(spec).unwrap();
        let fold = m.azimuth_fold();
        if m.is_isotropic() {
            assert_eq!(fold, IncidentFold::None, "{spec}");
            continue;
        }
        folded += usize::from(fold != IncidentFold::None);
        let sphere = |r: &mut rand_pcg::Pcg64| {
            from_spherical(
                (2.0 * r.gen::<f64>() - 1.0).acos(),
                std::f64::consts::TAU * r.gen::<f64>(),
            )
        };
        for _ in 0..200 {
            let (wi, wo) = (sphere(&mut r), sphere(&mut r));
            let signs = fold_signs(fold, wi);
            let (fi, fo) = (apply_signs(signs, wi), apply_signs(signs, wo));
            let (a, b) = (m.eval(wi, wo), m.eval(fi, fo));
            for c in 0..3 {
                assert!(
                    (a.0[c] - b.0[c]).abs() <= 1e-9 * a.0[c].abs().max(1e-12),
                    "{spec}"
                );
            }
            let (p, q) = (m.pdf(wi, wo), m.pdf(fi, fo));
            assert!(
                (p - q).abs() <= 1e-9 * p.abs().max(1e-12),
                "{spec}: {p} {q}"
            );
        }
    }
    assert!(
        folded >= 2,
        "only {folded} anisotropic materials declare a fold"
    );
}
