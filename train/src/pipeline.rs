//! The whole fit: pairs -> base net (max-lik) -> teacher (flow matching) -> reflow pairs
//! -> student (flow matching on straight pairs) -> kernel model. Every random draw comes
//! from one PCG64 seeded by the caller, and every parallel reduction has a fixed order, so
//! the same config and seed give the same blob bytes.

use crate::base_fit::{base_distributions, train_base, BaseConfig};
use crate::dataset::{MaterialPairs, TrainingData, TrainingSet};
use crate::error::TrainError;
use crate::export::model_from_nets;
use crate::flow_fit::{train_flow, Coupling, FlowConfig};
use crate::latent_table::{fit_latent_table, TableConfig};
use crate::mlp::Mlp;
use crate::progress::Progress;
use crate::refine::{refine, RefineConfig};
use crate::reflow::reflow_pairs;
use crate::start::StartDist;
use diffbsdf::internals::base::{warp, BaseDist};
use diffbsdf::spec::MAX_FREQS;
use diffbsdf::{AnyModel, Domain, IncidentFold, IncidentRange, ModelDef, ModelName, Net, NetShape};
use diffbsdf_materials::Material;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use serde::Serialize;
use std::time::Instant;

/// Training pairs of [`FitConfig::standard`].
pub const STANDARD_PAIRS: usize = 400_000;
/// Teacher width of [`FitConfig::standard`] (4 hidden layers, as [`FitConfig::quick`]).
pub const STANDARD_TEACHER_WIDTH: u16 = 96;
/// Teacher iterations of [`FitConfig::standard`].
pub const STANDARD_TEACHER_ITERS: usize = 48_000;

/// Everything that determines a fit (with the seed).
#[derive(Clone, Copy, Debug)]
pub struct FitConfig {
    /// The student as the kernel runs it: domain, base and velocity net shapes, and the
    /// Euler steps it is trained at (the blob's default). Name and `isotropic` are set by
    /// the fit.
    pub def: ModelDef,
    /// The teacher's velocity net (not exported; any shape).
    pub teacher_net: NetShape,
    /// Seed of every random draw.
    pub seed: u64,
    /// Training pairs drawn from the material.
    pub pairs: usize,
    /// Base net.
    pub base: BaseConfig,
    /// Teacher training.
    pub teacher: FlowConfig,
    /// Reflow pairs.
    pub reflow_pairs: usize,
    /// RK4 steps of the teacher per reflow pair.
    pub reflow_steps: usize,
    /// Student training (its shape is `def.velocity`).
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
    /// Variance refinement of the distilled student against the material (flat charts;
    /// [`crate::refine`], docs/math.md §11); `iters = 0` skips it.
    pub refine: RefineConfig,
    /// The latent table fitted last, in front of the final flow (models in standard
    /// coordinates only; [`crate::latent_table`], docs/math.md §6.5); `draws_per_slice =
    /// 0` skips it.
    pub table: TableConfig,
}

impl FitConfig {
    /// The defaults for `domain` (what `diffbsdf fit` runs): the paper's student shapes
    /// and [`FitConfig::quick`]'s stages, with a larger teacher trained four times as long
    /// on twice the pairs. The teacher's capacity and training is what limits measured materials (the
    /// reflowed student matches its teacher: its loss ends near 4e-4 and 16 steps sample
    /// no better than 8); measured in `docs/measured-materials.md`. About 11 minutes on
    /// the 2-core machine.
    ///
    /// On the half-vector chart the flow runs in the base's standard coordinates
    /// (`ModelDef::standardized`, docs/math.md §6.3), compressed by `3 asinh(z / 3)`
    /// (`ModelDef::standard_warp`, §6.4): measured on the RGL files, standard coordinates
    /// took golden yellow 2.29x -> 1.64x and orange 71.6x -> 42.7x the tabular sampler's
    /// mean RV, the warp golden yellow 1.64x -> 1.53x, orange -> 36.8x and `ilm_solo_m_68`
    /// 15.6x -> 11.2x (docs/measured-materials.md). It costs analytic lobes at grazing
    /// incidence (anisotropic copper 0.75x -> 1.23x its visible-normal sampler).
    ///
    /// The distilled student is then refined to lower its relative variance against the
    /// material directly ([`RefineConfig::default`], docs/math.md §11; measured in
    /// docs/measured-materials.md, "Variance refinement"), and a latent table is fitted in
    /// front of the refined flow where it runs in standard coordinates
    /// ([`TableConfig::DEFAULT`], docs/math.md §6.5; docs/measured-materials.md, "The
    /// latent table").
    pub fn standard(domain: Domain, seed: u64) -> Self {
        let mut def = paper_def(domain);
        def.standardized = domain == Domain::HalfVector;
        def.standard_warp = def.standardized;
        Self::for_def(def, seed)
    }

