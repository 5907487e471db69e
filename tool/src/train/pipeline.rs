//! The whole fit: pairs -> base net (max-lik) -> teacher (flow matching) -> reflow pairs
//! -> student (flow matching on straight pairs) -> kernel model. Every random draw comes
//! from one PCG64 seeded by the caller, and every parallel reduction has a fixed order, so
//! the same config and seed give the same blob bytes.

use super::base_fit::{base_distributions, train_base, BaseConfig};
use super::dataset::{MaterialPairs, TrainingData, TrainingSet};
use super::error::TrainError;
use super::export::LearnedModel;
use super::flow_fit::{new_velocity_net, train_flow, Coupling, FlowConfig};
use super::progress::Progress;
use super::reflow::reflow_pairs;
use crate::material::Material;
use diffbsdf::Domain;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use serde::Serialize;
use std::time::Instant;

/// Everything that determines a fit (with the seed).
#[derive(Clone, Copy, Debug)]
pub struct FitConfig {
    /// Flow domain.
    pub domain: Domain,
    /// Euler steps of the student (the blob's default).
    pub steps: u16,
    /// Seed of every random draw.
    pub seed: u64,
    /// Training pairs drawn from the material.
    pub pairs: usize,
    /// Base net.
    pub base: BaseConfig,
    /// Teacher velocity net.
    pub teacher: FlowConfig,
    /// Reflow pairs.
    pub reflow_pairs: usize,
    /// RK4 steps of the teacher per reflow pair.
    pub reflow_steps: usize,
    /// Student velocity net (width and layers are the kernel's: 32 x 3 disk, 32 x 4 sphere).
    pub student: FlowConfig,
    /// Train the student only at its Euler times `k / steps`.
    pub student_euler_times: bool,
    /// Extra training pairs with grazing `wi`, as a fraction of `pairs`.
    pub grazing: f64,
    /// Train in the incident frame when the material is isotropic (the model then has
    /// `isotropic` set and its nets see `theta_i` only).
    pub use_isotropy: bool,
    /// Isotropic fits: fraction of training `wi` with `theta_i` uniform in angle, the rest
    /// uniform in solid angle (see `MaterialPairs`). Measured on the alpha = 0.3 dielectric
    /// (sphere, seed 0): 1.0 gives mean RV 0.151, worst 0.66 (89 deg); 0.5 gives 0.139,
    /// worst 0.33; all solid angle starves normal incidence (copper disk: RV 0.39 there).
    pub angle_fraction: f64,
}

impl FitConfig {
    /// The defaults for `domain`: the paper's student shapes, a 4x64 teacher, the
    /// student trained at its Euler times (measured: mean RV 0.33 -> 0.19 on rough copper).
    pub fn standard(domain: Domain, seed: u64) -> Self {
        let student_layers = match domain {
            Domain::Disk => 3,
            Domain::Sphere => 4,
        };
        FitConfig {
            domain,
            steps: match domain {
                Domain::Disk => 4,
                Domain::Sphere => 8,
            },
            seed,
            pairs: 200_000,
            base: BaseConfig::default(),
            teacher: FlowConfig {
                width: 64,
                layers: 4,
                iters: 12000,
                batch: 1024,
                lr: 2e-3,
                ema: 0.999,
                t_grid: 0,
            },
            reflow_pairs: 100_000,
            reflow_steps: 16,
            student: FlowConfig {
                width: 32,
                layers: student_layers,
                iters: 20000,
                batch: 1024,
                lr: 2e-3,
                ema: 0.999,
                t_grid: 0,
            },
            student_euler_times: true,
            grazing: 0.0,
            use_isotropy: true,
            angle_fraction: 0.5,
        }
    }

    /// A fit of a few seconds, for tests and smoke runs.
    pub fn tiny(domain: Domain, seed: u64) -> Self {
        let mut c = Self::standard(domain, seed);
        c.pairs = 8_000;
        c.base.iters = 200;
        c.base.batch = 512;
        c.teacher.width = 32;
        c.teacher.layers = 2;
        c.teacher.iters = 150;
        c.teacher.batch = 256;
        c.reflow_pairs = 4_000;
        c.reflow_steps = 4;
        c.student.iters = 150;
        c.student.batch = 256;
        c
    }
}

/// Losses and times of one stage.
#[derive(Clone, Debug, Serialize)]
pub struct StageReport {
    /// Stage name.
    pub stage: &'static str,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Mean loss over the first 5 % of iterations.
    pub loss_start: f64,
    /// Mean loss over the last 5 % of iterations.
    pub loss_end: f64,
}

/// What a fit produced.
#[derive(Debug)]
pub struct Fitted {
    /// The student, loaded in the kernel.
    pub model: LearnedModel,
    /// Per-stage losses and times.
    pub stages: Vec<StageReport>,
    /// Total wall-clock seconds.
    pub seconds: f64,
    /// Number of training pairs used.
    pub pairs: usize,
}

/// Records a stage's loss curve.
struct Curve {
    losses: Vec<f64>,
}

