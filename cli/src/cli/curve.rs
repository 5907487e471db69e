//! `diffbsdf curve <material-spec>`: what accuracy costs in training. Fits the material once
//! per teacher length and student depth (every other setting the fit's default, the same
//! seed for all), measures each fit at its trained step count, f32 and f16 blobs, and writes
//! the curve a user reads to decide how long to train and how large a model to ship:
//! `NAME.md` (table), `NAME.json` and `NAME.svg` (mean RV against training minutes, one
//! line per student depth, the material's own sampler as a horizontal line).

use super::fit::{print_json, recipe, write_file, Bars, CommandError, DomainArg};
use crate::tradeoff::SweepError;
use clap::Args;
use diffbsdf::{AnyModel, Domain, Precision};
use diffbsdf_materials::{parse_spec, Material};
use diffbsdf_train::metrics::{evaluate, EvalConfig, Report};
use diffbsdf_train::{fit_material, FitConfig, ModelExt};
use plotters::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Arguments of `diffbsdf curve`.
#[derive(Debug, Args)]
pub struct CurveArgs {
    /// Material spec, e.g. `rgl:../shared/data/rgl/vch_golden_yellow_rgb.bsdf`.
    pub spec: String,
    /// Flow domain (as `fit --domain`; `auto` is not a single domain and is refused).
    #[arg(long, value_enum, default_value = "sphere")]
    pub domain: DomainArg,
    /// Teacher iterations, one fit each (the training-length axis).
    #[arg(long, value_delimiter = ',', default_value = "12000,24000,48000")]
    pub teacher_iters: Vec<usize>,
    /// Hidden layers of the student's velocity net, one fit each (the model-size axis; the
    /// kernel compiles 3 and 4 layers of 32).
    #[arg(long, value_delimiter = ',', default_value = "4", value_parser = super::depth::parse_student_layers)]
    pub student_layers: Vec<u8>,
    /// Start from the quick recipe (`fit --quick`) instead of the standard one.
    #[arg(long, conflicts_with = "tiny")]
    pub quick: bool,
    /// Start from the few-second recipe (tests, smoke runs).
    #[arg(long)]
    pub tiny: bool,
    /// Seed of every fit.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Samples per wi of each evaluation.
    #[arg(long, default_value_t = 1 << 16)]
    pub eval_samples: usize,
    /// Output folder.
    #[arg(long, default_value = "docs/curves")]
    pub out: PathBuf,
    /// File stem of the report (default: the material's name in its spec).
    #[arg(long)]
    pub name: Option<String>,
    /// Print the points as JSON on stdout too.
    #[arg(long)]
    pub json: bool,
}

/// Quality of one blob at its trained step count.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct Quality {
    /// Mean RV over the evaluation grid.
    pub rv_mean: f64,
    /// Worst RV over the grid.
    pub rv_worst: f64,
    /// `theta_i` of the worst RV, degrees.
    pub rv_worst_theta_deg: f64,
    /// Mean firefly ratio (99.99th percentile of w / E[w]).
    pub firefly_mean: f64,
    /// Worst firefly ratio.
    pub firefly_worst: f64,
}

impl Quality {
    fn of(r: &Report) -> Self {
        Quality {
            rv_mean: r.learned.rv_mean,
            rv_worst: r.learned.rv_worst,
            rv_worst_theta_deg: r.learned.rv_worst_theta_deg,
            firefly_mean: r.learned.firefly_mean,
            firefly_worst: r.learned.firefly_worst,
        }
    }
}

/// One fit of the curve.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CurvePoint {
    /// Teacher iterations.
    pub teacher_iters: usize,
    /// Hidden layers of the student.
    pub student_layers: u8,
    /// Euler steps the student was trained for (and is measured at).
    pub steps: u16,
    /// Wall seconds of the whole fit (pairs, base, teacher, reflow, student).
    pub train_seconds: f64,
    /// Wall seconds of the teacher alone.
    pub teacher_seconds: f64,
    /// Blob sizes in bytes (f32, f16).
    pub bytes: [usize; 2],
    /// The f32 blob.
    pub f32: Quality,
    /// The f16 blob.
    pub f16: Quality,
    /// Mean RV of the material's own sampler on the same grid.
    pub material_rv_mean: f64,
}

/// What `curve` writes as JSON.
#[derive(Debug, Serialize, Deserialize)]
pub struct CurveRecord {
    /// The command that produced it.
    pub command: String,
    /// Material spec.
    pub material: String,
    /// Samples per `wi` of each evaluation.
    pub samples: usize,
    /// Logical cores of the machine.
    pub cores: usize,
    /// One point per fit, in the order run.
    pub points: Vec<CurvePoint>,
}

