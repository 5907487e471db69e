//! A reflection BRDF seen in half-vector space: the "directions" of this material are the
//! half vectors `h = normalize(wi + wo)` of another material's reflections.
//!
//! For a fixed `wi`, `h -> wo = 2 (wi.h) h - wi` maps the hemisphere `wi.h > 0` one to one
//! onto the sphere, with `dw_o / dw_h = 4 (wi.h)` (Walter et al. 2007, eq. 14). Everything
//! is expressed per unit solid angle of `h`:
//!
//! - `f_h(wi, h) |h.z| = f(wi, wo) |wo.z| 4 (wi.h)`: the target `Y(f) |cos|` a sampler of
//!   `h` has to follow, with the same integral as the inner material's;
//! - `pdf_h(wi, h) = pdf(wi, wo) 4 (wi.h)`.
//!
//! Importance-sampling weights `f |cos| / pdf` are the same in both spaces, so a sampler
//! fitted to this material has the variance it would have on the inner one if its samples
//! were reflected back (`wo` of `h`). It lets the trainer measure the half-vector chart
//! (where a measured BRDF's specular peak sits at `h = n` for every `wi`, and the horizon
//! of `wo` lies inside the chart instead of on its rim) without a new kernel domain.

use crate::{reflect, DVec3, Material, MaterialSample, Rgb};

/// The half-vector view of a reflection-only material.
#[derive(Debug)]
pub struct Halfway {
    inner: Box<dyn Material>,
}

impl Halfway {
    /// Wraps `inner`; `None` for a material that transmits (its half vectors are not
    /// those of a reflection).
    pub fn new(inner: Box<dyn Material>) -> Option<Halfway> {
        (!inner.is_transmissive()).then_some(Halfway { inner })
    }

    /// The reflected direction of half vector `h` and `wi.h`; `None` where `h` is not the
    /// half vector of a reflection above the surface.
    fn reflection(wi: DVec3, h: DVec3) -> Option<(DVec3, f64)> {
        let cos_ih = wi.dot(h);
        if !(cos_ih > 0.0 && h.z > 0.0 && wi.z > 0.0) {
            return None;
        }
        let wo = reflect(wi, h);
        (wo.z > 0.0).then_some((wo, cos_ih))
    }
}

impl Material for Halfway {
    fn name(&self) -> &'static str {
        "halfway"
    }

    fn spec(&self) -> String {
        format!("halfway:{}", self.inner.spec())
    }

    /// `f_h = f(wi, wo) |wo.z| 4 (wi.h) / |h.z|`, 0 where `h` reflects below the surface.
    fn eval(&self, wi: DVec3, h: DVec3) -> Rgb {
        match Halfway::reflection(wi, h) {
            Some((wo, cos_ih)) => self.inner.eval(wi, wo) * (wo.z * 4.0 * cos_ih / h.z),
            None => Rgb::ZERO,
        }
    }

    fn sample(&self, wi: DVec3, u: [f64; 3]) -> Option<MaterialSample> {
        let s = self.inner.sample(wi, u)?;
        let sum = wi + s.wo;
        let len = sum.length();
        if !(len > 0.0) {
            return None;
        }
        let h = sum / len;
        let (_, cos_ih) = Halfway::reflection(wi, h)?;
        let pdf = s.pdf * 4.0 * cos_ih;
        (pdf > 0.0 && pdf.is_finite()).then_some(MaterialSample {
            wo: h,
            pdf,
            weight: s.weight,
        })
    }

    fn pdf(&self, wi: DVec3, h: DVec3) -> f64 {
        match Halfway::reflection(wi, h) {
            Some((wo, cos_ih)) => self.inner.pdf(wi, wo) * 4.0 * cos_ih,
            None => 0.0,
        }
    }

    fn is_transmissive(&self) -> bool {
        false
    }

    fn is_isotropic(&self) -> bool {
        self.inner.is_isotropic()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse_spec;

    fn halfway(spec: &str) -> Halfway {
        Halfway::new(parse_spec(spec).unwrap()).unwrap()
    }

    /// The sampler's weights and PDF agree with `eval` and `pdf` in half-vector space, and
    /// the target integrates to the inner material's albedo (checked against the inner
    /// sampler's mean weight).
    #[test]
    fn weights_and_densities_agree_in_half_vector_space() {
        let m = halfway("conductor:ggx,alpha=0.3,metal=Cu");
        let wi = DVec3::new(0.6, 0.0, 0.8);
        let (mut mean_w, mut n) = (0.0, 0u32);
        let mut rng = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..20_000 {
            let u = [next(), next(), next()];
            if let Some(s) = m.sample(wi, u) {
                let pdf = m.pdf(wi, s.wo);
                assert!((pdf - s.pdf).abs() <= 1e-9 * s.pdf, "{pdf} vs {}", s.pdf);
                let w = m.eval_cos(wi, s.wo).luminance() / s.pdf;
                assert!((w - s.weight.luminance()).abs() <= 1e-9 * w.max(1.0));
                mean_w += w;
            }
            n += 1;
        }
        let inner = parse_spec("conductor:ggx,alpha=0.3,metal=Cu").unwrap();
        let mut albedo = 0.0;
        for _ in 0..20_000 {
            let u = [next(), next(), next()];
            if let Some(s) = inner.sample(wi, u) {
                albedo += s.weight.luminance();
            }
        }
        let (a, b) = (mean_w / n as f64, albedo / 20_000.0);
        assert!((a - b).abs() < 0.02 * b, "{a} vs {b}");
    }

    #[test]
    fn refuses_transmission_and_reflections_below() {
        assert!(Halfway::new(parse_spec("dielectric:ggx,alpha=0.3,eta=1.5").unwrap()).is_none());
        let m = halfway("lambertian");
        let wi = DVec3::new(0.0, 0.0, 1.0);
        assert_eq!(m.pdf(wi, DVec3::new(1.0, 0.0, 0.0)), 0.0);
        assert_eq!(m.eval(wi, DVec3::new(0.0, 0.0, -1.0)).luminance(), 0.0);
    }
}
