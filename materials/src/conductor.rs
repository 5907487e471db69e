//! Rough conductor: a Cook-Torrance microfacet BRDF with exact complex-index Fresnel
//! (Walter 2007 eq. 20 with the conductor Fresnel term), sampled by visible normals.

use crate::fresnel::conductor_rgb;
use crate::microfacet::Microfacet;
use crate::spherical::reflect;
use crate::{DVec3, IncidentFold, Material, MaterialSample, Rgb};

/// Named metals with RGB complex indices of refraction `eta + i k`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metal {
    /// Copper.
    Cu,
    /// Gold.
    Au,
    /// Aluminium.
    Al,
    /// Silver.
    Ag,
}

impl Metal {
    /// Parses `Cu`, `Au`, `Al` or `Ag` (case-insensitive).
    pub fn from_name(s: &str) -> Option<Metal> {
        match s.to_ascii_lowercase().as_str() {
            "cu" => Some(Metal::Cu),
            "au" => Some(Metal::Au),
            "al" => Some(Metal::Al),
            "ag" => Some(Metal::Ag),
            _ => None,
        }
    }

    /// Spec name.
    pub fn name(self) -> &'static str {
        match self {
            Metal::Cu => "Cu",
            Metal::Au => "Au",
            Metal::Al => "Al",
            Metal::Ag => "Ag",
        }
    }

    /// `(eta, k)` per RGB channel. These are the RGB fits of measured spectral data used by
    /// several renderers (Mitsuba 0.5 / Tungsten material tables); approximate.
    pub fn eta_k(self) -> ([f64; 3], [f64; 3]) {
        match self {
            Metal::Cu => ([0.200438, 0.924033, 1.10221], [3.91295, 2.45285, 2.14219]),
            Metal::Au => ([0.143119, 0.374957, 1.44248], [3.98316, 2.38572, 1.60322]),
            Metal::Al => ([1.65746, 0.880369, 0.521229], [9.22387, 6.26952, 4.837]),
            Metal::Ag => ([0.155265, 0.116723, 0.138342], [4.82835, 3.12225, 2.14696]),
        }
    }
}

/// A rough conductor. `eval` returns `f = F(wi.m) D(m) G(wi, wo, m) / (4 cos_i cos_o)`,
/// `m = normalize(wi + wo)` (Walter 2007 eq. 20).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// Microfacet distribution.
    pub mf: Microfacet,
    /// Real part of the index per channel.
    pub eta: [f64; 3],
    /// Imaginary part (extinction) per channel.
    pub k: [f64; 3],
    /// The named metal the indices came from, if any.
    pub metal: Option<Metal>,
}

impl Conductor {
    /// A conductor made of a named metal.
    pub fn metal(mf: Microfacet, metal: Metal) -> Self {
        let (eta, k) = metal.eta_k();
        Self {
            mf,
            eta,
            k,
            metal: Some(metal),
        }
    }
}

impl Material for Conductor {
    fn name(&self) -> &'static str {
        "conductor"
    }

    fn spec(&self) -> String {
        let mut s = format!(
            "conductor:{},alpha={},alpha_y={}",
            self.mf.dist.keyword(),
            self.mf.alpha_x,
            self.mf.alpha_y
        );
        match self.metal {
            Some(m) => s.push_str(&format!(",metal={}", m.name())),
            None => s.push_str(&format!(
                ",eta={},k={}",
                crate::spec::format_rgb(Rgb(self.eta)),
                crate::spec::format_rgb(Rgb(self.k))
            )),
        }
        s
    }

    /// `f` (no cosine), Walter 2007 eq. 20.
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        let Some(m) = (wi + wo).try_normalize() else {
            return Rgb::ZERO;
        };
        let d = self.mf.d(m);
        let g = self.mf.g(wi, wo, m);
        if d == 0.0 || g == 0.0 {
            return Rgb::ZERO;
        }
        conductor_rgb(wi.dot(m), self.eta, self.k) * (d * g / (4.0 * wi.z * wo.z))
    }

    /// Visible-normal sampling, then mirror reflection; `pdf = D_wi(m) / (4 wi.m)`
    /// (Heitz 2014 eq. 17 with Walter 2007 eq. 14). Reflections below the horizon are lost.
    fn sample(&self, wi: DVec3, u: [f64; 3]) -> Option<MaterialSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let m = self.mf.sample_visible(wi, [u[0], u[1]]);
        let wo = reflect(wi, m);
        if wo.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wi, wo);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let weight = self.eval(wi, wo) * (wo.z / pdf);
        Some(MaterialSample { wo, pdf, weight })
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let Some(m) = (wi + wo).try_normalize() else {
            return 0.0;
        };
        let c = wi.dot(m);
        if c <= 0.0 {
            return 0.0;
        }
        self.mf.visible_pdf(wi, m) / (4.0 * c)
    }

    fn is_transmissive(&self) -> bool {
        false
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
}
