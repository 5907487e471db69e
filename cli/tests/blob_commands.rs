//! `diffbsdf sample`, `diffbsdf pdf` and `diffbsdf info` on shipped blobs, run as the built binary: the
//! CSV and JSON parse, the PDF of each sampled direction equals the sampled PDF, and bad
//! input fails with a non-zero status and a clear message.

use serde_json::Value;
use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

const BIN: &str = env!("CARGO_BIN_EXE_diffbsdf");

fn model() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models/conductor-ggx-a0.3-cu-disk.dbsdf")
}

fn run(args: &[&str], stdin: Option<&str>) -> Output {
    let mut child = Command::new(BIN)
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    {
        let mut input = child.stdin.take().unwrap();
        if let Some(s) = stdin {
            input.write_all(s.as_bytes()).unwrap();
        }
    }
    child.wait_with_output().unwrap()
}

fn ok(args: &[&str], stdin: Option<&str>) -> String {
    let out = run(args, stdin);
    assert!(
        out.status.success(),
        "{args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn failure(args: &[&str]) -> String {
    let out = run(args, None);
    assert!(!out.status.success(), "{args:?} should fail");
    assert!(
        out.stdout.is_empty(),
        "{args:?} printed rows before failing"
    );
    String::from_utf8(out.stderr).unwrap()
}

/// Parsed CSV: the header and the rows as strings.
fn csv(text: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_owned)
        .collect::<Vec<_>>();
    let rows = lines
        .map(|l| l.split(',').map(str::to_owned).collect::<Vec<_>>())
        .collect::<Vec<_>>();
    for r in &rows {
        assert_eq!(r.len(), header.len(), "{r:?}");
    }
    (header, rows)
}

fn f(s: &str) -> f32 {
    s.parse().unwrap()
}

struct Drawn {
    valid: bool,
    wo: [f32; 3],
    pdf: f32,
}

fn sample_csv(wi: &str, count: usize, seed: u64) -> (String, Vec<Drawn>) {
    let m = model();
    let text = ok(
        &[
            "sample",
            m.to_str().unwrap(),
            "--wi",
            wi,
            "--count",
            &count.to_string(),
            "--seed",
            &seed.to_string(),
        ],
        None,
    );
    let (header, rows) = csv(&text);
    assert_eq!(
        header,
        ["index", "u0", "u1", "valid", "wo_x", "wo_y", "wo_z", "pdf"]
    );
    assert_eq!(rows.len(), count);
    let drawn = rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            assert_eq!(r[0], i.to_string());
            let (u0, u1) = (f(&r[1]), f(&r[2]));
            assert!((0.0..1.0).contains(&u0) && (0.0..1.0).contains(&u1));
            let valid = match r[3].as_str() {
                "true" => true,
                "false" => false,
                other => panic!("valid = {other}"),
            };
            let wo = [f(&r[4]), f(&r[5]), f(&r[6])];
            let pdf = f(&r[7]);
            if valid {
                let l = (wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2]).sqrt();
                assert!((l - 1.0).abs() < 1e-4 && wo[2] >= 0.0 && pdf > 0.0, "{r:?}");
            } else {
                assert_eq!((wo, pdf), ([0.0; 3], 0.0));
            }
            Drawn { valid, wo, pdf }
        })
        .collect();
    (text, drawn)
}

fn assert_rel(a: f32, b: f32, what: &str) {
    assert!(
        (a - b).abs() <= 1e-4 * b.abs(),
        "{what}: {a} vs {b} (relative {})",
        (a - b).abs() / b.abs()
    );
}

#[test]
fn pdf_of_each_sample_equals_the_sampled_pdf() {
    let m = model();
    let m = m.to_str().unwrap();
    for wi in ["0.3,0,0.9539392", "0,0,1", "60,30"] {
        let (text, drawn) = sample_csv(wi, 300, 7);
        let valid = drawn.iter().filter(|d| d.valid).count();
        assert!(valid >= 250, "{wi}: only {valid} of 300 valid");
        // Many rows at once: the sample output piped in as is.
        let (header, rows) = csv(&ok(&["pdf", m, "--wi", wi, "--wo", "-"], Some(&text)));
        assert_eq!(header, ["index", "wo_x", "wo_y", "wo_z", "pdf"]);
        assert_eq!(rows.len(), drawn.len());
        for (d, r) in drawn.iter().zip(&rows) {
            if d.valid {
                assert_rel(f(&r[4]), d.pdf, &format!("wi {wi}, stdin row {r:?}"));
            }
        }
        // One row on the command line, for a few of them.
        for d in drawn.iter().filter(|d| d.valid).take(5) {
            let wo = format!("{},{},{}", d.wo[0], d.wo[1], d.wo[2]);
            let (_, rows) = csv(&ok(&["pdf", m, "--wi", wi, "--wo", &wo], None));
            assert_eq!(rows.len(), 1);
            assert_rel(f(&rows[0][4]), d.pdf, &format!("wi {wi}, wo {wo}"));
        }
    }
}

