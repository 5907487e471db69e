//! The three samplers compared on the same `wi`: the learned model, the material's own
//! sampler and cosine-weighted hemisphere sampling (on the side of `wi`).

use diffbsdf::glam;
use diffbsdf::AnyModel;
use diffbsdf_materials::{DVec3, Material};
use rand::Rng;
use rand_pcg::Pcg64;
use serde::Serialize;

/// Which sampler.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SamplerKind {
    /// The trained model in the kernel.
    Learned,
    /// The material's own analytic sampler.
    Material,
    /// Cosine-weighted hemisphere on the side of `wi`.
    Cosine,
}

/// A drawn direction and its density per unit solid angle.
#[derive(Clone, Copy, Debug)]
pub struct Drawn {
    /// The direction.
    pub wo: DVec3,
    /// Its density.
    pub pdf: f64,
}

/// Converts to the kernel's vector type.
pub fn to_glam(v: DVec3) -> glam::Vec3 {
    v.as_vec3()
}

/// Converts from the kernel's vector type (renormalised in f64).
pub fn from_glam(v: glam::Vec3) -> DVec3 {
    let w = v.as_dvec3();
    w.try_normalize().unwrap_or(w)
}

/// One draw of `kind` at `wi`; `None` for an invalid sample.
pub fn draw(
    kind: SamplerKind,
    material: &dyn Material,
    model: Option<&AnyModel>,
    wi: DVec3,
    rng: &mut Pcg64,
) -> Option<Drawn> {
    match kind {
        SamplerKind::Learned => {
            let u = glam::Vec2::new(rng.gen::<f32>(), rng.gen::<f32>());
            let s = model?.sample(to_glam(wi), u)?;
            Some(Drawn {
                wo: from_glam(s.wo),
                pdf: s.pdf as f64,
            })
        }
        SamplerKind::Material => {
            let s = material.sample(wi, [rng.gen(), rng.gen(), rng.gen()])?;
            Some(Drawn {
                wo: s.wo,
                pdf: s.pdf,
            })
        }
        SamplerKind::Cosine => {
            let (u0, u1): (f64, f64) = (rng.gen(), rng.gen());
            let r = u0.sqrt();
            let phi = 2.0 * std::f64::consts::PI * u1;
            let z = (1.0 - u0).max(0.0).sqrt();
            let z = if wi.z < 0.0 { -z } else { z };
            Some(Drawn {
                wo: DVec3::new(r * phi.cos(), r * phi.sin(), z),
                pdf: z.abs() / std::f64::consts::PI,
            })
        }
    }
}

/// Density of `kind` at `wo` (for KL): the learned model's by its exact inverse.
pub fn density(
    kind: SamplerKind,
    material: &dyn Material,
    model: Option<&AnyModel>,
    wi: DVec3,
    wo: DVec3,
) -> f64 {
    match kind {
        SamplerKind::Learned => model.map_or(0.0, |m| m.pdf(to_glam(wi), to_glam(wo)) as f64),
        SamplerKind::Material => material.pdf(wi, wo),
        SamplerKind::Cosine => {
            if wo.z * wi.z > 0.0 || (wi.z == 0.0 && wo.z > 0.0) {
                wo.z.abs() / std::f64::consts::PI
            } else {
                0.0
            }
        }
    }
}

/// `w = Y(f) |cos theta_o| / pdf` of a draw; 0 when invalid.
pub fn weight(material: &dyn Material, wi: DVec3, d: Option<Drawn>) -> f64 {
    let Some(d) = d else { return 0.0 };
    if !(d.pdf > 0.0 && d.pdf.is_finite()) {
        return 0.0;
    }
    let w = material.eval_luminance(wi, d.wo) * d.wo.z.abs() / d.pdf;
    if w.is_finite() && w > 0.0 {
        w
    } else {
        0.0
    }
}
