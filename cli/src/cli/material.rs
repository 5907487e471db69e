//! `diffbsdf material eval` and `diffbsdf material sample`: print a reference material's
//! `f`, `f |cos theta_o|` and sampler pdf, or samples, as CSV or JSON, so the materials can
//! be checked against another renderer.

use clap::{Subcommand, ValueEnum};
use diffbsdf_materials::{from_spherical, parse_spec, DVec3, Material, SpecError};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use serde::Serialize;
use std::fmt;

/// Output format.
#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum Format {
    /// Comma-separated values with a header line.
    Csv,
    /// One JSON array of objects.
    Json,
}

/// `diffbsdf material ...`
#[derive(Debug, Subcommand)]
pub enum MaterialCommand {
    /// Print f, f*|cos theta_o| and the material sampler's pdf (per unit solid angle) for
    /// direction pairs. Each PAIR is `wix,wiy,wiz,wox,woy,woz` (local frame, z = normal,
    /// normalised here) or `theta_i,phi_i,theta_o,phi_o` in degrees.
    Eval {
        /// Material spec, e.g. `conductor:ggx,alpha=0.05,alpha_y=0.3,metal=Cu`.
        spec: String,
        /// Direction pairs.
        #[arg(required = true, allow_hyphen_values = true)]
        pairs: Vec<String>,
        /// Output format.
        #[arg(long, value_enum, default_value = "csv")]
        format: Format,
    },
    /// Draw directions wo from the material's own sampler for one wi.
    Sample {
        /// Material spec.
        spec: String,
        /// Incident direction: `x,y,z` or `theta,phi` in degrees.
        #[arg(long, allow_hyphen_values = true)]
        wi: String,
        /// Number of samples (invalid samples are printed with valid = false).
        #[arg(long, default_value_t = 10)]
        count: usize,
        /// Random seed (PCG64).
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Output format.
        #[arg(long, value_enum, default_value = "csv")]
        format: Format,
    },
}

/// Why a material command failed.
#[derive(Debug)]
pub enum MaterialError {
    /// The spec did not parse.
    Spec(SpecError),
    /// A direction argument did not parse.
    BadDirection(String),
    /// Writing the output failed.
    Io(std::io::Error),
    /// JSON encoding failed.
    Json(String),
}

impl fmt::Display for MaterialError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MaterialError::Spec(e) => write!(f, "{e}"),
            MaterialError::BadDirection(s) => write!(
                f,
                "bad direction `{s}` (expected x,y,z or theta,phi in degrees; pairs: 6 or 4 numbers)"
            ),
            MaterialError::Io(e) => write!(f, "write failed: {e}"),
            MaterialError::Json(e) => write!(f, "JSON encoding failed: {e}"),
        }
    }
}

impl std::error::Error for MaterialError {}

fn numbers(s: &str) -> Result<Vec<f64>, MaterialError> {
    s.split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<Vec<_>, _>>()
        .ok()
        .filter(|v| v.iter().all(|x| x.is_finite()))
        .ok_or_else(|| MaterialError::BadDirection(s.to_string()))
}

fn direction(v: &[f64], s: &str) -> Result<DVec3, MaterialError> {
    let w = match v {
        [t, p] => from_spherical(t.to_radians(), p.to_radians()),
        [x, y, z] => DVec3::new(*x, *y, *z),
        _ => return Err(MaterialError::BadDirection(s.to_string())),
    };
    w.try_normalize()
        .ok_or_else(|| MaterialError::BadDirection(s.to_string()))
}

/// Parses a PAIR argument.
pub fn parse_pair(s: &str) -> Result<(DVec3, DVec3), MaterialError> {
    let v = numbers(s)?;
    match v.len() {
        6 => Ok((direction(&v[..3], s)?, direction(&v[3..], s)?)),
        4 => Ok((direction(&v[..2], s)?, direction(&v[2..], s)?)),
        _ => Err(MaterialError::BadDirection(s.to_string())),
    }
}

/// One evaluated pair.
#[derive(Debug, Serialize)]
pub struct EvalRow {
    /// Incident direction.
    pub wi: [f64; 3],
    /// Outgoing direction.
    pub wo: [f64; 3],
    /// `f` per channel.
    pub f: [f64; 3],
    /// `f |cos theta_o|` per channel.
    pub f_cos: [f64; 3],
    /// Luminance of `f`.
    pub f_luminance: f64,
    /// Sampler pdf per unit solid angle.
    pub pdf: f64,
}

