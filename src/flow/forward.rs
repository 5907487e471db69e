//! Forward Euler steps: without Jacobians (direction only) and with them (direction + PDF).

use super::{step_det, step_time, Conditioned};
use crate::math::ln;
use crate::model::Model;

impl<
        const BE: usize,
        const BW: usize,
        const BM: usize,
        const VE: usize,
        const VW: usize,
        const VM: usize,
    > Model<BE, BW, BM, VE, VW, VM>
{
    /// `x_N` from `x0` (eq. 4 of the paper): no Jacobians.
    #[inline(always)]
    pub(crate) fn flow(&self, c: &Conditioned<VW>, x0: [f32; 2], steps: u32) -> [f32; 2] {
        let domain = self.def.domain;
        let h = 1.0 / steps as f32;
        let mut x = domain.advance(x0, [0.0, 0.0]);
        for k in 0..steps {
            let step = self.velocity.at_time(&c.cond, step_time(k, h));
            let v = self.velocity.velocity(&step, domain.features(x));
            x = domain.advance(x, [h * v[0], h * v[1]]);
        }
        x
    }

    /// `x_N` and `sum_k ln det(I + h dv/dx(x_k))`; `None` if a step is not orientation
    /// preserving (`det <= 0`), where the density formula would not hold.
    #[inline(always)]
    pub(crate) fn flow_with_ln_det(
        &self,
        c: &Conditioned<VW>,
        x0: [f32; 2],
        steps: u32,
    ) -> Option<([f32; 2], f32)> {
        let domain = self.def.domain;
        let h = 1.0 / steps as f32;
        let mut x = domain.advance(x0, [0.0, 0.0]);
        let mut ln_det = 0.0;
        for k in 0..steps {
            let step = self.velocity.at_time(&c.cond, step_time(k, h));
            let (feat, dfeat) = domain.features_with_derivative(x);
            let (v, j) = self.velocity.velocity_jacobian(&step, feat, dfeat);
            let det = step_det(h, &j);
            if !(det > 0.0) {
                return None;
            }
            ln_det += ln(det);
            x = domain.advance(x, [h * v[0], h * v[1]]);
        }
        Some((x, ln_det))
    }
}
