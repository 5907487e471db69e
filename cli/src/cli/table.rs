//! `diffbsdf table m.dbsdf <material-spec> --out t.dbsdf`: fits a latent table to a fitted
//! model's flow (`diffbsdf_train::latent_table`, docs/math.md §6.5), as `fit` does last;
//! writes the f32 blob at `--out` and the f16 beside it.

use super::fit::{f16_path, write_file, CommandError};
use super::share::parse_share;
use clap::Args;
use diffbsdf::{AnyModel, Precision};
use diffbsdf_materials::parse_spec;
use diffbsdf_train::latent_table::{fit_latent_table, TableConfig};
use diffbsdf_train::ModelExt;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `diffbsdf table`.
#[derive(Debug, Args)]
pub struct TableArgs {
    /// The fitted model blob (standard coordinates: the half-vector chart's default).
    pub blob: PathBuf,
    /// Material spec it was fitted to.
    pub spec: String,
    /// Output blob (f32); the f16 blob is written beside it.
    #[arg(long)]
    pub out: PathBuf,
    /// Draws per incidence slice.
    #[arg(long, default_value_t = TableConfig::DEFAULT.draws_per_slice)]
    pub draws: usize,
    /// Share of the uniform density in every slice.
    #[arg(long, default_value_t = TableConfig::DEFAULT.floor as f32, value_parser = parse_share)]
    pub floor: f32,
    /// Multiplicative updates of the node values towards the least variance after their
    /// root-mean-square start (docs/math.md, (78); 0: the start alone).
    #[arg(long, default_value_t = TableConfig::DEFAULT.iterations)]
    pub iterations: usize,
    /// Joint updates of every slice after those, against the two slices the kernel mixes
    /// at each incidence (docs/math.md, (80); 0: each slice on its own).
    #[arg(long, default_value_t = TableConfig::DEFAULT.joint_iterations)]
    pub joint_iterations: usize,
    /// Keep the grid's cells evenly spaced (no axis warps, docs/math.md, (81)).
    #[arg(long)]
    pub no_axes: bool,
    /// The 32 slices evenly spaced in `1 - sqrt(wi.z)` (docs/math.md, (75)) instead of the
    /// 40 of the blended layout ((82)): the tables written before it (with `--no-axes`, the
    /// even-cell ones).
    #[arg(long)]
    pub even_slices: bool,
    /// Seed of the draws.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// Runs `diffbsdf table`.
pub fn run(args: TableArgs, out: &mut dyn std::io::Write) -> Result<(), CommandError> {
    let material = parse_spec(&args.spec).map_err(CommandError::Spec)?;
    let bytes = std::fs::read(&args.blob).map_err(|e| CommandError::Io(args.blob.clone(), e))?;
    let model = AnyModel::from_blob(&bytes)?;
    let cfg = TableConfig {
        draws_per_slice: args.draws,
        floor: f64::from(args.floor),
        iterations: args.iterations,
        joint_iterations: args.joint_iterations,
        axes: !args.no_axes,
        blended_slices: !args.even_slices,
        ..TableConfig::DEFAULT
    };
    let start = Instant::now();
    let (tabled, fit) = fit_latent_table(&model, material.as_ref(), &cfg, args.seed)?;
    writeln!(
        out,
        "latent table fitted, {:.1} s; mean relative variance on its draws {:.5} (flow alone) -> {:.5}; axis warps' share {}",
        start.elapsed().as_secs_f64(),
        fit.rv_flow,
        fit.rv_table,
        fit.axis_share
    )
    .map_err(CommandError::Output)?;
    write_file(&args.out, &tabled.blob(Precision::F32)?)?;
    write_file(&f16_path(&args.out), &tabled.blob(Precision::F16)?)
}
