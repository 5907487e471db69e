//! The shipped models of a folder: every `NAME.dbsdf` (f32) with its f16 twin
//! `NAME.f16.dbsdf` and the material spec recorded in `NAME.report.json` by `fit --json`.

use std::fmt;
use std::path::{Path, PathBuf};

/// One shipped model.
#[derive(Clone, Debug)]
pub struct ShippedModel {
    /// File stem, e.g. `conductor-ggx-a0.3-cu-disk`.
    pub name: String,
    /// The material spec it was trained for.
    pub spec: String,
    /// The f32 blob.
    pub f32_blob: Vec<u8>,
    /// The f16 blob, if present.
    pub f16_blob: Option<Vec<u8>>,
}

/// Why a folder could not be read as a catalog.
#[derive(Debug)]
pub enum CatalogError {
    /// A file could not be read.
    Io(PathBuf, std::io::Error),
    /// A report is not JSON or has no `"material"` string.
    Report(PathBuf, String),
    /// The folder holds no model with a report.
    Empty(PathBuf),
}

impl fmt::Display for CatalogError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CatalogError::Io(p, e) => write!(f, "{}: {e}", p.display()),
            CatalogError::Report(p, e) => write!(f, "{}: {e}", p.display()),
            CatalogError::Empty(p) => write!(
                f,
                "{}: no NAME.dbsdf with a NAME.report.json beside it",
                p.display()
            ),
        }
    }
}

impl std::error::Error for CatalogError {}

fn read(path: &Path) -> Result<Vec<u8>, CatalogError> {
    std::fs::read(path).map_err(|e| CatalogError::Io(path.to_path_buf(), e))
}

/// The material spec a `fit --json` report records.
fn spec_of(report: &Path) -> Result<String, CatalogError> {
    let bytes = read(report)?;
    let v: serde_json::Value = serde_json::from_slice(&bytes)
        .map_err(|e| CatalogError::Report(report.to_path_buf(), e.to_string()))?;
    v.get("material")
        .and_then(|m| m.as_str())
        .map(str::to_owned)
        .ok_or_else(|| CatalogError::Report(report.to_path_buf(), "no \"material\"".into()))
}

/// Every model in `dir` with a report, sorted by name; `only` keeps the names it lists.
pub fn load_catalog(dir: &Path, only: &[String]) -> Result<Vec<ShippedModel>, CatalogError> {
    let entries = std::fs::read_dir(dir).map_err(|e| CatalogError::Io(dir.to_path_buf(), e))?;
    let mut names: Vec<String> = entries
        .filter_map(|e| e.ok())
        .filter_map(|e| e.file_name().to_str().map(str::to_owned))
        .filter_map(|f| f.strip_suffix(".report.json").map(str::to_owned))
        .filter(|n| only.is_empty() || only.iter().any(|o| o == n))
        .collect();
    names.sort();
    let mut out = Vec::with_capacity(names.len());
    for name in names {
        let f16 = dir.join(format!("{name}.f16.dbsdf"));
        out.push(ShippedModel {
            spec: spec_of(&dir.join(format!("{name}.report.json")))?,
            f32_blob: read(&dir.join(format!("{name}.dbsdf")))?,
            f16_blob: if f16.exists() {
                Some(read(&f16)?)
            } else {
                None
            },
            name,
        });
    }
    if out.is_empty() {
        return Err(CatalogError::Empty(dir.to_path_buf()));
    }
    Ok(out)
}
