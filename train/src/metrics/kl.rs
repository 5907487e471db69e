//! KL divergence from the target, `KL(p || q) = int p ln(p / q) dw`, by midpoint
//! quadrature in `(theta, phi)` with `dw = sin theta dtheta dphi`. `p` is the target
//! `Y(f) |cos theta_o|` normalised on the grid; `q` is a sampler's density, not
//! renormalised (mass it loses raises the divergence).

use super::sampler::{density, SamplerKind};
use diffbsdf::AnyModel;
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
    let mut kl = 0.0;
    for (wo, p, dw) in cells {
        if p > 0.0 {
            let p = p / z;
            // Floor q so a hole in the sampler's support shows as a large, finite value.
            let q = density(kind, material, model, wi, wo).max(1e-12);
            kl += p * (p / q).ln() * dw;
        }
    }
    kl
}
