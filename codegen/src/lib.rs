//! # diffbsdf-codegen — the sampler as GLSL, WGSL or a standalone C header
//!
//! Reads a weight blob and emits code that samples directions and evaluates PDFs exactly
//! as the `diffbsdf` kernel does: the same encoding, the same nets (with hand-derived
//! Jacobians), the same base distributions, the same Euler flow and the same Newton
//! inverse.
//!
//! ```
//! # fn demo(blob: &[u8]) -> Result<(), diffbsdf_codegen::Error> {
//! use diffbsdf_codegen::{generate, Language, Options};
//! let glsl = generate(blob, &Options::new(Language::Glsl))?;
//! # let _ = glsl; Ok(()) }
//! ```
//!
//! Layout (naga-shaped): [`desc`] is the one model description every writer reads,
//! `emit/` writes the algorithm once over a [`dialect::Dialect`] (one file per kernel
//! concept, opposite the kernel file it mirrors, every constant read from
//! `diffbsdf::spec`), and each language module (`glsl`, `wgsl`, `c`) supplies the syntax,
//! its reserved words and its public entry points. `code.rs` holds the shared indent
//! buffer and [`code::Namer`].
//!
//! Output is deterministic (a function of the blob bytes and the options only).

#![forbid(unsafe_code)]

mod c;
pub mod cli;
pub mod code;
pub mod desc;
pub mod dialect;
mod emit;
mod glsl;
pub mod set;
mod wgsl;

use core::fmt;
pub use desc::ModelDesc;
pub use set::{generate_set, GroupBuffer, Material, SetCode};

/// Target language.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Language {
    /// Vulkan GLSL 450, to be `#include`d (`GL_GOOGLE_include_directive`) or pasted.
    Glsl,
    /// WGSL.
    Wgsl,
    /// A standalone C99 header (static inline, needs only `<math.h>`; also valid C++).
    C,
}

/// Arithmetic of the networks in the generated code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Float {
    /// Everything in f32: agrees with the kernel to 1e-5.
    F32,
    /// Weights and network activations in f16 (GLSL
    /// `GL_EXT_shader_explicit_arithmetic_types_float16`, WGSL `enable f16;`); the
    /// encoding, flow state, Jacobian determinants and densities stay f32. Not for C.
    F16,
}

/// Which public functions to emit; only the helpers they need are emitted with them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EntryPoints {
    /// `sample_direction(wi, u, steps)`: a direction, no PDF (no Jacobians).
    pub direction: bool,
    /// `sample(wi, u, steps)`: a direction and its PDF.
    pub sample: bool,
    /// `pdf(wi, wo, steps)`: the PDF of a given direction (exact inverse).
    pub pdf: bool,
}

impl EntryPoints {
    /// All three.
    pub const ALL: EntryPoints = EntryPoints {
        direction: true,
        sample: true,
        pdf: true,
    };

    /// Each entry point alone (a shader compiled for one of them carries only its code).
    pub const EACH_ALONE: [EntryPoints; 3] = [
        EntryPoints {
            direction: true,
            sample: false,
            pdf: false,
        },
        EntryPoints {
            direction: false,
            sample: true,
            pdf: false,
        },
        EntryPoints {
            direction: false,
            sample: false,
            pdf: true,
        },
    ];
}

/// Where the generated code reads the parameters from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weights {
    /// Baked in as a constant array.
    Baked,
    /// Read from a buffer of f32 holding the blob's parameters in blob order
    /// (`docs/codegen.md`); every public function takes the material's offset in floats
    /// (GLSL/WGSL: `base`; C: a `const float *params` pointer). GLSL binds it as an
    /// std430 storage buffer at (`set`, `binding`), WGSL at `@group(set) @binding(binding)`.
    Buffer { set: u32, binding: u32 },
}

/// What to generate.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Options {
    pub language: Language,
    pub float: Float,
    pub entry_points: EntryPoints,
    pub weights: Weights,
    /// Prefix of every generated name; default `diffbsdf_<model name>`.
    pub prefix: Option<String>,
    /// The networks' multiply-adds as fused multiply-adds (`fmaf` in C, `fma` in GLSL and
    /// WGSL), as the kernel built with its `fma` feature computes them
    /// ([`diffbsdf::spec::FUSED_MULTIPLY_ADD`]); otherwise a product and a sum, each rounded, as the
    /// default kernel computes them.
    pub fused: bool,
}

impl Options {
    /// f32, all entry points, baked weights, default prefix.
    pub fn new(language: Language) -> Self {
        Options {
            language,
            float: Float::F32,
            entry_points: EntryPoints::ALL,
            weights: Weights::Baked,
            prefix: None,
            fused: false,
        }
    }
}

/// Why nothing was generated.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Error {
    /// The blob is not valid.
    Blob(diffbsdf::BlobError),
    /// No entry point was asked for.
    NoEntryPoints,
    /// The combination of options is not supported (e.g. f16 in C).
    Unsupported(&'static str),
    /// A weight does not fit in f16.
    NotRepresentableInF16 { index: usize },
    /// A bug in the generator.
    Internal(&'static str),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Blob(e) => write!(f, "invalid model blob: {e}"),
            Error::NoEntryPoints => write!(f, "no entry point requested"),
            Error::Unsupported(what) => write!(f, "unsupported: {what}"),
            Error::NotRepresentableInF16 { index } => {
                write!(f, "parameter {index} does not fit in f16")
            }
            Error::Internal(what) => write!(f, "internal error: {what}"),
        }
    }
}

