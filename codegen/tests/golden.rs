//! Golden files: the output for small fixed random-weight models (disk, sphere,
//! half-vector chart, that with a latent table, and a folded anisotropic one) in
//! every language and in the main option combinations is committed under
//! `tests/golden/` and must not change unnoticed. Regenerate with
//! `DIFFBSDF_BLESS=1 cargo test -p diffbsdf-codegen --test golden` and review the diff.

mod support;

use diffbsdf::{Domain, IncidentFold, ModelDef, ModelName, NetShape, Precision, TableGrid};
use diffbsdf_codegen::{generate, EntryPoints, Float, Language, Options, Weights};
use std::path::Path;
use support::vectors::random_blob;

/// A deliberately tiny model so the golden files stay readable.
/// The disk one is isotropic, so the incident-frame rotation is in the goldens too; the
/// half-vector one runs its flow in standard coordinates (docs/math.md, §6.3).
fn tiny(domain: Domain, name: &str) -> Vec<u8> {
    tiny_with_table(domain, name, None)
}

/// [`tiny`], with a latent table on `table`'s grid in front of the half-vector flow (its
/// node values in the parameter buffer: the golden files use buffer mode for it).
fn tiny_with_table(domain: Domain, name: &str, table: Option<TableGrid>) -> Vec<u8> {
    tiny_model(domain, name, table, IncidentFold::None)
}

/// [`tiny_with_table`] for an anisotropic model folded by `fold` (`IncidentFold::None`:
/// isotropic off the sphere, as before).
fn tiny_model(domain: Domain, name: &str, table: Option<TableGrid>, fold: IncidentFold) -> Vec<u8> {
    let def = ModelDef {
        domain,
        precision: Precision::F32,
        activation: diffbsdf::Activation::Silu,
        base: NetShape {
            freqs: 1,
            width: 3,
            hidden_layers: 1,
        },
        velocity: NetShape {
            freqs: 2,
            width: 4,
            hidden_layers: 2,
        },
        default_steps: 2,
        isotropic: !domain.is_spherical() && fold == IncidentFold::None,
        fold,
        incident: if domain.is_spherical() {
            diffbsdf::IncidentRange::WholeSphere
        } else {
            diffbsdf::IncidentRange::UpperHemisphere
        },
        // As `fit` makes it by default: the half-vector flow in warped standard coordinates.
        standardized: domain == Domain::HalfVector,
        standard_warp: domain == Domain::HalfVector,
        latent_table: table,
        name: ModelName::new(name).expect("name"),
    };
    random_blob(&def, 5, 1.0)
}

