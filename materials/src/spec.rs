//! The one-string material spec accepted on the command line.
//!
//! Grammar: `model[:item,item,...]` where an item is a bare keyword (e.g. the
//! distribution `ggx` / `beckmann`) or `key=value`. RGB values are written `r/g/b` or as
//! one number for grey. Examples:
//!
//! - `lambertian:albedo=0.8/0.5/0.2`
//! - `conductor:ggx,alpha=0.05,alpha_y=0.3,metal=Cu` (or `eta=0.2/0.9/1.1,k=3.9/2.4/2.1`)
//! - `dielectric:beckmann,alpha=0.3,eta=1.5`
//! - `plastic:ggx,alpha=0.1,eta=1.5,diffuse=0.5/0.5/0.5`
//! - `principled:base=0.8/0.3/0.2,metallic=0,roughness=0.4,spec_trans=0.5`
//! - `rgl:/path/to/material_rgb.bsdf`
//!
//! `alpha_y` defaults to `alpha` (isotropic).

use crate::conductor::{Conductor, Metal};
use crate::dielectric::Dielectric;
use crate::halfway::Halfway;
use crate::lambertian::Lambertian;
use crate::microfacet::{Distribution, Microfacet};
use crate::plastic::Plastic;
use crate::principled::Principled;
use crate::rgl::{RglError, RglMaterial};
use crate::{Material, Rgb};
use std::fmt;

/// Why a spec string was rejected.
#[derive(Debug, Clone, PartialEq)]
pub enum SpecError {
    /// The model name before `:` is not known.
    UnknownModel(String),
    /// A key or bare keyword the model does not accept.
    UnknownKey {
        /// Model name.
        model: &'static str,
        /// The offending item.
        key: String,
    },
    /// A value that does not parse or is out of range.
    BadValue {
        /// The key.
        key: String,
        /// The value as written.
        value: String,
    },
    /// `metal=` names no known metal.
    UnknownMetal(String),
    /// The RGL file could not be read.
    Rgl(RglError),
}

impl fmt::Display for SpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SpecError::UnknownModel(m) => write!(
                f,
                "unknown material model `{m}` (expected lambertian, conductor, dielectric, plastic, principled or rgl)"
            ),
            SpecError::UnknownKey { model, key } => {
                write!(f, "`{key}` is not a parameter of `{model}`")
            }
            SpecError::BadValue { key, value } => write!(f, "bad value `{value}` for `{key}`"),
            SpecError::UnknownMetal(m) => write!(f, "unknown metal `{m}` (known: Cu, Au, Al, Ag)"),
            SpecError::Rgl(e) => write!(f, "RGL file: {e}"),
        }
    }
}

impl std::error::Error for SpecError {}

/// Formats an RGB value the way the parser reads it back (`r/g/b`, or one number if grey).
pub fn format_rgb(c: Rgb) -> String {
    if c.0[0] == c.0[1] && c.0[1] == c.0[2] {
        format!("{}", c.0[0])
    } else {
        format!("{}/{}/{}", c.0[0], c.0[1], c.0[2])
    }
}

/// The parsed items of a spec, consumed by each model's constructor.
#[derive(Debug)]
pub struct Params {
    model: &'static str,
    items: Vec<(String, Option<String>)>,
}

impl Params {
    fn new(model: &'static str, rest: &str) -> Self {
        let items = rest
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(|s| match s.split_once('=') {
                Some((k, v)) => (k.trim().to_ascii_lowercase(), Some(v.trim().to_string())),
                None => (s.to_ascii_lowercase(), None),
            })
            .collect();
        Self { model, items }
    }

    fn take(&mut self, key: &str) -> Option<String> {
        let i = self
            .items
            .iter()
            .position(|(k, v)| k == key && v.is_some())?;
        self.items.remove(i).1
    }

    /// Removes the bare keyword `word`; true if it was present.
    pub fn flag(&mut self, word: &str) -> bool {
        match self
            .items
            .iter()
            .position(|(k, v)| k == word && v.is_none())
        {
            Some(i) => {
                self.items.remove(i);
                true
            }
            None => false,
        }
    }

