//! `diffbsdf sample` and `diffbsdf pdf`: draw directions from a weight blob, or evaluate
//! its PDF, from the command line (CSV or JSON), through the kernel's runtime shape
//! dispatch [`AnyModel`].
//!
//! Directions follow the kernel's conventions (`docs/math.md`): local shading frame,
//! `z` the normal, unit vectors pointing away from the surface. A direction given on the
//! command line must be unit within the kernel's tolerance
//! ([`diffbsdf::spec::UNIT_TOLERANCE`] on `|w|^2`) unless `--normalize` is given; rows read
//! from stdin are passed to the kernel as they are (a non-unit row gets PDF 0).

use crate::cli::material::Format;
use clap::Args;
use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::spec::{MAX_STEPS, UNIT_TOLERANCE};
use diffbsdf::{AnyModel, BlobError};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use serde::Serialize;
use std::fmt;
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

/// `diffbsdf sample BLOB --wi X,Y,Z --count N`
#[derive(Debug, Args)]
pub struct SampleArgs {
    /// The weight blob (`.dbsdf`).
    pub blob: PathBuf,
    /// Incident direction: `x,y,z` (unit) or `theta,phi` in degrees.
    #[arg(long, allow_hyphen_values = true)]
    pub wi: String,
    /// Number of samples, with u drawn from a PCG64 seeded by `--seed`.
    #[arg(long, default_value_t = 10, conflicts_with = "u")]
    pub count: usize,
    /// Random seed (PCG64).
    #[arg(long, default_value_t = 0, conflicts_with = "u")]
    pub seed: u64,
    /// One sample for this u instead: `u0,u1`, each in [0, 1].
    #[arg(long, allow_hyphen_values = true)]
    pub u: Option<String>,
    /// Euler steps, 1 to 256 (`diffbsdf::spec::MAX_STEPS`; default: the blob's
    /// `default_steps`).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_STEPS)))]
    pub steps: Option<u32>,
    /// Normalise `--wi` instead of rejecting a non-unit vector.
    #[arg(long)]
    pub normalize: bool,
    /// Output format.
    #[arg(long, value_enum, default_value = "csv")]
    pub format: Format,
}

/// `diffbsdf pdf BLOB --wi X,Y,Z --wo X,Y,Z|-`
#[derive(Debug, Args)]
pub struct PdfArgs {
    /// The weight blob (`.dbsdf`).
    pub blob: PathBuf,
    /// Incident direction: `x,y,z` (unit) or `theta,phi` in degrees.
    #[arg(long, allow_hyphen_values = true)]
    pub wi: String,
    /// Outgoing direction `x,y,z` (or `theta,phi` in degrees), or `-`: one `x,y,z` row per
    /// line on stdin (blank lines and `#` comments skipped; a header line naming
    /// `wo_x,wo_y,wo_z` picks those columns, so `diffbsdf sample` output can be piped in).
    #[arg(long, allow_hyphen_values = true)]
    pub wo: String,
    /// Euler steps, 1 to 256 (`diffbsdf::spec::MAX_STEPS`; default: the blob's
    /// `default_steps`).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_STEPS)))]
    pub steps: Option<u32>,
    /// Normalise `--wi` and every `wo` instead of passing them as given.
    #[arg(long)]
    pub normalize: bool,
    /// Output format.
    #[arg(long, value_enum, default_value = "csv")]
    pub format: Format,
}

/// Why `sample` or `pdf` failed.
#[derive(Debug)]
pub enum BlobCommandError {
    /// The blob file could not be read.
    Read(PathBuf, std::io::Error),
    /// The blob is not a valid diffbsdf blob.
    Blob(PathBuf, BlobError),
    /// A direction argument did not parse or is not a usable direction.
    BadDirection {
        /// The option, e.g. `--wi`.
        arg: &'static str,
        /// What was given.
        value: String,
        /// Why it was rejected.
        why: String,
    },
    /// `--u` did not parse.
    BadU(String),
    /// A stdin row did not parse.
    BadRow {
        /// 1-based line number.
        line: usize,
        /// The line.
        text: String,
    },
    /// Reading stdin or writing the output failed.
    Io(std::io::Error),
    /// JSON encoding failed.
    Json(String),
}

