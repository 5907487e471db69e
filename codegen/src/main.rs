//! `diffbsdf-codegen`: emits GLSL, WGSL or a standalone C header for a model blob.

use diffbsdf_codegen::{generate, EntryPoints, Float, Language, Options, Weights};
use std::process::ExitCode;

const USAGE: &str = "usage: diffbsdf-codegen --lang glsl|wgsl|c [--f16] \
[--entry direction,sample,pdf] [--buffer [--set N] [--binding N]] [--prefix NAME] \
[-o OUT] MODEL.bin";

/// Why the command line could not be used.
#[derive(Debug)]
enum CliError {
    Usage(String),
    Io(String),
    Generate(diffbsdf_codegen::Error),
}

fn number(v: Option<String>, flag: &str) -> Result<u32, CliError> {
    v.and_then(|s| s.parse().ok())
        .ok_or_else(|| CliError::Usage(format!("{flag} needs a number")))
}

fn run() -> Result<(), CliError> {
    let mut args = std::env::args().skip(1);
    let mut lang = None;
    let mut opts = Options::new(Language::Glsl);
    let (mut buffer, mut set, mut binding) = (false, 0, 0);
    let mut out = None;
    let mut input = None;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--lang" => {
                lang = Some(match args.next().as_deref() {
                    Some("glsl") => Language::Glsl,
                    Some("wgsl") => Language::Wgsl,
                    Some("c") => Language::C,
                    _ => return Err(CliError::Usage("--lang takes glsl, wgsl or c".into())),
                })
            }
            "--f16" => opts.float = Float::F16,
            "--entry" => {
                let list = args.next().unwrap_or_default();
                let mut e = EntryPoints {
                    direction: false,
                    sample: false,
                    pdf: false,
                };
                for item in list.split(',') {
                    match item {
                        "direction" => e.direction = true,
                        "sample" => e.sample = true,
                        "pdf" => e.pdf = true,
                        other => {
                            return Err(CliError::Usage(format!("unknown entry point `{other}`")))
                        }
                    }
                }
                opts.entry_points = e;
            }
            "--buffer" => buffer = true,
            "--set" => set = number(args.next(), "--set")?,
            "--binding" => binding = number(args.next(), "--binding")?,
            "--prefix" => opts.prefix = args.next(),
            "-o" => out = args.next(),
            "-h" | "--help" => {
                println!("{USAGE}");
                return Ok(());
            }
            _ if input.is_none() && !a.starts_with('-') => input = Some(a),
            _ => return Err(CliError::Usage(format!("unexpected argument `{a}`"))),
        }
    }
    opts.language = lang.ok_or_else(|| CliError::Usage("--lang is required".into()))?;
    if buffer {
        opts.weights = Weights::Buffer { set, binding };
    }
    let input = input.ok_or_else(|| CliError::Usage("no model blob given".into()))?;
    let blob = std::fs::read(&input).map_err(|e| CliError::Io(format!("{input}: {e}")))?;
    let code = generate(&blob, &opts).map_err(CliError::Generate)?;
    match out {
        Some(path) => std::fs::write(&path, code).map_err(|e| CliError::Io(format!("{path}: {e}"))),
        None => {
            print!("{code}");
            Ok(())
        }
    }
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(CliError::Usage(m)) => {
            eprintln!("error: {m}\n{USAGE}");
            ExitCode::from(2)
        }
        Err(CliError::Io(m)) => {
            eprintln!("error: {m}");
            ExitCode::FAILURE
        }
        Err(CliError::Generate(e)) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