fn domain(arg: DomainArg, material: &dyn Material) -> Result<Domain, CommandError> {
    match arg {
        DomainArg::Auto => Err(CommandError::Usage(
            "curve needs one domain (disk, sphere, equatorial, half-vector or material), not auto"
                .into(),
        )),
        _ => Ok(arg.candidates(material)[0]),
    }
}

/// The fit configuration of one point.
fn config(args: &CurveArgs, domain: Domain, teacher_iters: usize, layers: u8) -> FitConfig {
    let mut c = recipe(args.tiny, args.quick, domain, args.seed);
    c.teacher.iters = teacher_iters.max(1);
    c.def.velocity.hidden_layers = layers;
    c
}

/// The command line that reproduces `args`.
fn command_line(args: &CurveArgs) -> String {
    let list = |v: &[String]| v.join(",");
    let iters: Vec<String> = args.teacher_iters.iter().map(|n| n.to_string()).collect();
    let layers: Vec<String> = args.student_layers.iter().map(|n| n.to_string()).collect();
    let mut s = format!(
        "cargo run --release -p diffbsdf-cli --bin diffbsdf -- curve \"{}\" --domain {} --teacher-iters {} --student-layers {} --seed {} --eval-samples {}",
        args.spec,
        format!("{:?}", args.domain).to_lowercase(),
        list(&iters),
        list(&layers),
        args.seed,
        args.eval_samples
    );
    if args.quick {
        s += " --quick";
    }
    if args.tiny {
        s += " --tiny";
    }
    s
}

/// Fits and measures one point.
fn point(
    args: &CurveArgs,
    material: &dyn Material,
    domain: Domain,
    teacher_iters: usize,
    layers: u8,
) -> Result<CurvePoint, CommandError> {
    let cfg = config(args, domain, teacher_iters, layers);
    let fitted = fit_material(material, "curve", &cfg, &Bars::default())?;
    let f32_blob = fitted.model.blob(Precision::F32)?;
    let f16_blob = fitted.model.blob(Precision::F16)?;
    let eval = EvalConfig {
        samples: args.eval_samples,
        consistency_samples: 0,
        exact_samples: 0,
        kl: None,
        timing_calls: 0,
        off_grid_incidences: 0,
        seed: 7,
    };
    let full = evaluate(&fitted.model, material, &eval);
    let half = evaluate(&AnyModel::from_blob(&f16_blob)?, material, &eval);
    Ok(CurvePoint {
        teacher_iters,
        student_layers: layers,
        steps: fitted.model.def().default_steps,
        train_seconds: fitted.seconds,
        teacher_seconds: fitted
            .stages
            .iter()
            .filter(|s| s.stage == "teacher")
            .map(|s| s.seconds)
            .sum(),
        bytes: [f32_blob.len(), f16_blob.len()],
        f32: Quality::of(&full),
        f16: Quality::of(&half),
        material_rv_mean: full.material_sampler.rv_mean,
    })
}

/// The report's table, with the plot at `svg` (a path relative to the report).
fn markdown(record: &CurveRecord, svg: &str) -> String {
    let mut s = format!(
        "# What accuracy costs in training: `{}`\n\nProduced by `{}` ({} samples per `wi`, {} logical cores; metrics as in `docs/math.md`, \"Metrics\"). Each row is a whole fit from the same seed; quality at the step count the student was trained for, without the exactness sweep that `fit` runs before it ships a step count. Training minutes are wall time of the whole fit on this machine.\n\n![mean RV against training minutes]({})\n\n",
        record.material,
        record.command,
        record.samples,
        record.cores,
        svg
    );
    s += "| student | teacher iterations | training min (teacher) | N | f32 bytes | mean RV f32 | worst RV (theta_i) | fireflies mean / worst | mean RV f16 | / material's sampler |\n";
    s += "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for p in &record.points {
        s += &format!(
            "| {}x32 | {} | {:.2} ({:.2}) | {} | {} | {:.4} | {:.3} ({:.0}°) | {:.1} / {:.1} | {:.4} | {:.1}x |\n",
            p.student_layers,
            p.teacher_iters,
            p.train_seconds / 60.0,
            p.teacher_seconds / 60.0,
            p.steps,
            p.bytes[0],
            p.f32.rv_mean,
            p.f32.rv_worst,
            p.f32.rv_worst_theta_deg,
            p.f32.firefly_mean,
            p.f32.firefly_worst,
            p.f16.rv_mean,
            p.f32.rv_mean / p.material_rv_mean
        );
    }
    if let Some(m) = record.points.first() {
        s += &format!(
            "\nThe material's own sampler: mean RV {:.4} on the same grid.\n",
            m.material_rv_mean
        );
    }
    s
}