    /// A number, or `default`; must be finite and within `[lo, hi]`.
    pub fn number(&mut self, key: &str, default: f64, lo: f64, hi: f64) -> Result<f64, SpecError> {
        match self.take(key) {
            None => Ok(default),
            Some(v) => match v.parse::<f64>() {
                Ok(x) if x.is_finite() && x >= lo && x <= hi => Ok(x),
                _ => Err(SpecError::BadValue {
                    key: key.to_string(),
                    value: v,
                }),
            },
        }
    }

    /// An optional number within `[lo, hi]`.
    pub fn opt_number(&mut self, key: &str, lo: f64, hi: f64) -> Result<Option<f64>, SpecError> {
        if self.items.iter().any(|(k, v)| k == key && v.is_some()) {
            self.number(key, 0.0, lo, hi).map(Some)
        } else {
            Ok(None)
        }
    }

    /// An RGB value (`r/g/b` or one number), each channel within `[lo, hi]`.
    pub fn rgb(&mut self, key: &str, default: Rgb, lo: f64, hi: f64) -> Result<Rgb, SpecError> {
        let Some(v) = self.take(key) else {
            return Ok(default);
        };
        let bad = || SpecError::BadValue {
            key: key.to_string(),
            value: v.clone(),
        };
        let parts: Vec<f64> = v
            .split('/')
            .map(|p| p.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad())?;
        let c = match parts.as_slice() {
            [g] => [*g; 3],
            [r, g, b] => [*r, *g, *b],
            _ => return Err(bad()),
        };
        if c.iter().all(|x| x.is_finite() && *x >= lo && *x <= hi) {
            Ok(Rgb(c))
        } else {
            Err(bad())
        }
    }

    /// The microfacet distribution from a bare `ggx` / `beckmann` keyword (default GGX)
    /// and `alpha`, `alpha_y` (default `alpha`).
    pub fn microfacet(&mut self, default_alpha: f64) -> Result<Microfacet, SpecError> {
        let beckmann = self.flag("beckmann");
        let ggx = self.flag("ggx");
        let dist = if beckmann && !ggx {
            Distribution::Beckmann
        } else {
            Distribution::Ggx
        };
        let ax = self.number("alpha", default_alpha, 1e-4, 10.0)?;
        let ay = self.number("alpha_y", ax, 1e-4, 10.0)?;
        Ok(Microfacet::new(dist, ax, ay))
    }

    /// Fails on any item no constructor consumed.
    pub fn finish(self) -> Result<(), SpecError> {
        match self.items.into_iter().next() {
            None => Ok(()),
            Some((k, v)) => Err(SpecError::UnknownKey {
                model: self.model,
                key: match v {
                    Some(v) => format!("{k}={v}"),
                    None => k,
                },
            }),
        }
    }
}

