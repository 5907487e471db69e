//! Disney principled BSDF (Burley 2012, 2015 "Extending the Disney BRDF to a BSDF with
//! integrated subsurface scattering"), without subsurface and thin-surface modes, in the
//! lobe structure of pbrt-v3's `DisneyMaterial`.
//!
//! Lobes, with `dw = (1 - metallic)(1 - spec_trans)` and `tw = (1 - metallic) spec_trans`:
//! - diffuse (Burley 2015 eqs. 4-5: Lambert times `(1 - F_L/2)(1 - F_V/2)` plus
//!   retro-reflection `R_R (F_L + F_V + F_L F_V (R_R - 1))`, `R_R = 2 roughness cos^2 theta_d`),
//!   weight `dw`;
//! - sheen `sheen C_sheen (1 - cos theta_d)^5`, weight `dw`;
//! - specular reflection, anisotropic GGX (`aspect = sqrt(1 - 0.9 anisotropic)`,
//!   `alpha_x = r^2 / aspect`, `alpha_y = r^2 aspect`), Fresnel
//!   `lerp(metallic, F_dielectric(eta), Schlick(C_spec0))`;
//! - clearcoat, GTR1 with `alpha = lerp(0.1, 0.001, clearcoat_gloss)`, Schlick F0 = 0.04,
//!   Smith GGX masking with `alpha = 0.25`, scaled by `clearcoat / 4`;
//! - specular transmission: the refracted part of a rough dielectric (Walter 2007), tinted
//!   by `sqrt(base_color)`, weight `tw`.
//!
//! Reflection lobes exist only for `wi.z > 0, wo.z > 0`; transmission works from either side.

use crate::dielectric::Dielectric;
use crate::fresnel::{dielectric as fr_dielectric, schlick, schlick_weight};
use crate::microfacet::{Distribution, Microfacet};
use crate::spec::{format_rgb, Params, SpecError};
use crate::spherical::{from_spherical, reflect};
use crate::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::{DVec3, Material, MaterialSample, Rgb};
use std::f64::consts::{FRAC_1_PI, PI};

/// Parameters of the principled BSDF (all in `[0, 1]` except `eta`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Principled {
    /// Base colour.
    pub base: Rgb,
    /// Metallic blend.
    pub metallic: f64,
    /// Perceptual roughness (`alpha = roughness^2`).
    pub roughness: f64,
    /// Anisotropy.
    pub anisotropic: f64,
    /// Dielectric specular amount (0.5 is F0 = 0.04 without `eta`).
    pub specular: f64,
    /// Tint of the dielectric specular towards the base hue.
    pub specular_tint: f64,
    /// Sheen amount.
    pub sheen: f64,
    /// Tint of the sheen.
    pub sheen_tint: f64,
    /// Clearcoat amount.
    pub clearcoat: f64,
    /// Clearcoat glossiness.
    pub clearcoat_gloss: f64,
    /// Specular transmission.
    pub spec_trans: f64,
    /// Index of refraction (inside over outside).
    pub eta: f64,
}

impl Default for Principled {
    fn default() -> Self {
        Self {
            base: Rgb::splat(0.8),
            metallic: 0.0,
            roughness: 0.5,
            anisotropic: 0.0,
            specular: 0.5,
            specular_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.5,
            clearcoat: 0.0,
            clearcoat_gloss: 1.0,
            spec_trans: 0.0,
            eta: 1.5,
        }
    }
}

/// Lobe selection probabilities.
struct LobeProbs {
    diffuse: f64,
    specular: f64,
    clearcoat: f64,
    transmission: f64,
}

/// GTR1 (Berry) distribution, Burley 2012 appendix B eq. 4: `(a^2 - 1) / (pi ln(a^2) (1 + (a^2 - 1) cos^2))`.
fn gtr1(cos_h: f64, a: f64) -> f64 {
    let a2 = a * a;
    (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * cos_h * cos_h))
}

impl Principled {
    /// Reads `base`, `metallic`, `roughness`, `anisotropic`, `specular`, `specular_tint`,
    /// `sheen`, `sheen_tint`, `clearcoat`, `clearcoat_gloss`, `spec_trans`, `eta`.
    pub fn from_params(p: &mut Params) -> Result<Self, SpecError> {
        let d = Self::default();
        Ok(Self {
            base: p.rgb("base", d.base, 0.0, 1.0)?,
            metallic: p.number("metallic", d.metallic, 0.0, 1.0)?,
            roughness: p.number("roughness", d.roughness, 0.0, 1.0)?,
            anisotropic: p.number("anisotropic", d.anisotropic, 0.0, 1.0)?,
            specular: p.number("specular", d.specular, 0.0, 1.0)?,
            specular_tint: p.number("specular_tint", d.specular_tint, 0.0, 1.0)?,
            sheen: p.number("sheen", d.sheen, 0.0, 1.0)?,
            sheen_tint: p.number("sheen_tint", d.sheen_tint, 0.0, 1.0)?,
            clearcoat: p.number("clearcoat", d.clearcoat, 0.0, 1.0)?,
            clearcoat_gloss: p.number("clearcoat_gloss", d.clearcoat_gloss, 0.0, 1.0)?,
            spec_trans: p.number("spec_trans", d.spec_trans, 0.0, 1.0)?,
            eta: p.number("eta", d.eta, 1.0001, 10.0)?,
        })
    }