#[test]
fn json_matches_csv_and_a_given_u_repeats_a_seeded_row() {
    let m = model();
    let m = m.to_str().unwrap();
    let wi = "0.3,0,0.9539392";
    let (text, drawn) = sample_csv(wi, 20, 3);
    let json: Value = serde_json::from_str(&ok(
        &[
            "sample", m, "--wi", wi, "--count", "20", "--seed", "3", "--format", "json",
        ],
        None,
    ))
    .unwrap();
    let rows = json.as_array().unwrap();
    assert_eq!(rows.len(), 20);
    for (d, r) in drawn.iter().zip(rows) {
        assert_eq!(r["valid"].as_bool().unwrap(), d.valid);
        let wo: Vec<f32> = r["wo"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap() as f32)
            .collect();
        assert_eq!(wo, d.wo);
        assert_eq!(r["pdf"].as_f64().unwrap() as f32, d.pdf);
    }
    // `--u` for the third seeded row gives that row.
    let (_, csv_rows) = csv(&text);
    let u = format!("{},{}", csv_rows[2][1], csv_rows[2][2]);
    let (_, one) = csv(&ok(&["sample", m, "--wi", wi, "--u", &u], None));
    assert_eq!(one.len(), 1);
    assert_eq!(one[0][1..], csv_rows[2][1..]);
    // pdf as JSON.
    let wo = format!("{},{},{}", drawn[2].wo[0], drawn[2].wo[1], drawn[2].wo[2]);
    let p: Value = serde_json::from_str(&ok(
        &["pdf", m, "--wi", wi, "--wo", &wo, "--format", "json"],
        None,
    ))
    .unwrap();
    assert_rel(
        p[0]["pdf"].as_f64().unwrap() as f32,
        drawn[2].pdf,
        "json pdf",
    );
    // More steps than the default keep the PDF exact.
    let (_, eight) = csv(&ok(
        &["sample", m, "--wi", wi, "--u", &u, "--steps", "8"],
        None,
    ));
    let wo8 = format!("{},{},{}", eight[0][4], eight[0][5], eight[0][6]);
    let (_, p8) = csv(&ok(
        &["pdf", m, "--wi", wi, "--wo", &wo8, "--steps", "8"],
        None,
    ));
    assert_rel(f(&p8[0][4]), f(&eight[0][7]), "8 steps");
}

#[test]
fn invalid_input_gives_invalid_rows_or_clear_errors() {
    let m = model();
    let m = m.to_str().unwrap();
    // Below the surface (a disk model is a BRDF) and u outside [0, 1]: invalid rows.
    let (_, rows) = csv(&ok(&["sample", m, "--wi", "0,0,-1", "--count", "3"], None));
    assert!(rows.iter().all(|r| r[3] == "false" && r[7] == "0"));
    let (_, rows) = csv(&ok(&["sample", m, "--wi", "0,0,1", "--u", "1.5,0.5"], None));
    assert_eq!(rows[0][3], "false");
    // A non-unit row on stdin gets PDF 0; a malformed one is an error naming its line.
    let (_, rows) = csv(&ok(
        &["pdf", m, "--wi", "0,0,1", "--wo", "-"],
        Some("0,0,1\n0,0,3\n"),
    ));
    assert!(f(&rows[0][4]) > 0.0);
    assert_eq!(rows[1][4], "0");
    let (_, rows) = csv(&ok(&["pdf", m, "--wi", "0,0,1", "--wo", "-"], Some("")));
    assert!(rows.is_empty());
    let out = run(
        &["pdf", m, "--wi", "0,0,1", "--wo", "-"],
        Some("0,0,1\n0,zero,1\n"),
    );
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("stdin line 2"), "{e}");
    // Non-unit and malformed directions on the command line.
    let e = failure(&["sample", m, "--wi", "0,0,2"]);
    assert!(e.contains("--wi") && e.contains("not a unit vector"), "{e}");
    let (_, rows) = csv(&ok(
        &["sample", m, "--wi", "0,0,2", "--normalize", "--count", "1"],
        None,
    ));
    assert_eq!(rows[0][3], "true");
    let e = failure(&["pdf", m, "--wi", "0,0,1", "--wo", "1,nan,0"]);
    assert!(e.contains("--wo"), "{e}");
    let e = failure(&["sample", m, "--wi", "0,0,1", "--u", "0.5"]);
    assert!(e.contains("--u"), "{e}");
    for steps in ["0", "257"] {
        let e = failure(&["sample", m, "--wi", "0,0,1", "--steps", steps]);
        assert!(e.contains("--steps"), "{e}");
    }
}

