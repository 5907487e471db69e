//! Rough dielectric interface (Walter, Marschner, Li & Torrance 2007), reflection and
//! transmission, light arriving from either side.
//!
//! `eta` is the index of the inside (below the surface, `z < 0`) over the outside.

use crate::fresnel;
use crate::microfacet::Microfacet;
use crate::spherical::reflect;
use crate::{DVec3, IncidentFold, Material, MaterialSample, Rgb};

/// A rough dielectric boundary with a white (colourless) response.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// Microfacet distribution.
    pub mf: Microfacet,
    /// Relative index of refraction, inside over outside (> 0, != 1 for refraction).
    pub eta: f64,
}

/// The pieces of the scattering geometry shared by `eval` and `pdf`.
struct Geometry {
    /// Microfacet normal (upper hemisphere).
    m: DVec3,
    /// Relative index of the side of `wo` over the side of `wi` (1 for reflection).
    etap: f64,
    /// True for reflection.
    reflect: bool,
}

impl Dielectric {
    /// Generalized half vector (Walter 2007 eqs. 13 and 16): `h_r = wi + wo` for
    /// reflection, `h_t = wi + etap wo` for transmission, flipped into the upper hemisphere;
    /// `None` when the configuration is degenerate or the microfacet would be back-facing.
    fn geometry(&self, wi: DVec3, wo: DVec3) -> Option<Geometry> {
        let (ci, co) = (wi.z, wo.z);
        if ci == 0.0 || co == 0.0 {
            return None;
        }
        let reflect = ci * co > 0.0;
        let etap = if reflect {
            1.0
        } else if ci > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let mut m = (wi + wo * etap).try_normalize()?;
        if m.z < 0.0 {
            m = -m;
        }
        // Discard back-facing microfacets (Walter 2007 eq. 19 / pbrt-v4).
        if m.dot(wi) * ci <= 0.0 || m.dot(wo) * co <= 0.0 {
            return None;
        }
        Some(Geometry { m, etap, reflect })
    }

    /// Transmission Jacobian `|dh_t / dwo| = etap^2 |wo.m| / (wi.m + etap wo.m)^2`
    /// (Walter 2007 eq. 17, in the form with `etap` = side of wo over side of wi).
    fn transmit_jacobian(wi: DVec3, wo: DVec3, m: DVec3, etap: f64) -> f64 {
        let denom = wi.dot(m) + etap * wo.dot(m);
        etap * etap * wo.dot(m).abs() / (denom * denom)
    }
}

/// Refraction of `w` (pointing away) through the microfacet `m` for the relative index
/// `eta` (inside over outside); `None` on total internal reflection.
fn refract(w: DVec3, m: DVec3, eta: f64) -> Option<DVec3> {
    let mut cos_i = w.dot(m);
    let mut eta = eta;
    let mut n = m;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-w * (1.0 / eta) + n * (cos_i / eta - cos_t))
}