/// One drawn sample.
#[derive(Debug, Serialize)]
pub struct SampleRow {
    /// Index of the draw.
    pub index: usize,
    /// False for an invalid sample (zero contribution).
    pub valid: bool,
    /// Sampled direction.
    pub wo: [f64; 3],
    /// Its pdf per unit solid angle.
    pub pdf: f64,
    /// Weight `f |cos| / pdf` per channel.
    pub weight: [f64; 3],
}

/// Evaluates `m` on the given pairs.
pub fn eval_rows(m: &dyn Material, pairs: &[(DVec3, DVec3)]) -> Vec<EvalRow> {
    pairs
        .iter()
        .map(|&(wi, wo)| {
            let f = m.eval(wi, wo);
            EvalRow {
                wi: wi.to_array(),
                wo: wo.to_array(),
                f: f.0,
                f_cos: m.eval_cos(wi, wo).0,
                f_luminance: f.luminance(),
                pdf: m.pdf(wi, wo),
            }
        })
        .collect()
}

/// Draws `count` samples with a seeded PCG64.
pub fn sample_rows(m: &dyn Material, wi: DVec3, count: usize, seed: u64) -> Vec<SampleRow> {
    let mut rng = Pcg64::seed_from_u64(seed);
    (0..count)
        .map(|index| {
            let u = [rng.gen(), rng.gen(), rng.gen()];
            match m.sample(wi, u) {
                Some(s) => SampleRow {
                    index,
                    valid: true,
                    wo: s.wo.to_array(),
                    pdf: s.pdf,
                    weight: s.weight.0,
                },
                None => SampleRow {
                    index,
                    valid: false,
                    wo: [0.0; 3],
                    pdf: 0.0,
                    weight: [0.0; 3],
                },
            }
        })
        .collect()
}

fn join(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x:e}"))
        .collect::<Vec<_>>()
        .join(",")
}

/// Runs a material subcommand.
pub fn run(cmd: MaterialCommand, out: &mut dyn std::io::Write) -> Result<(), MaterialError> {
    let io = MaterialError::Io;
    match cmd {
        MaterialCommand::Eval {
            spec,
            pairs,
            format,
        } => {
            let m = parse_spec(&spec).map_err(MaterialError::Spec)?;
            let pairs = pairs
                .iter()
                .map(|s| parse_pair(s))
                .collect::<Result<Vec<_>, _>>()?;
            let rows = eval_rows(m.as_ref(), &pairs);
            match format {
                Format::Json => {
                    let s = serde_json::to_string_pretty(&rows)
                        .map_err(|e| MaterialError::Json(e.to_string()))?;
                    writeln!(out, "{s}").map_err(io)?;
                }
                Format::Csv => {
                    writeln!(
                        out,
                        "wi_x,wi_y,wi_z,wo_x,wo_y,wo_z,f_r,f_g,f_b,fcos_r,fcos_g,fcos_b,f_lum,pdf"
                    )
                    .map_err(io)?;
                    for r in rows {
                        writeln!(
                            out,
                            "{},{},{},{},{:e},{:e}",
                            join(&r.wi),
                            join(&r.wo),
                            join(&r.f),
                            join(&r.f_cos),
                            r.f_luminance,
                            r.pdf
                        )
                        .map_err(io)?;
                    }
                }
            }
        }
        MaterialCommand::Sample {
            spec,
            wi,
            count,
            seed,
            format,
        } => {
            let m = parse_spec(&spec).map_err(MaterialError::Spec)?;
            let wi_dir = direction(&numbers(&wi)?, &wi)?;
            let rows = sample_rows(m.as_ref(), wi_dir, count, seed);
            match format {
                Format::Json => {
                    let s = serde_json::to_string_pretty(&rows)
                        .map_err(|e| MaterialError::Json(e.to_string()))?;
                    writeln!(out, "{s}").map_err(io)?;
                }
                Format::Csv => {
                    writeln!(
                        out,
                        "index,valid,wo_x,wo_y,wo_z,pdf,weight_r,weight_g,weight_b"
                    )
                    .map_err(io)?;
                    for r in rows {
                        writeln!(
                            out,
                            "{},{},{},{:e},{}",
                            r.index,
                            r.valid,
                            join(&r.wo),
                            r.pdf,
                            join(&r.weight)
                        )
                        .map_err(io)?;
                    }
                }
            }
        }
    }
    Ok(())
}
