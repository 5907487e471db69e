//! The flow: `N` explicit Euler steps `x_{k+1} = x_k + h v(x_k, t_k, wi)`, `h = 1/N`,
//! `t_k = k h`, and its exact inverse.
//!
//! `pdf_x(x_N) = p0(x0) / prod_k det(I + h dv/dx(x_k))` (docs/math.md, (1)) is exact
//! for the discrete map that runs, for any `N`, as long as each step is invertible.

mod forward;
mod inverse;
mod returned;

use crate::base::table::TableSlice;
use crate::base::{gaussian, warp, BaseDist};
use crate::model::Model;
use crate::net::encoding::{encode_wi, prefix};
use glam::Vec3;

/// What one `wi` fixes for a whole call: the base distribution and the first velocity
/// layer's `wi` part.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Conditioned<const VW: usize> {
    pub cond: [f32; VW],
    pub base: BaseDist,
    /// The latent table's slices for this `wi` (unused without a table).
    pub slice: TableSlice,
}

/// `det(I + h J)` for a 2x2 Jacobian: `(1 + h J00)(1 + h J11) - h^2 J01 J10`.
#[inline(always)]
pub(crate) fn step_det(h: f32, j: &crate::net::Jacobian) -> f32 {
    (1.0 + h * j[0][0]) * (1.0 + h * j[1][1]) - (h * j[0][1]) * (h * j[1][0])
}

/// `t_k = k h`.
#[inline(always)]
pub(crate) fn step_time(k: u32, h: f32) -> f32 {
    k as f32 * h
}

impl<
        const BE: usize,
        const BW: usize,
        const BM: usize,
        const VE: usize,
        const VW: usize,
        const VM: usize,
    > Model<BE, BW, BM, VE, VW, VM>
{
    /// Evaluates the base net and the velocity net's `wi` part, once per call.
    #[inline(always)]
    pub(crate) fn condition(&self, wi: Vec3) -> Conditioned<VW> {
        let enc: [f32; VE] = encode_wi(wi.to_array());
        let base_enc: [f32; BE] = prefix(&enc);
        let base = BaseDist::from_net(self.def.domain, self.base.forward(&base_enc));
        Conditioned {
            cond: self.velocity.condition(&enc),
            base,
            slice: self.table.slice(wi.z),
        }
    }

    /// The flow's start point for `u`: `x0` (26) / (27), `z0` (59) in standard
    /// coordinates, or its compression (63) in warped ones.
    #[inline(always)]
    pub(crate) fn flow_start(&self, c: &Conditioned<VW>, u: [f32; 2]) -> [f32; 2] {
        if self.def.latent_table.is_some() {
            // u drawn through the latent table first (docs/math.md, (76)).
            BaseDist::standard_start(self.table.warp(c.slice, u), self.def.standard_warp)
        } else if self.def.standardized {
            BaseDist::standard_start(u, self.def.standard_warp)
        } else {
            c.base.sample(u)
        }
    }

    /// `ln p0` of the start point `p0` in the flow's coordinates: (32) / (34), (60), or
    /// (60) at `z0` = (64) of `p0` plus `ln |dz/dy|` (65) in warped coordinates (66).
    #[inline(always)]
    pub(crate) fn start_ln_pdf(&self, c: &Conditioned<VW>, p0: [f32; 2]) -> f32 {
        if !self.def.standardized {
            c.base.ln_pdf(p0)
        } else if self.def.standard_warp {
            let z0 = warp::expand2(p0);
            c.base.standard_ln_pdf(z0) + warp::ln_expansion2(p0) + self.table_ln_density(c, z0)
        } else {
            c.base.standard_ln_pdf(p0) + self.table_ln_density(c, p0)
        }
    }

    /// `ln` of the latent table's density at `(Phi(z0_0), Phi(z0_1))`, the point of `[0,
    /// 1]^2` the standard start `z0` was drawn from (docs/math.md, (77)); 0 without a table.
    #[inline(always)]
    fn table_ln_density(&self, c: &Conditioned<VW>, z0: [f32; 2]) -> f32 {
        if self.def.latent_table.is_some() {
            let x = [gaussian::cdf(z0[0]), gaussian::cdf(z0[1])];
            self.table.ln_density(c.slice, x)
        } else {
            0.0
        }
    }

    /// `ln |det|` of the map from the flow's end point to standard coordinates:
    /// (65) at the end point in warped coordinates, 0 otherwise (docs/math.md, (66)).
    #[inline(always)]
    pub(crate) fn end_ln_expansion(&self, p: [f32; 2]) -> f32 {
        if self.def.standard_warp {
            warp::ln_expansion2(p)
        } else {
            0.0
        }
    }

    /// The chart point of the flow's end point: itself, (61) in standard coordinates,
    /// (61) of (64) in warped ones.
    #[inline(always)]
    pub(crate) fn chart_point(&self, c: &Conditioned<VW>, p: [f32; 2]) -> [f32; 2] {
        if !self.def.standardized {
            p
        } else if self.def.standard_warp {
            c.base.from_standard(warp::expand2(p))
        } else {
            c.base.from_standard(p)
        }
    }

    /// The flow's end point for the chart point `y`: itself, (62) in standard
    /// coordinates, (63) of (62) in warped ones.
    #[inline(always)]
    pub(crate) fn flow_point(&self, c: &Conditioned<VW>, y: [f32; 2]) -> [f32; 2] {
        if !self.def.standardized {
            y
        } else if self.def.standard_warp {
            warp::compress2(c.base.to_standard(y))
        } else {
            c.base.to_standard(y)
        }
    }
}
