//! `diffbsdf eval m.dbsdf <material-spec>`: the quality report of a blob against a
//! material, side by side with the material's own sampler and cosine sampling.

use super::fit::{print_json, CommandError};
use clap::Args;
use diffbsdf::AnyModel;
use diffbsdf_materials::parse_spec;
use diffbsdf_train::metrics::{evaluate, table, EvalConfig};
use diffbsdf_train::ModelExt;
use std::path::PathBuf;

/// Arguments of `diffbsdf eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// The model blob.
    pub blob: PathBuf,
    /// Material spec it was trained for.
    pub spec: String,
    /// Samples per wi and sampler.
    #[arg(long, default_value_t = 1 << 16)]
    pub samples: usize,
    /// Skip the KL quadrature.
    #[arg(long)]
    pub no_kl: bool,
    /// Seed of the evaluation's random numbers.
    #[arg(long, default_value_t = 7)]
    pub seed: u64,
    /// Euler steps (default: the blob's). The PDF stays exact for any count.
    #[arg(long)]
    pub steps: Option<u16>,
    /// Valid samples of the exactness sweep (`pdf()` against the sampled PDF, f32 and
    /// f16 together, normal to grazing wi, u at the edges of [0, 1]); 0 skips it.
    #[arg(long, default_value_t = diffbsdf_train::metrics::exactness::DEFAULT_SAMPLES)]
    pub exact_samples: usize,
    /// Incidences off the grid (theta_i in equal strata of [0, 89.5] deg, each jittered,
    /// phi_i uniform; `--samples` draws each): the learned model's and the material's
    /// sampler's relative variance pooled over them; 0 skips them.
    #[arg(long, default_value_t = 0)]
    pub off_grid: usize,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs `diffbsdf eval`.
pub fn run(args: EvalArgs, out: &mut dyn std::io::Write) -> Result<(), CommandError> {
    let material = parse_spec(&args.spec).map_err(CommandError::Spec)?;
    let bytes = std::fs::read(&args.blob).map_err(|e| CommandError::Io(args.blob.clone(), e))?;
    let mut model = AnyModel::from_blob(&bytes)?;
    if let Some(n) = args.steps {
        model = model.with_steps(n);
    }
    let mut cfg = EvalConfig {
        samples: args.samples,
        seed: args.seed,
        exact_samples: args.exact_samples,
        off_grid_incidences: args.off_grid,
        ..EvalConfig::default()
    };
    if args.no_kl {
        cfg.kl = None;
    }
    let report = evaluate(&model, material.as_ref(), &cfg);
    if args.json {
        return print_json(&report, out);
    }
    write!(out, "{}", table::render(&report)).map_err(CommandError::Output)
}