    /// The defaults for a student of definition `def` ([`FitConfig::standard`]).
    pub fn for_def(def: ModelDef, seed: u64) -> Self {
        let mut c = Self::quick_for_def(def, seed);
        c.pairs = STANDARD_PAIRS;
        c.teacher_net.width = STANDARD_TEACHER_WIDTH;
        c.teacher.iters = STANDARD_TEACHER_ITERS;
        c.refine = RefineConfig::default();
        if def.standardized {
            c.table = TableConfig::DEFAULT;
        }
        c
    }

    /// The recipe every analytic model in `models/` was fitted with (`fit --quick`): a
    /// 4x64 teacher, 12 000 iterations on 200 000 pairs; about 2.5 minutes on 2 cores.
    /// Enough for the rough analytic lobes (copper disk mean RV 1.08x its visible-normal
    /// sampler), not for measured ones. The student is trained at its Euler times
    /// (measured: mean RV 0.33 -> 0.19 on rough copper).
    pub fn quick(domain: Domain, seed: u64) -> Self {
        Self::quick_for_def(paper_def(domain), seed)
    }

    /// [`FitConfig::quick`] for a student of definition `def`.
    pub fn quick_for_def(def: ModelDef, seed: u64) -> Self {
        FitConfig {
            def,
            teacher_net: NetShape {
                width: 64,
                hidden_layers: 4,
                ..def.velocity
            },
            seed,
            pairs: 200_000,
            base: BaseConfig::default(),
            teacher: FlowConfig {
                iters: 12000,
                batch: 1024,
                lr: 2e-3,
                ema: 0.999,
                t_grid: 0,
                ot_group: 0,
            },
            reflow_pairs: 100_000,
            reflow_steps: 16,
            student: FlowConfig {
                iters: 20000,
                batch: 1024,
                lr: 2e-3,
                ema: 0.999,
                t_grid: 0,
                ot_group: 0,
            },
            student_euler_times: true,
            grazing: 0.0,
            use_isotropy: true,
            angle_fraction: 0.5,
            refine: RefineConfig::OFF,
            table: TableConfig::OFF,
        }
    }

    /// A fit of a few seconds, for tests and smoke runs.
    pub fn tiny(domain: Domain, seed: u64) -> Self {
        let mut c = Self::quick(domain, seed);
        c.pairs = 8_000;
        c.base.iters = 200;
        c.base.batch = 512;
        c.teacher_net.width = 32;
        c.teacher_net.hidden_layers = 2;
        c.teacher.iters = 150;
        c.teacher.batch = 256;
        c.reflow_pairs = 4_000;
        c.reflow_steps = 4;
        c.student.iters = 150;
        c.student.batch = 256;
        c
    }
}

/// The paper's student definition for `domain` (velocity 3x32 on the disk, 4x32 on the
/// sphere).
pub fn paper_def(domain: Domain) -> ModelDef {
    match domain {
        Domain::Disk => ModelDef::paper_disk(),
        Domain::Sphere => ModelDef::paper_sphere(),
        Domain::Equatorial => ModelDef {
            domain: Domain::Equatorial,
            ..ModelDef::paper_sphere()
        },
        Domain::HalfVector => ModelDef {
            domain: Domain::HalfVector,
            ..ModelDef::paper_disk()
        },
    }
}

impl FitConfig {
    /// The flow domain.
    pub fn domain(&self) -> Domain {
        self.def.domain
    }

    /// The Euler steps the student is trained at.
    pub fn steps(&self) -> u16 {
        self.def.default_steps
    }

    /// The teacher as a definition: the student's with the teacher's velocity net.
    pub fn teacher_def(&self) -> ModelDef {
        ModelDef {
            velocity: self.teacher_net,
            ..self.def
        }
    }

