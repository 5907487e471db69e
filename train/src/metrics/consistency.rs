//! Forward/inverse PDF consistency `|pdf(wi, wo) - pdf_sampled| / pdf_sampled` over sampled
//! directions, and the smallest step determinant `det(I + h dv/dx)` along trajectories.

use super::sampler::to_glam;
use diffbsdf::glam::Vec2;
use diffbsdf::internals::Diagnostics;
use diffbsdf::AnyModel;
use diffbsdf_materials::DVec3;
use rand::Rng;
use rand_pcg::Pcg64;
use serde::Serialize;

/// Raw measurements at one or more `wi`.
#[derive(Clone, Debug, Default)]
pub struct ConsistencySamples {
    /// Relative errors of valid samples.
    pub rel: Vec<f64>,
    /// Smallest determinant seen.
    pub min_det: f64,
    /// Trajectories with a determinant <= 0 somewhere.
    pub non_positive: usize,
    /// Trajectories measured.
    pub trajectories: usize,
    /// Valid samples whose `pdf()` is 0 or disagrees beyond what f32 rounding allows
    /// (`Diagnostics::pdf_consistent`, the kernel's own exactness check).
    pub inconsistent: usize,
}

impl ConsistencySamples {
    /// Appends another set.
    pub fn merge(&mut self, o: ConsistencySamples) {
        self.rel.extend(o.rel);
        self.min_det = self.min_det.min(o.min_det);
        self.non_positive += o.non_positive;
        self.trajectories += o.trajectories;
        self.inconsistent += o.inconsistent;
    }
}

/// Summary over the grid.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Consistency {
    /// Median relative PDF error.
    pub median: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Largest.
    pub max: f64,
    /// Fraction of samples with relative error above 1e-3.
    pub above_1e3: f64,
    /// Smallest step determinant over all trajectories.
    pub min_det: f64,
    /// Fraction of trajectories with a non-positive determinant.
    pub non_positive_det: f64,
    /// Valid samples whose `pdf()` is 0 or disagrees beyond f32 rounding (must be 0).
    pub inconsistent: usize,
}

/// `n` samples at `wi`.
pub fn measure(model: &AnyModel, wi: DVec3, n: usize, rng: &mut Pcg64) -> ConsistencySamples {
    let wi = to_glam(wi);
    let mut out = ConsistencySamples {
        min_det: f64::INFINITY,
        ..Default::default()
    };
    let steps = model.def().default_steps as u32;
    let mut points = vec![[0.0f32; 2]; steps as usize + 1];
    for _ in 0..n {
        let u = Vec2::new(rng.gen::<f32>(), rng.gen::<f32>());
        if let Some(d) = model.trajectory(wi, u, steps, &mut points) {
            out.trajectories += 1;
            out.min_det = out.min_det.min(d as f64);
            if !(d > 0.0) {
                out.non_positive += 1;
            }
        }
        if let Some(s) = model.sample(wi, u) {
            let back = model.pdf(wi, s.wo);
            let (q, p) = (back as f64, s.pdf as f64);
            out.rel.push((q - p).abs() / p);
            if !model.pdf_consistent(wi, s.wo, s.pdf, back, points[0]) {
                out.inconsistent += 1;
            }
        }
    }
    out
}

impl ConsistencySamples {
    /// The summary.
    pub fn summary(mut self) -> Consistency {
        self.rel.sort_by(|a, b| a.total_cmp(b));
        let n = self.rel.len();
        let at = |q: f64| {
            if n == 0 {
                0.0
            } else {
                self.rel[((n as f64 * q) as usize).min(n - 1)]
            }
        };
        Consistency {
            median: at(0.5),
            p99: at(0.99),
            max: self.rel.last().copied().unwrap_or(0.0),
            above_1e3: self.rel.iter().filter(|r| **r > 1e-3).count() as f64 / n.max(1) as f64,
            min_det: self.min_det,
            non_positive_det: self.non_positive as f64 / self.trajectories.max(1) as f64,
            inconsistent: self.inconsistent,
        }
    }
}
