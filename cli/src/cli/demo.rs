//! `diffbsdf demo`: the main job, no arguments needed. Loads the embedded default model
//! (rough conductor, GGX alpha = 0.3, copper, disk domain, 4 Euler steps; see
//! `models/README.md` for the command that made it), measures its quality and cost
//! against the material's own sampler and cosine sampling, and writes the blobs and the
//! report, and the generated GLSL, WGSL and C header, to an output folder. `--train` refits it from scratch with the recorded command
//! and seed and says whether the bytes match the shipped blob.

use super::fit::{print_json, write_file, Bars, CommandError};
use clap::Args;
use diffbsdf::AnyModel;
use diffbsdf::{Domain, Precision};
use diffbsdf_materials::parse_spec;
use diffbsdf_train::metrics::{evaluate, table, EvalConfig, Report};
use diffbsdf_train::{fit_material, FitConfig, ModelExt};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// The embedded default model (f32 blob).
pub const DEFAULT_BLOB: &[u8] = include_bytes!("../../../models/conductor-ggx-a0.3-cu-disk.dbsdf");
/// The material it was trained for.
pub const DEFAULT_SPEC: &str = "conductor:ggx,alpha=0.3,metal=Cu";
/// The seed it was trained with (`diffbsdf fit ... --seed 0`).
pub const DEFAULT_SEED: u64 = 0;

/// Arguments of `diffbsdf demo` (all optional).
#[derive(Debug, Args)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "diffbsdf-demo")]
    pub out_dir: PathBuf,
    /// Retrain the default model from scratch (standard config, seed 0) instead of loading
    /// the embedded blob, and check the bytes against it.
    #[arg(long)]
    pub train: bool,
    /// Samples per wi in the evaluation.
    #[arg(long, default_value_t = 1 << 15)]
    pub samples: usize,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// What `demo --json` prints (also written as `report.json`).
#[derive(Debug, Serialize)]
pub struct DemoOutput {
    /// Material spec.
    pub material: String,
    /// `embedded` or `trained`.
    pub source: &'static str,
    /// Seconds spent training (0 when embedded).
    pub train_seconds: f64,
    /// With `--train`: whether the retrained blob equals the embedded one byte for byte.
    pub reproduces_embedded: Option<bool>,
    /// Files written.
    pub files: Vec<String>,
    /// Quality and cost.
    pub report: Report,
}

/// Runs `diffbsdf demo`.
pub fn run(args: DemoArgs, out: &mut dyn std::io::Write) -> Result<(), CommandError> {
    let material = parse_spec(DEFAULT_SPEC).map_err(CommandError::Spec)?;
    let start = Instant::now();
    let (model, source, reproduces) = if args.train {
        let cfg = FitConfig::quick(Domain::Disk, DEFAULT_SEED);
        let fitted = fit_material(
            material.as_ref(),
            "conductor-ggx-a0.3-cu-disk",
            &cfg,
            &Bars::default(),
        )?;
        let same = fitted.model.blob(Precision::F32)? == DEFAULT_BLOB;
        (fitted.model, "trained", Some(same))
    } else {
        (AnyModel::from_blob(DEFAULT_BLOB)?, "embedded", None)
    };
    let train_seconds = if args.train {
        start.elapsed().as_secs_f64()
    } else {
        0.0
    };
    let cfg = EvalConfig {
        samples: args.samples,
        ..EvalConfig::default()
    };
    let report = evaluate(&model, material.as_ref(), &cfg);
    let dir = &args.out_dir;
    let f32_path = dir.join("model.dbsdf");
    let f16_path = dir.join("model.f16.dbsdf");
    write_file(&f32_path, &model.blob(Precision::F32)?)?;
    write_file(&f16_path, &model.blob(Precision::F16)?)?;
    let text = table::render(&report);
    write_file(&dir.join("report.txt"), text.as_bytes())?;
    let shaders = super::codegen::emit_all(&model.blob(Precision::F32)?, dir)
        .map_err(|e| CommandError::Codegen(e.to_string()))?;
    let mut files: Vec<String> = [
        &f32_path,
        &f16_path,
        &dir.join("report.txt"),
        &dir.join("report.json"),
    ]
    .iter()
    .map(|p| p.display().to_string())
    .collect();
    files.extend(shaders.iter().map(|p| p.display().to_string()));
    let output = DemoOutput {
        material: material.spec(),
        source,
        train_seconds,
        reproduces_embedded: reproduces,
        files,
        report,
    };
    let json =
        serde_json::to_string_pretty(&output).map_err(|e| CommandError::Json(e.to_string()))?;
    write_file(&dir.join("report.json"), json.as_bytes())?;
    if args.json {
        return print_json(&output, out);
    }
    let mut head = format!("diffbsdf demo: {} model for {}\n", source, output.material);
    if args.train {
        head += &format!(
            "trained in {:.1} s; bytes equal to the embedded blob: {}\n",
            train_seconds,
            reproduces.unwrap_or(false)
        );
    }
    head += &format!("wrote {}\n\n", output.files.join(", "));
    write!(out, "{head}{text}").map_err(CommandError::Output)
}
