//! The sweep itself: each shipped model at every step count and weight precision, its
//! accuracy on the fixed `wi` grid and its time per call next to the material's own
//! sampler, timed in the same run on one thread while nothing else runs.

use super::catalog::ShippedModel;
use diffbsdf::AnyModel;
use diffbsdf_materials::{from_spherical, parse_spec, Material, SpecError};
use diffbsdf_train::metrics::cost::{self, Cost};
use diffbsdf_train::metrics::exactness;
use diffbsdf_train::metrics::kl::KlGrid;
use diffbsdf_train::metrics::{evaluate, EvalConfig, Report};
use diffbsdf_train::{ModelExt, TrainError};
use serde::{Deserialize, Serialize};
use std::fmt;

/// How much work the sweep does.
#[derive(Clone, Debug)]
pub struct SweepConfig {
    /// Euler step counts.
    pub steps: Vec<u16>,
    /// Whether to include the f16 blobs.
    pub f16: bool,
    /// Samples per `wi` and sampler for RV and fireflies.
    pub samples: usize,
    /// Samples per `wi` for forward/inverse PDF consistency.
    pub consistency_samples: usize,
    /// Valid samples of the exactness sweep per point (`metrics::exactness`, the check
    /// `fit` runs with 10^6 before it ships a step count).
    pub exact_samples: usize,
    /// KL quadrature; `None` skips KL.
    pub kl: Option<KlGrid>,
    /// Calls timed per entry point.
    pub timing_calls: usize,
    /// Seed of the evaluation.
    pub seed: u64,
}

impl Default for SweepConfig {
    fn default() -> Self {
        SweepConfig {
            steps: vec![1, 2, 4, 8, 16, 32],
            f16: true,
            samples: 1 << 14,
            consistency_samples: 256,
            exact_samples: 20_000,
            kl: Some(KlGrid { theta: 32, phi: 64 }),
            timing_calls: 20_000,
            seed: 7,
        }
    }
}

/// One model at one step count and precision.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Point {
    /// Model name (file stem).
    pub model: String,
    /// Material spec.
    pub material: String,
    /// `disk` or `sphere`.
    pub domain: String,
    /// `f32` or `f16` weights.
    pub precision: String,
    /// Euler steps of this point.
    pub steps: u16,
    /// The blob's default steps.
    pub shipped_steps: u16,
    /// Times per call (ns) and their ratios to the material's sampler.
    pub cost: Cost,
    /// `direction_ns / material_ns`.
    pub ratio_direction: f64,
    /// `pdf_ns / material_ns`.
    pub ratio_pdf: f64,
    /// Mean RV over the grid.
    pub rv_mean: f64,
    /// Worst RV over the grid.
    pub rv_worst: f64,
    /// Mean firefly ratio.
    pub firefly_mean: f64,
    /// Worst firefly ratio.
    pub firefly_worst: f64,
    /// Mean KL on the phi = 0 column.
    pub kl_mean: Option<f64>,
    /// The material sampler's mean RV (same `wi`, same run).
    pub material_rv_mean: f64,
    /// The material sampler's mean KL.
    pub material_kl_mean: Option<f64>,
    /// Mean fraction of valid samples.
    pub valid_mean: f64,
    /// 99th percentile of the forward/inverse relative PDF difference.
    pub consistency_p99: f64,
    /// Largest forward/inverse relative PDF difference.
    pub consistency_max: f64,
    /// Fraction of trajectories with a step determinant <= 0.
    pub non_positive_det: f64,
    /// Valid samples of the exactness sweep (0 in reports measured before it existed).
    #[serde(default)]
    pub exact_checked: usize,
    /// Of them, samples that break the contract (folded step, `pdf()` 0 or inexact).
    #[serde(default)]
    pub exact_failures: usize,
}

/// A measured sweep as `tradeoff.json` keeps it: how it was measured, and its points.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SweepRecord {
    /// The command that measured it.
    pub command: String,
    /// Samples per `wi` and sampler.
    pub samples: usize,
    /// Calls timed per entry point.
    pub timing_calls: usize,
    /// Interleaved rounds those calls were split into, the median round reported (0 in a
    /// record written before the rounds: one pass).
    #[serde(default)]
    pub timing_rounds: usize,
    /// Logical cores of the machine.
    pub cores: usize,
    /// The points.
    pub points: Vec<Point>,
}

