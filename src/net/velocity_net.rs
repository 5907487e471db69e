//! The velocity net `v(x, t, wi)` and its hand-derived input Jacobian `dv/dx`.
//!
//! The first layer is split by input: `z1 = Wx feat(x) + wt t + (Wc enc(wi) + b)`. The
//! bracket does not depend on `x` or `t`, so it is computed once per call
//! ([`VelocityNet::condition`]); each Euler step adds `wt t` ([`VelocityNet::at_time`]);
//! each evaluation adds the state columns.
//!
//! Forward-mode Jacobian: with `dz1/dx_j = Wx dfeat/dx_j`, every hidden layer maps
//! `dh = silu'(z) * dz` and `dz' = W dh`, and the readout gives `dv/dx_j = Wout dh_j`.

use super::activation::{silu, silu_layer, silu_layer_tangents};
use super::dense::{Dense, Readout};

use crate::math::mul_add;
use crate::spec::MAX_FEATURES;

/// A 2x2 matrix, row-major: `j[r][c] = dv_r / dx_c`.
pub type Jacobian = [[f32; 2]; 2];

/// `E` encoding inputs, `M + 1` hidden layers of width `W`, 2 outputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VelocityNet<const E: usize, const W: usize, const M: usize> {
    /// First-layer columns of the state features (the third is zero for disk models).
    pub wx: [[f32; W]; MAX_FEATURES],
    /// First-layer column of the time `t`.
    pub wt: [f32; W],
    /// First-layer columns of the `wi` encoding, and the first layer's bias.
    pub wc: Dense<E, W>,
    /// The further hidden layers.
    pub mid: [Dense<W, W>; M],
    /// The readout: the velocity.
    pub out: Readout<W, 2>,
}

impl<const E: usize, const W: usize, const M: usize> VelocityNet<E, W, M> {
    /// Every parameter zero.
    pub const ZERO: Self = VelocityNet {
        wx: [[0.0; W]; MAX_FEATURES],
        wt: [0.0; W],
        wc: Dense::ZERO,
        mid: [Dense::ZERO; M],
        out: Readout::ZERO,
    };

    /// `Wc enc(wi) + b`: the part of the first layer fixed for one call.
    #[inline]
    pub fn condition(&self, enc: &[f32; E]) -> [f32; W] {
        self.wc.forward(enc)
    }

    /// `condition + wt t`: the part of the first layer fixed for one Euler step.
    #[inline(always)]
    pub fn at_time(&self, cond: &[f32; W], t: f32) -> [f32; W] {
        let mut z = *cond;
        for (zo, &w) in z.iter_mut().zip(&self.wt) {
            *zo = mul_add(w, t, *zo);
        }
        z
    }

    #[inline(always)]
    fn first_layer(&self, step: &[f32; W], feat: [f32; MAX_FEATURES]) -> [f32; W] {
        let mut z = *step;
        for (col, &f) in self.wx.iter().zip(&feat) {
            for (zo, &w) in z.iter_mut().zip(col) {
                *zo = mul_add(w, f, *zo);
            }
        }
        z
    }

    /// `v` at state features `feat`, given the step's first-layer part `step`.
    #[inline(always)]
    pub fn velocity(&self, step: &[f32; W], feat: [f32; MAX_FEATURES]) -> [f32; 2] {
        let mut h = self.first_layer(step, feat);
        silu_layer(&mut h);
        for layer in &self.mid {
            h = layer.forward(&h);
            silu_layer(&mut h);
        }
        self.out.forward(&h)
    }

    /// [`VelocityNet::velocity`] at `K` states at once, each lane bit for bit as alone: the
    /// hidden layers laid out lanes innermost (`h[o][s]`, [`Dense::forward_lanes`]).
    #[inline(always)]
    pub fn velocity_lanes<const K: usize>(
        &self,
        step: &[[f32; W]; K],
        feat: &[[f32; MAX_FEATURES]; K],
    ) -> [[f32; 2]; K] {
        // The first layer as `first_layer` computes it, lane by lane.
        let mut h = [[0.0f32; K]; W];
        for (o, ho) in h.iter_mut().enumerate() {
            for (hs, st) in ho.iter_mut().zip(step) {
                *hs = st[o];
            }
        }
        for (f, col) in self.wx.iter().enumerate() {
            for (ho, &w) in h.iter_mut().zip(col) {
                for (hs, ft) in ho.iter_mut().zip(feat) {
                    *hs = mul_add(w, ft[f], *hs);
                }
            }
        }
        h.iter_mut().flatten().for_each(|v| *v = silu(*v));
        for layer in &self.mid {
            h = layer.forward_lanes(&h);
            h.iter_mut().flatten().for_each(|v| *v = silu(*v));
        }
        let v = self.out.forward_lanes(&h);
        core::array::from_fn(|s| [v[0][s], v[1][s]])
    }

    /// `v` and `dv/dx`, where `dfeat[j]` is the derivative of the features along `x_j`.
    #[inline(always)]
    pub fn velocity_jacobian(
        &self,
        step: &[f32; W],
        feat: [f32; MAX_FEATURES],
        dfeat: [[f32; MAX_FEATURES]; 2],
    ) -> ([f32; 2], Jacobian) {
        let mut h = self.first_layer(step, feat);
        let mut dh = [[0.0; W]; 2];
        for (dz, df) in dh.iter_mut().zip(&dfeat) {
            for (col, &d) in self.wx.iter().zip(df) {
                for (o, &w) in dz.iter_mut().zip(col) {
                    *o = mul_add(w, d, *o);
                }
            }
        }
        silu_layer_tangents(&mut h, &mut dh);
        for layer in &self.mid {
            let (z, dz) = layer.forward_tangents(&h, &dh);
            h = z;
            dh = dz;
            silu_layer_tangents(&mut h, &mut dh);
        }
        let v = self.out.forward(&h);
        let d0 = self.out.tangent(&dh[0]);
        let d1 = self.out.tangent(&dh[1]);
        (v, [[d0[0], d1[0]], [d0[1], d1[1]]])
    }

    /// Every parameter in blob order. The first layer is stored row by row over the
    /// inputs `[features (feature_count), t, encoding]`, then its bias.
    pub(crate) fn visit_mut(&mut self, feature_count: usize, f: &mut impl FnMut(&mut f32)) {
        for o in 0..W {
            for col in self.wx.iter_mut().take(feature_count) {
                f(&mut col[o]);
            }
            f(&mut self.wt[o]);
            for col in self.wc.w.iter_mut() {
                f(&mut col[o]);
            }
        }
        self.wc.b.iter_mut().for_each(&mut *f);
        for layer in self.mid.iter_mut() {
            layer.visit_mut(f);
        }
        self.out.visit_mut(f);
    }

    /// Reads every parameter in the order of [`VelocityNet::visit_mut`].
    pub(crate) fn visit(&self, feature_count: usize, f: &mut impl FnMut(f32)) {
        for o in 0..W {
            for col in self.wx.iter().take(feature_count) {
                f(col[o]);
            }
            f(self.wt[o]);
            for col in self.wc.w.iter() {
                f(col[o]);
            }
        }
        self.wc.b.iter().for_each(|&b| f(b));
        for layer in self.mid.iter() {
            layer.visit(f);
        }
        self.out.visit(f);
    }
}
