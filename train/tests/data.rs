//! Training pairs: a chi-square test of the `wo` histogram against the quadrature of the
//! target, for several `wi` bins, for the exact (resampling) and MCMC generators.

// The chi-square machinery is the material tests' own.
#[path = "../../materials/tests/common/mod.rs"]
mod common;

use common::{chi2, Domain as Bins, ALPHA};
use diffbsdf::Domain;
use diffbsdf_materials::{from_spherical, parse_spec, DVec3, Material, Spherical};
use diffbsdf_train::data::{
    exact_pairs_for_wi, mcmc_pairs, Band, DomainTarget, ExactConfig, McmcConfig,
};

const SPECS: &[(&str, Domain)] = &[
    ("lambertian:albedo=0.7", Domain::Disk),
    ("conductor:ggx,alpha=0.3,metal=Cu", Domain::Disk),
    (
        "plastic:beckmann,alpha=0.2,eta=1.5,diffuse=0.5",
        Domain::Disk,
    ),
    ("dielectric:ggx,alpha=0.4,eta=1.5", Domain::Sphere),
];

/// Bands of theta_i (degrees).
const BANDS: &[(f64, f64)] = &[(10.0, 14.0), (44.0, 48.0), (76.0, 80.0)];

/// Expected bin probabilities of wo for a set of (wi, weight) nodes: the mixture of the
/// conditionals `target(wi, .) / Z(wi)` when `conditional`, else `sum weight target`
/// normalised once (the law of a joint sampler whose wi-marginal is proportional to Z).
fn expected(m: &dyn Material, domain: Domain, nodes: &[(DVec3, f64)], bins: &Bins) -> Vec<f64> {
    let f = |wo: DVec3| -> f64 {
        nodes
            .iter()
            .map(|(wi, w)| w * domain.target(m, *wi, wo))
            .sum()
    };
    let v = bins.integrate(&f);
    let s: f64 = v.iter().sum();
    v.iter().map(|x| x / s).collect()
}

fn gauss_nodes(band: (f64, f64)) -> Vec<(DVec3, f64)> {
    // 5-point Gauss-Legendre in theta_i, weight sin(theta) (uniform solid-angle measure).
    const X: [f64; 5] = [
        -0.906_179_845_938_664,
        -0.538_469_310_105_683,
        0.0,
        0.538_469_310_105_683,
        0.906_179_845_938_664,
    ];
    const W: [f64; 5] = [
        0.236_926_885_056_189,
        0.478_628_670_499_366,
        0.568_888_888_888_889,
        0.478_628_670_499_366,
        0.236_926_885_056_189,
    ];
    let (a, b) = (band.0.to_radians(), band.1.to_radians());
    X.iter()
        .zip(W)
        .map(|(x, w)| {
            let t = 0.5 * (a + b) + 0.5 * (b - a) * x;
            (from_spherical(t, 0.0), w * t.sin())
        })
        .collect()
}

#[test]
fn exact_and_mcmc_pairs_match_the_target() {
    const N: usize = 60_000;
    let tests = SPECS.len() * BANDS.len() * 2;
    let threshold = ALPHA / tests as f64;
    let mut failures = Vec::new();
    for (s, (spec, domain)) in SPECS.iter().enumerate() {
        let m = parse_spec(spec).unwrap();
        let m = m.as_ref();
        for (b, band) in BANDS.iter().enumerate() {
            let mid = 0.5 * (band.0 + band.1);
            let wi = from_spherical(mid.to_radians(), 0.0);
            let bins = Bins::new(DVec3::new(-wi.x, -wi.y, wi.z));
            let n_bins = common::NA * common::NP;

            // Exact generator at the band's centre.
            let cfg = ExactConfig {
                domain: *domain,
                candidates: 64,
                seed: 11 + (s * 10 + b) as u64,
                group: 1,
            };
            let g = exact_pairs_for_wi(m, wi, N, &cfg);
            let exp = expected(m, *domain, &[(wi, 1.0)], &bins);
            let mut obs = vec![0.0; n_bins];
            for p in &g.pairs {
                obs[bins.bin(p.wo)] += 1.0;
            }
            let e: Vec<f64> = exp.iter().map(|p| p * g.pairs.len() as f64).collect();
            let c = chi2(&obs, &e);
            println!(
                "exact {spec:<48} theta_i={mid:4.1} chi2={:8.1} dof={:4} p={:.4} pairs/s={:.0}",
                c.stat,
                c.dof,
                c.p,
                g.pairs_per_second()
            );
            if c.p < threshold || g.pairs.len() != N {
                failures.push(format!("exact {spec} {mid}: p={:.2e}", c.p));
            }

            // MCMC in the band; pairs rotated to relative azimuth (isotropic materials).
            let band_r = Band {
                theta_min: band.0.to_radians(),
                theta_max: band.1.to_radians(),
            };
            let cfg = McmcConfig {
                domain: *domain,
                seed: 77 + (s * 10 + b) as u64,
                ..McmcConfig::default()
            };
            let g = mcmc_pairs(m, &[band_r], N, &cfg);
            let exp = expected(m, *domain, &gauss_nodes(*band), &bins);
            let mut obs = vec![0.0; n_bins];
            for p in &g.pairs {
                obs[bins.bin(p.wo.rotate_z(-p.wi.phi()))] += 1.0;
            }
            let e: Vec<f64> = exp.iter().map(|p| p * g.pairs.len() as f64).collect();
            let c = chi2(&obs, &e);
            println!("mcmc  {spec:<48} theta_i={mid:4.1} chi2={:8.1} dof={:4} p={:.4} pairs/s={:.0} acc={:.2}", c.stat, c.dof, c.p, g.pairs_per_second(), g.acceptance);
            if c.p < threshold || g.pairs.len() != N {
                failures.push(format!(
                    "mcmc {spec} {mid}: p={:.2e} n={}",
                    c.p,
                    g.pairs.len()
                ));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "threshold {threshold:.2e}\n{}",
        failures.join("\n")
    );
}

#[test]
fn generators_are_deterministic() {
    let m = parse_spec("conductor:ggx,alpha=0.3,metal=Cu").unwrap();
    let band = Band {
        theta_min: 0.2,
        theta_max: 0.6,
    };
    let cfg = McmcConfig {
        seed: 5,
        ..McmcConfig::default()
    };
    let a = mcmc_pairs(m.as_ref(), &[band, band], 5000, &cfg);
    let b = mcmc_pairs(m.as_ref(), &[band, band], 5000, &cfg);
    assert_eq!(a.pairs, b.pairs);
    let cfg = ExactConfig {
        seed: 5,
        ..ExactConfig::default()
    };
    let wi = from_spherical(0.5, 0.0);
    assert_eq!(
        exact_pairs_for_wi(m.as_ref(), wi, 9000, &cfg).pairs,
        exact_pairs_for_wi(m.as_ref(), wi, 9000, &cfg).pairs
    );
}