/// Why the sweep failed.
#[derive(Debug)]
pub enum SweepError {
    /// A model's material spec did not parse.
    Spec(String, SpecError),
    /// A blob did not load.
    Blob(String, TrainError),
    /// An image or plot could not be written.
    Image(String, String),
}

impl fmt::Display for SweepError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SweepError::Spec(m, e) => write!(f, "{m}: {e}"),
            SweepError::Blob(m, e) => write!(f, "{m}: {e}"),
            SweepError::Image(p, e) => write!(f, "{p}: {e}"),
        }
    }
}

impl std::error::Error for SweepError {}

/// The number of points [`sweep`] measures.
pub fn point_count(models: &[ShippedModel], cfg: &SweepConfig) -> usize {
    let blobs: usize = models
        .iter()
        .map(|m| 1 + usize::from(cfg.f16 && m.f16_blob.is_some()))
        .sum();
    blobs * cfg.steps.len()
}

/// Measures one model at one step count.
pub fn measure_point(
    name: &str,
    material: &dyn Material,
    model: &AnyModel,
    precision: &'static str,
    cfg: &SweepConfig,
) -> Point {
    let eval = EvalConfig {
        samples: cfg.samples,
        consistency_samples: cfg.consistency_samples,
        exact_samples: 0,
        kl: cfg.kl,
        timing_calls: 0,
        off_grid_incidences: 0,
        seed: cfg.seed,
    };
    let r: Report = evaluate(model, material, &eval);
    let sweep = exactness::sweep(model, cfg.exact_samples, cfg.seed);
    // Timed after the parallel evaluation has finished: one thread, nothing beside it.
    let wi = from_spherical(45f64.to_radians(), 0.3);
    let c = cost::measure(model, material, wi, cfg.timing_calls);
    let valid_mean =
        r.rows.iter().map(|w| w.learned.stats.valid).sum::<f64>() / r.rows.len().max(1) as f64;
    Point {
        model: name.to_owned(),
        material: r.material.clone(),
        domain: r.domain.to_owned(),
        precision: precision.to_owned(),
        steps: model.def().default_steps,
        shipped_steps: 0,
        ratio_direction: c.learned_direction_ns / c.material_sample_ns.max(1e-9),
        ratio_pdf: c.learned_pdf_ns / c.material_sample_ns.max(1e-9),
        cost: c,
        rv_mean: r.learned.rv_mean,
        rv_worst: r.learned.rv_worst,
        firefly_mean: r.learned.firefly_mean,
        firefly_worst: r.learned.firefly_worst,
        kl_mean: r.learned.kl_mean,
        material_rv_mean: r.material_sampler.rv_mean,
        material_kl_mean: r.material_sampler.kl_mean,
        valid_mean,
        consistency_p99: r.consistency.p99,
        consistency_max: r.consistency.max,
        non_positive_det: r.consistency.non_positive_det,
        exact_checked: sweep.valid,
        exact_failures: sweep.failures(),
    }
}

/// Every model x precision x step count; `done` is called after each point.
pub fn sweep(
    models: &[ShippedModel],
    cfg: &SweepConfig,
    done: &dyn Fn(&Point),
) -> Result<Vec<Point>, SweepError> {
    let mut out = Vec::with_capacity(point_count(models, cfg));
    for m in models {
        let material = parse_spec(&m.spec).map_err(|e| SweepError::Spec(m.name.clone(), e))?;
        let mut blobs = vec![("f32", &m.f32_blob)];
        if let (true, Some(b)) = (cfg.f16, &m.f16_blob) {
            blobs.push(("f16", b));
        }
        for (precision, blob) in blobs {
            let model = AnyModel::from_blob(blob)
                .map_err(|e| SweepError::Blob(m.name.clone(), e.into()))?;
            let shipped = model.def().default_steps;
            for &n in &cfg.steps {
                let at = model.with_steps(n.max(1));
                let mut p = measure_point(&m.name, material.as_ref(), &at, precision, cfg);
                p.shipped_steps = shipped;
                done(&p);
                out.push(p);
            }
        }
    }
    Ok(out)
}