    /// Encoding frequencies the training set must hold (the largest any net reads).
    pub fn freqs(&self) -> u8 {
        self.def
            .base
            .freqs
            .max(self.def.velocity.freqs)
            .max(self.teacher_net.freqs)
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
    pub model: AnyModel,
    /// Per-stage losses and times.
    pub stages: Vec<StageReport>,
    /// Total wall-clock seconds.
    pub seconds: f64,
    /// Number of training pairs used.
    pub pairs: usize,
}

/// The training set with every target in the standard coordinates of its base
/// distribution (compressed when `warped`, docs/math.md (63)), and the standard normal in
/// the same coordinates as every pair's start.
fn standardize(
    data: &TrainingSet,
    dists: &[BaseDist],
    warped: bool,
) -> (TrainingSet, Vec<StartDist>) {
    let mut set = data.clone();
    for (x1, base) in set.x1.iter_mut().zip(dists) {
        let z1 = base.to_standard(*x1);
        *x1 = if warped { warp::compress2(z1) } else { z1 };
    }
    (set, vec![StartDist::Standard { warped }; dists.len()])
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
        domain: cfg.domain(),
        count: cfg.pairs,
        seed: cfg.seed,
        grazing: cfg.grazing,
        isotropic: cfg.use_isotropy && material.is_isotropic(),
        fold: if cfg.use_isotropy && !material.is_isotropic() {
            material.azimuth_fold()
        } else {
            IncidentFold::None
        },
        angle_fraction: cfg.angle_fraction,
        group: cfg.teacher.ot_group.max(1),
    };
    let data = TrainingSet::from_source(cfg.domain(), cfg.freqs(), &source);
    progress.advance(cfg.pairs as u64, None);
    let mut fitted = fit_data(&data, name, cfg, progress)?;
    if cfg.refine.iters > 0 {
        let t = Instant::now();
        let (model, what) = refine(&fitted.model, material, &cfg.refine, cfg.seed, progress)?;
        progress.finish();
        fitted.model = model;
        // The validation loss (mean ln(1 + RV)) before and after; the refined weights are
        // kept only where it fell.
        fitted.stages.push(StageReport {
            stage: "refine",
            seconds: t.elapsed().as_secs_f64(),
            loss_start: what.loss_before,
            loss_end: what.loss_after,
        });
        fitted.seconds += t.elapsed().as_secs_f64();
    }
    if cfg.table.draws_per_slice > 0 && fitted.model.def().standardized {
        let t = Instant::now();
        let (model, fit) = fit_latent_table(&fitted.model, material, &cfg.table, cfg.seed)?;
        fitted.model = model;
        // The mean relative variance over the table's own draws, the flow alone and with it.
        fitted.stages.push(StageReport {
            stage: "table",
            seconds: t.elapsed().as_secs_f64(),
            loss_start: fit.rv_flow,
            loss_end: fit.rv_table,
        });
        fitted.seconds += t.elapsed().as_secs_f64();
    }
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

/// Fits a student to training pairs from any source (in `cfg`'s domain).
pub fn fit_source(
    source: &dyn TrainingData,
    name: &str,
    cfg: &FitConfig,
    progress: &dyn Progress,
) -> Result<Fitted, TrainError> {
    fit_data(
        &TrainingSet::from_source(cfg.domain(), cfg.freqs(), source),
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
    let mut def = cfg.def;
    def.name = ModelName::new(name).ok_or(TrainError::NameTooLong)?;
    def.default_steps = def.default_steps.max(1);
    def.isotropic = data.isotropic;
    def.fold = data.fold;
    // The model is declared for the incident directions it was trained on.
    def.incident = if data.wi.iter().any(|wi| wi[2] < 0.0) {
        IncidentRange::WholeSphere
    } else {
        IncidentRange::UpperHemisphere
    };
    // Fail before training, not at export.
    if !AnyModel::accepts(&def) {
        return Err(TrainError::Blob(diffbsdf::BlobError::ShapeMismatch));
    }
    if data.domain != def.domain || cfg.freqs() > data.freqs || cfg.freqs() > MAX_FREQS {
        return Err(TrainError::Mismatch);
    }
    let teacher_def = cfg.teacher_def();
    let start = Instant::now();
    let mut rng = Pcg64::seed_from_u64(cfg.seed ^ 0x9e37_79b9_7f4a_7c15);
    let mut stages = Vec::new();

    let t = Instant::now();
    progress.stage("base", cfg.base.iters as u64);
    let mut curve = Curve { losses: Vec::new() };
    let base = train_base(data, &def, &cfg.base, &mut rng, &mut |_, l| {
        curve.losses.push(l);
        progress.advance(1, Some(l));
    });
    stages.push(curve.report("base", t.elapsed().as_secs_f64())?);
    let dists = base_distributions(&base, &def, data);
    // In standard coordinates (docs/math.md, §6.3) every later stage sees the targets as
    // `z1 = (x1 - mu) / sigma` of their own `wi` (compressed by §6.4 when warped) and the
    // standard normal (likewise compressed) as the base.
    let standard;
    let (data, dists) = if def.standardized {
        standard = standardize(data, &dists, def.standard_warp);
        (&standard.0, standard.1)
    } else {
        (data, dists.into_iter().map(StartDist::Chart).collect())
    };

    let t = Instant::now();
    progress.stage("teacher", cfg.teacher.iters as u64);
    let mut teacher = Mlp::new(&teacher_def, Net::Velocity, &mut rng);
    let mut curve = Curve { losses: Vec::new() };
    train_flow(
        &mut teacher,
        &teacher_def,
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
        &teacher_def,
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
    let mut student = Mlp::new(&def, Net::Velocity, &mut rng);
    let mut student_cfg = cfg.student;
    if cfg.student_euler_times {
        student_cfg.t_grid = def.default_steps as usize;
    }
    let mut curve = Curve { losses: Vec::new() };
    train_flow(
        &mut student,
        &def,
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

    let model = model_from_nets(def, &base, &student)?;
    Ok(Fitted {
        model,
        stages,
        seconds: start.elapsed().as_secs_f64(),
        pairs: data.len(),
    })
}