impl fmt::Display for BlobCommandError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BlobCommandError::Read(p, e) => write!(f, "cannot read {}: {e}", p.display()),
            BlobCommandError::Blob(p, e) => {
                write!(f, "{} is not a valid diffbsdf blob: {e}", p.display())
            }
            BlobCommandError::BadDirection { arg, value, why } => {
                write!(f, "{arg} `{value}`: {why}")
            }
            BlobCommandError::BadU(s) => write!(
                f,
                "--u `{s}`: expected two numbers u0,u1 (each in [0, 1] for a valid sample)"
            ),
            BlobCommandError::BadRow { line, text } => write!(
                f,
                "stdin line {line}: `{text}` is not a direction (expected x,y,z)"
            ),
            BlobCommandError::Io(e) => write!(f, "I/O failed: {e}"),
            BlobCommandError::Json(e) => write!(f, "JSON encoding failed: {e}"),
        }
    }
}

impl std::error::Error for BlobCommandError {}

/// One drawn sample.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SampleRow {
    /// Index of the draw.
    pub index: usize,
    /// The random numbers used.
    pub u: [f32; 2],
    /// False for an invalid sample (it left the model's domain, or the input was refused):
    /// `wo = 0`, `pdf = 0`.
    pub valid: bool,
    /// Sampled direction.
    pub wo: [f32; 3],
    /// Its PDF per unit solid angle.
    pub pdf: f32,
}

/// One evaluated direction.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PdfRow {
    /// Index of the direction (stdin: the data row, from 0).
    pub index: usize,
    /// The direction as passed to the kernel.
    pub wo: [f32; 3],
    /// PDF per unit solid angle (0 outside the model's support or for a refused input).
    pub pdf: f32,
}

/// Loads a blob file.
pub fn load(path: &Path) -> Result<AnyModel, BlobCommandError> {
    let bytes = std::fs::read(path).map_err(|e| BlobCommandError::Read(path.to_owned(), e))?;
    AnyModel::from_blob(&bytes).map_err(|e| BlobCommandError::Blob(path.to_owned(), e))
}

fn numbers(s: &str) -> Option<Vec<f32>> {
    s.split(',')
        .map(|p| p.trim().parse::<f32>().ok())
        .collect::<Option<Vec<_>>>()
}

/// Parses a direction option: `x,y,z` or `theta,phi` in degrees. Without `normalize` a
/// Cartesian direction must be unit within the kernel's tolerance.
pub fn parse_direction(
    arg: &'static str,
    s: &str,
    normalize: bool,
) -> Result<Vec3, BlobCommandError> {
    let bad = |why: String| BlobCommandError::BadDirection {
        arg,
        value: s.to_owned(),
        why,
    };
    let v = numbers(s).ok_or_else(|| bad("expected x,y,z or theta,phi in degrees".to_owned()))?;
    if !v.iter().all(|x| x.is_finite()) {
        return Err(bad("NaN or infinite component".to_owned()));
    }
    let w = match v.as_slice() {
        [t, p] => {
            let (t, p) = (f64::from(*t).to_radians(), f64::from(*p).to_radians());
            Vec3::new(
                (t.sin() * p.cos()) as f32,
                (t.sin() * p.sin()) as f32,
                t.cos() as f32,
            )
        }
        [x, y, z] => Vec3::new(*x, *y, *z),
        _ => {
            return Err(bad(format!(
                "expected 3 numbers x,y,z or 2 numbers theta,phi in degrees, got {}",
                v.len()
            )))
        }
    };
    let l2 = w.length_squared();
    if normalize {
        w.try_normalize()
            .ok_or_else(|| bad("cannot normalise a zero vector".to_owned()))
    } else if (l2 - 1.0).abs() <= UNIT_TOLERANCE {
        Ok(w)
    } else {
        Err(bad(format!(
            "not a unit vector (|w| = {}); pass a unit vector or add --normalize",
            l2.sqrt()
        )))
    }
}

