//! The quality report of a learned model against a material, side by side with the
//! material's own sampler and cosine sampling on the same `wi` grid.

use super::consistency::{self, Consistency, ConsistencySamples};
use super::cost::{self, Cost};
use super::exactness::{self, Exactness};
use super::grid::wi_grid;
use super::kl::{kl_divergence, KlGrid};
use super::off_grid::{self, OffGrid};
use super::sampler::{draw, learned_weights, weight, SamplerKind};
use super::stats::WeightStats;
use diffbsdf::{AnyModel, ModelDef, Precision};
use diffbsdf_materials::{from_spherical, DVec3, Material};
use rand::SeedableRng;
use rand_pcg::Pcg64;
use rayon::prelude::*;
use serde::Serialize;

/// How much work the evaluation does.
#[derive(Clone, Copy, Debug)]
pub struct EvalConfig {
    /// Samples per `wi` and sampler (>= 10^4 for the 99.99th percentile to mean much).
    pub samples: usize,
    /// Samples per `wi` for PDF consistency and determinants.
    pub consistency_samples: usize,
    /// Valid samples of the exactness sweep (f32 and f16 together, `exactness::check`);
    /// 0 skips it.
    pub exact_samples: usize,
    /// KL quadrature; `None` skips KL.
    pub kl: Option<KlGrid>,
    /// Calls timed for the cost figures; 0 skips timing.
    pub timing_calls: usize,
    /// Incidences off the grid (`off_grid`, `samples` draws each, per hemisphere
    /// measured); 0 skips them.
    pub off_grid_incidences: usize,
    /// Seed.
    pub seed: u64,
}

impl Default for EvalConfig {
    fn default() -> Self {
        EvalConfig {
            samples: 1 << 16,
            consistency_samples: 2048,
            exact_samples: super::exactness::DEFAULT_SAMPLES,
            kl: Some(KlGrid {
                theta: 64,
                phi: 128,
            }),
            timing_calls: 100_000,
            off_grid_incidences: 0,
            seed: 7,
        }
    }
}

/// One sampler at one `wi`.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SamplerRow {
    /// Weight statistics.
    #[serde(flatten)]
    pub stats: WeightStats,
    /// KL divergence from the target (on the phi = 0 column of the grid).
    pub kl: Option<f64>,
}

/// All samplers at one `wi`.
#[derive(Clone, Debug, Serialize)]
pub struct WiRow {
    /// Polar angle of `wi` in degrees.
    pub theta_deg: f64,
    /// Azimuth of `wi` in degrees.
    pub phi_deg: f64,
    /// The learned model.
    pub learned: SamplerRow,
    /// The material's own sampler.
    pub material: SamplerRow,
    /// Cosine-weighted hemisphere.
    pub cosine: SamplerRow,
}

/// Mean and worst over the grid for one sampler.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SamplerSummary {
    /// Mean RV over the grid.
    pub rv_mean: f64,
    /// Worst RV.
    pub rv_worst: f64,
    /// `theta_i` of the worst RV, degrees.
    pub rv_worst_theta_deg: f64,
    /// Mean firefly ratio.
    pub firefly_mean: f64,
    /// Worst firefly ratio.
    pub firefly_worst: f64,
    /// Mean KL over the `wi` where it was computed.
    pub kl_mean: Option<f64>,
}

/// The full report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Material spec.
    pub material: String,
    /// Flow domain of the model.
    pub domain: &'static str,
    /// Euler steps.
    pub steps: u16,
    /// f32 blob size in bytes.
    pub blob_bytes_f32: usize,
    /// f16 blob size in bytes.
    pub blob_bytes_f16: usize,
    /// Samples per `wi`.
    pub samples_per_wi: usize,
    /// Learned sampler summary.
    pub learned: SamplerSummary,
    /// Material's sampler summary.
    pub material_sampler: SamplerSummary,
    /// Cosine sampling summary.
    pub cosine: SamplerSummary,
    /// `learned.rv_mean / material_sampler.rv_mean`.
    pub rv_ratio_to_material: f64,
    /// PDF consistency and determinants of the learned model.
    pub consistency: Consistency,
    /// The exactness sweep (f32 and f16), if run.
    pub exactness: Option<Exactness>,
    /// Time per sample, if measured.
    pub cost: Option<Cost>,
    /// The relative variance pooled over incidences off the grid, if measured.
    pub off_grid: Option<OffGrid>,
    /// Per-`wi` rows.
    pub rows: Vec<WiRow>,
}

/// What one `wi` of the grid is measured with.
struct At<'a> {
    material: &'a dyn Material,
    model: &'a AnyModel,
    wi: DVec3,
    both: bool,
    cfg: &'a EvalConfig,
}