impl Curve {
    fn report(&self, stage: &'static str, seconds: f64) -> Result<StageReport, TrainError> {
        let n = self.losses.len();
        let k = (n / 20).max(1).min(n.max(1));
        let mean = |s: &[f64]| s.iter().sum::<f64>() / s.len().max(1) as f64;
        let (start, end) = (
            mean(&self.losses[..k.min(n)]),
            mean(&self.losses[n.saturating_sub(k)..]),
        );
        if !(start.is_finite() && end.is_finite()) {
            return Err(TrainError::Diverged { stage });
        }
        Ok(StageReport {
            stage,
            seconds,
            loss_start: start,
            loss_end: end,
        })
    }
}

/// Fits a student to `material`.
pub fn fit_material(
    material: &dyn Material,
    name: &str,
    cfg: &FitConfig,
    progress: &dyn Progress,
) -> Result<Fitted, TrainError> {
    let start = Instant::now();
    progress.stage("pairs", cfg.pairs as u64);
    let source = MaterialPairs {
        material,
        domain: cfg.domain,
        count: cfg.pairs,
        seed: cfg.seed,
        grazing: cfg.grazing,
        isotropic: cfg.use_isotropy && material.is_isotropic(),
        angle_fraction: cfg.angle_fraction,
    };
    let data = TrainingSet::from_source(cfg.domain, &source);
    progress.advance(cfg.pairs as u64, None);
    let mut fitted = fit_data(&data, name, cfg, progress)?;
    fitted.stages.insert(
        0,
        StageReport {
            stage: "pairs",
            seconds: start.elapsed().as_secs_f64() - fitted.seconds,
            loss_start: 0.0,
            loss_end: 0.0,
        },
    );
    fitted.seconds = start.elapsed().as_secs_f64();
    Ok(fitted)
}

/// Fits a student to training pairs from any source.
pub fn fit_source(
    source: &dyn TrainingData,
    domain: Domain,
    name: &str,
    cfg: &FitConfig,
    progress: &dyn Progress,
) -> Result<Fitted, TrainError> {
    fit_data(
        &TrainingSet::from_source(domain, source),
        name,
        cfg,
        progress,
    )
}

/// Fits a student to a prepared training set.
pub fn fit_data(
    data: &TrainingSet,
    name: &str,
    cfg: &FitConfig,
    progress: &dyn Progress,
) -> Result<Fitted, TrainError> {
    if data.is_empty() {
        return Err(TrainError::NoData);
    }
    let mut def = LearnedModel::definition(cfg.domain, name, cfg.steps)?;
    def.isotropic = data.isotropic;
    let start = Instant::now();
    let mut rng = Pcg64::seed_from_u64(cfg.seed ^ 0x9e37_79b9_7f4a_7c15);
    let mut stages = Vec::new();

    let t = Instant::now();
    progress.stage("base", cfg.base.iters as u64);
    let mut curve = Curve { losses: Vec::new() };
    let base = train_base(data, &cfg.base, &mut rng, &mut |_, l| {
        curve.losses.push(l);
        progress.advance(1, Some(l));
    });
    stages.push(curve.report("base", t.elapsed().as_secs_f64())?);
    let dists = base_distributions(&base, data);

    let t = Instant::now();
    progress.stage("teacher", cfg.teacher.iters as u64);
    let mut teacher = new_velocity_net(data, cfg.teacher.width, cfg.teacher.layers, &mut rng);
    let mut curve = Curve { losses: Vec::new() };
    train_flow(
        &mut teacher,
        data,
        Coupling::Independent { base: &dists },
        &cfg.teacher,
        &mut rng,
        &mut |_, l| {
            curve.losses.push(l);
            progress.advance(1, Some(l));
        },
    );
    stages.push(curve.report("teacher", t.elapsed().as_secs_f64())?);

    let t = Instant::now();
    progress.stage("reflow", cfg.reflow_pairs as u64);
    let pairs = reflow_pairs(
        &teacher,
        data,
        &dists,
        cfg.reflow_pairs,
        cfg.reflow_steps,
        &mut rng,
        &|n| progress.advance(n as u64, None),
    );
    stages.push(StageReport {
        stage: "reflow",
        seconds: t.elapsed().as_secs_f64(),
        loss_start: 0.0,
        loss_end: 0.0,
    });

    let t = Instant::now();
    progress.stage("student", cfg.student.iters as u64);
    let mut student = new_velocity_net(data, cfg.student.width, cfg.student.layers, &mut rng);
    let mut student_cfg = cfg.student;
    if cfg.student_euler_times {
        student_cfg.t_grid = cfg.steps as usize;
    }
    let mut curve = Curve { losses: Vec::new() };
    train_flow(
        &mut student,
        data,
        Coupling::Fixed { pairs: &pairs },
        &student_cfg,
        &mut rng,
        &mut |_, l| {
            curve.losses.push(l);
            progress.advance(1, Some(l));
        },
    );
    stages.push(curve.report("student", t.elapsed().as_secs_f64())?);
    progress.finish();

    let model = LearnedModel::from_nets(def, &base, &student)?;
    Ok(Fitted {
        model,
        stages,
        seconds: start.elapsed().as_secs_f64(),
        pairs: data.len(),
    })
}
