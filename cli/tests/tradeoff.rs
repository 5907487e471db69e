//! `diffbsdf tradeoff` end to end on one shipped model at two step counts (small sample
//! counts): the table, JSON, plot and slice image are written, the JSON reads back into
//! the same points, the timing ratios are those of the times, and re-rendering from the
//! JSON gives the same table.

use clap::Parser;
use diffbsdf_cli::cli::{run, Cli};
use diffbsdf_cli::tradeoff::markdown::{exact, plateau};
use diffbsdf_cli::tradeoff::{Point, SweepRecord};

fn tradeoff(extra: &[&str], out: &std::path::Path) {
    let models = concat!(env!("CARGO_MANIFEST_DIR"), "/../models");
    let mut args = vec![
        "diffbsdf",
        "tradeoff",
        "--models",
        models,
        "--only",
        "conductor-ggx-a0.3-cu-disk",
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let mut sink = Vec::new();
    run(Cli::try_parse_from(args).unwrap(), &mut sink).unwrap();
}

#[test]
fn tradeoff_writes_a_consistent_report() {
    let out = std::env::temp_dir().join(format!("diffbsdf-tradeoff-{}", std::process::id()));
    tradeoff(
        &[
            "--steps",
            "1,4",
            "--samples",
            "1024",
            "--timing-calls",
            "500",
            "--no-kl",
        ],
        &out,
    );
    for f in [
        "tradeoff.md",
        "tradeoff.json",
        "tradeoff.svg",
        "slices/conductor-ggx-a0.3-cu-disk.png",
    ] {
        let len = std::fs::metadata(out.join(f)).map(|m| m.len()).unwrap_or(0);
        assert!(len > 500, "{f}: {len} bytes");
    }
    let json = std::fs::read(out.join("tradeoff.json")).unwrap();
    let record: SweepRecord = serde_json::from_slice(&json).unwrap();
    let points = record.points;
    // 2 step counts x (f32, f16).
    assert_eq!(points.len(), 4);
    for p in &points {
        assert!(p.cost.learned_direction_ns > 0.0 && p.cost.material_sample_ns > 0.0);
        let r = p.cost.learned_sample_ns / p.cost.material_sample_ns;
        assert!((p.cost.ratio_sample - r).abs() <= 1e-9 * r);
        assert!(p.rv_mean.is_finite() && p.rv_mean >= 0.0 && p.rv_worst >= p.rv_mean);
        assert_eq!(p.shipped_steps, 4);
    }
    // The shipped N = 4 is exact (every step invertible, PDFs consistent).
    let shipped: Vec<&Point> = points.iter().filter(|p| p.steps == 4).collect();
    assert!(shipped.iter().all(|p| exact(p)), "{shipped:?}");
    let curve: Vec<&Point> = points.iter().filter(|p| p.precision == "f32").collect();
    let pl = plateau(&curve).expect("an exact point");
    assert!(exact(pl));
    let md = std::fs::read_to_string(out.join("tradeoff.md")).unwrap();
    assert!(md.contains("**Headline.** `conductor-ggx-a0.3-cu-disk` (disk, N = 4)"));
    // Re-rendering from the JSON reproduces the report.
    let again = out.join("again");
    tradeoff(
        &[
            "--from",
            out.join("tradeoff.json").to_str().unwrap(),
            "--no-slices",
            "--steps",
            "1,4",
            "--samples",
            "1024",
            "--no-kl",
        ],
        &again,
    );
    assert_eq!(
        md,
        std::fs::read_to_string(again.join("tradeoff.md")).unwrap()
    );
    std::fs::remove_dir_all(&out).ok();
}
