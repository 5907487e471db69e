//! `diffbsdf refine` and `fit --refine-iters` end to end on tiny fits (seconds): the
//! refined blobs load with the fitted model's definition, the stage reports its
//! validation losses, and `fit --refine-iters N` gives the bytes of `fit --refine-iters 0`
//! followed by `refine --iters N` with the same seed (the stage is a function of the
//! distilled model and the seed).

use clap::Parser;
use diffbsdf::AnyModel;
use diffbsdf_cli::cli::{run, Cli};
use serde_json::Value;

const SPEC: &str = "conductor:ggx,alpha=0.3,metal=Cu";

fn call(args: &[&str]) -> Vec<u8> {
    let cli = Cli::try_parse_from(args).unwrap();
    let mut buf = Vec::new();
    run(cli, &mut buf).unwrap();
    buf
}

fn fit(out: &std::path::Path, refine_iters: &str, extra: &[&str]) -> Value {
    let out = out.to_str().unwrap();
    let mut args = vec![
        "diffbsdf",
        "fit",
        SPEC,
        "--tiny",
        "--domain",
        "half-vector",
        "--coordinates",
        "warped",
        "--refine-iters",
        refine_iters,
        "--no-eval",
        "--json",
        "--exact-samples",
        "20000",
        "--out",
        out,
    ];
    args.extend_from_slice(extra);
    serde_json::from_slice(&call(&args)).unwrap()
}

/// `diffbsdf refine PLAIN SPEC --iters 4 --out OUT EXTRA...`; its text output.
fn refine_blob(plain: &std::path::Path, out: &std::path::Path, extra: &[&str]) -> Vec<u8> {
    let mut args = vec![
        "diffbsdf",
        "refine",
        plain.to_str().unwrap(),
        SPEC,
        "--iters",
        "4",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    call(&args)
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("diffbsdf-refine-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn params(m: &AnyModel) -> Vec<f32> {
    let mut p = vec![0.0f32; 4096];
    let n = m.params(&mut p).unwrap();
    p.truncate(n);
    p
}

fn blob_params(path: &std::path::Path) -> Vec<f32> {
    params(&AnyModel::from_blob(&std::fs::read(path).unwrap()).unwrap())
}

#[test]
fn refine_command_matches_the_fit_stage() {
    let (plain, fitted) = (scratch("plain.dbsdf"), scratch("fitted.dbsdf"));
    let without = fit(&plain, "0", &[]);
    assert!(without["stages"]
        .as_array()
        .unwrap()
        .iter()
        .all(|s| s["stage"] != "refine"));
    let with = fit(&fitted, "4", &[]);
    let stage = with["stages"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["stage"] == "refine")
        .expect("a refine stage");
    assert!(stage["loss_start"].as_f64().unwrap() > 0.0);

    let refined = scratch("refined.dbsdf");
    let text = String::from_utf8(refine_blob(&plain, &refined, &[])).unwrap();
    assert!(text.starts_with("validation mean ln(1 + RV): "), "{text}");
    let bytes = |p: &std::path::Path| std::fs::read(p).unwrap();
    let (a, b) = (bytes(&refined), bytes(&fitted));
    let (ma, mb) = (
        AnyModel::from_blob(&a).unwrap(),
        AnyModel::from_blob(&b).unwrap(),
    );
    assert_eq!(ma.def().domain, mb.def().domain);
    assert!(ma.def().standard_warp);
    // Same weights; the stored names differ (each blob's file stem).
    assert!(params(&ma) == params(&mb), "the two refinements differ");
    let f16 = refined.with_file_name("refined.f16.dbsdf");
    assert!(AnyModel::from_blob(&bytes(&f16)).is_ok());
}

#[test]
fn fit_passes_its_refinement_rate_to_the_stage() {
    let plain = scratch("plain-lr.dbsdf");
    fit(&plain, "0", &[]);
    let (fitted, default_rate) = (scratch("fitted-lr.dbsdf"), scratch("default-lr.dbsdf"));
    fit(&fitted, "4", &["--refine-lr", "1e-3"]);
    fit(&default_rate, "4", &[]);
    let refined = scratch("refined-lr.dbsdf");
    refine_blob(&plain, &refined, &["--lr", "1e-3"]);
    let (with_rate, stage) = (blob_params(&fitted), blob_params(&refined));
    assert!(with_rate == stage, "fit --refine-lr and refine --lr differ");
    assert!(
        with_rate != blob_params(&default_rate),
        "--refine-lr changed nothing"
    );
}
