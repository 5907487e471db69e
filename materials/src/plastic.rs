//! Rough plastic: a Lambertian base under a rough dielectric coat, in the form of
//! Mitsuba's `roughplastic` (Weidlich & Wilkie 2007 layering, with internal scattering
//! summed as a geometric series).

use crate::fresnel;
use crate::microfacet::Microfacet;
use crate::spec::{format_rgb, Params, SpecError};
use crate::spherical::reflect;
use crate::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::{DVec3, Material, MaterialSample, Rgb};
use std::f64::consts::FRAC_1_PI;

/// Rough plastic. `eval` returns
/// `f = F(wi.m) D G / (4 cos_i cos_o) + rho (1 - F(cos_i)) (1 - F(cos_o)) / (pi eta^2 (1 - rho Fdr))`
/// where `Fdr` is the hemispherical average of the internal Fresnel reflectance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plastic {
    /// Coat roughness.
    pub mf: Microfacet,
    /// Index of the coat (inside over outside).
    pub eta: f64,
    /// Albedo of the diffuse base.
    pub diffuse: Rgb,
    /// Hemispherical-average internal Fresnel reflectance (from `eta`).
    fdr_int: f64,
}

/// `Fdr = int_0^1 F(cos; 1/eta) 2 cos dcos`: the cosine-weighted hemispherical average
/// of the Fresnel reflectance seen from inside the coat, by midpoint quadrature.
pub fn internal_diffuse_fresnel(eta: f64) -> f64 {
    let n = 4096;
    let mut s = 0.0;
    for i in 0..n {
        let c = (i as f64 + 0.5) / n as f64;
        s += fresnel::dielectric(-c, eta) * 2.0 * c;
    }
    s / n as f64
}

impl Plastic {
    /// Builds a plastic; `eta` > 0.
    pub fn new(mf: Microfacet, eta: f64, diffuse: Rgb) -> Self {
        Self {
            mf,
            eta,
            diffuse,
            fdr_int: internal_diffuse_fresnel(eta),
        }
    }

    /// Reads `ggx|beckmann`, `alpha`, `alpha_y`, `eta` (1.5), `diffuse` (0.5).
    pub fn from_params(p: &mut Params) -> Result<Self, SpecError> {
        let mf = p.microfacet(0.1)?;
        let eta = p.number("eta", 1.5, 1.0001, 10.0)?;
        let diffuse = p.rgb("diffuse", Rgb::splat(0.5), 0.0, 1.0)?;
        Ok(Self::new(mf, eta, diffuse))
    }

    /// Probability of sampling the specular lobe for a given `cos_i`.
    fn specular_probability(&self, cos_i: f64) -> f64 {
        let fs = fresnel::dielectric(cos_i, self.eta);
        let fd = (1.0 - fs) * self.diffuse.luminance();
        if fs + fd <= 0.0 {
            return 1.0;
        }
        (fs / (fs + fd)).clamp(0.1, 0.9)
    }

    fn specular_pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let Some(m) = (wi + wo).try_normalize() else {
            return 0.0;
        };
        let c = wi.dot(m);
        if c <= 0.0 {
            return 0.0;
        }
        self.mf.visible_pdf(wi, m) / (4.0 * c)
    }
}

impl Material for Plastic {
    fn name(&self) -> &'static str {
        "plastic"
    }

    fn spec(&self) -> String {
        format!(
            "plastic:{},alpha={},alpha_y={},eta={},diffuse={}",
            self.mf.dist.keyword(),
            self.mf.alpha_x,
            self.mf.alpha_y,
            self.eta,
            format_rgb(self.diffuse)
        )
    }

    /// `f` (no cosine): specular coat (Walter 2007 eq. 20) plus the Fresnel-weighted
    /// diffuse base (Mitsuba `roughplastic`).
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        let mut spec = 0.0;
        if let Some(m) = (wi + wo).try_normalize() {
            let d = self.mf.d(m);
            let g = self.mf.g(wi, wo, m);
            spec = fresnel::dielectric(wi.dot(m), self.eta) * d * g / (4.0 * wi.z * wo.z);
        }
        let ti = 1.0 - fresnel::dielectric(wi.z, self.eta);
        let to = 1.0 - fresnel::dielectric(wo.z, self.eta);
        let scale = ti * to * FRAC_1_PI / (self.eta * self.eta);
        let base = Rgb([
            self.diffuse.0[0] / (1.0 - self.diffuse.0[0] * self.fdr_int),
            self.diffuse.0[1] / (1.0 - self.diffuse.0[1] * self.fdr_int),
            self.diffuse.0[2] / (1.0 - self.diffuse.0[2] * self.fdr_int),
        ]);
        base * scale + Rgb::splat(spec)
    }

    /// One-sample mixture of visible-normal sampling (probability `p_s` from the Fresnel
    /// and diffuse weights at `cos_i`) and cosine sampling; the pdf is the mixture pdf.
    fn sample(&self, wi: DVec3, u: [f64; 3]) -> Option<MaterialSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let ps = self.specular_probability(wi.z);
        let wo = if u[2] < ps {
            let m = self.mf.sample_visible(wi, [u[0], u[1]]);
            reflect(wi, m)
        } else {
            square_to_cosine_hemisphere([u[0], u[1]])
        };
        if wo.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wi, wo);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(MaterialSample {
            wo,
            pdf,
            weight: self.eval(wi, wo) * (wo.z / pdf),
        })
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let ps = self.specular_probability(wi.z);
        ps * self.specular_pdf(wi, wo) + (1.0 - ps) * cosine_hemisphere_pdf(wo)
    }

    fn is_transmissive(&self) -> bool {
        false
    }

    fn is_isotropic(&self) -> bool {
        self.mf.is_isotropic()
    }
}