impl At<'_> {
    fn row(&self, kind: SamplerKind, with_kl: bool, seed: u64) -> SamplerRow {
        let (material, model, wi) = (self.material, self.model, self.wi);
        let mut rng = Pcg64::seed_from_u64(seed);
        let mut w: Vec<f64> = if kind == SamplerKind::Learned {
            learned_weights(material, model, wi, self.cfg.samples, &mut rng)
        } else {
            (0..self.cfg.samples)
                .map(|_| {
                    weight(
                        material,
                        wi,
                        draw(kind, material, Some(model), wi, &mut rng),
                    )
                })
                .collect()
        };
        let kl = match (self.cfg.kl, with_kl) {
            (Some(g), true) => Some(kl_divergence(kind, material, Some(model), wi, self.both, g)),
            _ => None,
        };
        SamplerRow {
            stats: WeightStats::from_weights(&mut w),
            kl,
        }
    }
}

fn summarize(rows: &[WiRow], pick: impl Fn(&WiRow) -> &SamplerRow) -> SamplerSummary {
    let n = rows.len().max(1) as f64;
    let mut worst = (f64::NEG_INFINITY, 0.0);
    let mut ff_worst = 0.0f64;
    let (mut rv_sum, mut ff_sum, mut kl_sum, mut kl_n) = (0.0, 0.0, 0.0, 0);
    for r in rows {
        let s = pick(r);
        rv_sum += s.stats.rv;
        ff_sum += s.stats.firefly;
        ff_worst = ff_worst.max(s.stats.firefly);
        if s.stats.rv > worst.0 {
            worst = (s.stats.rv, r.theta_deg);
        }
        if let Some(k) = s.kl {
            kl_sum += k;
            kl_n += 1;
        }
    }
    SamplerSummary {
        rv_mean: rv_sum / n,
        rv_worst: worst.0,
        rv_worst_theta_deg: worst.1,
        firefly_mean: ff_sum / n,
        firefly_worst: ff_worst,
        kl_mean: (kl_n > 0).then(|| kl_sum / kl_n as f64),
    }
}

/// Measures `model` against `material` on the fixed grid.
pub fn evaluate(model: &AnyModel, material: &dyn Material, cfg: &EvalConfig) -> Report {
    let domain = model.def().domain;
    let both = domain.is_spherical() && material.is_transmissive();
    let grid = wi_grid(both);
    let per_wi: Vec<(WiRow, ConsistencySamples)> = grid
        .par_iter()
        .enumerate()
        .map(|(k, g)| {
            let seed = cfg.seed.wrapping_mul(1_000_003).wrapping_add(k as u64);
            let with_kl = g.phi_deg == 0.0;
            let at = At {
                material,
                model,
                wi: g.wi,
                both,
                cfg,
            };
            let r = |kind, s| at.row(kind, with_kl, s);
            let wi_row = WiRow {
                theta_deg: g.theta_deg,
                phi_deg: g.phi_deg,
                learned: r(SamplerKind::Learned, seed),
                material: r(SamplerKind::Material, seed ^ 1),
                cosine: r(SamplerKind::Cosine, seed ^ 2),
            };
            let mut rng = Pcg64::seed_from_u64(seed ^ 3);
            let c = consistency::measure(model, g.wi, cfg.consistency_samples, &mut rng);
            (wi_row, c)
        })
        .collect();
    let mut all = ConsistencySamples {
        min_det: f64::INFINITY,
        ..Default::default()
    };
    let mut rows = Vec::with_capacity(per_wi.len());
    for (r, c) in per_wi {
        rows.push(r);
        all.merge(c);
    }
    let learned = summarize(&rows, |r| &r.learned);
    let material_sampler = summarize(&rows, |r| &r.material);
    let cosine = summarize(&rows, |r| &r.cosine);
    let def = *model.def();
    let bytes = |precision| diffbsdf::internals::blob::blob_len(&ModelDef { precision, ..def });
    let cost = (cfg.timing_calls > 0).then(|| {
        let wi = from_spherical(45f64.to_radians(), 0.3);
        cost::measure(model, material, wi, cfg.timing_calls)
    });
    Report {
        material: material.spec(),
        domain: domain.name(),
        steps: def.default_steps,
        blob_bytes_f32: bytes(Precision::F32),
        blob_bytes_f16: bytes(Precision::F16),
        samples_per_wi: cfg.samples,
        rv_ratio_to_material: learned.rv_mean / material_sampler.rv_mean,
        learned,
        material_sampler,
        cosine,
        consistency: all.summary(),
        exactness: (cfg.exact_samples > 0)
            .then(|| exactness::check(model, cfg.exact_samples, cfg.seed).ok())
            .flatten(),
        cost,
        off_grid: (cfg.off_grid_incidences > 0).then(|| {
            let n = cfg.off_grid_incidences;
            off_grid::measure(model, material, n, cfg.samples, both, cfg.seed)
        }),
        rows,
    }
}
