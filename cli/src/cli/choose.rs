//! Choosing the cheapest sufficient model (`fit --domain auto`, `fit --target-rv R`):
//! the disk for reflective materials where it suffices, the sphere only where the material
//! transmits or the disk model falls short (its grazing firefly ratio above the limit, or
//! the RV target missed at every step count); and the fewest Euler steps that reach the
//! target with every checked sample exact (`metrics::exactness`: `pdf()` equals the
//! sampled PDF, f32 and f16, normal to grazing `wi`, `u` at the edges of [0, 1]).

use diffbsdf::AnyModel;
use diffbsdf_materials::Material;
use diffbsdf_train::metrics::exactness::{self, Exactness};
use diffbsdf_train::metrics::{evaluate, EvalConfig, Report};
use diffbsdf_train::{ModelExt, TrainError};
use serde::Serialize;

/// Step counts tried, fewest first.
pub const STEP_LADDER: [u16; 6] = [1, 2, 4, 8, 16, 32];
/// `wi` at or beyond this polar angle (degrees) count as grazing.
pub const GRAZING_DEG: f64 = 85.0;
/// Seed of the exactness sweep of `fit` (the shipped-model tests use other seeds).
const EXACTNESS_SEED: u64 = 11;

/// What "sufficient" means.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Criteria {
    /// Mean RV to reach; `None`: keep the trained step count.
    pub target_rv: Option<f64>,
    /// Largest firefly ratio allowed at grazing `wi`.
    pub max_grazing_firefly: f64,
    /// Samples per `wi` of the quality checks.
    pub samples: usize,
    /// Valid samples of the exactness sweep (f32 and f16 together).
    pub exact_samples: usize,
}

impl Criteria {
    /// Whether anything beyond exactness is asked for (so the quality must be measured).
    fn measures_quality(&self) -> bool {
        self.target_rv.is_some() || self.max_grazing_firefly.is_finite()
    }
}

/// One model at one step count, as checked.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Candidate {
    /// `disk` or `sphere`.
    pub domain: &'static str,
    /// Euler steps.
    pub steps: u16,
    /// Mean RV over the grid (when measured).
    pub rv_mean: Option<f64>,
    /// Worst firefly ratio at grazing `wi` (when measured).
    pub grazing_firefly: Option<f64>,
    /// The exactness sweep.
    pub exactness: Exactness,
    /// Whether it meets the criteria.
    pub sufficient: bool,
}

impl Candidate {
    /// One line for the fit's text output.
    pub fn line(&self) -> String {
        let quality = match (self.rv_mean, self.grazing_firefly) {
            (Some(rv), Some(ff)) => format!("mean RV {rv:.4}, grazing firefly {ff:.1}, "),
            _ => String::new(),
        };
        let e = &self.exactness;
        format!(
            "checked {:<6} N={:<2}: {quality}exactness f32 {} / f16 {} failures of {} / {} -> {}",
            self.domain,
            self.steps,
            e.f32.failures(),
            e.f16.failures(),
            e.f32.valid,
            e.f16.valid,
            if self.sufficient {
                "sufficient"
            } else {
                "short"
            }
        )
    }
}

/// The worst firefly ratio over the grazing rows of a report.
fn grazing_firefly(r: &Report) -> f64 {
    r.rows
        .iter()
        .filter(|w| w.theta_deg >= GRAZING_DEG && w.theta_deg <= 90.0)
        .map(|w| w.learned.stats.firefly)
        .fold(0.0, f64::max)
}

/// Checks `model` at `steps` against the criteria.
pub fn check(
    model: &AnyModel,
    material: &dyn Material,
    steps: u16,
    c: &Criteria,
) -> Result<Candidate, TrainError> {
    let at = (*model).with_steps(steps);
    let exactness = exactness::check(&at, c.exact_samples, EXACTNESS_SEED)?;
    let quality = c.measures_quality().then(|| {
        let cfg = EvalConfig {
            samples: c.samples,
            consistency_samples: 0,
            exact_samples: 0,
            kl: None,
            timing_calls: 0,
            off_grid_incidences: 0,
            seed: 11,
        };
        let r = evaluate(&at, material, &cfg);
        (r.learned.rv_mean, grazing_firefly(&r))
    });
    let rv_ok = match (c.target_rv, quality) {
        (Some(t), Some((rv, _))) => rv <= t,
        _ => true,
    };
    let ff_ok = quality.is_none_or(|(_, ff)| ff <= c.max_grazing_firefly);
    Ok(Candidate {
        domain: domain_name(model),
        steps,
        rv_mean: quality.map(|q| q.0),
        grazing_firefly: quality.map(|q| q.1),
        exactness,
        sufficient: rv_ok && ff_ok && exactness.passes(),
    })
}

fn domain_name(model: &AnyModel) -> &'static str {
    model.def().domain.name()
}

/// The fewest of `from`, `2 from`, `4 from`, ... (up to the ladder's top) at which every
/// sample of the exactness sweep of `model` is exact; `None` if none is. A sharp lobe can
/// make a step fold, or the inverse lose a root, at the trained `N` (a measured material
/// at N = 8: min det -0.098 on 0.003 % of trajectories); more, smaller steps unfold it.
pub fn exact_steps(
    model: &AnyModel,
    material: &dyn Material,
    from: u16,
    exact_samples: usize,
) -> Result<(Option<u16>, Vec<Candidate>), TrainError> {
    let c = Criteria {
        target_rv: None,
        max_grazing_firefly: f64::INFINITY,
        samples: 0,
        exact_samples,
    };
    let top = STEP_LADDER[STEP_LADDER.len() - 1];
    let mut tried = Vec::new();
    let mut n = from.max(1);
    loop {
        let cand = check(model, material, n, &c)?;
        tried.push(cand);
        if cand.sufficient {
            return Ok((Some(n), tried));
        }
        if n >= top {
            return Ok((None, tried));
        }
        n = (n * 2).min(top);
    }
}

/// The fewest steps of `model` that are sufficient, with every candidate checked; without
/// a target the trained step count `N`, then `2N`, `4N`, ... while only exactness is short.
pub fn fewest_steps(
    model: &AnyModel,
    material: &dyn Material,
    c: &Criteria,
) -> Result<(Option<Candidate>, Vec<Candidate>), TrainError> {
    let trained = model.def().default_steps;
    let ladder: Vec<u16> = match c.target_rv {
        Some(_) => STEP_LADDER.to_vec(),
        None => core::iter::successors(Some(trained.max(1)), |&n| {
            (n < STEP_LADDER[STEP_LADDER.len() - 1])
                .then(|| (n * 2).min(STEP_LADDER[STEP_LADDER.len() - 1]))
        })
        .collect(),
    };
    let mut tried = Vec::new();
    for n in ladder {
        let cand = check(model, material, n, c)?;
        tried.push(cand);
        if cand.sufficient {
            return Ok((Some(cand), tried));
        }
        if c.target_rv.is_none() && cand.exactness.passes() {
            // Short on quality at the trained steps: more steps are not the remedy.
            break;
        }
    }
    Ok((None, tried))
}