    fn microfacet(&self) -> Microfacet {
        let aspect = (1.0 - 0.9 * self.anisotropic).sqrt();
        let r2 = self.roughness * self.roughness;
        Microfacet::new(Distribution::Ggx, r2 / aspect, r2 * aspect)
    }

    fn tint(&self) -> Rgb {
        let l = self.base.luminance();
        if l > 0.0 {
            self.base * (1.0 / l)
        } else {
            Rgb::splat(1.0)
        }
    }

    fn lerp_rgb(t: f64, a: Rgb, b: Rgb) -> Rgb {
        a * (1.0 - t) + b * t
    }

    /// `C_spec0 = lerp(metallic, R0(eta) lerp(specular_tint, 1, C_tint), base)` as in
    /// pbrt-v3 (`specular` scales R0 by `specular / 0.5`).
    fn cspec0(&self) -> Rgb {
        let r0 = ((self.eta - 1.0) / (self.eta + 1.0)).powi(2) * (self.specular / 0.5);
        let tinted = Self::lerp_rgb(self.specular_tint, Rgb::splat(1.0), self.tint()) * r0;
        Self::lerp_rgb(self.metallic, tinted, self.base)
    }

    fn specular_fresnel(&self, cos: f64) -> Rgb {
        let c0 = self.cspec0();
        let fs = Rgb([
            schlick(cos, c0.0[0]),
            schlick(cos, c0.0[1]),
            schlick(cos, c0.0[2]),
        ]);
        Self::lerp_rgb(self.metallic, Rgb::splat(fr_dielectric(cos, self.eta)), fs)
    }

    fn dielectric(&self) -> Dielectric {
        Dielectric {
            mf: self.microfacet(),
            eta: self.eta,
        }
    }

    fn clearcoat_alpha(&self) -> f64 {
        0.1 * (1.0 - self.clearcoat_gloss) + 0.001 * self.clearcoat_gloss
    }

    fn probs(&self, wi: DVec3) -> LobeProbs {
        let dw = (1.0 - self.metallic) * (1.0 - self.spec_trans);
        let tw = (1.0 - self.metallic) * self.spec_trans;
        if wi.z <= 0.0 {
            return LobeProbs {
                diffuse: 0.0,
                specular: 0.0,
                clearcoat: 0.0,
                transmission: if tw > 0.0 { 1.0 } else { 0.0 },
            };
        }
        let ci = wi.z;
        let fd = fr_dielectric(ci, self.eta);
        let mut p = LobeProbs {
            diffuse: dw * (self.base.luminance() + self.sheen * 0.1),
            specular: self.specular_fresnel(ci).luminance().max(0.02),
            clearcoat: 0.25 * self.clearcoat * schlick(ci, 0.04),
            transmission: tw * self.base.0.map(f64::sqrt).iter().sum::<f64>() / 3.0 * (1.0 - fd),
        };
        let s = p.diffuse + p.specular + p.clearcoat + p.transmission;
        if s > 0.0 {
            p.diffuse /= s;
            p.specular /= s;
            p.clearcoat /= s;
            p.transmission /= s;
        }
        p
    }

    fn specular_pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let Some(h) = (wi + wo).try_normalize() else {
            return 0.0;
        };
        let c = wi.dot(h);
        if c <= 0.0 {
            return 0.0;
        }
        self.microfacet().visible_pdf(wi, h) / (4.0 * c)
    }

    /// Density of GTR1 half-vector sampling, `D_c(h) cos theta_h / (4 wo.h)`.
    fn clearcoat_pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let Some(h) = (wi + wo).try_normalize() else {
            return 0.0;
        };
        let c = wo.dot(h);
        if c <= 0.0 {
            return 0.0;
        }
        gtr1(h.z, self.clearcoat_alpha()) * h.z / (4.0 * c)
    }
}

