//! The exactness sweep of a model, f32 and f16 (`diffbsdf::internals::exactness`): every
//! valid sample's `pdf()` against the PDF `sample` returned, on normal to grazing `wi` and
//! `u` in strips at 0 and 1. What `fit` checks before it ships a step count and what
//! `eval` reports; the shipped-model tests run the same sweep with their own seeds and the
//! same allowance. A model close to the allowance (`Sweep::worst_over_rounding` near it)
//! may pass one sweep and fail another: the quick iridescent disk model at N = 4 passed
//! the fit's 10^6 samples and a 10^6-sample test sweep found one sample at 1.19e-4
//! relative, just past it.

use crate::error::TrainError;
use crate::export::ModelExt;
use diffbsdf::internals::exactness::{self, Broken, Failure, Outcome};
use diffbsdf::{AnyModel, Precision};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;
use serde::Serialize;

/// Valid samples per model and step count that `fit` and `eval` check by default, split
/// evenly between the f32 model and its f16 rounding.
pub const DEFAULT_SAMPLES: usize = 1_000_000;

/// The rounding allowance of the sweep: the kernel's promise, as in the tests.
const SPAN: f32 = diffbsdf::spec::PDF_ROUNDING_SPAN;
/// The plain tolerance (relative) the shipped models are held to.
const TOL: f32 = diffbsdf::spec::PDF_CONSISTENCY_TOL;

/// What the sweep of one precision found.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Sweep {
    /// Valid samples checked.
    pub valid: usize,
    /// Valid samples with `pdf() == 0`.
    pub zero_pdf: usize,
    /// Valid samples whose `pdf()` disagrees beyond what f32 rounding allows.
    pub inexact: usize,
    /// Valid samples whose trajectory has a step with determinant <= 0.
    pub folded: usize,
    /// Samples where `sample` and `sample_direction` disagree, or the sampled PDF is bad.
    pub other: usize,
    /// Exact samples beyond the plain tolerance (`spec::PDF_CONSISTENCY_TOL`), within
    /// the rounding allowance.
    pub past_plain_tol: usize,
    /// Largest relative difference over the exact samples.
    pub worst_rel: f32,
    /// Largest ratio of a difference past the plain tolerance to the density's change
    /// over one f32 rounding (what the span bounds).
    pub worst_over_rounding: f32,
    /// Smallest step determinant over the valid samples.
    pub min_det: f32,
    /// The first failure met, for the message.
    #[serde(skip)]
    pub first_failure: Option<Broken>,
}

impl Sweep {
    /// Samples that break the contract.
    pub fn failures(&self) -> usize {
        self.zero_pdf + self.inexact + self.folded + self.other
    }

    fn add(&mut self, o: Outcome) {
        match o {
            Outcome::Invalid => {}
            Outcome::Exact {
                rel,
                over_rounding,
                min_det,
            } => {
                self.valid += 1;
                self.worst_rel = self.worst_rel.max(rel);
                self.worst_over_rounding = self.worst_over_rounding.max(over_rounding);
                self.min_det = self.min_det.min(min_det);
                if !exactness::within_plain_tolerance(rel) {
                    self.past_plain_tol += 1;
                }
            }
            Outcome::Broken(b) => {
                self.valid += 1;
                match b.failure {
                    Failure::ZeroPdf => self.zero_pdf += 1,
                    Failure::Inexact => self.inexact += 1,
                    Failure::Folded => self.folded += 1,
                    Failure::PathsDisagree | Failure::BadPdf => self.other += 1,
                }
                if b.min_det.is_finite() {
                    self.min_det = self.min_det.min(b.min_det);
                }
                self.first_failure.get_or_insert(b);
            }
        }
    }

    fn merge(mut self, o: Sweep) -> Sweep {
        self.valid += o.valid;
        self.zero_pdf += o.zero_pdf;
        self.inexact += o.inexact;
        self.folded += o.folded;
        self.other += o.other;
        self.past_plain_tol += o.past_plain_tol;
        self.worst_rel = self.worst_rel.max(o.worst_rel);
        self.worst_over_rounding = self.worst_over_rounding.max(o.worst_over_rounding);
        self.min_det = self.min_det.min(o.min_det);
        self.first_failure = self.first_failure.or(o.first_failure);
        self
    }

