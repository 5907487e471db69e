//! The exact inverse of the Euler steps, for the PDF of a given direction.
//!
//! Each step `y = x + h v(x, t)` is solved for `x` by Newton's method on the 2x2 system
//! `F(x) = x + h v(x, t) - y = 0`, `x <- x - (I + h dv/dx)^-1 F(x)`, starting from
//! `x = y - h v(y, t)`. Unlike integrating the ODE backwards, this recovers the very `x_k`
//! the forward pass visited, so the PDF of a sampled direction equals the PDF reported
//! when it was sampled.

use super::{step_det, step_time, Conditioned};
use crate::math::ln;
use crate::model::Model;

/// Newton iterations before a step is declared not invertible.
pub const NEWTON_MAX_ITERS: u32 = 16;
/// Newton stops when the update is below `NEWTON_TOL * (1 + |x|)` (max norm); f32 noise in
/// `x + h v(x)` sits near 3e-7 of that scale.
pub const NEWTON_TOL: f32 = 1e-6;

impl<
        const BE: usize,
        const BW: usize,
        const BM: usize,
        const VE: usize,
        const VW: usize,
        const VM: usize,
    > Model<BE, BW, BM, VE, VW, VM>
{
    /// `x0` and `sum_k ln det(I + h dv/dx(x_k))` for the end point `y`; `None` if a step
    /// cannot be inverted (Newton did not converge, or `det <= 0`).
    #[inline]
    pub(crate) fn flow_inverse(
        &self,
        c: &Conditioned<VW>,
        y: [f32; 2],
        steps: u32,
    ) -> Option<([f32; 2], f32)> {
        let h = 1.0 / steps as f32;
        let mut x = self.def.domain.advance(y, [0.0, 0.0]);
        let mut ln_det = 0.0;
        for k in (0..steps).rev() {
            let step = self.velocity.at_time(&c.cond, step_time(k, h));
            let (prev, det) = self.invert_step(&step, x, h)?;
            ln_det += ln(det);
            x = prev;
        }
        Some((x, ln_det))
    }

    /// Solves `x + h v(x) = y` for one step; returns `x` and `det(I + h dv/dx(x))`.
    #[inline]
    fn invert_step(&self, step: &[f32; VW], y: [f32; 2], h: f32) -> Option<([f32; 2], f32)> {
        let domain = self.def.domain;
        let v = self.velocity.velocity(step, domain.features(y));
        let mut x = domain.advance(y, [-h * v[0], -h * v[1]]);
        for _ in 0..NEWTON_MAX_ITERS {
            let (feat, dfeat) = domain.features_with_derivative(x);
            let (v, j) = self.velocity.velocity_jacobian(step, feat, dfeat);
            let det = step_det(h, &j);
            if !(det > 0.0) {
                return None;
            }
            let r = domain.difference(domain.advance(x, [h * v[0], h * v[1]]), y);
            // d = (I + h J)^-1 r, by the 2x2 adjugate.
            let (a00, a01, a10, a11) = (
                1.0 + h * j[0][0],
                h * j[0][1],
                h * j[1][0],
                1.0 + h * j[1][1],
            );
            let d = [
                (a11 * r[0] - a01 * r[1]) / det,
                (a00 * r[1] - a10 * r[0]) / det,
            ];
            x = domain.advance(x, [-d[0], -d[1]]);
            let scale = 1.0 + x[0].abs().max(x[1].abs());
            let size = d[0].abs().max(d[1].abs());
            if size <= NEWTON_TOL * scale {
                return Some((x, det));
            }
            if !size.is_finite() {
                return None;
            }
        }
        None
    }
}