impl std::error::Error for Error {}

/// Generates code for the model in `blob`.
pub fn generate(blob: &[u8], options: &Options) -> Result<String, Error> {
    let model = ModelDesc::from_blob(blob)?;
    generate_from(&model, options)
}

/// Generates code for an already parsed model.
pub fn generate_from(model: &ModelDesc, options: &Options) -> Result<String, Error> {
    let e = options.entry_points;
    if !(e.direction || e.sample || e.pdf) {
        return Err(Error::NoEntryPoints);
    }
    if options.float == Float::F16 {
        if options.language == Language::C {
            return Err(Error::Unsupported("f16 arithmetic in the C header"));
        }
        if let Some(index) = model
            .params
            .iter()
            .position(|w| !half::f16::from_f32(*w).is_finite())
        {
            return Err(Error::NotRepresentableInF16 { index });
        }
    }
    Ok(match options.language {
        Language::Glsl => glsl::write(model, options),
        Language::Wgsl => wgsl::write(model, options),
        Language::C => c::write(model, options),
    })
}

/// The comment lines every output starts with (without comment markers).
pub(crate) fn header_lines(model: &ModelDesc, options: &Options, prefix: &str) -> Vec<String> {
    let d = &model.def;
    let domain = match d.domain {
        diffbsdf::Domain::Disk => "disk (BRDF, upper hemisphere)",
        diffbsdf::Domain::Sphere => "sphere (full BSDF)",
        diffbsdf::Domain::Equatorial => "equatorial sphere (full BSDF, pole on the y axis)",
        diffbsdf::Domain::HalfVector => "half vector on the disk (BRDF, upper hemisphere)",
    };
    let e = options.entry_points;
    let mut entries = Vec::new();
    for (on, name) in [
        (e.direction, "sample_direction"),
        (e.sample, "sample"),
        (e.pdf, "pdf"),
    ] {
        if on {
            entries.push(format!("{prefix}_{name}"));
        }
    }
    let name = if d.name.as_str().is_empty() {
        "(unnamed)"
    } else {
        d.name.as_str()
    };
    vec![
        format!(
            "generated by diffbsdf-codegen (blob format version {}) \u{2014} do not edit",
            diffbsdf::internals::blob::VERSION
        ),
        format!("model \"{name}\", blob CRC-32 {:08x}, {} parameters", model.crc32, model.params.len()),
        format!(
            "domain {domain}{}{}{}; base net {}x{} ({} freqs), velocity net {}x{} ({} freqs); {} default steps",
            match (d.isotropic, d.fold) {
                (true, _) => ", isotropic (nets see wi turned to phi = 0)",
                (false, diffbsdf::IncidentFold::HalfTurn) => ", folded by a half turn (nets see phi_i in [-pi, 0])",
                (false, diffbsdf::IncidentFold::Quarter) => ", folded into a quarter turn (nets see phi_i in [-pi, -pi/2])",
                (false, diffbsdf::IncidentFold::None) => "",
            },
            if d.domain.is_spherical() && !d.accepts_incident_z(-1.0) { ", wi above the surface only" } else { "" },
            match (d.standardized, d.standard_warp) {
                (true, true) => ", flow in the base's standard coordinates, compressed by K asinh(z / K)",
                (true, false) => ", flow in the base's standard coordinates",
                _ => "",
            },
            d.base.hidden_layers, d.base.width, d.base.freqs, d.velocity.hidden_layers,
            d.velocity.width, d.velocity.freqs, d.default_steps
        ),
        format!(
            "arithmetic {}; weights {}",
            match (options.float, options.fused) {
                (Float::F32, false) => "f32",
                (Float::F32, true) => "f32, the networks' multiply-adds fused",
                (Float::F16, false) => "f16 networks, f32 flow state and densities",
                (Float::F16, true) => "f16 networks (multiply-adds fused), f32 flow state and densities",
            },
            match options.weights {
                Weights::Baked => "baked in".to_string(),
                Weights::Buffer { set, binding } => format!(
                    "read from a buffer of {} f32 per material (set/group {set}, binding {binding}; layout in docs/codegen.md)",
                    model.params.len()
                ),
            }
        ),
        format!("entry points: {}", entries.join(", ")),
        "directions in the local shading frame (z = normal), wi pointing away from the surface;".into(),
        "PDFs per unit solid angle; steps = 0 uses the default; invalid results are all zero.".into(),
    ]
}

/// Formats an f32 so that it parses back to the same value (`1.0`, `1e-7`, `-0.25`).
pub(crate) fn float_repr(v: f32) -> String {
    let s = format!("{v:?}");
    if s.contains('.') || s.contains('e') || s.contains("inf") || s.contains("NaN") {
        s
    } else {
        format!("{s}.0")
    }
}

/// The default name prefix, made legal by `namer`.
pub(crate) fn prefix_for(model: &ModelDesc, options: &Options, namer: &code::Namer) -> String {
    match &options.prefix {
        Some(p) => namer.ident(p),
        None => namer.ident(&format!("diffbsdf_{}", model.def.name.as_str())),
    }
}