impl Material for Principled {
    fn name(&self) -> &'static str {
        "principled"
    }

    fn spec(&self) -> String {
        format!(
            "principled:base={},metallic={},roughness={},anisotropic={},specular={},specular_tint={},sheen={},sheen_tint={},clearcoat={},clearcoat_gloss={},spec_trans={},eta={}",
            format_rgb(self.base),
            self.metallic,
            self.roughness,
            self.anisotropic,
            self.specular,
            self.specular_tint,
            self.sheen,
            self.sheen_tint,
            self.clearcoat,
            self.clearcoat_gloss,
            self.spec_trans,
            self.eta
        )
    }

    /// `f` (no cosine): the sum of the lobes in the module docs.
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        let dw = (1.0 - self.metallic) * (1.0 - self.spec_trans);
        let tw = (1.0 - self.metallic) * self.spec_trans;
        if wi.z * wo.z < 0.0 {
            if tw <= 0.0 {
                return Rgb::ZERO;
            }
            let t = self.dielectric().eval(wi, wo).0[0] * tw;
            return Rgb(self.base.0.map(f64::sqrt)) * t;
        }
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        let Some(h) = (wi + wo).try_normalize() else {
            return Rgb::ZERO;
        };
        let (ci, co) = (wi.z, wo.z);
        let cd = wi.dot(h);
        let mut out = Rgb::ZERO;
        if dw > 0.0 {
            let (fl, fv) = (schlick_weight(co), schlick_weight(ci));
            let rr = 2.0 * self.roughness * cd * cd;
            let lambert = (1.0 - 0.5 * fl) * (1.0 - 0.5 * fv);
            let retro = rr * (fl + fv + fl * fv * (rr - 1.0));
            out = out + self.base * (dw * FRAC_1_PI * (lambert + retro));
            if self.sheen > 0.0 {
                let csheen = Self::lerp_rgb(self.sheen_tint, Rgb::splat(1.0), self.tint());
                out = out + csheen * (dw * self.sheen * schlick_weight(cd));
            }
        }
        let mf = self.microfacet();
        let dg = mf.d(h) * mf.g(wi, wo, h) / (4.0 * ci * co);
        if dg > 0.0 {
            out = out + self.specular_fresnel(cd) * dg;
        }
        if self.clearcoat > 0.0 {
            let cc = Microfacet::new(Distribution::Ggx, 0.25, 0.25);
            let v = 0.25
                * self.clearcoat
                * gtr1(h.z, self.clearcoat_alpha())
                * schlick(cd, 0.04)
                * cc.g(wi, wo, h)
                / (4.0 * ci * co);
            out = out + Rgb::splat(v);
        }
        if out.is_finite() {
            out
        } else {
            Rgb::ZERO
        }
    }

    /// One-sample lobe selection with `u[2]`; the pdf is the full mixture pdf.
    fn sample(&self, wi: DVec3, u: [f64; 3]) -> Option<MaterialSample> {
        let p = self.probs(wi);
        let uv = [u[0], u[1]];
        let x = u[2];
        let wo = if x < p.diffuse {
            square_to_cosine_hemisphere(uv)
        } else if x < p.diffuse + p.specular {
            let wo = reflect(wi, self.microfacet().sample_visible(wi, uv));
            if wo.z <= 0.0 {
                return None;
            }
            wo
        } else if x < p.diffuse + p.specular + p.clearcoat {
            let a2 = self.clearcoat_alpha().powi(2);
            let cos_h = ((1.0 - a2.powf(1.0 - uv[0])) / (1.0 - a2))
                .clamp(0.0, 1.0)
                .sqrt();
            let h = from_spherical(cos_h.acos(), 2.0 * PI * uv[1]);
            let wo = reflect(wi, h);
            if wo.z <= 0.0 {
                return None;
            }
            wo
        } else {
            self.dielectric().sample_refraction(wi, uv)?
        };
        let pdf = self.pdf(wi, wo);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(MaterialSample {
            wo,
            pdf,
            weight: self.eval(wi, wo) * (wo.z.abs() / pdf),
        })
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let p = self.probs(wi);
        let mut v = 0.0;
        if wi.z * wo.z < 0.0 {
            if p.transmission > 0.0 {
                v += p.transmission * self.dielectric().refraction_pdf(wi, wo);
            }
            return v;
        }
        if wi.z > 0.0 && wo.z > 0.0 {
            v += p.diffuse * cosine_hemisphere_pdf(wo);
            v += p.specular * self.specular_pdf(wi, wo);
            if p.clearcoat > 0.0 {
                v += p.clearcoat * self.clearcoat_pdf(wi, wo);
            }
        }
        v
    }

    fn is_transmissive(&self) -> bool {
        self.spec_trans > 0.0 && self.metallic < 1.0
    }

    fn is_isotropic(&self) -> bool {
        self.anisotropic == 0.0
    }

    fn index_of_side(&self, w: DVec3) -> f64 {
        if w.z < 0.0 && self.is_transmissive() {
            self.eta
        } else {
            1.0
        }
    }
}
