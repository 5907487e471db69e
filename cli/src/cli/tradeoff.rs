//! `diffbsdf tradeoff`: what accuracy costs in time. Sweeps the shipped models over Euler
//! steps and weight precision, times each next to the material's own sampler, and writes
//! `tradeoff.md` (table), `tradeoff.json`, `tradeoff.svg` (accuracy vs time) and PDF slice
//! images `slices/NAME.png` (labelled: `slices/NAME.svg`) to the output folder (default `docs/`).

use super::fit::{print_json, write_file, CommandError};
use crate::tradeoff::{
    load_catalog, markdown, plot, slices, sweep, Point, SweepConfig, SweepError, SweepRecord,
};
use clap::Args;
use diffbsdf::AnyModel;
use diffbsdf_materials::parse_spec;
use diffbsdf_train::metrics::cost;
use diffbsdf_train::metrics::kl::KlGrid;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

/// Arguments of `diffbsdf tradeoff`.
#[derive(Debug, Args)]
pub struct TradeoffArgs {
    /// Folder of shipped models (`NAME.dbsdf`, `NAME.f16.dbsdf`, `NAME.report.json`).
    #[arg(long, default_value = "models")]
    pub models: PathBuf,
    /// Only these models (file stems); repeatable.
    #[arg(long)]
    pub only: Vec<String>,
    /// Euler step counts.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16,32")]
    pub steps: Vec<u16>,
    /// Skip the f16 blobs.
    #[arg(long)]
    pub no_f16: bool,
    /// Samples per wi and sampler.
    #[arg(long, default_value_t = 1 << 14)]
    pub samples: usize,
    /// Calls timed per entry point.
    #[arg(long, default_value_t = 20_000)]
    pub timing_calls: usize,
    /// Skip the KL quadrature.
    #[arg(long)]
    pub no_kl: bool,
    /// Skip the PDF slice images.
    #[arg(long)]
    pub no_slices: bool,
    /// Output folder.
    #[arg(long, default_value = "docs")]
    pub out: PathBuf,
    /// Model whose shipped point is the headline.
    #[arg(long, default_value = "conductor-ggx-a0.3-cu-disk")]
    pub headline: String,
    /// Print the points as JSON on stdout too.
    #[arg(long)]
    pub json: bool,
    /// Re-render the report from a `tradeoff.json` written earlier instead of measuring
    /// (the table, plot and headline; slices are drawn anew unless --no-slices).
    #[arg(long)]
    pub from: Option<PathBuf>,
}

/// The command line that reproduces `args` (for the report's header).
fn command_line(args: &TradeoffArgs) -> String {
    let mut s = String::from("cargo run --release -p diffbsdf-cli --bin diffbsdf -- tradeoff");
    let steps: Vec<String> = args.steps.iter().map(|n| n.to_string()).collect();
    if steps.join(",") != "1,2,4,8,16,32" {
        s += &format!(" --steps {}", steps.join(","));
    }
    for o in &args.only {
        s += &format!(" --only {o}");
    }
    if args.no_f16 {
        s += " --no-f16";
    }
    if args.samples != 1 << 14 {
        s += &format!(" --samples {}", args.samples);
    }
    if args.no_kl {
        s += " --no-kl";
    }
    s
}

fn bar(total: usize) -> ProgressBar {
    let bar = ProgressBar::new(total as u64);
    if let Ok(style) =
        ProgressStyle::with_template("tradeoff [{bar:32}] {pos}/{len} {msg} ({elapsed})")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// Runs `diffbsdf tradeoff`.
pub fn run(args: TradeoffArgs, out: &mut dyn std::io::Write) -> Result<(), CommandError> {
    let models = load_catalog(&args.models, &args.only).map_err(CommandError::Catalog)?;
    let cfg = SweepConfig {
        steps: args.steps.clone(),
        f16: !args.no_f16,
        samples: args.samples,
        timing_calls: args.timing_calls,
        kl: (!args.no_kl).then_some(KlGrid { theta: 32, phi: 64 }),
        ..SweepConfig::default()
    };
    let record: SweepRecord = match &args.from {
        Some(path) => {
            let bytes = std::fs::read(path).map_err(|e| CommandError::Io(path.clone(), e))?;
            serde_json::from_slice(&bytes).map_err(|e| CommandError::Json(e.to_string()))?
        }
        None => {
            let progress = bar(sweep::point_count(&models, &cfg));
            let points: Vec<Point> = sweep::sweep(&models, &cfg, &|p| {
                progress.set_message(format!("{} {} N={}", p.model, p.precision, p.steps));
                progress.inc(1);
            })
            .map_err(CommandError::Sweep)?;
            progress.finish();
            SweepRecord {
                command: command_line(&args),
                samples: cfg.samples,
                timing_calls: cfg.timing_calls,
                timing_rounds: cost::TIMING_ROUNDS,
                cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
                points,
            }
        }
    };
    let points = &record.points;
    std::fs::create_dir_all(&args.out).map_err(|e| CommandError::Io(args.out.clone(), e))?;
    let md = format!(
        "# What accuracy costs in time\n\nProduced by `{}` ({} samples per `wi` and sampler, {} timed calls per entry point{}, {} logical cores; metrics as defined in `docs/math.md`, \"Metrics\"). Plot: [tradeoff.svg](tradeoff.svg) (x: time of a direction + PDF over the material's own sample; y: mean RV; open circles: the material's own sampler at x = 1; f16 curves thin with triangles). PDF slices, labelled: `slices/NAME.svg` (the bare images: `slices/NAME.png`).\n\n![accuracy vs time](tradeoff.svg)\n\n{}",
        record.command,
        record.samples,
        record.timing_calls,
        match record.timing_rounds {
            0 | 1 => String::new(),
            r => format!(" in {r} interleaved rounds, the median round"),
        },
        record.cores,
        markdown::render(points, &args.headline)
    );
    write_file(&args.out.join("tradeoff.md"), md.as_bytes())?;
    let json =
        serde_json::to_string_pretty(&record).map_err(|e| CommandError::Json(e.to_string()))?;
    write_file(&args.out.join("tradeoff.json"), json.as_bytes())?;
    let svg = args.out.join("tradeoff.svg");
    plot::write_svg(points, &svg, "diffbsdf: accuracy vs time")
        .map_err(|e| CommandError::Sweep(SweepError::Image(svg.display().to_string(), e)))?;
    if !args.no_slices {
        let dir = args.out.join("slices");
        std::fs::create_dir_all(&dir).map_err(|e| CommandError::Io(dir.clone(), e))?;
        for m in &models {
            let material = parse_spec(&m.spec).map_err(CommandError::Spec)?;
            let model = AnyModel::from_blob(&m.f32_blob)?;
            let sphere = model.def().domain.is_spherical();
            slices::write_png(
                &model,
                material.as_ref(),
                sphere,
                &dir.join(format!("{}.png", m.name)),
            )
            .map_err(CommandError::Sweep)?;
        }
    }
    if args.json {
        return print_json(&record, out);
    }
    let head = markdown::headline(points, &args.headline).unwrap_or_default();
    writeln!(
        out,
        "{head}\nwrote {} (table), tradeoff.json, tradeoff.svg{}",
        args.out.join("tradeoff.md").display(),
        if args.no_slices {
            ""
        } else {
            ", slices/*.png and their labelled slices/*.svg"
        }
    )
    .map_err(CommandError::Output)
}
