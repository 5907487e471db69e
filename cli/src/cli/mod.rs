//! The `diffbsdf` command line. Each top-level subcommand lives in its own file and adds
//! one variant to [`Command`]; [`run`] dispatches.

pub mod blob;
pub mod choose;
pub mod codegen;
pub mod curve;
pub mod demo;
pub mod depth;
pub mod eval;
pub mod fit;
pub mod info;
pub mod material;
pub mod refine;
pub mod share;
pub mod table;
pub mod tradeoff;

use clap::{Parser, Subcommand};

/// diffbsdf: learned BSDF importance sampling — reference materials, training data,
/// training and evaluation.
#[derive(Debug, Parser)]
#[command(name = "diffbsdf", version, about)]
pub struct Cli {
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// Top-level subcommands. New ones (fit, eval, demo, codegen, tradeoff, curve) add a variant
/// here and a module beside this file.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Reference materials: evaluate and sample them.
    #[command(subcommand)]
    Material(material::MaterialCommand),
    /// Draw directions (and their PDFs) from a weight blob.
    Sample(blob::SampleArgs),
    /// The PDF of given directions under a weight blob (`--wo -`: rows from stdin).
    Pdf(blob::PdfArgs),
    /// What a weight blob is: its definition, size and checksum.
    Info(info::InfoArgs),
    /// Train a sampler for a material and write its blob.
    Fit(Box<fit::FitArgs>),
    /// Measure a blob's sampling quality against a material.
    Eval(eval::EvalArgs),
    /// Refine a fitted blob's student to lower its variance against its material.
    Refine(refine::RefineArgs),
    /// Fit a latent table to a fitted blob's flow against its material.
    Table(table::TableArgs),
    /// The main job: the embedded default model, its quality and cost, written to a folder.
    Demo(demo::DemoArgs),
    /// GLSL, WGSL or a standalone C header from a blob.
    Codegen(codegen::CodegenArgs),
    /// What accuracy costs in time: the shipped models over steps and precision.
    Tradeoff(tradeoff::TradeoffArgs),
    /// What accuracy costs in training: one material fitted at several teacher lengths
    /// and student depths.
    Curve(curve::CurveArgs),
}

/// Errors the command line reports before exiting with a failure status.
#[derive(Debug)]
pub enum CliError {
    /// A material command failed.
    Material(material::MaterialError),
    /// A fit, eval or demo command failed.
    Train(fit::CommandError),
    /// A codegen command failed.
    Codegen(codegen::CodegenError),
    /// A sample, pdf or info command failed.
    Blob(blob::BlobCommandError),
}

impl std::fmt::Display for CliError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CliError::Material(e) => write!(f, "{e}"),
            CliError::Train(e) => write!(f, "{e}"),
            CliError::Codegen(e) => write!(f, "{e}"),
            CliError::Blob(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for CliError {}

/// Runs a parsed command, writing results to `out`.
pub fn run(cli: Cli, out: &mut dyn std::io::Write) -> Result<(), CliError> {
    match cli.command {
        Command::Material(c) => material::run(c, out).map_err(CliError::Material),
        Command::Sample(a) => blob::run_sample(a, out).map_err(CliError::Blob),
        Command::Pdf(a) => blob::run_pdf(a, out).map_err(CliError::Blob),
        Command::Info(a) => info::run(&a, out).map_err(CliError::Blob),
        Command::Fit(a) => fit::run(*a, out).map_err(CliError::Train),
        Command::Eval(a) => eval::run(a, out).map_err(CliError::Train),
        Command::Refine(a) => refine::run(a, out).map_err(CliError::Train),
        Command::Table(a) => table::run(a, out).map_err(CliError::Train),
        Command::Demo(a) => demo::run(a, out).map_err(CliError::Train),
        Command::Codegen(a) => codegen::run(&a, out).map_err(CliError::Codegen),
        Command::Tradeoff(a) => tradeoff::run(a, out).map_err(CliError::Train),
        Command::Curve(a) => curve::run(a, out).map_err(CliError::Train),
    }
}