/// Parses a one-string spec into a material. See the module docs for the grammar.
pub fn parse_spec(spec: &str) -> Result<Box<dyn Material>, SpecError> {
    let spec = spec.trim();
    let (model, rest) = spec.split_once(':').unwrap_or((spec, ""));
    let model = model.trim().to_ascii_lowercase();
    let m: Box<dyn Material> = match model.as_str() {
        "lambertian" | "diffuse" => {
            let mut p = Params::new("lambertian", rest);
            let albedo = p.rgb("albedo", Rgb::splat(0.8), 0.0, 1.0)?;
            p.finish()?;
            Box::new(Lambertian { albedo })
        }
        "conductor" => {
            let mut p = Params::new("conductor", rest);
            let mf = p.microfacet(0.1)?;
            let c = match p.take("metal") {
                Some(name) => Conductor::metal(
                    mf,
                    Metal::from_name(&name).ok_or(SpecError::UnknownMetal(name))?,
                ),
                None => {
                    let eta = p.rgb("eta", Rgb([0.200438, 0.924033, 1.10221]), 1e-4, 100.0)?;
                    let k = p.rgb("k", Rgb([3.91295, 2.45285, 2.14219]), 0.0, 1e4)?;
                    Conductor {
                        mf,
                        eta: eta.0,
                        k: k.0,
                        metal: None,
                    }
                }
            };
            p.finish()?;
            Box::new(c)
        }
        "dielectric" => {
            let mut p = Params::new("dielectric", rest);
            let mf = p.microfacet(0.1)?;
            let eta = p.number("eta", 1.5, 1e-3, 10.0)?;
            if eta == 1.0 {
                return Err(SpecError::BadValue {
                    key: "eta".into(),
                    value: "1".into(),
                });
            }
            p.finish()?;
            Box::new(Dielectric { mf, eta })
        }
        "plastic" => {
            let mut p = Params::new("plastic", rest);
            let m = Plastic::from_params(&mut p)?;
            p.finish()?;
            Box::new(m)
        }
        "principled" | "disney" => {
            let mut p = Params::new("principled", rest);
            let m = Principled::from_params(&mut p)?;
            p.finish()?;
            Box::new(m)
        }
        "rgl" | "measured" => {
            let path = rest.trim();
            Box::new(RglMaterial::open(path).map_err(SpecError::Rgl)?)
        }
        "halfway" => {
            let inner = parse_spec(rest)?;
            let spec = inner.spec();
            Box::new(Halfway::new(inner).ok_or(SpecError::BadValue {
                key: "halfway".into(),
                value: spec,
            })?)
        }
        "zoom" => {
            let (k, inner) = rest.split_once(':').ok_or(SpecError::BadValue {
                key: "zoom".into(),
                value: rest.into(),
            })?;
            let k: f64 = k.parse().map_err(|_| SpecError::BadValue {
                key: "zoom".into(),
                value: k.into(),
            })?;
            let inner = parse_spec(inner)?;
            Box::new(crate::zoom::Zoom::new(inner, k).ok_or(SpecError::BadValue {
                key: "zoom".into(),
                value: rest.into(),
            })?)
        }
        "radial" => {
            let bad = |v: &str| SpecError::BadValue {
                key: "radial".into(),
                value: v.into(),
            };
            let mut parts = rest.splitn(3, ':');
            let (Some(eps), Some(theta), Some(inner)) = (parts.next(), parts.next(), parts.next())
            else {
                return Err(bad(rest));
            };
            let eps: f64 = eps.parse().map_err(|_| bad(eps))?;
            let theta: f64 = theta.parse().map_err(|_| bad(theta))?;
            let inner = parse_spec(inner)?;
            Box::new(crate::radial::Radial::new(inner, eps, theta).ok_or_else(|| bad(rest))?)
        }
        _ => return Err(SpecError::UnknownModel(model)),
    };
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_issue_example() {
        let m = parse_spec("conductor:ggx,alpha=0.05,alpha_y=0.3,metal=Cu").unwrap();
        assert_eq!(m.name(), "conductor");
        assert_eq!(m.spec(), "conductor:ggx,alpha=0.05,alpha_y=0.3,metal=Cu");
    }

    #[test]
    fn round_trips_specs() {
        for s in [
            "lambertian:albedo=0.8/0.5/0.2",
            "conductor:beckmann,alpha=0.3,alpha_y=0.3,eta=1.5/1/0.5,k=3/2/1",
            "dielectric:ggx,alpha=0.01,alpha_y=0.01,eta=1.33",
        ] {
            let m = parse_spec(s).unwrap();
            assert_eq!(parse_spec(&m.spec()).unwrap().spec(), m.spec(), "{s}");
        }
    }

    #[test]
    fn rejects_bad_specs() {
        assert!(matches!(
            parse_spec("velvet"),
            Err(SpecError::UnknownModel(_))
        ));
        assert!(matches!(
            parse_spec("conductor:metal=Pb"),
            Err(SpecError::UnknownMetal(_))
        ));
        assert!(matches!(
            parse_spec("dielectric:alpha=-1"),
            Err(SpecError::BadValue { .. })
        ));
        assert!(matches!(
            parse_spec("lambertian:albedo=1/2"),
            Err(SpecError::BadValue { .. })
        ));
        assert!(matches!(
            parse_spec("lambertian:shiny=1"),
            Err(SpecError::UnknownKey { .. })
        ));
    }
}