fn cases() -> Vec<(&'static str, Vec<u8>, Options)> {
    let disk = tiny(Domain::Disk, "tiny disk");
    let sphere = tiny(Domain::Sphere, "tiny-sphere");
    let half_vector = tiny(Domain::HalfVector, "tiny half vector");
    let table = tiny_with_table(
        Domain::HalfVector,
        "tiny half vector table",
        Some(TableGrid::Codes),
    );
    let axes_table = tiny_with_table(
        Domain::HalfVector,
        "tiny half vector axes",
        Some(TableGrid::WarpedCodes),
    );
    let blended_table = tiny_with_table(
        Domain::HalfVector,
        "tiny half vector blended",
        Some(TableGrid::BlendedSlices),
    );
    let quarter = tiny_model(
        Domain::HalfVector,
        "tiny half vector quarter",
        None,
        IncidentFold::Quarter,
    );
    let opt = |language, float, weights, entry_points| Options {
        language,
        float,
        entry_points,
        weights,
        prefix: None,
        fused: false,
    };
    let fused = |o: Options| Options { fused: true, ..o };
    let buf = Weights::Buffer { set: 1, binding: 3 };
    let dir_only = EntryPoints {
        direction: true,
        sample: false,
        pdf: false,
    };
    let pdf_only = EntryPoints {
        direction: false,
        sample: false,
        pdf: true,
    };
    vec![
        (
            "disk_all.glsl",
            disk.clone(),
            opt(Language::Glsl, Float::F32, Weights::Baked, EntryPoints::ALL),
        ),
        (
            "sphere_all_f16_buffer.glsl",
            sphere.clone(),
            opt(Language::Glsl, Float::F16, buf, EntryPoints::ALL),
        ),
        (
            "disk_all_buffer.wgsl",
            disk.clone(),
            opt(Language::Wgsl, Float::F32, buf, EntryPoints::ALL),
        ),
        (
            "sphere_direction_f16.wgsl",
            sphere.clone(),
            opt(Language::Wgsl, Float::F16, Weights::Baked, dir_only),
        ),
        (
            "disk_all.h",
            disk,
            opt(Language::C, Float::F32, Weights::Baked, EntryPoints::ALL),
        ),
        (
            "sphere_pdf_buffer.h",
            sphere,
            opt(Language::C, Float::F32, buf, pdf_only),
        ),
        (
            "half_vector_all.h",
            half_vector.clone(),
            opt(Language::C, Float::F32, Weights::Baked, EntryPoints::ALL),
        ),
        (
            "half_vector_all_f16.wgsl",
            half_vector.clone(),
            opt(Language::Wgsl, Float::F16, Weights::Baked, EntryPoints::ALL),
        ),
        // the networks' multiply-adds fused, as the kernel's `fma` feature computes them
        (
            "half_vector_all_fused.h",
            half_vector.clone(),
            fused(opt(
                Language::C,
                Float::F32,
                Weights::Baked,
                EntryPoints::ALL,
            )),
        ),
        (
            "half_vector_all_fused.glsl",
            half_vector.clone(),
            fused(opt(Language::Glsl, Float::F32, buf, EntryPoints::ALL)),
        ),
        // the latent table (docs/math.md, section 6.5), its nodes in the buffer
        (
            "half_vector_table_buffer.wgsl",
            table,
            opt(Language::Wgsl, Float::F32, buf, EntryPoints::ALL),
        ),
        // with its axis warps (docs/math.md, (81)), as the trainer writes it
        (
            "half_vector_axes_table_buffer.glsl",
            axes_table,
            opt(Language::Glsl, Float::F32, buf, EntryPoints::ALL),
        ),
        (
            "half_vector_blended_table_buffer.h",
            blended_table,
            opt(Language::C, Float::F32, buf, EntryPoints::ALL),
        ),
        // an anisotropic model folded into a quarter of the turn (docs/math.md, (83))
        (
            "half_vector_quarter.h",
            quarter,
            opt(Language::C, Float::F32, Weights::Baked, EntryPoints::ALL),
        ),
        (
            "half_vector_all_f16_fused.wgsl",
            half_vector,
            fused(opt(
                Language::Wgsl,
                Float::F16,
                Weights::Baked,
                EntryPoints::ALL,
            )),
        ),
    ]
}

#[test]
fn outputs_match_golden_files() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let bless = std::env::var_os("DIFFBSDF_BLESS").is_some();
    let mut stale = Vec::new();
    for (name, blob, options) in cases() {
        let code = generate(&blob, &options).expect("generate");
        assert_eq!(
            code,
            generate(&blob, &options).expect("generate"),
            "{name}: not deterministic"
        );
        assert!(
            code.contains("generated by diffbsdf-codegen"),
            "{name}: no header comment"
        );
        assert!(code.contains("do not edit"));
        let path = dir.join(name);
        if bless {
            std::fs::create_dir_all(&dir).expect("golden dir");
            std::fs::write(&path, &code).expect("write golden");
            continue;
        }
        match std::fs::read_to_string(&path) {
            Ok(want) if want == code => {}
            Ok(_) => stale.push(format!("{name} differs")),
            Err(e) => stale.push(format!("{name}: {e}")),
        }
    }
    assert!(
        stale.is_empty(),
        "golden files out of date ({}); if the change is intended, run \
         `DIFFBSDF_BLESS=1 cargo test -p diffbsdf-codegen --test golden` and review the diff",
        stale.join(", ")
    );
}
