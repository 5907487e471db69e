//! `diffbsdf info`: what a weight blob is (its definition, size and checksum) without
//! running it. The blob is parsed and validated as the kernel loads it
//! ([`diffbsdf::internals::blob::Blob::parse`]), so a blob of a shape this build does not
//! compile is still described; a corrupt one fails with the kernel's typed error.

use crate::cli::blob::BlobCommandError;
use clap::Args;
use diffbsdf::internals::blob::{Blob, VERSION};
use diffbsdf::{IncidentFold, ModelDef, Precision, TableGrid};
use serde::Serialize;
use std::io::Write;
use std::path::PathBuf;

/// `diffbsdf info BLOB [--json]`
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The weight blob (`.dbsdf`).
    pub blob: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// What `info` prints, field by field (`--json`).
#[derive(Debug, Serialize)]
pub struct BlobInfo {
    /// The model's name.
    pub name: String,
    /// Bytes of the blob file.
    pub bytes: usize,
    /// The blob format's version.
    pub format_version: u16,
    /// The CRC-32 stored at the blob's end.
    pub crc32: String,
    /// `disk`, `sphere`, `equatorial` or `half-vector`.
    pub domain: &'static str,
    /// `f32` or `f16`.
    pub precision: &'static str,
    /// Euler steps for `steps = 0`.
    pub default_steps: u16,
    /// Base net: hidden layers, width, encoding frequencies.
    pub base_net: [usize; 3],
    /// Velocity net: hidden layers, width, encoding frequencies.
    pub velocity_net: [usize; 3],
    /// Stored parameters (both nets and the latent table).
    pub params: usize,
    /// Of them, the latent table's.
    pub table_params: usize,
    /// `isotropic`, `every azimuth`, `half turn` or `quarter turn`: what the nets see of
    /// `wi`'s azimuth.
    pub incident_frame: &'static str,
    /// The same in a sentence.
    #[serde(skip)]
    frame_text: &'static str,
    /// `above the surface` or `whole sphere`.
    pub incident_range: &'static str,
    /// `chart`, `standard` or `warped standard`.
    pub flow_coordinates: &'static str,
    /// The latent table, or `none`.
    pub latent_table: String,
}

impl BlobInfo {
    /// Describes a parsed definition of a blob of `bytes` bytes ending in `crc32`.
    #[must_use]
    pub fn new(def: &ModelDef, bytes: usize, crc32: u32) -> Self {
        let (incident_frame, frame_text) = match (def.isotropic, def.fold) {
            (true, _) => ("isotropic", "isotropic: the nets see wi turned to phi = 0"),
            (false, IncidentFold::None) => (
                "every azimuth",
                "anisotropic: the nets see wi at every azimuth",
            ),
            (false, IncidentFold::HalfTurn) => (
                "half turn",
                "folded by a half turn: the nets see phi_i in [-pi, 0]",
            ),
            (false, IncidentFold::Quarter) => (
                "quarter turn",
                "folded into a quarter turn: the nets see phi_i in [-pi, -pi/2]",
            ),
        };
        let net = |s: diffbsdf::NetShape| {
            [
                usize::from(s.hidden_layers),
                usize::from(s.width),
                usize::from(s.freqs),
            ]
        };
        BlobInfo {
            name: def.name.as_str().to_owned(),
            bytes,
            format_version: VERSION,
            crc32: format!("{crc32:08x}"),
            domain: def.domain.name(),
            precision: match def.precision {
                Precision::F32 => "f32",
                Precision::F16 => "f16",
            },
            default_steps: def.default_steps,
            base_net: net(def.base),
            velocity_net: net(def.velocity),
            params: def.param_count(),
            table_params: def.table_len(),
            incident_frame,
            frame_text,
            incident_range: if def.accepts_incident_z(-1.0) {
                "whole sphere"
            } else {
                "above the surface"
            },
            flow_coordinates: match (def.standardized, def.standard_warp) {
                (false, _) => "chart",
                (true, false) => "standard",
                (true, true) => "warped standard",
            },
            latent_table: def.latent_table.map_or_else(|| "none".to_owned(), table),
        }
    }

    /// The text form, one fact per line.
    #[must_use]
    pub fn text(&self) -> String {
        let [bl, bw, bf] = self.base_net;
        let [vl, vw, vf] = self.velocity_net;
        format!(
            "model \"{}\": {} bytes, blob format version {}, CRC-32 {}\n\
             domain: {} ({}), weights {}, {} default steps\n\
             base net {bl}x{bw} ({bf} frequencies), velocity net {vl}x{vw} ({vf} frequencies); \
             {} parameters, {} of them the latent table's\n\
             incident frame: {}; wi: {}\n\
             flow coordinates: {}\n\
             latent table: {}\n",
            self.name,
            self.bytes,
            self.format_version,
            self.crc32,
            self.domain,
            if self.domain == "sphere" || self.domain == "equatorial" {
                "BSDF"
            } else {
                "BRDF"
            },
            self.precision,
            self.default_steps,
            self.params,
            self.table_params,
            self.frame_text,
            self.incident_range,
            self.flow_coordinates,
            self.latent_table,
        )
    }
}

/// The latent table's grid in words.
fn table(grid: TableGrid) -> String {
    let cells = grid.cells();
    format!(
        "{} slices of {cells} x {cells} cells, {}, {} axes{}",
        grid.slices(),
        if grid.is_coded() {
            "8-bit codes"
        } else {
            "values of the blob's precision"
        },
        if grid.is_warped() { "warped" } else { "even" },
        if grid.is_blended() {
            ", blended layout"
        } else {
            ""
        },
    )
}

/// Runs `diffbsdf info`.
pub fn run(a: &InfoArgs, out: &mut dyn Write) -> Result<(), BlobCommandError> {
    let bytes = std::fs::read(&a.blob).map_err(|e| BlobCommandError::Read(a.blob.clone(), e))?;
    let blob = Blob::parse(&bytes).map_err(|e| BlobCommandError::Blob(a.blob.clone(), e))?;
    let tail: [u8; 4] = bytes
        .get(bytes.len().saturating_sub(4)..)
        .and_then(|t| t.try_into().ok())
        .unwrap_or([0; 4]);
    let info = BlobInfo::new(&blob.def, bytes.len(), u32::from_le_bytes(tail));
    let text = if a.json {
        let mut s = serde_json::to_string_pretty(&info)
            .map_err(|e| BlobCommandError::Json(e.to_string()))?;
        s.push('\n');
        s
    } else {
        info.text()
    };
    out.write_all(text.as_bytes()).map_err(BlobCommandError::Io)
}