impl Material for Dielectric {
    fn name(&self) -> &'static str {
        "dielectric"
    }

    fn spec(&self) -> String {
        format!(
            "dielectric:{},alpha={},alpha_y={},eta={}",
            self.mf.dist.keyword(),
            self.mf.alpha_x,
            self.mf.alpha_y,
            self.eta
        )
    }

    /// `f` (no cosine). Reflection: `F D G / (4 |cos_i cos_o|)` (Walter 2007 eq. 20).
    /// Transmission: `|wi.m| |wo.m| (1 - F) D G / (|cos_i cos_o| (wi.m + etap wo.m)^2)`
    /// (Walter 2007 eq. 21 with `eta_o^2` replaced by 1), i.e. the radiance-transport BTDF
    /// for light arriving along `wo` and leaving along `wi`; it obeys
    /// `f(wi, wo) / eta(wi)^2 = f(wo, wi) / eta(wo)^2`.
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        let Some(g) = self.geometry(wi, wo) else {
            return Rgb::ZERO;
        };
        let d = self.mf.d(g.m);
        let shadow = self.mf.g(wi, wo, g.m);
        if d == 0.0 || shadow == 0.0 {
            return Rgb::ZERO;
        }
        let f = fresnel::dielectric(wi.dot(g.m), self.eta);
        let v = if g.reflect {
            f * d * shadow / (4.0 * (wi.z * wo.z).abs())
        } else {
            let denom = wi.dot(g.m) + g.etap * wo.dot(g.m);
            (1.0 - f) * d * shadow * (wi.dot(g.m) * wo.dot(g.m)).abs()
                / ((wi.z * wo.z).abs() * denom * denom)
        };
        if v.is_finite() {
            Rgb::splat(v)
        } else {
            Rgb::ZERO
        }
    }

    /// Visible-normal sampling of `m`, then reflection with probability `F(wi.m)` or
    /// refraction otherwise (Walter 2007 section 5.3, with Heitz 2014 visible normals).
    fn sample(&self, wi: DVec3, u: [f64; 3]) -> Option<MaterialSample> {
        if wi.z == 0.0 {
            return None;
        }
        let m = self.mf.sample_visible(wi, [u[0], u[1]]);
        let f = fresnel::dielectric(wi.dot(m), self.eta);
        let wo = if u[2] < f {
            let wo = reflect(wi, m);
            if wo.z * wi.z <= 0.0 {
                return None;
            }
            wo
        } else {
            let wo = refract(wi, m, self.eta)?;
            if wo.z * wi.z >= 0.0 {
                return None;
            }
            wo.try_normalize()?
        };
        let pdf = self.pdf(wi, wo);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let weight = self.eval(wi, wo) * (wo.z.abs() / pdf);
        Some(MaterialSample { wo, pdf, weight })
    }

    /// `D_wi(m) F / (4 |wi.m|)` for reflection, `D_wi(m) (1 - F) |dh_t/dwo|` for
    /// transmission.
    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let Some(g) = self.geometry(wi, wo) else {
            return 0.0;
        };
        let pm = self.mf.visible_pdf(wi, g.m);
        let f = fresnel::dielectric(wi.dot(g.m), self.eta);
        let v = if g.reflect {
            pm * f / (4.0 * wi.dot(g.m).abs())
        } else {
            pm * (1.0 - f) * Self::transmit_jacobian(wi, wo, g.m, g.etap)
        };
        if v.is_finite() {
            v
        } else {
            0.0
        }
    }

    fn is_transmissive(&self) -> bool {
        true
    }

    fn is_isotropic(&self) -> bool {
        self.mf.is_isotropic()
    }

    /// An anisotropic lobe aligned with the axes is unchanged by mirroring either.
    fn azimuth_fold(&self) -> IncidentFold {
        if self.mf.is_isotropic() {
            IncidentFold::None
        } else {
            IncidentFold::Quarter
        }
    }

    fn index_of_side(&self, w: DVec3) -> f64 {
        if w.z < 0.0 {
            self.eta
        } else {
            1.0
        }
    }
}

impl Dielectric {
    /// Samples only the refracted lobe: a visible normal, then refraction (no Fresnel
    /// choice). `None` on total internal reflection or a same-side result.
    pub fn sample_refraction(&self, wi: DVec3, u: [f64; 2]) -> Option<DVec3> {
        if wi.z == 0.0 {
            return None;
        }
        let m = self.mf.sample_visible(wi, u);
        let wo = refract(wi, m, self.eta)?.try_normalize()?;
        if wo.z * wi.z >= 0.0 {
            return None;
        }
        Some(wo)
    }

    /// Density of [`Self::sample_refraction`]: `D_wi(m) |dh_t/dwo|` (no Fresnel factor).
    pub fn refraction_pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        match self.geometry(wi, wo) {
            Some(g) if !g.reflect => {
                let v = self.mf.visible_pdf(wi, g.m) * Self::transmit_jacobian(wi, wo, g.m, g.etap);
                if v.is_finite() {
                    v
                } else {
                    0.0
                }
            }
            _ => 0.0,
        }
    }
}
