//! The command line shared by `diffbsdf-codegen` and `diffbsdf codegen` (clap).

use crate::set::{generate_set, Material};
use crate::{generate_from, EntryPoints, Float, Language, ModelDesc, Options, Weights};
use clap::{Args, ValueEnum};
use std::fmt;
use std::path::{Path, PathBuf};

/// Target language.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Lang {
    /// Vulkan GLSL 450.
    Glsl,
    /// WGSL.
    Wgsl,
    /// A standalone C99 header.
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

/// Arguments: one blob gives one model's code; several give the code of the set (only
/// the architectures and entry points it uses; see `docs/codegen.md`).
#[derive(Debug, Args)]
pub struct CodegenArgs {
    /// The model blob(s).
    #[arg(required = true)]
    pub models: Vec<PathBuf>,
    /// Target language.
    #[arg(long, value_enum)]
    pub lang: Lang,
    /// Evaluate the networks in f16 (GLSL, WGSL).
    #[arg(long)]
    pub f16: bool,
    /// Fuse the networks' multiply-adds (`fmaf` / `fma`), as the kernel built with its
    /// `fma` feature computes them; C callers then compile for a CPU with FMA (`-mfma`),
    /// where `fmaf` is one instruction.
    #[arg(long)]
    pub fma: bool,
    /// Entry points to emit (comma separated); all by default.
    #[arg(long, value_enum, value_delimiter = ',')]
    pub entry: Vec<Entry>,
    /// Read the weights from a buffer instead of baking them in.
    #[arg(long)]
    pub buffer: bool,
    /// Descriptor set / WGSL group of the weight buffer.
    #[arg(long, default_value_t = 0)]
    pub set: u32,
    /// Binding of the (first) weight buffer.
    #[arg(long, default_value_t = 0)]
    pub binding: u32,
    /// Prefix of every generated name.
    #[arg(long)]
    pub prefix: Option<String>,
    /// Output file (stdout if absent).
    #[arg(short, long)]
    pub out: Option<PathBuf>,
    /// With --buffer: write each architecture group's weights (little-endian f32, the
    /// buffer's contents) to `DIR/<group prefix>.f32`.
    #[arg(long)]
    pub params_dir: Option<PathBuf>,
}

/// Why code generation from the command line failed.
#[derive(Debug)]
pub enum CodegenError {
    /// Reading a blob or writing an output.
    Io(PathBuf, std::io::Error),
    /// The generator refused (bad blob, f16 in C, ...).
    Generate(PathBuf, crate::Error),
    /// `--params-dir` without `--buffer`.
    ParamsWithoutBuffer,
}

impl fmt::Display for CodegenError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CodegenError::Io(p, e) => write!(f, "{}: {e}", p.display()),
            CodegenError::Generate(p, e) => {
                write!(f, "{}: code generation failed: {e}", p.display())
            }
            CodegenError::ParamsWithoutBuffer => {
                write!(
                    f,
                    "--params-dir needs --buffer (baked weights need no buffer)"
                )
            }
        }
    }
}

impl std::error::Error for CodegenError {}

impl CodegenArgs {
    /// The generator options the arguments ask for.
    pub fn options(&self) -> Options {
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
        o.fused = self.fma;
        o
    }
}

/// Writes `bytes` to `path`, creating its folder.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), CodegenError> {
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| CodegenError::Io(parent.to_path_buf(), e))?;
    }
    std::fs::write(path, bytes).map_err(|e| CodegenError::Io(path.to_path_buf(), e))
}

fn read(path: &Path) -> Result<Vec<u8>, CodegenError> {
    std::fs::read(path).map_err(|e| CodegenError::Io(path.to_path_buf(), e))
}

/// The generated code, and the group buffers to write (buffer mode, several models).
fn code_of(args: &CodegenArgs) -> Result<(String, Vec<crate::GroupBuffer>), CodegenError> {
    let options = args.options();
    if let [one] = args.models.as_slice() {
        let blob = read(one)?;
        let desc =
            ModelDesc::from_blob(&blob).map_err(|e| CodegenError::Generate(one.clone(), e))?;
        let code =
            generate_from(&desc, &options).map_err(|e| CodegenError::Generate(one.clone(), e))?;
        let buffers = match options.weights {
            Weights::Baked => Vec::new(),
            Weights::Buffer { binding, .. } => vec![crate::GroupBuffer {
                prefix: options.prefix.clone().unwrap_or_else(|| "params".into()),
                binding,
                params: desc.params,
            }],
        };
        return Ok((code, buffers));
    }
    let mut materials = Vec::with_capacity(args.models.len());
    for path in &args.models {
        let blob = read(path)?;
        let model =
            ModelDesc::from_blob(&blob).map_err(|e| CodegenError::Generate(path.clone(), e))?;
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("model");
        materials.push(Material {
            name: stem.to_owned(),
            model,
        });
    }
    let first = args.models[0].clone();
    let set = generate_set(&materials, &options).map_err(|e| CodegenError::Generate(first, e))?;
    Ok((set.code, set.buffers))
}

/// Runs the command: the code to `--out` (or `out`), the buffers to `--params-dir`.
pub fn run(args: &CodegenArgs, out: &mut dyn std::io::Write) -> Result<(), CodegenError> {
    if args.params_dir.is_some() && !args.buffer {
        return Err(CodegenError::ParamsWithoutBuffer);
    }
    let (code, buffers) = code_of(args)?;
    if let Some(dir) = &args.params_dir {
        for b in &buffers {
            let bytes: Vec<u8> = b.params.iter().flat_map(|w| w.to_le_bytes()).collect();
            write_file(&dir.join(format!("{}.f32", b.prefix)), &bytes)?;
        }
    }
    match &args.out {
        Some(path) => write_file(path, code.as_bytes()),
        None => out
            .write_all(code.as_bytes())
            .map_err(|e| CodegenError::Io(PathBuf::from("<stdout>"), e)),
    }
}
