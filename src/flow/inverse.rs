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
use crate::spec::{LINE_SEARCH_HALVINGS, NEWTON_MAX_ITERS, NEWTON_TOL};

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
    ///
    /// Newton steps where `I + h dv/dx` is orientation preserving, fixed-point steps
    /// `x <- y - h v(x)` where it is not, each with a backtracking line search on the
    /// residual (halving the step until the residual shrinks), which breaks the two-cycles
    /// plain Newton can fall into on strongly curved velocity fields.
    #[inline]
    fn invert_step(&self, step: &[f32; VW], y: [f32; 2], h: f32) -> Option<([f32; 2], f32)> {
        let domain = self.def.domain;
        let v = self.velocity.velocity(step, domain.features(y));
        let first = domain.advance(y, [-h * v[0], -h * v[1]]);
        // Rarely, Newton from `y - h v(y)` falls into a cycle on a strongly curved field;
        // then it restarts from one fixed-point iterate further, and from `y - h v / 2`.
        self.newton(step, first, y, h)
            .or_else(|| {
                let v1 = self.velocity.velocity(step, domain.features(first));
                self.newton(step, domain.advance(y, [-h * v1[0], -h * v1[1]]), y, h)
            })
            .or_else(|| {
                self.newton(
                    step,
                    domain.advance(y, [-0.5 * h * v[0], -0.5 * h * v[1]]),
                    y,
                    h,
                )
            })
    }

    /// Newton's method for `x + h v(x) = y` from `x`.
    #[inline]
    fn newton(
        &self,
        step: &[f32; VW],
        mut x: [f32; 2],
        y: [f32; 2],
        h: f32,
    ) -> Option<([f32; 2], f32)> {
        let domain = self.def.domain;
        let mut at = self.residual(step, x, y, h);
        for _ in 0..NEWTON_MAX_ITERS {
            let (r, j, det) = at;
            let d = if det > 0.0 {
                // d = (I + h J)^-1 r, by the 2x2 adjugate.
                let (a00, a01, a10, a11) = (
                    1.0 + h * j[0][0],
                    h * j[0][1],
                    h * j[1][0],
                    1.0 + h * j[1][1],
                );
                [
                    (a11 * r[0] - a01 * r[1]) / det,
                    (a00 * r[1] - a10 * r[0]) / det,
                ]
            } else {
                r
            };
            let size = d[0].abs().max(d[1].abs());
            if !size.is_finite() {
                return None;
            }
            let scale = 1.0 + x[0].abs().max(x[1].abs());
            if size <= NEWTON_TOL * scale {
                // Converged: the last update is below the f32 noise of `x + h v(x)`. The
                // determinant is re-evaluated at the returned point, as the forward pass
                // evaluates it at x_k: where the flow compresses (det << 1) the one at the
                // previous iterate differs by far more than rounding.
                let x = domain.advance(x, [-d[0], -d[1]]);
                let det = self.residual(step, x, y, h).2;
                return (det > 0.0).then_some((x, det));
            }
            // Backtracking line search on the residual: from the same `x`, try the full
            // step, then half of it, ... (at most LINE_SEARCH_HALVINGS halvings) and take
            // the first that shrinks the residual, or the shortest tried if none does.
            let norm = r[0].abs().max(r[1].abs());
            let mut lambda = 1.0;
            let mut halvings = 0;
            let (trial, next) = loop {
                let trial = domain.advance(x, [-lambda * d[0], -lambda * d[1]]);
                let next = self.residual(step, trial, y, h);
                if next.0[0].abs().max(next.0[1].abs()) < norm || halvings == LINE_SEARCH_HALVINGS {
                    break (trial, next);
                }
                lambda *= 0.5;
                halvings += 1;
            };
            (x, at) = (trial, next);
            if lambda * size <= NEWTON_TOL * scale && at.2 > 0.0 {
                // The step just taken was below the f32 noise of `x + h v(x)`: converged,
                // with the determinant evaluated at the returned point.
                return Some((x, at.2));
            }
        }
        None
    }

    /// `x + h v(x) - y` (phi difference wrapped), `dv/dx` and `det(I + h dv/dx)` at `x`.
    #[inline(always)]
    fn residual(
        &self,
        step: &[f32; VW],
        x: [f32; 2],
        y: [f32; 2],
        h: f32,
    ) -> ([f32; 2], crate::net::Jacobian, f32) {
        let domain = self.def.domain;
        let (feat, dfeat) = domain.features_with_derivative(x);
        let (v, j) = self.velocity.velocity_jacobian(step, feat, dfeat);
        let r = domain.difference(domain.advance(x, [h * v[0], h * v[1]]), y);
        (r, j, step_det(h, &j))
    }
}
