//! The C API from C: the header compiled by gcc (`-std=c99 -Wall -Wextra -Werror
//! -pedantic`) and once as C++ by g++, linked against the staticlib this test run built,
//! run on the shared conformance vectors and compared with the Rust kernel within 1e-5.

#[path = "../../codegen/tests/support/vectors.rs"]
mod vectors;

use std::path::{Path, PathBuf};
use std::process::Command;
use vectors::*;

fn crate_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The static library cargo built for this very test run, next to the test binary (the lib
/// target is built with all its crate types before integration tests run; the copy in
/// `target/<profile>/` may come from another build).
fn staticlib() -> PathBuf {
    let exe = std::env::current_exe().expect("test exe path");
    let deps = exe.parent().expect("target/<profile>/deps");
    let lib = deps.join("libdiffbsdf_ffi.a");
    assert!(
        lib.exists(),
        "{} missing: cargo did not build the staticlib for this test run",
        lib.display()
    );
    lib
}

fn build_harness(dir: &Path) -> PathBuf {
    let exe = dir.join("harness");
    let mut cmd = Command::new("gcc");
    cmd.args(C_FLAGS)
        .arg("-I")
        .arg(crate_dir().join("include"))
        .arg(crate_dir().join("tests/c/harness.c"))
        .arg(staticlib())
        .args(["-lm", "-lpthread", "-ldl", "-o"])
        .arg(&exe);
    run_tool(&mut cmd, GCC_HINT);
    exe
}

#[test]
fn header_compiles_as_cpp() {
    let dir = scratch("ffi_cpp");
    let src = dir.join("use.cpp");
    std::fs::write(
        &src,
        "#include \"diffbsdf.h\"\nint main() { diffbsdf_sample_result s = {{0, 0, 1}, 1}; \
         return diffbsdf_version() == DIFFBSDF_VERSION && s.pdf > 0 ? 0 : 1; }\n",
    )
    .expect("write");
    let mut cmd = Command::new("g++");
    cmd.args([
        "-std=c++11",
        "-Wall",
        "-Wextra",
        "-Werror",
        "-pedantic",
        "-I",
    ])
    .arg(crate_dir().join("include"))
    .arg(&src)
    .arg(staticlib())
    .args(["-lm", "-lpthread", "-ldl", "-o"])
    .arg(dir.join("use"));
    run_tool(&mut cmd, GCC_HINT);
    run_tool(&mut Command::new(dir.join("use")), "");
}

#[test]
fn header_version_matches_crate() {
    let header = std::fs::read_to_string(crate_dir().join("include/diffbsdf.h")).expect("header");
    let want = format!(
        "#define DIFFBSDF_VERSION_STRING \"{}\"",
        env!("CARGO_PKG_VERSION")
    );
    assert!(
        header.contains(&want),
        "header version macros out of date: want `{want}`"
    );
    let v = diffbsdf_ffi::diffbsdf_version();
    assert!(
        header.contains(&format!("#define DIFFBSDF_VERSION {v}\n")),
        "DIFFBSDF_VERSION != {v}"
    );
}

#[test]
fn header_agrees_with_the_kernel_definition() {
    let header = std::fs::read_to_string(crate_dir().join("include/diffbsdf.h")).expect("header");
    // The info struct's name holds the kernel's longest name and a NUL.
    let name = format!("char name[{}];", diffbsdf::NAME_CAPACITY + 1);
    assert!(header.contains(&name), "header lacks `{name}`");
    let steps = [
        format!(
            "#define DIFFBSDF_DEFAULT_STEPS {}u",
            diffbsdf::spec::DEFAULT_STEPS
        ),
        format!("#define DIFFBSDF_MAX_STEPS {}u", diffbsdf::spec::MAX_STEPS),
    ];
    for line in steps {
        assert!(header.contains(&line), "header lacks `{line}`");
    }
}

/// The header's structs as gcc lays them out: size, alignment and every field's offset
/// equal the Rust definitions' (a field added on one side only fails here).
#[test]
fn header_structs_have_the_rust_layout() {
    use diffbsdf_ffi::{diffbsdf_info, diffbsdf_sample_result};
    use std::mem::{align_of, offset_of, size_of};
    let dir = scratch("ffi_layout");
    let src = dir.join("layout.c");
    let info_fields = [
        ("domain", offset_of!(diffbsdf_info, domain)),
        ("precision", offset_of!(diffbsdf_info, precision)),
        ("default_steps", offset_of!(diffbsdf_info, default_steps)),
        (
            "velocity_hidden_layers",
            offset_of!(diffbsdf_info, velocity_hidden_layers),
        ),
        ("velocity_width", offset_of!(diffbsdf_info, velocity_width)),
        ("param_count", offset_of!(diffbsdf_info, param_count)),
        ("isotropic", offset_of!(diffbsdf_info, isotropic)),
        ("incident_range", offset_of!(diffbsdf_info, incident_range)),
        ("incident_fold", offset_of!(diffbsdf_info, incident_fold)),
        ("name", offset_of!(diffbsdf_info, name)),
    ];
    let sample_fields = [
        ("wo", offset_of!(diffbsdf_sample_result, wo)),
        ("pdf", offset_of!(diffbsdf_sample_result, pdf)),
    ];
    let mut c = String::from(
        "#include <stddef.h>\n#include <stdio.h>\n#include \"diffbsdf.h\"\nint main(void) {\n",
    );
    let mut want = Vec::new();
    for (ty, size, align, fields) in [
        (
            "diffbsdf_info",
            size_of::<diffbsdf_info>(),
            align_of::<diffbsdf_info>(),
            &info_fields[..],
        ),
        (
            "diffbsdf_sample_result",
            size_of::<diffbsdf_sample_result>(),
            align_of::<diffbsdf_sample_result>(),
            &sample_fields[..],
        ),
    ] {
        c += &format!("    printf(\"{ty} size %zu\\n\", sizeof({ty}));\n");
        c += &format!("    printf(\"{ty} align %zu\\n\", _Alignof({ty}));\n");
        want.push(format!("{ty} size {size}"));
        want.push(format!("{ty} align {align}"));
        for (field, offset) in fields {
            c += &format!("    printf(\"{ty}.{field} %zu\\n\", offsetof({ty}, {field}));\n");
            want.push(format!("{ty}.{field} {offset}"));
        }
    }
    c += "    return 0;\n}\n";
    std::fs::write(&src, c).expect("write");
    let exe = dir.join("layout");
    let mut cmd = Command::new("gcc");
    cmd.args(["-std=c11", "-Wall", "-Wextra", "-Werror", "-pedantic", "-I"])
        .arg(crate_dir().join("include"))
        .arg(&src)
        .arg("-o")
        .arg(&exe);
    run_tool(&mut cmd, GCC_HINT);
    let got = run_tool(&mut Command::new(&exe), "");
    let got: Vec<&str> = got.lines().collect();
    assert_eq!(
        got, want,
        "the header's layout differs from the Rust structs"
    );
}

/// `diffbsdf_model_info` says what each conformance model's definition says (the folded
/// and unfolded, isotropic and anisotropic, f32 and f16 random models).
#[test]
fn info_describes_each_model() {
    use diffbsdf::{AnyModel, IncidentFold, IncidentRange, Precision};
    use diffbsdf_ffi::*;
    let mut folds = [0usize; 3];
    for model in test_models() {
        let any = AnyModel::from_blob(&model.blob).expect("blob loads");
        let def = any.def();
        let mut status = -100;
        // SAFETY: a valid blob and status pointer; the model is freed below.
        let m = unsafe { diffbsdf_model_new(model.blob.as_ptr(), model.blob.len(), &mut status) };
        assert!(!m.is_null() && status == 0, "{}: {status}", model.name);
        let mut info = std::mem::MaybeUninit::<diffbsdf_info>::uninit();
        // SAFETY: a loaded model and a writable struct.
        let info = unsafe {
            assert_eq!(
                diffbsdf_model_info(m, info.as_mut_ptr()),
                diffbsdf_status::DIFFBSDF_OK
            );
            diffbsdf_model_free(m);
            info.assume_init()
        };
        let fold = u32::from(def.fold.code());
        // The codes the header documents: 1 a half turn, 2 a quarter.
        assert_eq!(
            (
                def.fold == IncidentFold::HalfTurn,
                def.fold == IncidentFold::Quarter
            ),
            (info.incident_fold == 1, info.incident_fold == 2),
            "{}",
            model.name
        );
        folds[fold as usize] += 1;
        let name: Vec<u8> = info
            .name
            .iter()
            .take_while(|&&c| c != 0)
            .map(|&c| c as u8)
            .collect();
        assert_eq!(
            (
                info.domain,
                info.precision,
                info.default_steps,
                info.velocity_hidden_layers,
                info.velocity_width,
                info.param_count,
                info.isotropic,
                info.incident_range,
                info.incident_fold,
                name.as_slice(),
            ),
            (
                u32::from(def.domain.code()),
                u32::from(def.precision == Precision::F16),
                def.default_steps as u32,
                def.velocity.hidden_layers as u32,
                def.velocity.width as u32,
                def.param_count() as u32,
                u32::from(def.isotropic),
                u32::from(def.incident == IncidentRange::WholeSphere),
                fold,
                def.name.as_bytes(),
            ),
            "{}",
            model.name
        );
    }
    assert!(
        folds.iter().all(|&n| n > 0),
        "every fold among the models: {folds:?}"
    );
}

#[test]
fn header_lists_every_status() {
    let header = std::fs::read_to_string(crate_dir().join("include/diffbsdf.h")).expect("header");
    for s in diffbsdf_ffi::diffbsdf_status::ALL {
        let line = format!("{s:?} = {},", s as i32);
        let last = format!("{s:?} = {} ", s as i32);
        assert!(
            header.contains(&line) || header.contains(&last),
            "header lacks `{line}`"
        );
    }
}

#[test]
fn c_program_matches_kernel() {
    let dir = scratch("ffi_conformance");
    let exe = build_harness(&dir);
    let mut total = Errors::default();
    for model in test_models() {
        let kernel = Kernel::load(&model.blob);
        let samples = sample_vectors(kernel.domain());
        let pdfs = pdf_vectors(&kernel, &samples);
        let blob = dir.join(format!("{}.bin", model.name));
        std::fs::write(&blob, &model.blob).expect("write blob");
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
        for steps in [0u32, 2 * kernel.default_steps()] {
            let out_path = dir.join("out.f32");
            let mut cmd = Command::new(&exe);
            cmd.arg(&blob)
                .arg(dir.join("s.f32"))
                .arg(dir.join("p.f32"))
                .arg(steps.to_string())
                .arg(&out_path);
            run_tool(&mut cmd, "");
            let out = read_f32s(&out_path);
            assert_eq!(out.len(), 16 * samples.len() + 2 * pdfs.len());
            let mut e = Errors::default();
            for (i, &(wi, u)) in samples.iter().enumerate() {
                let o = &out[16 * i..16 * i + 16];
                let what = format!("{} steps {steps} wi {wi:?} u {u:?}", model.name);
                let d = kernel.direction(wi, u, steps);
                assert_eq!(
                    o[0],
                    if d.is_some() { 0.0 } else { 1.0 },
                    "{what}: direction status"
                );
                check_dir(&what, [o[1], o[2], o[3]], d, TOL_F32, &mut e);
                check_dir(&what, [o[9], o[10], o[11]], d, TOL_F32, &mut e);
                let s = kernel.sample(wi, u, steps);
                assert_eq!(
                    o[4],
                    if s.is_some() { 0.0 } else { 1.0 },
                    "{what}: sample status"
                );
                for (wo, pdf) in [([o[5], o[6], o[7]], o[8]), ([o[12], o[13], o[14]], o[15])] {
                    check_dir(&what, wo, s.map(|s| s.0), TOL_F32, &mut e);
                    check_pdf(&what, pdf, s.map_or(0.0, |s| s.1), 0.0, TOL_F32, &mut e);
                }
            }
            let base = 16 * samples.len();
            for (i, &(wi, wo)) in pdfs.iter().enumerate() {
                let what = format!("{} steps {steps} pdf wi {wi:?} wo {wo:?}", model.name);
                let want = kernel.pdf(wi, wo, steps);
                check_pdf(&what, out[base + 2 * i], want, 0.0, TOL_F32, &mut e);
                check_pdf(&what, out[base + 2 * i + 1], want, 0.0, TOL_F32, &mut e);
            }
            println!("{} steps {steps}: {e:?}", model.name);
            total.max_dir = total.max_dir.max(e.max_dir);
            total.max_pdf_rel = total.max_pdf_rel.max(e.max_pdf_rel);
            total.compared += e.compared;
            total.valid += e.valid;
        }
    }
    println!("FFI vs kernel, all models: {total:?}");
    assert!(total.compared > 1000, "too few comparisons: {total:?}");
    assert!(
        total.valid * 2 > total.compared,
        "most vectors should be valid samples: {total:?}"
    );
}

#[test]
fn example_program_runs() {
    let dir = scratch("ffi_example");
    let exe = dir.join("sample");
    let mut cmd = Command::new("gcc");
    cmd.args(C_FLAGS)
        .arg("-I")
        .arg(crate_dir().join("include"))
        .arg(crate_dir().join("examples/sample.c"))
        .arg(staticlib())
        .args(["-lm", "-lpthread", "-ldl", "-o"])
        .arg(&exe);
    run_tool(&mut cmd, GCC_HINT);
    // Every shipped model, or the random ones while none is shipped.
    let shipped = shipped_models();
    let models = if shipped.is_empty() {
        test_models()
    } else {
        shipped
    };
    for m in models {
        let blob = dir.join(format!("{}.bin", m.name));
        std::fs::write(&blob, &m.blob).expect("write blob");
        let out = run_tool(Command::new(&exe).arg(&blob), "");
        assert!(
            out.contains(&format!("model \"{}\"", m.name)) || !m.name.starts_with("random"),
            "{out}"
        );
        assert!(out.contains("pdf"), "{out}");
        assert!(
            !out.contains("unknown"),
            "the example names every domain and fold: {out}"
        );
    }
}
