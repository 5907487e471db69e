//! `fit --domain auto` and `--target-rv`: the disk where it suffices, the sphere for
//! transmissive materials or where the disk falls short, and the fewest sufficient steps.
//! Tiny fits (seconds); the decisions are read back from `fit --json`.

use clap::Parser;
use diffbsdf::AnyModel;
use diffbsdf_cli::cli::{run, Cli};
use serde_json::Value;

fn fit(spec: &str, extra: &[&str], out: &std::path::Path) -> Value {
    let out_s = out.to_str().unwrap();
    let mut args = vec![
        "diffbsdf",
        "fit",
        spec,
        "--tiny",
        "--no-eval",
        "--json",
        "--check-samples",
        "2048",
        "--exact-samples",
        "20000",
        "--out",
        out_s,
    ];
    args.extend_from_slice(extra);
    let cli = Cli::try_parse_from(args).unwrap();
    let mut buf = Vec::new();
    run(cli, &mut buf).unwrap();
    serde_json::from_slice(&buf).unwrap()
}

fn checks(v: &Value) -> Vec<(String, u64, bool)> {
    v["choice"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            (
                c["domain"].as_str().unwrap().to_owned(),
                c["steps"].as_u64().unwrap(),
                c["sufficient"].as_bool().unwrap(),
            )
        })
        .collect()
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("diffbsdf-fit-auto-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn blob_steps_and_domain(path: &std::path::Path) -> (u16, diffbsdf::Domain) {
    let m = AnyModel::from_blob(&std::fs::read(path).unwrap()).unwrap();
    (m.def().default_steps, m.def().domain)
}

#[test]
fn auto_uses_the_disk_with_the_fewest_steps_when_it_suffices() {
    let out = scratch("easy.dbsdf");
    let v = fit(
        "conductor:ggx,alpha=0.3,metal=Cu",
        &[
            "--domain",
            "auto",
            "--target-rv",
            "1e6",
            "--max-grazing-firefly",
            "1e9",
        ],
        &out,
    );
    // Any model reaches a target this loose: the cheapest one, disk at N = 1, is kept.
    assert_eq!(checks(&v), vec![("disk".into(), 1, true)]);
    assert_eq!(blob_steps_and_domain(&out), (1, diffbsdf::Domain::Disk));
}

#[test]
fn auto_gives_way_to_the_sphere_when_the_disk_falls_short() {
    let out = scratch("hard.dbsdf");
    let v = fit(
        "conductor:ggx,alpha=0.3,metal=Cu",
        &["--domain", "auto", "--target-rv", "1e-9"],
        &out,
    );
    let c = checks(&v);
    // Every step count of the disk, then of the sphere, all short of an unreachable target.
    assert!(c.len() > 12, "{c:?}");
    assert!(c[..6].iter().all(|(d, _, ok)| d == "disk" && !ok), "{c:?}");
    assert!(
        c[6..12].iter().all(|(d, _, ok)| d == "sphere" && !ok),
        "{c:?}"
    );
    let steps: Vec<u64> = c[..6].iter().map(|x| x.1).collect();
    assert_eq!(steps, vec![1, 2, 4, 8, 16, 32]);
    // Nothing sufficed: the sphere model at the fewest exact steps from its trained 8.
    ladder_ends_at_the_shipped_steps(&c[12..], 8, &out);
    assert_eq!(blob_steps_and_domain(&out).1, diffbsdf::Domain::Sphere);
}

#[test]
fn auto_goes_straight_to_the_sphere_for_transmissive_materials() {
    let out = scratch("glass.dbsdf");
    let v = fit(
        "dielectric:beckmann,alpha=0.3,eta=1.5",
        &["--domain", "auto", "--max-grazing-firefly", "1e9"],
        &out,
    );
    let c = checks(&v);
    // No RV target: the sphere's trained step count, then more only where not exact; no
    // disk fit.
    assert!(c.iter().all(|x| x.0 == "sphere"), "{c:?}");
    ladder_ends_at_the_shipped_steps(&c, 8, &out);
    assert_eq!(blob_steps_and_domain(&out).1, diffbsdf::Domain::Sphere);
}

#[test]
fn plain_fit_ships_steps_it_checked_to_be_exact() {
    let out = scratch("plain.dbsdf");
    let v = fit(
        "conductor:ggx,alpha=0.3,metal=Cu",
        &["--domain", "disk"],
        &out,
    );
    let c = checks(&v);
    ladder_ends_at_the_shipped_steps(&c, 4, &out);
}

/// The checks are N, 2N, 4N, ... from `first` until one is exact, and that one shipped.
fn ladder_ends_at_the_shipped_steps(c: &[(String, u64, bool)], first: u64, out: &std::path::Path) {
    assert!(!c.is_empty(), "no exactness check was made");
    assert_eq!(c[0].1, first, "{c:?}");
    for pair in c.windows(2) {
        assert_eq!(pair[1].1, (pair[0].1 * 2).min(32), "{c:?}");
        assert!(!pair[0].2, "checked on past a sufficient step count: {c:?}");
    }
    let last = c.last().unwrap();
    assert!(
        last.2,
        "the fit wrote a blob without an exact step count: {c:?}"
    );
    assert_eq!(blob_steps_and_domain(out).0 as u64, last.1, "{c:?}");
}

#[test]
fn export_steps_is_the_first_step_count_checked() {
    let out = scratch("exported.dbsdf");
    let v = fit(
        "conductor:ggx,alpha=0.3,metal=Cu",
        &["--domain", "disk", "--export-steps", "3"],
        &out,
    );
    ladder_ends_at_the_shipped_steps(&checks(&v), 3, &out);
}

/// The default domain (`material`): the half-vector chart (the disk's nets, N = 4) for a
/// reflection-only material, the sphere for a transmissive one; each ships an exact step
/// count.
#[test]
fn the_default_domain_is_the_half_vector_chart_for_brdfs_and_the_sphere_for_bsdfs() {
    let brdf = scratch("material-brdf.dbsdf");
    let v = fit("conductor:ggx,alpha=0.3,metal=Cu", &[], &brdf);
    let c = checks(&v);
    assert!(c.iter().all(|x| x.0 == "half-vector"), "{c:?}");
    ladder_ends_at_the_shipped_steps(&c, 4, &brdf);
    assert_eq!(blob_steps_and_domain(&brdf).1, diffbsdf::Domain::HalfVector);
    let bsdf = scratch("material-bsdf.dbsdf");
    let v = fit("dielectric:beckmann,alpha=0.3,eta=1.5", &[], &bsdf);
    let c = checks(&v);
    assert!(c.iter().all(|x| x.0 == "sphere"), "{c:?}");
    assert_eq!(blob_steps_and_domain(&bsdf).1, diffbsdf::Domain::Sphere);
}
