//! `diffbsdf codegen`: GLSL, WGSL or a standalone C header from one blob or a set (the
//! `diffbsdf-codegen` command line; options in `docs/codegen.md`), and [`emit_all`], the
//! five renderings the demo writes.

use diffbsdf_codegen::cli::write_file;
pub use diffbsdf_codegen::cli::{run, CodegenArgs, CodegenError};
use diffbsdf_codegen::{generate, Float, Language, Options};
use std::path::{Path, PathBuf};

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
        let path = dir.join(name);
        let code = generate(blob, &o).map_err(|e| CodegenError::Generate(path.clone(), e))?;
        write_file(&path, code.as_bytes())?;
        written.push(path);
    }
    Ok(written)
}
