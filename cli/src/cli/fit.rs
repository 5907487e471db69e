//! `diffbsdf fit <material-spec> --domain disk|sphere --steps N --seed S --out m.dbsdf`:
//! trains a sampler for a material and writes its blob (f32 at `--out`, f16 beside it as
//! `<stem>.f16.dbsdf`), then measures its quality unless `--no-eval`.

use super::choose::{exact_steps, fewest_steps, Candidate, Criteria};
use clap::{Args, ValueEnum};
use diffbsdf::{Domain, Precision};
use diffbsdf_materials::{parse_spec, SpecError};
use diffbsdf_train::metrics::{evaluate, table, EvalConfig, Report};
use diffbsdf_train::{fit_material, FitConfig, ModelExt, Progress, StageReport, TrainError};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Flow domain on the command line.
#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum DomainArg {
    /// Projected unit disk (BRDFs).
    Disk,
    /// (theta, phi) over the sphere (full BSDFs, grazing specular BRDFs).
    Sphere,
    /// Spherical coordinates about the tangent y axis (the normal on the equator).
    Equatorial,
    /// The half vector of the reflection on the projected disk (BRDFs; the specular peak
    /// at the disk's centre for every wi).
    HalfVector,
    /// The half-vector chart for a reflection-only material, the sphere for a
    /// transmissive one.
    Material,
    /// The disk where it suffices; the sphere for transmissive materials, or when the
    /// disk model misses `--max-grazing-firefly` or `--target-rv`.
    Auto,
}

/// Coordinates of the flow on the command line (`ModelDef::standardized`,
/// `ModelDef::standard_warp`).
#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum CoordinatesArg {
    /// The base distribution's standard coordinates (disk and half-vector chart).
    Standard,
    /// The standard coordinates compressed by `K asinh(z / K)` (disk and half-vector chart).
    Warped,
    /// The chart's own coordinates.
    Chart,
}

impl DomainArg {
    /// The domains to try, cheapest first.
    pub fn candidates(self, material: &dyn diffbsdf_materials::Material) -> Vec<Domain> {
        match self {
            DomainArg::Disk => vec![Domain::Disk],
            DomainArg::Sphere => vec![Domain::Sphere],
            DomainArg::Equatorial => vec![Domain::Equatorial],
            DomainArg::HalfVector => vec![Domain::HalfVector],
            DomainArg::Material if material.is_transmissive() => vec![Domain::Sphere],
            DomainArg::Material => vec![Domain::HalfVector],
            DomainArg::Auto if material.is_transmissive() => vec![Domain::Sphere],
            DomainArg::Auto => vec![Domain::Disk, Domain::Sphere],
        }
    }
}

