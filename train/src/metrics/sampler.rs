//! The three samplers compared on the same `wi`: the learned model, the material's own
//! sampler and cosine-weighted hemisphere sampling (on the side of `wi`).

use diffbsdf::glam;
use diffbsdf::{AnyModel, Sample};
use diffbsdf_ffi::slices::sample_batch;
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

/// Draws per call of the kernel's batch in [`learned_weights`].
const BATCH: usize = 4096;

/// The weights ([`weight`]) of `n` draws of the learned model at `wi`: the same `u` from
/// `rng` and the same samples as `n` calls of [`draw`], the kernel run in batches through
/// `diffbsdf_ffi::slices` (its copy compiled with AVX2 where the CPU has it, the same bits).
pub fn learned_weights(
    material: &dyn Material,
    model: &AnyModel,
    wi: DVec3,
    n: usize,
    rng: &mut Pcg64,
) -> Vec<f64> {
    let wi32 = to_glam(wi);
    let mut weights = Vec::with_capacity(n);
    let mut samples = vec![Sample::INVALID; BATCH];
    while weights.len() < n {
        let m = BATCH.min(n - weights.len());
        let u: Vec<glam::Vec2> = (0..m)
            .map(|_| glam::Vec2::new(rng.gen::<f32>(), rng.gen::<f32>()))
            .collect();
        let out = &mut samples[..m];
        if sample_batch(model, &vec![wi32; m], &u, 0, out).is_err() {
            out.fill(Sample::INVALID);
        }
        weights.extend(out.iter().map(|s| {
            let drawn = s.is_valid().then(|| Drawn {
                wo: from_glam(s.wo),
                pdf: s.pdf as f64,
            });
            weight(material, wi, drawn)
        }));
    }
    weights
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

#[cfg(test)]
mod tests {
    use super::*;
    use diffbsdf_materials::{from_spherical, parse_spec};
    use rand::SeedableRng;

    fn shipped(name: &str) -> AnyModel {
        let path = format!("{}/../models/{name}.dbsdf", env!("CARGO_MANIFEST_DIR"));
        AnyModel::from_blob(&std::fs::read(path).unwrap()).unwrap()
    }

    /// The batched draws are [`draw`]'s, one at a time, bit for bit: the same `u` from the
    /// stream, the same samples, the same weights (a length that is not a multiple of the
    /// batch, normal to grazing `wi`, a disk model and a half-vector one with its table).
    #[test]
    fn learned_weights_are_the_draws_one_at_a_time() {
        let cases = [
            (
                "conductor-ggx-a0.3-cu-disk",
                "conductor:ggx,alpha=0.3,metal=Cu",
            ),
            (
                "conductor-ggx-a0.05-0.3-cu-hv",
                "conductor:ggx,alpha=0.05,alpha_y=0.3,metal=Cu",
            ),
        ];
        for (name, spec) in cases {
            let model = shipped(name);
            let material = parse_spec(spec).unwrap();
            for theta in [0.0f64, 45.0, 89.0] {
                let wi = from_spherical(theta.to_radians(), 0.7);
                let n = BATCH + 37;
                let mut rng = Pcg64::seed_from_u64(5);
                let batched = learned_weights(material.as_ref(), &model, wi, n, &mut rng);
                let mut rng = Pcg64::seed_from_u64(5);
                let single: Vec<f64> = (0..n)
                    .map(|_| {
                        let d = draw(
                            SamplerKind::Learned,
                            material.as_ref(),
                            Some(&model),
                            wi,
                            &mut rng,
                        );
                        weight(material.as_ref(), wi, d)
                    })
                    .collect();
                assert_eq!(batched.len(), n);
                let differ = batched
                    .iter()
                    .zip(&single)
                    .filter(|(a, b)| a.to_bits() != b.to_bits())
                    .count();
                assert_eq!(differ, 0, "{name} at {theta} deg");
                assert!(single.iter().filter(|&&w| w > 0.0).count() > n / 2);
                // The stream is left where the draws one at a time leave it.
                assert_eq!(rng.gen::<u64>(), {
                    let mut again = Pcg64::seed_from_u64(5);
                    learned_weights(material.as_ref(), &model, wi, n, &mut again);
                    again.gen::<u64>()
                });
            }
        }
    }
}
