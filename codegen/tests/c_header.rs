//! The generated standalone C header, compiled by gcc with
//! `-std=c99 -Wall -Wextra -Werror -pedantic` (and once by g++ as C++), run on the shared
//! conformance vectors and compared with the Rust kernel within 1e-5.

mod support;

use diffbsdf_codegen::{generate, EntryPoints, Language, Options, Weights};
use std::path::{Path, PathBuf};
use std::process::Command;
use support::vectors::*;

fn options(weights: Weights, entry_points: EntryPoints) -> Options {
    Options {
        language: Language::C,
        float: diffbsdf_codegen::Float::F32,
        entry_points,
        weights,
        prefix: Some("dbsdf".into()),
        // as the kernel under test computes its multiply-adds
        fused: diffbsdf::spec::FUSED_MULTIPLY_ADD,
    }
}

fn compile(dir: &Path, header: &str, buffer: bool) -> PathBuf {
    let h = dir.join("gen.h");
    std::fs::write(&h, header).expect("write header");
    let exe = dir.join(if buffer { "harness_buf" } else { "harness" });
    let mut cmd = Command::new("gcc");
    cmd.args(C_FLAGS)
        .arg("-O2")
        .arg(format!("-DGENERATED_HEADER=\"{}\"", h.display()))
        .args(if buffer {
            vec!["-DDBSDF_BUFFER"]
        } else {
            vec![]
        })
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/c/harness.c"))
        .args(["-lm", "-o"])
        .arg(&exe);
    run_tool(&mut cmd, GCC_HINT);
    exe
}

#[test]
fn header_compiles_as_cpp_with_each_entry_point_alone() {
    let dir = scratch("codegen_cpp");
    let blob = &test_models()[1].blob;
    for (k, e) in EntryPoints::EACH_ALONE.into_iter().enumerate() {
        let code = generate(blob, &options(Weights::Baked, e)).expect("generate");
        let h = dir.join(format!("gen{k}.h"));
        std::fs::write(&h, &code).expect("write");
        let src = dir.join(format!("use{k}.cpp"));
        std::fs::write(
            &src,
            format!("#include \"{}\"\nint main() {{ return 0; }}\n", h.display()),
        )
        .expect("write");
        let mut cmd = Command::new("g++");
        cmd.args([
            "-std=c++11",
            "-Wall",
            "-Wextra",
            "-Werror",
            "-pedantic",
            "-fsyntax-only",
        ])
        .arg(&src);
        run_tool(&mut cmd, GCC_HINT);
        // And as C: an entry point alone compiles without unused-function warnings.
        let mut cmd = Command::new("gcc");
        cmd.args(C_FLAGS).args(["-fsyntax-only", "-x", "c"]).arg(&h);
        run_tool(&mut cmd, GCC_HINT);
    }
}

#[test]
fn generated_c_matches_kernel() {
    let dir = scratch("codegen_c");
    let mut total = Errors::default();
    for model in test_models() {
        let kernel = Kernel::load(&model.blob);
        let samples = sample_vectors(kernel.domain());
        let pdfs = pdf_vectors(&kernel, &samples);
        let flat: Vec<f32> = samples
            .iter()
            .flat_map(|(w, u)| w.iter().chain(u).copied())
            .collect();
        write_f32s(&dir.join("s.f32"), &flat);
        let flat: Vec<f32> = pdfs
            .iter()
            .flat_map(|(a, b)| a.iter().chain(b).copied())
            .collect();
        write_f32s(&dir.join("p.f32"), &flat);
        let desc = diffbsdf_codegen::ModelDesc::from_blob(&model.blob).expect("blob");
        // Two materials in one buffer: garbage first, the model second.
        let mut params: Vec<f32> = desc.params.iter().map(|w| -w * 3.0).collect();
        params.extend(&desc.params);
        write_f32s(&dir.join("params.f32"), &params);
        for buffer in [false, true] {
            let w = if buffer {
                Weights::Buffer { set: 0, binding: 0 }
            } else {
                Weights::Baked
            };
            let code = generate(&model.blob, &options(w, EntryPoints::ALL)).expect("generate");
            let exe = compile(&dir, &code, buffer);
            for steps in [
                0u32,
                2 * kernel.default_steps(),
                diffbsdf::spec::MAX_STEPS + 1,
            ] {
                let out_path = dir.join("out.f32");
                let mut cmd = Command::new(&exe);
                cmd.arg(dir.join("s.f32"))
                    .arg(dir.join("p.f32"))
                    .arg(steps.to_string())
                    .arg(&out_path);
                if buffer {
                    cmd.arg(dir.join("params.f32"));
                }
                run_tool(&mut cmd, "");
                let out = read_f32s(&out_path);
                assert_eq!(out.len(), 9 * samples.len() + pdfs.len());
                let mut e = Errors::default();
                for (i, &(wi, u)) in samples.iter().enumerate() {
                    let o = &out[9 * i..9 * i + 9];
                    let what = format!(
                        "{} buffer={buffer} steps {steps} wi {wi:?} u {u:?}",
                        model.name
                    );
                    let d = kernel.direction(wi, u, steps);
                    let tol = TOL_F32 * kernel.amplification(wi, u, steps);
                    assert_eq!(o[0] == 1.0, d.is_some(), "{what}: direction validity");
                    check_dir(&what, [o[1], o[2], o[3]], d, tol, &mut e);
                    let s = kernel.sample(wi, u, steps);
                    assert_eq!(o[4] == 1.0, s.is_some(), "{what}: sample validity");
                    check_dir(&what, [o[5], o[6], o[7]], s.map(|s| s.0), tol, &mut e);
                    // The sampled PDF is the density at the sampled direction: allowed what
                    // a PDF of that direction is (the measure's and the density's condition
                    // there), as the GPU test allows it.
                    let mc = s.map_or(0.0, |s| {
                        measure_condition(kernel.domain(), wi, s.0)
                            .max(kernel.pdf_condition(wi, s.0, steps))
                    });
                    check_pdf(&what, o[8], s.map_or(0.0, |s| s.1), mc, tol, &mut e);
                }
                let base = 9 * samples.len();
                for (i, &(wi, wo)) in pdfs.iter().enumerate() {
                    let what = format!(
                        "{} buffer={buffer} steps {steps} pdf wi {wi:?} wo {wo:?}",
                        model.name
                    );
                    let mc = measure_condition(kernel.domain(), wi, wo)
                        .max(kernel.pdf_condition(wi, wo, steps));
                    check_pdf(
                        &what,
                        out[base + i],
                        kernel.pdf(wi, wo, steps),
                        mc,
                        TOL_F32,
                        &mut e,
                    );
                }
                println!("{} buffer={buffer} steps {steps}: {e:?}", model.name);
                e.assert_allowances(&format!("{} buffer={buffer} steps {steps}", model.name));
                if steps > diffbsdf::spec::MAX_STEPS {
                    // Every call above the bound is invalid in both (checked above).
                    assert_eq!(e.valid, 0, "{}: a sample above MAX_STEPS", model.name);
                    continue;
                }
                total.merge(&e);
            }
        }
    }
    println!("generated C vs kernel, all models: {total:?}");
    total.assert_raw_bounds("generated C", RAW_DIR_F32, Some(RAW_PDF_F32));
    assert!(
        total.valid * 2 > total.compared,
        "most vectors should be valid: {total:?}"
    );
}
