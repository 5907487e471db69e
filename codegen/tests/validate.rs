//! Every combination of options, for the paper's disk and sphere shapes, goes through
//! the real compilers: GLSL through `glslangValidator -V` and `spirv-val`, WGSL through
//! naga's parser and validator.

mod support;

use diffbsdf_codegen::{generate, EntryPoints, Float, Language, Options, Weights};
use support::shaders::*;
use support::vectors::*;

fn all_options(language: Language) -> Vec<Options> {
    let mut v = Vec::new();
    let mut entries = vec![EntryPoints::ALL];
    entries.extend(EntryPoints::EACH_ALONE);
    for float in [Float::F32, Float::F16] {
        for weights in [Weights::Baked, Weights::Buffer { set: 0, binding: 0 }] {
            for &entry_points in &entries {
                for fused in [false, true] {
                    v.push(Options {
                        language,
                        float,
                        entry_points,
                        weights,
                        prefix: Some("dbsdf".into()),
                        fused,
                    });
                }
            }
        }
    }
    v
}

/// A shader that calls only the entry points generated.
fn calls(e: EntryPoints, buffer: bool, wgsl: bool) -> String {
    let b = if buffer { "0u, " } else { "" };
    let (v3, v2) = if wgsl {
        ("vec3<f32>(0.0, 0.0, 1.0)", "vec2<f32>(0.5)")
    } else {
        ("vec3(0.0, 0.0, 1.0)", "vec2(0.5)")
    };
    let mut s = String::new();
    if e.direction {
        s.push_str(&format!(
            "acc += dbsdf_sample_direction({b}{v3}, {v2}, 0u).x;\n"
        ));
    }
    if e.sample {
        s.push_str(&format!("acc += dbsdf_sample({b}{v3}, {v2}, 0u).w;\n"));
    }
    if e.pdf {
        s.push_str(&format!("acc += dbsdf_pdf({b}{v3}, {v3}, 0u);\n"));
    }
    s
}

#[test]
fn glsl_compiles_and_validates() {
    let dir = scratch("validate_glsl");
    for model in test_models().iter().take(2) {
        for (k, o) in all_options(Language::Glsl).into_iter().enumerate() {
            let code = generate(&model.blob, &o).expect("generate");
            let buffer = o.weights != Weights::Baked;
            let src = format!(
                "#version 450\n{code}\nlayout(local_size_x = 1) in;\n\
                 layout(std430, set = 0, binding = 1) buffer Out {{ float result[]; }};\n\
                 void main() {{\nfloat acc = 0.0;\n{}result[0] = acc;\n}}\n",
                calls(o.entry_points, buffer, false)
            );
            glslang(&dir, &format!("{}_{k}", model.name), &src);
        }
    }
}

#[test]
fn wgsl_validates_with_naga() {
    for model in test_models().iter().take(2) {
        for (k, o) in all_options(Language::Wgsl).into_iter().enumerate() {
            let code = generate(&model.blob, &o).expect("generate");
            let buffer = o.weights != Weights::Baked;
            let src = format!(
                "{code}\n@group(0) @binding(1) var<storage, read_write> result: array<f32>;\n\
                 @compute @workgroup_size(1)\nfn main() {{\nvar acc = 0.0;\n{}result[0] = acc;\n}}\n",
                calls(o.entry_points, buffer, true)
            );
            naga_validate(&format!("{} options #{k}", model.name), &src);
        }
    }
}

#[test]
fn only_requested_helpers_are_emitted() {
    let blob = &test_models()[1].blob;
    let mut o = Options::new(Language::Glsl);
    o.prefix = Some("dbsdf".into());
    o.entry_points = EntryPoints {
        direction: true,
        sample: false,
        pdf: false,
    };
    let dir_only = generate(blob, &o).expect("generate");
    assert!(
        !dir_only.contains("velocity_jacobian"),
        "direction-only output has Jacobians"
    );
    assert!(
        !dir_only.contains("dbsdf_pdf"),
        "direction-only output has the PDF"
    );
    assert!(!dir_only.contains("base_ln_pdf"));
    o.entry_points = EntryPoints {
        direction: false,
        sample: false,
        pdf: true,
    };
    let pdf_only = generate(blob, &o).expect("generate");
    assert!(
        !pdf_only.contains("quantile"),
        "PDF-only output samples the base"
    );
    assert!(!pdf_only.contains("dbsdf_sample("));
    o.entry_points = EntryPoints {
        direction: false,
        sample: false,
        pdf: false,
    };
    assert_eq!(
        generate(blob, &o),
        Err(diffbsdf_codegen::Error::NoEntryPoints)
    );
    let mut c = Options::new(Language::C);
    c.float = Float::F16;
    assert!(matches!(
        generate(blob, &c),
        Err(diffbsdf_codegen::Error::Unsupported(_))
    ));
    assert!(matches!(
        generate(&blob[..10], &c),
        Err(diffbsdf_codegen::Error::Blob(_))
    ));
}