fn parse_u(s: &str) -> Result<Vec2, BlobCommandError> {
    match numbers(s).as_deref() {
        Some([a, b]) => Ok(Vec2::new(*a, *b)),
        _ => Err(BlobCommandError::BadU(s.to_owned())),
    }
}

/// The rows of `diffbsdf sample`: `us` in order, or `count` draws from a PCG64 seeded
/// with `seed`.
pub fn sample_rows(model: &AnyModel, wi: Vec3, us: &[Vec2], steps: u32) -> Vec<SampleRow> {
    us.iter()
        .enumerate()
        .map(|(index, &u)| match model.sample_steps(wi, u, steps) {
            Some(s) => SampleRow {
                index,
                u: u.to_array(),
                valid: true,
                wo: s.wo.to_array(),
                pdf: s.pdf,
            },
            None => SampleRow {
                index,
                u: u.to_array(),
                valid: false,
                wo: [0.0; 3],
                pdf: 0.0,
            },
        })
        .collect()
}

/// `count` uniform pairs in [0, 1) from a PCG64 seeded with `seed`.
pub fn seeded_us(count: usize, seed: u64) -> Vec<Vec2> {
    let mut rng = Pcg64::seed_from_u64(seed);
    (0..count)
        .map(|_| Vec2::new(rng.gen::<f32>(), rng.gen::<f32>()))
        .collect()
}

/// Reads `wo` rows (`x,y,z` per line) from `input`; see [`PdfArgs::wo`].
pub fn read_rows(input: impl BufRead, normalize: bool) -> Result<Vec<Vec3>, BlobCommandError> {
    let mut columns: Option<[usize; 3]> = None;
    let mut rows = Vec::new();
    let mut first = true;
    for (i, line) in input.lines().enumerate() {
        let line = line.map_err(BlobCommandError::Io)?;
        let text = line.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = text.split(',').map(str::trim).collect();
        if first {
            first = false;
            let find = |name: &str| cells.iter().position(|c| c.eq_ignore_ascii_case(name));
            if let (Some(x), Some(y), Some(z)) = (find("wo_x"), find("wo_y"), find("wo_z")) {
                columns = Some([x, y, z]);
                continue;
            }
        }
        let bad = || BlobCommandError::BadRow {
            line: i + 1,
            text: text.to_owned(),
        };
        let picked: Vec<&str> = match columns {
            Some(c) => c
                .iter()
                .map(|&k| cells.get(k).copied())
                .collect::<Option<Vec<_>>>()
                .ok_or_else(bad)?,
            None if cells.len() == 3 => cells,
            None => return Err(bad()),
        };
        let v = picked
            .iter()
            .map(|c| c.parse::<f32>().ok())
            .collect::<Option<Vec<_>>>()
            .ok_or_else(bad)?;
        let w = Vec3::new(v[0], v[1], v[2]);
        rows.push(if normalize {
            w.try_normalize().unwrap_or(w)
        } else {
            w
        });
    }
    Ok(rows)
}

/// The rows of `diffbsdf pdf`.
pub fn pdf_rows(model: &AnyModel, wi: Vec3, wos: &[Vec3], steps: u32) -> Vec<PdfRow> {
    wos.iter()
        .enumerate()
        .map(|(index, &wo)| PdfRow {
            index,
            wo: wo.to_array(),
            pdf: model.pdf_steps(wi, wo, steps),
        })
        .collect()
}

fn steps_or_default(model: &AnyModel, steps: Option<u32>) -> u32 {
    steps.unwrap_or_else(|| u32::from(model.def().default_steps))
}

fn write_json<T: Serialize>(out: &mut dyn Write, rows: &T) -> Result<(), BlobCommandError> {
    let s =
        serde_json::to_string_pretty(rows).map_err(|e| BlobCommandError::Json(e.to_string()))?;
    writeln!(out, "{s}").map_err(BlobCommandError::Io)
}

