//! Forward Euler steps: without Jacobians (direction only) and with them (direction + PDF).

use super::{step_det, step_time, Conditioned};
use crate::math::ln;
use crate::model::Model;
use crate::net::Jacobian;

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

    /// [`Model::flow`] from `K` start points at once, each lane bit for bit as alone
    /// ([`crate::net::VelocityNet::velocity_lanes`]).
    #[inline(always)]
    pub(crate) fn flow_lanes<const K: usize>(
        &self,
        c: &[Conditioned<VW>; K],
        x0: [[f32; 2]; K],
        steps: u32,
    ) -> [[f32; 2]; K] {
        let domain = self.def.domain;
        let h = 1.0 / steps as f32;
        let mut x = x0.map(|p| domain.advance(p, [0.0, 0.0]));
        for k in 0..steps {
            let t = step_time(k, h);
            let step = c.map(|ci| self.velocity.at_time(&ci.cond, t));
            let feat = x.map(|p| domain.features(p));
            let v = self.velocity.velocity_lanes(&step, &feat);
            for (p, vs) in x.iter_mut().zip(v) {
                *p = domain.advance(*p, [h * vs[0], h * vs[1]]);
            }
        }
        x
    }

    /// The pass with Jacobians from `x0`: `x_N`, `sum_k ln det(I + h dv/dx(x_k))` and the
    /// product of the step matrices; `None` if a step is not orientation preserving
    /// (`det <= 0`), where the density formula would not hold.
    #[inline(always)]
    pub(crate) fn flow_with_ln_det(
        &self,
        c: &Conditioned<VW>,
        x0: [f32; 2],
        steps: u32,
    ) -> Option<ForwardPass> {
        let domain = self.def.domain;
        let h = 1.0 / steps as f32;
        let start = domain.advance(x0, [0.0, 0.0]);
        let mut x = start;
        let mut ln_det = 0.0;
        let mut m = IDENTITY;
        for k in 0..steps {
            let step = self.velocity.at_time(&c.cond, step_time(k, h));
            let (feat, dfeat) = domain.features_with_derivative(x);
            let (v, j) = self.velocity.velocity_jacobian(&step, feat, dfeat);
            let det = step_det(h, &j);
            if !(det > 0.0) {
                return None;
            }
            ln_det += ln(det);
            m = step_times(h, &j, &m);
            x = domain.advance(x, [h * v[0], h * v[1]]);
        }
        Some(ForwardPass {
            start,
            end: x,
            ln_det,
            m,
        })
    }
}

/// What the pass with Jacobians computed: its start and end points, the steps'
/// `sum_k ln det(I + h J_k)` and `M = prod_k (I + h J_k)` (the last step leftmost), the
/// derivative of the end point by the start point.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ForwardPass {
    pub start: [f32; 2],
    pub end: [f32; 2],
    pub ln_det: f32,
    pub m: [[f32; 2]; 2],
}

const IDENTITY: [[f32; 2]; 2] = [[1.0, 0.0], [0.0, 1.0]];

/// `(I + h J) M`, row-major.
#[inline(always)]
fn step_times(h: f32, j: &Jacobian, m: &[[f32; 2]; 2]) -> [[f32; 2]; 2] {
    let a = [
        [1.0 + h * j[0][0], h * j[0][1]],
        [h * j[1][0], 1.0 + h * j[1][1]],
    ];
    let row = |r: [f32; 2]| {
        [
            r[0] * m[0][0] + r[1] * m[1][0],
            r[0] * m[0][1] + r[1] * m[1][1],
        ]
    };
    [row(a[0]), row(a[1])]
}
