//! KL divergence from the target, `KL(p || q) = int p ln(p / q) dw`, by midpoint
//! quadrature in `(theta, phi)` with `dw = sin theta dtheta dphi`. `p` is the target
//! `Y(f) |cos theta_o|` normalised on the grid; `q` is a sampler's density, not
//! renormalised (mass it loses raises the divergence).

use super::sampler::{density, to_glam, SamplerKind};
use diffbsdf::glam::Vec3;
use diffbsdf::AnyModel;
use diffbsdf_ffi::slices::pdf_batch;
use diffbsdf_materials::{from_spherical, DVec3, Material};
use std::f64::consts::PI;

/// Quadrature resolution.
#[derive(Clone, Copy, Debug)]
pub struct KlGrid {
    /// Cells in theta over the hemisphere (twice as many over the sphere).
    pub theta: usize,
    /// Cells in phi.
    pub phi: usize,
}

/// `KL(target || kind)` at `wi` over the upper hemisphere, or the sphere when `both_sides`.
pub fn kl_divergence(
    kind: SamplerKind,
    material: &dyn Material,
    model: Option<&AnyModel>,
    wi: DVec3,
    both_sides: bool,
    grid: KlGrid,
) -> f64 {
    let nt = if both_sides {
        2 * grid.theta
    } else {
        grid.theta
    };
    let top = if both_sides { PI } else { PI / 2.0 };
    let (dt, dp) = (top / nt as f64, 2.0 * PI / grid.phi as f64);
    let mut cells = Vec::with_capacity(nt * grid.phi);
    let mut z = 0.0;
    for i in 0..nt {
        let theta = (i as f64 + 0.5) * dt;
        let dw = theta.sin() * dt * dp;
        for j in 0..grid.phi {
            let phi = -PI + (j as f64 + 0.5) * dp;
            let wo = from_spherical(theta, phi);
            let p = (material.eval_luminance(wi, wo) * wo.z.abs()).max(0.0);
            let p = if p.is_finite() { p } else { 0.0 };
            z += p * dw;
            cells.push((wo, p, dw));
        }
    }
    if !(z > 0.0) {
        return 0.0;
    }
    let q = densities(kind, material, model, wi, &cells);
    let mut kl = 0.0;
    for ((_, p, dw), q) in cells.into_iter().zip(q) {
        if p > 0.0 {
            let p = p / z;
            // Floor q so a hole in the sampler's support shows as a large, finite value.
            let q = q.max(1e-12);
            kl += p * (p / q).ln() * dw;
        }
    }
    kl
}

/// The density of `kind` at every cell's `wo` (0 where the target is 0, unused there); the
/// learned model's in one batch through `diffbsdf_ffi::slices` (the kernel's copy compiled
/// with AVX2 where the CPU has it, the same bits as [`density`]).
fn densities(
    kind: SamplerKind,
    material: &dyn Material,
    model: Option<&AnyModel>,
    wi: DVec3,
    cells: &[(DVec3, f64, f64)],
) -> Vec<f64> {
    if let (SamplerKind::Learned, Some(m)) = (kind, model) {
        let wo: Vec<Vec3> = cells
            .iter()
            .filter(|c| c.1 > 0.0)
            .map(|c| to_glam(c.0))
            .collect();
        let mut pdf = vec![0.0f32; wo.len()];
        if pdf_batch(m, &vec![to_glam(wi); wo.len()], &wo, 0, &mut pdf).is_ok() {
            let mut next = pdf.into_iter();
            return cells
                .iter()
                .map(|c| match c.1 > 0.0 {
                    true => next.next().map_or(0.0, f64::from),
                    false => 0.0,
                })
                .collect();
        }
    }
    cells
        .iter()
        .map(|&(wo, p, _)| {
            if p > 0.0 {
                density(kind, material, model, wi, wo)
            } else {
                0.0
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use diffbsdf_materials::parse_spec;

    /// The learned densities in one batch are [`density`]'s, cell by cell, bit for bit (0
    /// where the target is 0).
    #[test]
    fn batched_densities_are_the_calls_one_at_a_time() {
        let path = format!(
            "{}/../models/conductor-ggx-a0.05-0.3-cu-hv.dbsdf",
            env!("CARGO_MANIFEST_DIR")
        );
        let model = AnyModel::from_blob(&std::fs::read(path).unwrap()).unwrap();
        let material = parse_spec("conductor:ggx,alpha=0.05,alpha_y=0.3,metal=Cu").unwrap();
        let wi = from_spherical(60f64.to_radians(), 0.4);
        let cells: Vec<(DVec3, f64, f64)> = (0..40)
            .flat_map(|i| (0..40).map(move |j| (i, j)))
            .map(|(i, j)| {
                let wo = from_spherical((i as f64 + 0.5) * 0.0392, (j as f64 + 0.5) * 0.157);
                let p = if (i + j) % 7 == 0 { 0.0 } else { 1.0 };
                (wo, p, 1.0)
            })
            .collect();
        let batched = densities(
            SamplerKind::Learned,
            material.as_ref(),
            Some(&model),
            wi,
            &cells,
        );
        let mut positive = 0;
        for (c, q) in cells.iter().zip(&batched) {
            let want = if c.1 > 0.0 {
                density(
                    SamplerKind::Learned,
                    material.as_ref(),
                    Some(&model),
                    wi,
                    c.0,
                )
            } else {
                0.0
            };
            assert_eq!(q.to_bits(), want.to_bits(), "at {:?}", c.0);
            positive += usize::from(*q > 0.0);
        }
        assert!(positive > cells.len() / 2, "{positive} positive densities");
    }
}
