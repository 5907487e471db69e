//! Code for a set of materials: only the architectures and entry points the set uses, one
//! buffer per architecture holding every material at the offset its constant names, and
//! code that the real compilers accept (glslang + spirv-val, naga) with every group bound.

mod support;

use diffbsdf_codegen::{
    generate_set, EntryPoints, Language, Material, ModelDesc, Options, Weights,
};
use support::shaders::*;
use support::vectors::*;

fn materials(models: &[TestModel]) -> Vec<Material> {
    models
        .iter()
        .map(|m| Material {
            name: m.name.clone(),
            model: ModelDesc::from_blob(&m.blob).expect("blob"),
        })
        .collect()
}

fn buffer_options(language: Language, entry_points: EntryPoints) -> Options {
    Options {
        language,
        entry_points,
        weights: Weights::Buffer { set: 0, binding: 4 },
        prefix: Some("mat".into()),
        ..Options::new(language)
    }
}

/// The value of the constant `name` in generated code (any of the three syntaxes).
fn constant(code: &str, name: &str) -> usize {
    let line = code
        .lines()
        .find(|l| l.contains(&format!("{name} ")) || l.contains(&format!("{name}:")))
        .unwrap_or_else(|| panic!("no constant {name}"));
    let value = line
        .split(['=', ' '])
        .rev()
        .find(|s| !s.is_empty())
        .expect("value");
    value
        .trim_end_matches(';')
        .trim_end_matches('u')
        .parse()
        .expect("number")
}

#[test]
fn a_disk_only_set_has_one_group_and_no_sphere_code() {
    let all = materials(&shipped_models());
    let disk: Vec<Material> = all
        .into_iter()
        .filter(|m| m.model.def.domain == diffbsdf::Domain::Disk)
        .collect();
    assert!(disk.len() >= 3, "need several shipped disk models");
    let o = buffer_options(Language::Glsl, EntryPoints::ALL);
    let set = generate_set(&disk, &o).expect("generate");
    assert_eq!(set.buffers.len(), 1);
    assert!(
        !set.code.contains("_wrap("),
        "disk-only set has sphere code"
    );
    assert!(!set.code.contains("wrapped_cauchy"));
    let b = &set.buffers[0];
    assert_eq!(b.binding, 4);
    let mut offset = 0;
    for m in &disk {
        let stem = format!("{}_{}", b.prefix, m.name)
            .to_uppercase()
            .replace(['-', '.'], "_");
        let base = constant(&set.code, &format!("{stem}_BASE"));
        assert_eq!(base, offset, "{stem}");
        assert_eq!(
            &b.params[base..base + m.model.params.len()],
            &m.model.params[..]
        );
        let steps = constant(&set.code, &format!("{stem}_STEPS"));
        assert_eq!(steps, m.model.def.default_steps as usize);
        offset += m.model.params.len();
    }
    assert_eq!(b.params.len(), offset);
}

#[test]
fn a_mixed_set_compiles_with_one_buffer_per_architecture() {
    // The shipped models and one in uncompressed standard coordinates (no shipped model
    // keeps them since 2026-12-08; a renderer's set may still hold one).
    let mut models = shipped_models();
    models.extend(
        test_models()
            .into_iter()
            .filter(|m| m.name == "random_half_vector_std"),
    );
    let mats = materials(&models);
    let direction = EntryPoints {
        direction: true,
        sample: false,
        pdf: false,
    };
    for entry_points in [EntryPoints::ALL, direction] {
        let o = buffer_options(Language::Glsl, entry_points);
        let set = generate_set(&mats, &o).expect("generate");
        // Isotropic disk, isotropic sphere for every wi (dielectrics, principled),
        // isotropic sphere above the surface only (copper), isotropic half-vector chart
        // in warped standard coordinates (measured materials, rough copper), in
        // uncompressed ones (the test model) and the anisotropic half-vector chart folded
        // into a quarter turn (the anisotropic copper).
        assert_eq!(set.buffers.len(), 6, "one group per architecture");
        assert_eq!(
            set.buffers.iter().map(|b| b.binding).collect::<Vec<_>>(),
            vec![4, 5, 6, 7, 8, 9]
        );
        assert_eq!(
            set.code.contains("velocity_jacobian"),
            entry_points.sample || entry_points.pdf,
            "Jacobians emitted iff an entry point needs them"
        );
        // Every group's sample_direction called from one shader.
        let mut calls = String::new();
        for b in &set.buffers {
            calls += &format!(
                "acc += {}_sample_direction(0u, vec3(0.0, 0.0, 1.0), vec2(0.5), 0u).x;\n",
                b.prefix
            );
        }
        let src = format!(
            "#version 450\n{}\nlayout(local_size_x = 1) in;\n\
             layout(std430, set = 0, binding = 1) buffer Out {{ float result[]; }};\n\
             void main() {{\nfloat acc = 0.0;\n{calls}result[0] = acc;\n}}\n",
            set.code
        );
        glslang(&scratch("set_glsl"), "mixed", &src);

        let o = buffer_options(Language::Wgsl, entry_points);
        let set = generate_set(&mats, &o).expect("generate");
        let mut calls = String::new();
        for b in &set.buffers {
            calls += &format!(
                "acc += {}_sample_direction(0u, vec3<f32>(0.0, 0.0, 1.0), vec2<f32>(0.5), 0u).x;\n",
                b.prefix
            );
        }
        let src = format!(
            "{}\n@group(0) @binding(1) var<storage, read_write> result: array<f32>;\n\
             @compute @workgroup_size(1)\nfn main() {{\nvar acc = 0.0;\n{calls}result[0] = acc;\n}}\n",
            set.code
        );
        naga_validate("mixed set", &src);
    }
}

#[test]
fn baked_sets_give_every_material_its_own_functions() {
    let mats = materials(&shipped_models());
    let o = Options {
        prefix: Some("mat".into()),
        ..Options::new(Language::C)
    };
    let set = generate_set(&mats, &o).expect("generate");
    assert!(set.buffers.is_empty());
    for m in &mats {
        let f = format!("mat_{}_sample(", m.name.replace(['-', '.'], "_"));
        assert!(set.code.contains(&f), "{f} missing");
    }
}

#[test]
fn duplicate_names_are_refused() {
    let mut mats = materials(&shipped_models());
    mats.truncate(1);
    mats.push(mats[0].clone());
    let o = Options::new(Language::Glsl);
    assert!(generate_set(&mats, &o).is_err());
}