/// Plots mean RV (f32) against training minutes, one line per student depth.
fn write_svg(record: &CurveRecord, path: &Path) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let pts = &record.points;
    let span = |v: &mut dyn Iterator<Item = f64>| {
        v.filter(|x| x.is_finite() && *x > 0.0)
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), x| {
                (lo.min(x), hi.max(x))
            })
    };
    let (x0, x1) = span(&mut pts.iter().map(|p| p.train_seconds / 60.0));
    let (y0, y1) = span(
        &mut pts
            .iter()
            .flat_map(|p| [p.f32.rv_mean, p.f16.rv_mean, p.material_rv_mean]),
    );
    if !(x0.is_finite() && y0.is_finite()) {
        return Err(err(&"no finite point to plot"));
    }
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{}: accuracy vs training", record.material),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (x0 / 1.3..x1 * 1.3).log_scale(),
            (y0 / 1.5..y1 * 1.5).log_scale(),
        )
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("training minutes (whole fit, wall)")
        .y_desc("mean relative variance RV over the wi grid")
        .draw()
        .map_err(|e| err(&e))?;
    let mut depths: Vec<u8> = pts.iter().map(|p| p.student_layers).collect();
    depths.sort_unstable();
    depths.dedup();
    for (k, &d) in depths.iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let mut line: Vec<&CurvePoint> = pts.iter().filter(|p| p.student_layers == d).collect();
        line.sort_by(|a, b| a.train_seconds.total_cmp(&b.train_seconds));
        let xy: Vec<(f64, f64)> = line
            .iter()
            .map(|p| (p.train_seconds / 60.0, p.f32.rv_mean))
            .collect();
        let style = color.stroke_width(2);
        chart
            .draw_series(LineSeries::new(xy.clone(), style))
            .map_err(|e| err(&e))?
            .label(format!("student {d}x32 (f32; labels: teacher iterations)"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        chart
            .draw_series(xy.iter().map(|&p| Circle::new(p, 3, color.filled())))
            .map_err(|e| err(&e))?;
        chart
            .draw_series(line.iter().map(|p| {
                Text::new(
                    format!("{}", p.teacher_iters),
                    (p.train_seconds / 60.0, p.f32.rv_mean),
                    ("sans-serif", 11).into_font().color(&color),
                )
            }))
            .map_err(|e| err(&e))?;
    }
    if let Some(m) = pts.first() {
        let y = m.material_rv_mean;
        chart
            .draw_series(LineSeries::new(
                [(x0 / 1.3, y), (x1 * 1.3, y)],
                BLACK.stroke_width(1),
            ))
            .map_err(|e| err(&e))?
            .label("the material's own sampler")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))
}

/// The report's file stem: `--name`; for a file spec (`rgl:PATH`) the file's stem; otherwise
/// the spec with every character but letters and digits turned into `-`.
fn stem(args: &CurveArgs) -> String {
    if let Some(n) = &args.name {
        return n.clone();
    }
    let spec = match args.spec.rsplit_once('/') {
        Some((_, file)) => file.trim_end_matches(".bsdf"),
        None => args.spec.as_str(),
    };
    spec.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect()
}

/// Runs `diffbsdf curve`.
pub fn run(args: CurveArgs, out: &mut dyn std::io::Write) -> Result<(), CommandError> {
    let material = parse_spec(&args.spec).map_err(CommandError::Spec)?;
    let domain = domain(args.domain, material.as_ref())?;
    for &layers in &args.student_layers {
        let mut def = config(&args, domain, 1, layers).def;
        def.default_steps = def.default_steps.max(1);
        if !AnyModel::accepts(&def) {
            return Err(CommandError::Usage(format!(
                "no compiled model has a {layers}-layer student on this domain"
            )));
        }
    }
    let mut points = Vec::new();
    for &layers in &args.student_layers {
        for &iters in &args.teacher_iters {
            points.push(point(&args, material.as_ref(), domain, iters, layers)?);
        }
    }
    let record = CurveRecord {
        command: command_line(&args),
        material: material.spec(),
        samples: args.eval_samples,
        cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
        points,
    };
    let name = stem(&args);
    let md = markdown(&record, &format!("{name}.svg"));
    write_file(&args.out.join(format!("{name}.md")), md.as_bytes())?;
    let json =
        serde_json::to_string_pretty(&record).map_err(|e| CommandError::Json(e.to_string()))?;
    write_file(&args.out.join(format!("{name}.json")), json.as_bytes())?;
    let svg = args.out.join(format!("{name}.svg"));
    write_svg(&record, &svg)
        .map_err(|e| CommandError::Sweep(SweepError::Image(svg.display().to_string(), e)))?;
    if args.json {
        return print_json(&record, out);
    }
    write!(out, "{md}").map_err(CommandError::Output)
}