/// Arguments of `diffbsdf fit`.
#[derive(Debug, Args)]
pub struct FitArgs {
    /// Material spec, e.g. `conductor:ggx,alpha=0.3,metal=Cu`.
    pub spec: String,
    /// Flow domain. By default (`material`) the half-vector chart for a reflection-only
    /// material, where a measured BRDF's peak sits at the chart's centre for every wi and
    /// its horizon inside the chart (2-8x lower variance than the sphere on measured
    /// materials, `docs/measured-materials.md`), and the sphere for a transmissive one.
    #[arg(long, value_enum, default_value = "material")]
    pub domain: DomainArg,
    /// Mean RV to reach: the blob's default steps become the fewest of 1, 2, 4, ..., 32
    /// that reach it (with every step invertible); with `--domain auto` a disk model that
    /// cannot reach it gives way to a sphere model.
    #[arg(long)]
    pub target_rv: Option<f64>,
    /// With `--domain auto`: the largest firefly ratio (99.99th percentile of w / E[w])
    /// allowed at grazing wi (theta_i >= 85 deg) before the sphere is used instead.
    #[arg(long, default_value_t = 20.0)]
    pub max_grazing_firefly: f64,
    /// Samples per wi of the quality checks (`--domain auto`, `--target-rv`).
    #[arg(long, default_value_t = 1 << 14)]
    pub check_samples: usize,
    /// Valid samples of the exactness sweep that every shipped step count must pass
    /// (`pdf()` equal to the sampled PDF, f32 and f16 together, normal to grazing wi, u at
    /// the edges of [0, 1]); the fit refuses a model that fails it at every step count.
    #[arg(long, default_value_t = diffbsdf_train::metrics::exactness::DEFAULT_SAMPLES)]
    pub exact_samples: usize,
    /// Euler steps of the student (default 4 on the disk, 8 on the sphere).
    #[arg(long)]
    pub steps: Option<u16>,
    /// Seed of every random draw: the same command and seed give the same blob.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Euler steps stored in the blob as its default, when they should differ from the
    /// steps the student was trained at (`--steps`). Like the trained steps, they are the
    /// first of N, 2N, 4N, ... (to 32) checked for exactness: the fewest that pass ship.
    #[arg(long)]
    pub export_steps: Option<u16>,
    /// Output blob (f32); the f16 blob is written beside it.
    #[arg(long)]
    pub out: PathBuf,
    /// Name stored in the blob (at most 32 bytes; default: the file stem).
    #[arg(long)]
    pub name: Option<String>,
    /// A fit of a few seconds (tests, smoke runs) instead of the standard one.
    #[arg(long)]
    pub tiny: bool,
    /// The quick recipe (about 2.5 minutes on 2 cores; every analytic model in `models/`):
    /// a 4x64 teacher, 12 000 iterations on 200 000 pairs. Enough for rough analytic
    /// lobes, not for measured materials.
    #[arg(long, conflicts_with = "tiny")]
    pub quick: bool,
    /// Training pairs.
    #[arg(long)]
    pub pairs: Option<usize>,
    /// Base-net iterations.
    #[arg(long)]
    pub base_iters: Option<usize>,
    /// Teacher iterations.
    #[arg(long)]
    pub teacher_iters: Option<usize>,
    /// Teacher hidden width.
    #[arg(long)]
    pub teacher_width: Option<usize>,
    /// Teacher hidden layers.
    #[arg(long)]
    pub teacher_layers: Option<usize>,
    /// Hidden layers of the student's velocity net, 3 or 4 (the depths of 32 the kernel
    /// compiles; default 3 on the disk and the half-vector chart, 4 on the sphere).
    #[arg(long, value_parser = super::depth::parse_student_layers)]
    pub student_layers: Option<u8>,
    /// Reflow pairs.
    #[arg(long)]
    pub reflow_pairs: Option<usize>,
    /// RK4 steps of the teacher per reflow pair.
    #[arg(long)]
    pub reflow_steps: Option<usize>,
    /// Student iterations.
    #[arg(long)]
    pub student_iters: Option<usize>,
    /// Peak learning rate of the teacher.
    #[arg(long)]
    pub teacher_lr: Option<f32>,
    /// Peak learning rate of the student.
    #[arg(long)]
    pub student_lr: Option<f32>,
    /// Decay of the teacher's weight average (`ema <- d ema + (1 - d) params`; 0.999 by
    /// default).
    #[arg(long)]
    pub teacher_ema: Option<f32>,
    /// Couple the teacher's pairs by optimal transport in runs of this many per `wi`: the
    /// pairs are generated in such runs and each run's base draws are assigned to its data
    /// points to shorten `x1 - x0` (16 is the measured choice; off by default, see
    /// docs/measured-materials.md). 0 for the independent coupling.
    #[arg(long)]
    pub teacher_ot: Option<usize>,
    /// Extra training pairs with wi within 30 degrees of the horizon, as a fraction of
    /// --pairs.
    #[arg(long)]
    pub grazing: Option<f64>,
    /// Train the student only at its Euler times k/N.
    #[arg(long)]
    pub euler_times: bool,
    /// Iterations of the variance refinement of the student against the material
    /// (docs/math.md section 11): 0 skips it (the fits before 2026-12-05). Default: 1800
    /// with the standard recipe, 0 with --quick and --tiny.
    #[arg(long)]
    pub refine_iters: Option<usize>,
    /// Draws per incidence slice of the latent table fitted last, in front of the final
    /// flow (docs/math.md section 6.5): 0 skips it (the fits before 2026-12-06). Default:
    /// 1 000 000 with the standard recipe in standard coordinates (the half-vector chart),
    /// 0 otherwise.
    #[arg(long)]
    pub table_draws: Option<usize>,
    /// Peak learning rate of the variance refinement (cosine decay to 5 %). Default
    /// 8e-4 (docs/measured-materials.md, "Twice the peak rate again"; 4e-4 until
    /// 2026-12-06, 2e-4 before 2026-12-05).
    #[arg(long)]
    pub refine_lr: Option<f32>,
    /// Share of the variance refinement's incidences drawn from the grazing band (60 to
    /// 89.5 degrees) instead of the whole range, from 0 to 1. Default 0.
    #[arg(long, value_parser = super::share::parse_share)]
    pub refine_grazing: Option<f32>,
    /// Coordinates of the flow on the disk and the half-vector chart: the base
    /// distribution's standard coordinates z = (x - mu) / sigma (docs/math.md, section
    /// 6.3), those compressed by 3 asinh(z / 3) (warped, section 6.4), or the chart's own.
    /// Default: warped on the half-vector chart with the default recipe, the chart's
    /// otherwise.
    #[arg(long, value_enum)]
    pub coordinates: Option<CoordinatesArg>,
    /// Condition on the full wi even when the material is isotropic or declares a symmetry
    /// in the incident azimuth (by default an isotropic material is fitted in the incident
    /// frame, wi turned to phi = 0, and such an anisotropic one with wi folded into half or
    /// a quarter of the turn).
    #[arg(long)]
    pub ignore_isotropy: bool,
    /// Isotropic fits: fraction of the training wi drawn with theta_i uniform in angle
    /// (the rest uniform in solid angle, which favours grazing). Default 0.5.
    #[arg(long)]
    pub angle_fraction: Option<f64>,
    /// Batch size of the teacher and the student.
    #[arg(long)]
    pub batch: Option<usize>,
    /// Skip the quality evaluation.
    #[arg(long)]
    pub no_eval: bool,
    /// Samples per wi in the evaluation.
    #[arg(long, default_value_t = 1 << 16)]
    pub eval_samples: usize,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Why `fit`, `eval` or `demo` failed.
#[derive(Debug)]
pub enum CommandError {
    /// The material spec did not parse.
    Spec(SpecError),
    /// Training or export failed.
    Train(TrainError),
    /// Reading or writing a file failed.
    Io(PathBuf, std::io::Error),
    /// Writing the output failed.
    Output(std::io::Error),
    /// JSON encoding failed.
    Json(String),
    /// Generating shader or header code failed.
    Codegen(String),
    /// The models folder could not be read.
    Catalog(crate::tradeoff::CatalogError),
    /// The tradeoff sweep, its plot or its images failed.
    Sweep(crate::tradeoff::SweepError),
    /// `fit` found no step count at which the model's `pdf()` is exact (what it checked).
    NotExact(String),
    /// Arguments that make no sense together (what is wrong).
    Usage(String),
}

impl fmt::Display for CommandError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CommandError::Spec(e) => write!(f, "{e}"),
            CommandError::Train(e) => write!(f, "{e}"),
            CommandError::Io(p, e) => write!(f, "{}: {e}", p.display()),
            CommandError::Output(e) => write!(f, "write failed: {e}"),
            CommandError::Json(e) => write!(f, "JSON encoding failed: {e}"),
            CommandError::Codegen(e) => write!(f, "{e}"),
            CommandError::Catalog(e) => write!(f, "{e}"),
            CommandError::Sweep(e) => write!(f, "{e}"),
            CommandError::NotExact(e) => write!(f, "{e}"),
            CommandError::Usage(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for CommandError {}

impl From<diffbsdf::BlobError> for CommandError {
    fn from(e: diffbsdf::BlobError) -> Self {
        CommandError::Train(TrainError::Blob(e))
    }
}

impl From<TrainError> for CommandError {
    fn from(e: TrainError) -> Self {
        CommandError::Train(e)
    }
}

/// Progress bars on stderr, one per training stage.
#[derive(Debug, Default)]
pub struct Bars {
    bar: Mutex<Option<ProgressBar>>,
}

impl Progress for Bars {
    fn stage(&self, name: &'static str, total: u64) {
        let bar = ProgressBar::new(total);
        if let Ok(style) =
            ProgressStyle::with_template("{prefix:>8} [{bar:32}] {pos}/{len} {msg} ({elapsed})")
        {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_prefix(name);
        if let Ok(mut slot) = self.bar.lock() {
            if let Some(old) = slot.replace(bar) {
                old.finish();
            }
        }
    }

    fn advance(&self, n: u64, loss: Option<f64>) {
        if let Ok(slot) = self.bar.lock() {
            if let Some(bar) = slot.as_ref() {
                bar.inc(n);
                if let Some(l) = loss {
                    if bar.position() % 25 == 0 {
                        bar.set_message(format!("loss {l:.4}"));
                    }
                }
            }
        }
    }

    fn finish(&self) {
        if let Ok(mut slot) = self.bar.lock() {
            if let Some(old) = slot.take() {
                old.finish();
            }
        }
    }
}

/// What `fit --json` prints.
#[derive(Debug, Serialize)]
pub struct FitOutput {
    /// Material spec.
    pub material: String,
    /// Seed.
    pub seed: u64,
    /// Output blob paths (f32, f16).
    pub blobs: [String; 2],
    /// Blob sizes in bytes (f32, f16).
    pub bytes: [usize; 2],
    /// Training wall time in seconds.
    pub train_seconds: f64,
    /// Training pairs.
    pub pairs: usize,
    /// Per-stage losses and times.
    pub stages: Vec<StageReport>,
    /// Quality report.
    pub report: Option<Report>,
    /// The `--domain auto` / `--target-rv` checks, in order, if any were made.
    pub choice: Vec<Candidate>,
}

/// The f16 blob's path beside `out`.
pub fn f16_path(out: &Path) -> PathBuf {
    let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("model");
    out.with_file_name(format!("{stem}.f16.dbsdf"))
}

/// Writes `bytes` to `path`.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), CommandError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| CommandError::Io(dir.to_path_buf(), e))?;
    }
    std::fs::write(path, bytes).map_err(|e| CommandError::Io(path.to_path_buf(), e))
}

/// Prints `value` as pretty JSON.
pub fn print_json<T: Serialize>(
    value: &T,
    out: &mut dyn std::io::Write,
) -> Result<(), CommandError> {
    let s = serde_json::to_string_pretty(value).map_err(|e| CommandError::Json(e.to_string()))?;
    writeln!(out, "{s}").map_err(CommandError::Output)
}

/// The recipe a fit starts from: `--tiny`, `--quick` or the standard one.
pub fn recipe(tiny: bool, quick: bool, domain: Domain, seed: u64) -> FitConfig {
    if tiny {
        FitConfig::tiny(domain, seed)
    } else if quick {
        FitConfig::quick(domain, seed)
    } else {
        FitConfig::standard(domain, seed)
    }
}

/// The fit configuration the arguments ask for, on `domain`.
pub fn config(args: &FitArgs, domain: Domain) -> FitConfig {
    let mut c = recipe(args.tiny, args.quick, domain, args.seed);
    let set = |dst: &mut usize, v: Option<usize>| {
        if let Some(v) = v {
            *dst = v.max(1);
        }
    };
    if let Some(s) = args.steps {
        c.def.default_steps = s.max(1);
    }
    set(&mut c.pairs, args.pairs);
    set(&mut c.base.iters, args.base_iters);
    set(&mut c.teacher.iters, args.teacher_iters);
    if let Some(w) = args.teacher_width {
        c.teacher_net.width = w.clamp(1, u16::MAX as usize) as u16;
    }
    if let Some(l) = args.teacher_layers {
        c.teacher_net.hidden_layers = l.clamp(1, u8::MAX as usize) as u8;
    }
    if let Some(l) = args.student_layers {
        c.def.velocity.hidden_layers = l;
    }
    set(&mut c.reflow_pairs, args.reflow_pairs);
    set(&mut c.reflow_steps, args.reflow_steps);
    set(&mut c.student.iters, args.student_iters);
    set(&mut c.teacher.batch, args.batch);
    c.student_euler_times |= args.euler_times;
    if let Some(k) = args.coordinates {
        let standard = k != CoordinatesArg::Chart && !domain.is_spherical();
        c.def.standardized = standard;
        c.def.standard_warp = standard && k == CoordinatesArg::Warped;
    }
    if args.ignore_isotropy {
        c.use_isotropy = false;
    }
    if let Some(a) = args.angle_fraction {
        c.angle_fraction = a.clamp(0.0, 1.0);
    }
    if let Some(g) = args.grazing {
        c.grazing = g;
    }
    if let Some(lr) = args.teacher_lr {
        c.teacher.lr = lr;
    }
    if let Some(d) = args.teacher_ema {
        c.teacher.ema = d;
    }
    if let Some(g) = args.teacher_ot {
        c.teacher.ot_group = g;
    }
    if let Some(n) = args.refine_iters {
        c.refine.iters = n;
    }
    if let Some(n) = args.table_draws {
        c.table.draws_per_slice = n;
    }
    if let Some(lr) = args.refine_lr {
        c.refine.lr = lr;
    }
    if let Some(g) = args.refine_grazing {
        c.refine.grazing_share = g;
    }
    if let Some(lr) = args.student_lr {
        c.student.lr = lr;
    }
    set(&mut c.student.batch, args.batch);
    c
}

/// Trains on each candidate domain in turn (cheapest first) until one is sufficient;
/// returns the fit kept, with the fewest exact step counts, and the checks made. Every
/// shipped step count passes the exactness sweep; where none up to 32 does, the model is
/// refused (`CommandError::NotExact`).
fn fit_choosing(
    args: &FitArgs,
    material: &dyn diffbsdf_materials::Material,
    name: &str,
) -> Result<(diffbsdf_train::Fitted, Vec<Candidate>), CommandError> {
    let choosing = args.domain == DomainArg::Auto || args.target_rv.is_some();
    let criteria = Criteria {
        target_rv: args.target_rv,
        max_grazing_firefly: if args.domain == DomainArg::Auto {
            args.max_grazing_firefly
        } else {
            f64::INFINITY
        },
        samples: args.check_samples,
        exact_samples: args.exact_samples,
    };
    let mut domains = args.domain.candidates(material).into_iter();
    let mut domain = domains.next().unwrap_or(Domain::Sphere);
    let mut checks = Vec::new();
    loop {
        let bars = Bars::default();
        let mut fitted = fit_material(material, name, &config(args, domain), &bars)?;
        let trained = fitted.model.def().default_steps;
        let picked = if choosing {
            let (pick, tried) = fewest_steps(&fitted.model, material, &criteria)?;
            checks.extend(tried);
            match (pick, domains.next()) {
                (Some(p), _) => Some(p.steps),
                (None, Some(next)) => {
                    domain = next;
                    continue;
                }
                // Nothing sufficed: the most capable domain, at the fewest exact steps.
                (None, None) => None,
            }
        } else {
            None
        };
        // `--export-steps` starts the ladder where given; a pick that is already exact
        // ships as it is.
        let steps = match (args.export_steps, picked) {
            (None, Some(p)) => p,
            (from, _) => {
                let from = from.unwrap_or(trained);
                let (exact, tried) =
                    exact_steps(&fitted.model, material, from, args.exact_samples)?;
                checks.extend(tried);
                match exact {
                    Some(n) => n,
                    None => {
                        return Err(refuse(args, &fitted, &checks));
                    }
                }
            }
        };
        fitted.model = fitted.model.with_steps(steps);
        return Ok((fitted, checks));
    }
}

/// The error for a model that is not exact at any step count; its blob is kept beside
/// `--out` as `<stem>.not-exact.dbsdf` for inspection, never at `--out`.
fn refuse(args: &FitArgs, fitted: &diffbsdf_train::Fitted, checks: &[Candidate]) -> CommandError {
    let kept = args.out.with_extension("not-exact.dbsdf");
    let saved = fitted
        .model
        .blob(Precision::F32)
        .map_err(CommandError::from)
        .and_then(|b| write_file(&kept, &b));
    let last = checks
        .last()
        .map(|c| c.exactness.summary())
        .unwrap_or_default();
    CommandError::NotExact(format!(
        "no step count up to 32 keeps pdf() equal to the sampled PDF on every checked sample; nothing written at {}{}\n{last}",
        args.out.display(),
        match saved {
            Ok(()) => format!(" (the model is at {} for inspection)", kept.display()),
            Err(e) => format!(" (keeping it for inspection failed too: {e})"),
        }
    ))
}

/// Runs `diffbsdf fit`.
pub fn run(args: FitArgs, out: &mut dyn std::io::Write) -> Result<(), CommandError> {
    let material = parse_spec(&args.spec).map_err(CommandError::Spec)?;
    let name = args.name.clone().unwrap_or_else(|| {
        let stem = args
            .out
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("model");
        stem.chars().take(32).collect()
    });
    let (fitted, choice) = fit_choosing(&args, material.as_ref(), &name)?;
    let f32_blob = fitted.model.blob(Precision::F32)?;
    let f16_blob = fitted.model.blob(Precision::F16)?;
    let f16_out = f16_path(&args.out);
    write_file(&args.out, &f32_blob)?;
    write_file(&f16_out, &f16_blob)?;
    let report = (!args.no_eval).then(|| {
        let eval = EvalConfig {
            samples: args.eval_samples,
            exact_samples: args.exact_samples,
            ..EvalConfig::default()
        };
        evaluate(&fitted.model, material.as_ref(), &eval)
    });
    if args.json {
        return print_json(
            &FitOutput {
                material: material.spec(),
                seed: args.seed,
                blobs: [
                    args.out.display().to_string(),
                    f16_out.display().to_string(),
                ],
                bytes: [f32_blob.len(), f16_blob.len()],
                train_seconds: fitted.seconds,
                pairs: fitted.pairs,
                stages: fitted.stages,
                report,
                choice,
            },
            out,
        );
    }
    let mut text = format!(
        "trained {} in {:.1} s on {} pairs -> {} ({} B), {} ({} B)\n",
        material.spec(),
        fitted.seconds,
        fitted.pairs,
        args.out.display(),
        f32_blob.len(),
        f16_out.display(),
        f16_blob.len()
    );
    for s in &fitted.stages {
        text += &format!(
            "  {:<8} {:>7.1} s  loss {:.5} -> {:.5}\n",
            s.stage, s.seconds, s.loss_start, s.loss_end
        );
    }
    for c in &choice {
        text += &format!("  {}\n", c.line());
    }
    if let Some(r) = &report {
        text += &table::render(r);
    }
    write!(out, "{text}").map_err(CommandError::Output)
}