#[test]
fn corrupt_or_missing_blobs_fail_with_a_clear_message() {
    let good = std::fs::read(model()).unwrap();
    let dir = std::env::temp_dir().join(format!("diffbsdf-blob-cmd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cases: [(&str, Vec<u8>, &str); 3] = [
        (
            "flipped.dbsdf",
            {
                let mut b = good.clone();
                b[200] ^= 0xFF;
                b
            },
            "checksum",
        ),
        ("short.dbsdf", good[..good.len() - 10].to_vec(), "truncated"),
        ("text.dbsdf", b"hello, not a blob".to_vec(), "magic"),
    ];
    for (name, bytes, why) in cases {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let p = path.to_str().unwrap();
        for args in [
            vec!["sample", p, "--wi", "0,0,1"],
            vec!["pdf", p, "--wi", "0,0,1", "--wo", "0,0,1"],
            vec!["info", p],
        ] {
            let e = failure(&args);
            assert!(
                e.contains("is not a valid diffbsdf blob") && e.contains(why) && e.contains(name),
                "{args:?}: {e}"
            );
        }
    }
    let missing = dir.join("missing.dbsdf");
    let e = failure(&["sample", missing.to_str().unwrap(), "--wi", "0,0,1"]);
    assert!(
        e.contains("cannot read") && e.contains("missing.dbsdf"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `info --json` on every shipped blob says what the kernel's parse of it says: size,
/// checksum, domain, precision, steps, shapes, parameters, incident frame and range.
#[test]
fn info_describes_every_shipped_blob() {
    use diffbsdf::{AnyModel, IncidentFold, Precision};
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../models");
    let mut frames = std::collections::BTreeSet::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("dbsdf") {
            continue;
        }
        let bytes = std::fs::read(&path).unwrap();
        let def = *AnyModel::from_blob(&bytes).unwrap().def();
        let v: Value =
            serde_json::from_str(&ok(&["info", path.to_str().unwrap(), "--json"], None)).unwrap();
        let crc = u32::from_le_bytes(bytes[bytes.len() - 4..].try_into().unwrap());
        let frame = match (def.isotropic, def.fold) {
            (true, _) => "isotropic",
            (false, IncidentFold::None) => "every azimuth",
            (false, IncidentFold::HalfTurn) => "half turn",
            (false, IncidentFold::Quarter) => "quarter turn",
        };
        frames.insert(frame);
        let what = path.display().to_string();
        assert_eq!(v["name"], def.name.as_str(), "{what}");
        assert_eq!(v["bytes"], bytes.len(), "{what}");
        assert_eq!(v["crc32"], format!("{crc:08x}"), "{what}");
        assert_eq!(v["domain"], def.domain.name(), "{what}");
        let precision = if def.precision == Precision::F16 {
            "f16"
        } else {
            "f32"
        };
        assert_eq!(v["precision"], precision, "{what}");
        assert_eq!(v["default_steps"], def.default_steps, "{what}");
        assert_eq!(v["params"], def.param_count(), "{what}");
        assert_eq!(v["table_params"], def.table_len(), "{what}");
        assert_eq!(
            v["velocity_net"],
            serde_json::json!([
                def.velocity.hidden_layers,
                def.velocity.width,
                def.velocity.freqs
            ]),
            "{what}"
        );
        assert_eq!(v["incident_frame"], frame, "{what}");
        assert_eq!(
            v["latent_table"] == "none",
            def.latent_table.is_none(),
            "{what}"
        );
        let text = ok(&["info", path.to_str().unwrap()], None);
        assert!(
            text.contains(&format!(
                "model \"{}\": {} bytes",
                def.name.as_str(),
                bytes.len()
            )),
            "{what}: {text}"
        );
    }
    // The shipped models include isotropic ones and the folded anisotropic copper.
    assert!(
        frames.contains("isotropic") && frames.contains("quarter turn"),
        "{frames:?}"
    );
}
