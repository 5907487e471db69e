//! The start point of the direction `sample` returns.
//!
//! `sample` returns `wo` rounded to f32 (and turned into the world frame), and `pdf` reads
//! that rounded `wo`. Where the map from `x0` to `wo` compresses strongly (grazing
//! incidence near the mirror direction on the half-vector chart, the far tails of a sharp
//! base), one rounding of `wo` moves the density by more than float precision. So `sample`
//! reports the density at the flow point `pdf` reads for the returned `wo` (`end`), not at
//! the pass's own end point `x_N`: the start point that reaches `end` is, to first order,
//! `x0 + M^-1 (end - x_N)` with `M = prod_k (I + h J_k)` from the pass (docs/math.md,
//! (71)); where that moves the start by more than [`RETURNED_START_TOL`] of its size, the
//! steps' determinants are taken again along the trajectory from the moved start (72).

use super::forward::ForwardPass;
use super::Conditioned;
use crate::model::Model;
use crate::spec::RETURNED_START_TOL;

impl<
        const BE: usize,
        const BW: usize,
        const BM: usize,
        const VE: usize,
        const VW: usize,
        const VM: usize,
    > Model<BE, BW, BM, VE, VW, VM>
{
    /// The start point whose trajectory ends at `end` (near `pass.end`), and the steps'
    /// `sum_k ln det` along it; `None` where the pass from the moved start folds.
    #[inline(always)]
    pub(crate) fn returned_start(
        &self,
        c: &Conditioned<VW>,
        pass: &ForwardPass,
        end: [f32; 2],
        steps: u32,
    ) -> Option<([f32; 2], f32)> {
        let domain = self.def.domain;
        let d = domain.difference(end, pass.end);
        let m = pass.m;
        // dx0 = M^-1 (end - x_N) by the 2x2 adjugate   (docs/math.md, (71))
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        let dx = [
            (m[1][1] * d[0] - m[0][1] * d[1]) / det,
            (m[0][0] * d[1] - m[1][0] * d[0]) / det,
        ];
        if !(dx[0].is_finite() && dx[1].is_finite()) {
            return Some((pass.start, pass.ln_det));
        }
        let start = domain.advance(pass.start, dx);
        let size = dx[0].abs().max(dx[1].abs());
        let scale = 1.0 + pass.start[0].abs().max(pass.start[1].abs());
        if size <= RETURNED_START_TOL * scale {
            return Some((start, pass.ln_det));
        }
        // (72): the determinants along the trajectory from the moved start.
        let again = self.flow_with_ln_det(c, start, steps)?;
        Some((start, again.ln_det))
    }
}
