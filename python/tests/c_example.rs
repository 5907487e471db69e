//! The C++ integration example `ffi/examples/mis_estimate.cpp`, compiled with g++ against
//! the C ABI's static library and run: BSDF sampling and MIS with the learned sampler
//! converge to a quadrature of the same reflected-radiance integral.

use std::path::PathBuf;
use std::process::Command;

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(PathBuf::from)
        .unwrap_or_default()
}

/// `libdiffbsdf_ffi.a` cargo built for this test run (a dev-dependency builds every crate
/// type it declares), next to the test binary in `target/<profile>/deps/`.
fn staticlib() -> PathBuf {
    let exe = std::env::current_exe().expect("test exe path");
    let deps = exe.parent().expect("target/<profile>/deps");
    let lib = deps.join("libdiffbsdf_ffi.a");
    assert!(
        lib.exists(),
        "{} missing: the ffi staticlib was not built",
        lib.display()
    );
    lib
}

#[test]
fn cpp_mis_example_converges_to_the_reference() {
    let root = workspace();
    let dir = std::env::temp_dir().join(format!("diffbsdf_cpp_example_{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let exe = dir.join("mis_estimate");
    let out = Command::new("g++")
        .args([
            "-std=c++11",
            "-O2",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-pedantic",
            "-I",
        ])
        .arg(root.join("ffi/include"))
        .arg(root.join("ffi/examples/mis_estimate.cpp"))
        .arg(staticlib())
        .args(["-lpthread", "-ldl", "-o"])
        .arg(&exe)
        .output()
        .expect("g++ not found: install g++ (scripts/test.sh does)");
    assert!(
        out.status.success(),
        "g++ failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let run = Command::new(&exe)
        .arg(root.join("models/conductor-ggx-a0.3-cu-disk.dbsdf"))
        .output()
        .expect("run the example");
    let stdout = String::from_utf8_lossy(&run.stdout).into_owned();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        run.status.success(),
        "example reported a mismatch:\n{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let results: Vec<&str> = stdout.lines().filter(|l| l.starts_with("RESULT")).collect();
    assert_eq!(results.len(), 4, "{stdout}");
    for line in results {
        let field = |name: &str| -> f64 {
            line.split_whitespace()
                .find_map(|kv| kv.strip_prefix(&format!("{name}=")))
                .and_then(|v| v.parse().ok())
                .unwrap_or_else(|| panic!("no {name} in {line}"))
        };
        let reference = field("reference");
        for (est, se) in [("bsdf", "bsdf_se"), ("mis", "mis_se")] {
            let (m, s) = (field(est), field(se));
            assert!(
                (m - reference).abs() <= 4.0 * s && (m - reference).abs() <= 0.03 * reference,
                "{est}: {m} +- {s} vs reference {reference} ({line})"
            );
        }
        // MIS with cosine sampling never does worse than 1.5x the learned sampler's error.
        assert!(field("mis_se") <= 1.5 * field("bsdf_se"), "{line}");
    }
}
