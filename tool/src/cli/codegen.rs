//! `diffbsdf codegen`: GLSL, WGSL or a standalone C header from a blob (the
//! `diffbsdf-codegen` library; options in `docs/codegen.md`).

use clap::{Args, ValueEnum};
use diffbsdf_codegen::{generate, EntryPoints, Float, Language, Options, Weights};
use std::path::{Path, PathBuf};

/// Target language.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Lang {
    Glsl,
    Wgsl,
    C,
}

/// An entry point to emit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Entry {
    /// `sample_direction`: a direction, no PDF.
    Direction,
    /// `sample`: a direction and its PDF.
    Sample,
    /// `pdf`: the PDF of a given direction.
    Pdf,
}

/// Arguments of `diffbsdf codegen`.
#[derive(Debug, Args)]
pub struct CodegenArgs {
    /// The model blob.
    pub model: PathBuf,
    /// Target language.
    #[arg(long, value_enum)]
    pub lang: Lang,
    /// Evaluate the networks in f16 (GLSL, WGSL).
    #[arg(long)]
    pub f16: bool,
    /// Entry points to emit (comma separated); all by default.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub entry: Vec<Entry>,
    /// Read the weights from a buffer instead of baking them in.
    #[arg(long)]
    pub buffer: bool,
    /// Descriptor set / WGSL group of the weight buffer.
    #[arg(long, default_value_t = 0)]
    pub set: u32,
    /// Binding of the weight buffer.
    #[arg(long, default_value_t = 0)]
    pub binding: u32,
    /// Prefix of every generated name.
    #[arg(long)]
    pub prefix: Option<String>,
    /// Output file (stdout if absent).
    #[arg(short, long)]
    pub out: Option<PathBuf>,
}

/// Why `codegen` failed.
#[derive(Debug)]
pub enum CodegenError {
    /// Reading the blob or writing the output.
    Io(PathBuf, std::io::Error),
    /// The generator refused (bad blob, f16 in C, ...).
    Generate(diffbsdf_codegen::Error),
}

impl std::fmt::Display for CodegenError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CodegenError::Io(p, e) => write!(f, "{}: {e}", p.display()),
            CodegenError::Generate(e) => write!(f, "code generation failed: {e}"),
        }
    }
}

impl CodegenArgs {
    fn options(&self) -> Options {
        let mut o = Options::new(match self.lang {
            Lang::Glsl => Language::Glsl,
            Lang::Wgsl => Language::Wgsl,
            Lang::C => Language::C,
        });
        if self.f16 {
            o.float = Float::F16;
        }
        if !self.entry.is_empty() {
            o.entry_points = EntryPoints {
                direction: self.entry.contains(&Entry::Direction),
                sample: self.entry.contains(&Entry::Sample),
                pdf: self.entry.contains(&Entry::Pdf),
            };
        }
        if self.buffer {
            o.weights = Weights::Buffer {
                set: self.set,
                binding: self.binding,
            };
        }
        o.prefix = self.prefix.clone();
        o
    }
}

/// Runs `diffbsdf codegen`.
pub fn run(args: CodegenArgs, out: &mut dyn std::io::Write) -> Result<(), CodegenError> {
    let blob = std::fs::read(&args.model).map_err(|e| CodegenError::Io(args.model.clone(), e))?;
    let code = generate(&blob, &args.options()).map_err(CodegenError::Generate)?;
    match &args.out {
        Some(path) => write(path, &code),
        None => out
            .write_all(code.as_bytes())
            .map_err(|e| CodegenError::Io(PathBuf::from("<stdout>"), e)),
    }
}

/// Writes the GLSL, WGSL (f32 and f16) and C renderings of `blob` into `dir`; returns the
/// paths written.
pub fn emit_all(blob: &[u8], dir: &Path) -> Result<Vec<PathBuf>, CodegenError> {
    let cases = [
        ("model.glsl", Language::Glsl, Float::F32),
        ("model.f16.glsl", Language::Glsl, Float::F16),
        ("model.wgsl", Language::Wgsl, Float::F32),
        ("model.f16.wgsl", Language::Wgsl, Float::F16),
        ("model.h", Language::C, Float::F32),
    ];
    let mut written = Vec::new();
    for (name, language, float) in cases {
        let mut o = Options::new(language);
        o.float = float;
        let code = generate(blob, &o).map_err(CodegenError::Generate)?;
        let path = dir.join(name);
        write(&path, &code)?;
        written.push(path);
    }
    Ok(written)
}

fn write(path: &Path, code: &str) -> Result<(), CodegenError> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| CodegenError::Io(parent.to_path_buf(), e))?;
    }
    std::fs::write(path, code).map_err(|e| CodegenError::Io(path.to_path_buf(), e))
}