    fn empty() -> Sweep {
        Sweep {
            min_det: f32::INFINITY,
            ..Default::default()
        }
    }
}

/// The sweep of the f32 model and of its f16 rounding.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Exactness {
    /// Euler steps checked (the model's default).
    pub steps: u16,
    /// The f32 model.
    pub f32: Sweep,
    /// The same model read back from its f16 blob.
    pub f16: Sweep,
}

impl Exactness {
    /// Whether every valid sample of both precisions keeps the contract.
    pub fn passes(&self) -> bool {
        self.f32.failures() == 0 && self.f16.failures() == 0
    }

    /// One line for the fit's and eval's text output.
    pub fn summary(&self) -> String {
        let one = |s: &Sweep| {
            format!(
                "{} valid, pdf() = 0 on {}, inexact {}, folded {}, other {}; worst rel {:.1e} (past {TOL:e} within rounding: {}, at most {:.1} x the rounding change of {SPAN} allowed), min det {:.3}",
                s.valid, s.zero_pdf, s.inexact, s.folded, s.other, s.worst_rel, s.past_plain_tol, s.worst_over_rounding, s.min_det
            )
        };
        let past = self.f32.past_plain_tol + self.f16.past_plain_tol;
        let verdict = match (self.passes(), past) {
            (false, _) => "NOT EXACT".to_string(),
            (true, 0) => "exact".to_string(),
            // Accepted (`fit` ships it), but short of the shipped models' bar of none past
            // the plain tolerance (models/README.md, "Exactness of the inverse").
            (true, n) => format!("exact within f32 rounding ({n} past {TOL:e})"),
        };
        let mut text = format!(
            "exactness at N={} -> {verdict}\n  f32: {}\n  f16: {}\n",
            self.steps,
            one(&self.f32),
            one(&self.f16)
        );
        for (p, s) in [("f32", &self.f32), ("f16", &self.f16)] {
            if let Some(b) = s.first_failure {
                text += &format!(
                    "  first {p} failure: {:?} at wi {:?} u {:?}: sampled {:e}, pdf() {:e}, min det {:e}\n",
                    b.failure, b.wi, b.u, b.sampled, b.back, b.min_det
                );
            }
        }
        text
    }
}

/// About `valid` valid samples of `model` at its default steps, spread evenly over the
/// sweep's incident angles, each angle on its own stream of `seed`.
pub fn sweep(model: &AnyModel, valid: usize, seed: u64) -> Sweep {
    let (thetas, n) = exactness::thetas(model);
    let per_theta = valid.div_ceil(n.max(1));
    // Chunks of a few thousand samples, so that both cores stay busy on every angle.
    const CHUNK: usize = 4096;
    let chunks = per_theta.div_ceil(CHUNK);
    let jobs: Vec<(usize, usize)> = (0..n)
        .flat_map(|t| (0..chunks).map(move |c| (t, c)))
        .collect();
    let steps = model.default_steps() as usize;
    jobs.par_iter()
        .map(|&(t, c)| {
            let stream = seed
                .wrapping_mul(1_000_003)
                .wrapping_add((t * chunks + c) as u64);
            let mut rng = Pcg64::seed_from_u64(stream);
            let mut points = vec![[0.0f32; 2]; steps + 1];
            let mut s = Sweep::empty();
            let want = CHUNK.min(per_theta - c * CHUNK);
            let mut k = 0;
            // At most 4 draws per wanted valid sample (models without support somewhere).
            while s.valid < want && k < 4 * want {
                let phi = std::f32::consts::TAU * rng.gen::<f32>();
                let wi = exactness::incident(thetas[t], phi);
                let u = exactness::sweep_u(k, rng.gen());
                k += 1;
                s.add(exactness::check(model, wi, u, &mut points, SPAN));
            }
            s
        })
        .reduce(Sweep::empty, Sweep::merge)
}

/// The sweep of `model` and of its f16 blob read back, `samples` valid samples in all.
pub fn check(model: &AnyModel, samples: usize, seed: u64) -> Result<Exactness, TrainError> {
    let f16 = AnyModel::from_blob(&model.blob(Precision::F16)?)?;
    Ok(Exactness {
        steps: model.def().default_steps,
        f32: sweep(model, samples / 2, seed),
        f16: sweep(&f16, samples - samples / 2, seed ^ 0x5eed),
    })
}
