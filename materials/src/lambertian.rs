//! Lambertian (ideal diffuse) BRDF.

use crate::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::{DVec3, Material, MaterialSample, Rgb};
use std::f64::consts::FRAC_1_PI;

/// `f = albedo / pi` on the upper hemisphere; sampled by the cosine-weighted hemisphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambertian {
    /// Directional-hemispherical reflectance per channel.
    pub albedo: Rgb,
}

impl Material for Lambertian {
    fn name(&self) -> &'static str {
        "lambertian"
    }

    fn spec(&self) -> String {
        format!("lambertian:albedo={}", crate::spec::format_rgb(self.albedo))
    }

    /// `f = albedo / pi` when both directions are above the surface.
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        self.albedo * FRAC_1_PI
    }

    fn sample(&self, wi: DVec3, u: [f64; 3]) -> Option<MaterialSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let wo = square_to_cosine_hemisphere([u[0], u[1]]);
        let pdf = cosine_hemisphere_pdf(wo);
        if pdf <= 0.0 {
            return None;
        }
        Some(MaterialSample {
            wo,
            pdf,
            weight: self.albedo,
        })
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        if wi.z <= 0.0 {
            return 0.0;
        }
        cosine_hemisphere_pdf(wo)
    }

    fn is_transmissive(&self) -> bool {
        false
    }

    fn is_isotropic(&self) -> bool {
        true
    }
}
