//! The flow: `N` explicit Euler steps `x_{k+1} = x_k + h v(x_k, t_k, wi)`, `h = 1/N`,
//! `t_k = k h`, and its exact inverse.
//!
//! `pdf_x(x_N) = p0(x0) / prod_k det(I + h dv/dx(x_k))` (docs/math.md, (1)) is exact
//! for the discrete map that runs, for any `N`, as long as each step is invertible.

mod forward;
mod inverse;

use crate::base::BaseDist;
use crate::model::Model;
use crate::net::encoding::{encode_wi, prefix};
use glam::Vec3;

/// What one `wi` fixes for a whole call: the base distribution and the first velocity
/// layer's `wi` part.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Conditioned<const VW: usize> {
    pub cond: [f32; VW],
    pub base: BaseDist,
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
        }
    }
}