/// Runs `diffbsdf sample`. CSV columns: `index,u0,u1,valid,wo_x,wo_y,wo_z,pdf`; numbers
/// are printed so that they read back to the same f32.
pub fn run_sample(a: SampleArgs, out: &mut dyn Write) -> Result<(), BlobCommandError> {
    let model = load(&a.blob)?;
    let wi = parse_direction("--wi", &a.wi, a.normalize)?;
    let us = match &a.u {
        Some(s) => vec![parse_u(s)?],
        None => seeded_us(a.count, a.seed),
    };
    let rows = sample_rows(&model, wi, &us, steps_or_default(&model, a.steps));
    match a.format {
        Format::Json => write_json(out, &rows),
        Format::Csv => {
            let io = BlobCommandError::Io;
            writeln!(out, "index,u0,u1,valid,wo_x,wo_y,wo_z,pdf").map_err(io)?;
            for r in rows {
                writeln!(
                    out,
                    "{},{},{},{},{},{},{},{}",
                    r.index, r.u[0], r.u[1], r.valid, r.wo[0], r.wo[1], r.wo[2], r.pdf
                )
                .map_err(io)?;
            }
            Ok(())
        }
    }
}

/// Runs `diffbsdf pdf` (`--wo -` reads the rows from stdin). CSV columns:
/// `index,wo_x,wo_y,wo_z,pdf`.
pub fn run_pdf(a: PdfArgs, out: &mut dyn Write) -> Result<(), BlobCommandError> {
    let model = load(&a.blob)?;
    let wi = parse_direction("--wi", &a.wi, a.normalize)?;
    let wos = if a.wo.trim() == "-" {
        read_rows(std::io::stdin().lock(), a.normalize)?
    } else {
        vec![parse_direction("--wo", &a.wo, a.normalize)?]
    };
    let rows = pdf_rows(&model, wi, &wos, steps_or_default(&model, a.steps));
    match a.format {
        Format::Json => write_json(out, &rows),
        Format::Csv => {
            let io = BlobCommandError::Io;
            writeln!(out, "index,wo_x,wo_y,wo_z,pdf").map_err(io)?;
            for r in rows {
                writeln!(
                    out,
                    "{},{},{},{},{}",
                    r.index, r.wo[0], r.wo[1], r.wo[2], r.pdf
                )
                .map_err(io)?;
            }
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_parse_or_explain() {
        assert_eq!(
            parse_direction("--wi", "0,0,1", false).unwrap(),
            Vec3::new(0.0, 0.0, 1.0)
        );
        let w = parse_direction("--wi", "90,0", false).unwrap();
        assert!((w.x - 1.0).abs() < 1e-6 && w.z.abs() < 1e-6);
        for bad in ["0,0,2", "1", "a,b,c", "0,0,nan", "0,0,0", "1,2,3,4", ""] {
            let e = parse_direction("--wi", bad, false).unwrap_err();
            assert!(e.to_string().starts_with("--wi"), "{bad}: {e}");
        }
        assert!(parse_direction("--wi", "0,0,2", true).is_ok());
        assert!(parse_direction("--wi", "0,0,0", true).is_err());
    }

    #[test]
    fn stdin_rows_plain_and_with_a_header() {
        let plain = "# comment\n0,0,1\n\n0.6,0,0.8\n";
        assert_eq!(read_rows(plain.as_bytes(), false).unwrap().len(), 2);
        let piped = "index,u0,u1,valid,wo_x,wo_y,wo_z,pdf\n0,0.5,0.5,true,0,0,1,2.0\n";
        let rows = read_rows(piped.as_bytes(), false).unwrap();
        assert_eq!(rows, vec![Vec3::Z]);
        let e = read_rows("0,0,1\n1,x,0\n".as_bytes(), false).unwrap_err();
        assert!(e.to_string().contains("line 2"), "{e}");
    }
}
