//! `diffbsdf curve` end to end with the few-second recipe: one fit per teacher length and
//! student depth, each measured f32 and f16 on the same grid; the table, JSON and plot are
//! written and the JSON reads back into the points asked for.

use clap::Parser;
use diffbsdf_cli::cli::curve::CurveRecord;
use diffbsdf_cli::cli::{run, Cli};

fn curve(extra: &[&str]) -> Result<String, String> {
    let mut args = vec![
        "diffbsdf",
        "curve",
        "conductor:ggx,alpha=0.3,metal=Cu",
        "--tiny",
    ];
    args.extend_from_slice(extra);
    let mut sink = Vec::new();
    run(
        Cli::try_parse_from(args).map_err(|e| e.to_string())?,
        &mut sink,
    )
    .map_err(|e| e.to_string())?;
    Ok(String::from_utf8(sink).unwrap())
}

#[test]
fn curve_fits_every_point_and_writes_its_report() {
    let out = std::env::temp_dir().join(format!("diffbsdf-curve-{}", std::process::id()));
    let text = curve(&[
        "--domain",
        "disk",
        "--teacher-iters",
        "60,240",
        "--student-layers",
        "3,4",
        "--eval-samples",
        "2048",
        "--name",
        "copper",
        "--out",
        out.to_str().unwrap(),
    ])
    .unwrap();
    for f in ["copper.md", "copper.json", "copper.svg"] {
        let len = std::fs::metadata(out.join(f)).map(|m| m.len()).unwrap_or(0);
        assert!(len > 500, "{f}: {len} bytes");
    }
    // The table: a header, a rule and one row per fit.
    let rows = text.lines().filter(|l| l.starts_with("| ")).count();
    assert_eq!(rows, 1 + 4, "{text}");
    let json = std::fs::read(out.join("copper.json")).unwrap();
    let record: CurveRecord = serde_json::from_slice(&json).unwrap();
    let asked: Vec<(u8, usize)> = record
        .points
        .iter()
        .map(|p| (p.student_layers, p.teacher_iters))
        .collect();
    assert_eq!(asked, [(3, 60), (3, 240), (4, 60), (4, 240)]);
    let first = &record.points[0];
    for p in &record.points {
        // f16 blobs are smaller, deeper students larger; every figure measured.
        assert!(p.bytes[1] < p.bytes[0], "{:?}", p.bytes);
        for q in [p.f32, p.f16] {
            assert!(q.rv_mean.is_finite() && q.rv_mean > 0.0, "{q:?}");
            assert!(q.rv_worst >= q.rv_mean && q.firefly_worst >= q.firefly_mean);
        }
        assert!(p.train_seconds >= p.teacher_seconds && p.teacher_seconds > 0.0);
        // The same grid and seed for every point: the material's sampler measures the same.
        assert_eq!(p.material_rv_mean, first.material_rv_mean);
    }
    assert!(record.points[0].bytes[0] < record.points[2].bytes[0]);
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn curve_refuses_what_it_cannot_fit() {
    let out = std::env::temp_dir().join("diffbsdf-curve-refused");
    let out = out.to_str().unwrap();
    let auto = curve(&["--domain", "auto", "--out", out]).unwrap_err();
    assert!(auto.contains("not auto"), "{auto}");
    // A depth the kernel does not compile is refused as the command line is read.
    let deep = curve(&["--domain", "disk", "--student-layers", "7", "--out", out]).unwrap_err();
    assert!(deep.contains("3 or 4 hidden layers, not 7"), "{deep}");
    assert!(!std::path::Path::new(out).exists());
}
