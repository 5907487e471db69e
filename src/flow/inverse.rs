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
use crate::spec::{
    DET_REUSE_TOL, DET_SECANT_TOL, LINE_SEARCH_HALVINGS, NEWTON_MAX_ITERS, NEWTON_TOL,
};

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
    ///
    /// Each step starts from `x_{k+1} - h v(x_{k+1}, t_{k+1})`: the velocity where the
    /// trajectory is at the next time, which the previous inversion already evaluated (for
    /// the last step, one evaluation at `t = 1`). A rectified flow moves along nearly
    /// straight lines at nearly constant speed, so this start is close to `x_k`
    /// (docs/math.md, (43)).
    #[inline(always)]
    pub(crate) fn flow_inverse(
        &self,
        c: &Conditioned<VW>,
        y: [f32; 2],
        steps: u32,
    ) -> Option<([f32; 2], f32)> {
        let domain = self.def.domain;
        let h = 1.0 / steps as f32;
        let mut x = domain.advance(y, [0.0, 0.0]);
        let end = self.velocity.at_time(&c.cond, step_time(steps, h));
        let mut v = self.velocity.velocity(&end, domain.features(x));
        let mut ln_det = 0.0;
        for k in (0..steps).rev() {
            let step = self.velocity.at_time(&c.cond, step_time(k, h));
            let root = self.invert_step(&step, x, v, h)?;
            ln_det += ln(root.det);
            (x, v) = (root.x, root.v);
        }
        Some((x, ln_det))
    }

    /// Solves `x + h v(x) = y` for one step, starting from `y - h v_next`.
    ///
    /// Newton steps where `I + h dv/dx` is orientation preserving, fixed-point steps
    /// `x <- y - h v(x)` where it is not, each with a backtracking line search on the
    /// residual (halving the step until the residual shrinks), which breaks the two-cycles
    /// plain Newton can fall into on strongly curved velocity fields.
    #[inline(always)]
    fn invert_step(&self, step: &[f32; VW], y: [f32; 2], v_next: [f32; 2], h: f32) -> Option<Root> {
        let domain = self.def.domain;
        let from = |v: [f32; 2], s: f32| domain.advance(y, [-s * h * v[0], -s * h * v[1]]);
        // Rarely, Newton falls into a cycle on a strongly curved field; then it restarts
        // from `y - h v(y)` (the velocity at this step's time), from one fixed-point
        // iterate further, and from `y - h v(y) / 2` (docs/math.md, (43)). One call site
        // of `newton`, so that it is inlined once.
        let mut v = v_next;
        for start in 0..4 {
            let x = match start {
                0 => from(v_next, 1.0),
                1 => {
                    v = self.velocity.velocity(step, domain.features(y));
                    from(v, 1.0)
                }
                2 => {
                    let v1 = self.velocity.velocity(step, domain.features(from(v, 1.0)));
                    from(v1, 1.0)
                }
                _ => from(v, 0.5),
            };
            if let Some(root) = self.newton(step, x, y, h) {
                return Some(root);
            }
        }
        None
    }

    /// Newton's method for `x + h v(x) = y` from `x`.
    #[inline(always)]
    fn newton(&self, step: &[f32; VW], mut x: [f32; 2], y: [f32; 2], h: f32) -> Option<Root> {
        let domain = self.def.domain;
        let mut at = self.residual(step, x, y, h);
        // The determinant at the iterate before `x` and the length of the step taken from
        // it (0: `x` is the start).
        let (mut prev_det, mut prev_step) = (0.0f32, 0.0f32);
        for _ in 0..NEWTON_MAX_ITERS {
            let (r, j, det) = (at.r, at.j, at.det);
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
                // determinant is taken at the returned point, as the forward pass takes it
                // at x_k: where the flow compresses (det << 1) the one at an iterate farther
                // away differs by more than rounding. Where the update is about one rounding
                // of `x` (DET_REUSE_TOL), or the determinant changes by less than
                // DET_SECANT_TOL over it, the evaluation at `x` stands for it.
                let next = domain.advance(x, [-d[0], -d[1]]);
                let flat = det_flat(at.det, prev_det, size, prev_step);
                let fin = if size <= DET_REUSE_TOL * scale || flat {
                    at
                } else {
                    self.residual(step, next, y, h)
                };
                return (fin.det > 0.0).then_some(Root {
                    x: next,
                    det: fin.det,
                    v: fin.v,
                });
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
                if next.r[0].abs().max(next.r[1].abs()) < norm || halvings == LINE_SEARCH_HALVINGS {
                    break (trial, next);
                }
                lambda *= 0.5;
                halvings += 1;
            };
            (prev_det, prev_step) = (at.det, lambda * size);
            (x, at) = (trial, next);
            if lambda * size <= NEWTON_TOL * scale && at.det > 0.0 {
                // The step just taken was below the f32 noise of `x + h v(x)`: converged,
                // with the determinant evaluated at the returned point.
                return Some(Root {
                    x,
                    det: at.det,
                    v: at.v,
                });
            }
        }
        None
    }

    /// `x + h v(x) - y` (phi difference wrapped), `v`, `dv/dx` and `det(I + h dv/dx)` at
    /// `x`.
    #[inline(always)]
    fn residual(&self, step: &[f32; VW], x: [f32; 2], y: [f32; 2], h: f32) -> Residual {
        let domain = self.def.domain;
        let (feat, dfeat) = domain.features_with_derivative(x);
        let (v, j) = self.velocity.velocity_jacobian(step, feat, dfeat);
        let r = domain.difference(domain.advance(x, [h * v[0], h * v[1]]), y);
        Residual {
            r,
            v,
            j,
            det: step_det(h, &j),
        }
    }
}

/// Whether the determinant changes by at most `DET_SECANT_TOL` (relative) over Newton's
/// last update of length `size`, extrapolated from its change from `prev_det` to `det`
/// over the step of length `prev_step` before it (docs/math.md, "Determinant at the
/// returned point"); false where there was no step before or either determinant is not
/// positive.
#[inline(always)]
fn det_flat(det: f32, prev_det: f32, size: f32, prev_step: f32) -> bool {
    det > 0.0
        && prev_det > 0.0
        && prev_step > 0.0
        && ((det - prev_det).abs() / det) * (size / prev_step) <= DET_SECANT_TOL
}

/// One step's solution: `x_k`, `det(I + h dv/dx(x_k))` and `v(x_k, t_k)`.
#[derive(Clone, Copy, Debug)]
struct Root {
    x: [f32; 2],
    det: f32,
    v: [f32; 2],
}

/// Newton's state at a point: residual, velocity, Jacobian, step determinant.
#[derive(Clone, Copy, Debug)]
struct Residual {
    r: [f32; 2],
    v: [f32; 2],
    j: crate::net::Jacobian,
    det: f32,
}
