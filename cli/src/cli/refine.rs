//! `diffbsdf refine m.dbsdf <material-spec> --out r.dbsdf`: the variance refinement of a
//! fitted model's student (`diffbsdf_train::refine`, docs/math.md §11) on its own, for a
//! blob that was fitted without it; writes the f32 blob at `--out` and the f16 beside it.

use super::fit::{f16_path, write_file, Bars, CommandError};
use super::share::parse_share;
use clap::Args;
use diffbsdf::{AnyModel, Precision};
use diffbsdf_materials::parse_spec;
use diffbsdf_train::refine::{refine, RefineConfig};
use diffbsdf_train::ModelExt;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `diffbsdf refine`.
#[derive(Debug, Args)]
pub struct RefineArgs {
    /// The fitted model blob.
    pub blob: PathBuf,
    /// Material spec it was fitted to.
    pub spec: String,
    /// Output blob (f32); the f16 blob is written beside it.
    #[arg(long)]
    pub out: PathBuf,
    /// Adam iterations.
    #[arg(long, default_value_t = RefineConfig::default().iters)]
    pub iters: usize,
    /// Incidences per iteration.
    #[arg(long, default_value_t = RefineConfig::default().incidences)]
    pub incidences: usize,
    /// Samples per incidence.
    #[arg(long, default_value_t = RefineConfig::default().samples)]
    pub samples: usize,
    /// Peak learning rate.
    #[arg(long, default_value_t = RefineConfig::default().lr)]
    pub lr: f32,
    /// Share of the gradient estimated from the material's own samples.
    #[arg(long, default_value_t = RefineConfig::default().target_share, value_parser = parse_share)]
    pub target_share: f32,
    /// Share of the incidences drawn from the grazing band (60 to 89.5 degrees).
    #[arg(long, default_value_t = RefineConfig::default().grazing_share, value_parser = parse_share)]
    pub grazing_share: f32,
    /// Seed of the refinement's random draws.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// Runs `diffbsdf refine`.
pub fn run(args: RefineArgs, out: &mut dyn std::io::Write) -> Result<(), CommandError> {
    let material = parse_spec(&args.spec).map_err(CommandError::Spec)?;
    let bytes = std::fs::read(&args.blob).map_err(|e| CommandError::Io(args.blob.clone(), e))?;
    let model = AnyModel::from_blob(&bytes)?;
    let cfg = RefineConfig {
        iters: args.iters,
        incidences: args.incidences,
        samples: args.samples,
        lr: args.lr,
        target_share: args.target_share,
        grazing_share: args.grazing_share,
    };
    let start = Instant::now();
    let (refined, what) = refine(&model, material.as_ref(), &cfg, args.seed, &Bars::default())?;
    writeln!(
        out,
        "validation mean ln(1 + RV): {:.5} -> {:.5} ({}), {:.1} s",
        what.loss_before,
        what.loss_after,
        if what.kept { "kept" } else { "not kept" },
        start.elapsed().as_secs_f64()
    )
    .map_err(CommandError::Output)?;
    write_file(&args.out, &refined.blob(Precision::F32)?)?;
    write_file(&f16_path(&args.out), &refined.blob(Precision::F16)?)
}
