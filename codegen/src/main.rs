//! `diffbsdf-codegen`: emits GLSL, WGSL or a standalone C header for one model blob or a
//! set of them (the same command as `diffbsdf codegen`).

use clap::Parser;
use diffbsdf_codegen::cli::{run, CodegenArgs};
use std::process::ExitCode;

/// GLSL, WGSL or a standalone C header from diffbsdf model blobs.
#[derive(Debug, Parser)]
#[command(name = "diffbsdf-codegen", version, about)]
struct Cli {
    #[command(flatten)]
    args: CodegenArgs,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(&cli.args, &mut std::io::stdout().lock()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
