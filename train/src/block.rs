//! A chunk of rows through an [`Mlp`] layer by layer: each layer's three matrix products
//! run over the whole chunk in register tiles ([`crate::tiles`]).
//!
//! Every sum keeps the order of the row-at-a-time pass ([`Mlp::forward_tape`],
//! [`Mlp::backward`]), with no fused multiply-add, so the results are the same bits, only
//! computed with far fewer loads and stores (`block_matches_the_row_pass` below checks it).

use crate::mlp::{LayerAt, Mlp};
use crate::tiles::{affine, transpose, transpose_times, weight_grad};
use diffbsdf::internals::net::activation::silu_with_slope;

/// The activations of a chunk, kept for its backward pass, and two scratch matrices.
#[derive(Clone, Debug, Default)]
pub struct Block {
    /// `z` of every layer, `rows x outputs` row-major; the last is the net's output.
    pre: Vec<Vec<f32>>,
    /// `silu(z)` of every hidden layer.
    post: Vec<Vec<f32>>,
    /// `silu'(z)` of every hidden layer.
    slope: Vec<Vec<f32>>,
    /// `dL/dz` of the current layer.
    dz: Vec<f32>,
    /// `dL/da` of the layer below.
    da: Vec<f32>,
    /// The weights of the layer being run, transposed.
    wt: Vec<f32>,
}

impl Block {
    /// Forward pass of `rows` input rows (`x`, back to back); returns the outputs,
    /// `rows x outputs` row-major.
    pub fn forward(&mut self, net: &Mlp, x: &[f32]) -> &[f32] {
        let layers = net.layers().len();
        self.pre.resize(layers, Vec::new());
        self.post.resize(layers.saturating_sub(1), Vec::new());
        self.slope.resize(layers.saturating_sub(1), Vec::new());
        let rows = x.len() / net.inputs().max(1);
        for l in 0..layers {
            let at = net.layer(l);
            let input: &[f32] = if l == 0 { x } else { &self.post[l - 1] };
            let z = &mut self.pre[l];
            z.resize(rows * at.n_out, 0.0);
            transpose(net.params(), at, &mut self.wt);
            affine(net.params(), at, &self.wt, input, z);
            if net.layers()[l].activated {
                let (h, slope) = (&mut self.post[l], &mut self.slope[l]);
                h.resize(z.len(), 0.0);
                slope.resize(z.len(), 0.0);
                for ((hv, sv), zv) in h.iter_mut().zip(slope.iter_mut()).zip(z.iter()) {
                    (*hv, *sv) = silu_with_slope(*zv);
                }
            }
        }
        self.pre.last().map_or(&[], Vec::as_slice)
    }

    /// Backward pass of the rows last run forward on `x`: adds `dL/dparams` to `grad`
    /// given `dL/doutput` (`rows x outputs`).
    pub fn backward(&mut self, net: &Mlp, x: &[f32], d_out: &[f32], grad: &mut [f32]) {
        let rows = x.len() / net.inputs().max(1);
        self.dz.clear();
        self.dz.extend_from_slice(d_out);
        for l in (0..net.layers().len()).rev() {
            let at = net.layer(l);
            let input: &[f32] = if l == 0 { x } else { &self.post[l - 1] };
            // dL/db = sum_rows dz, dL/dW[o][i] = sum_rows dz[o] a[i]
            bias_grad(&self.dz, at, rows, grad);
            weight_grad(&self.dz, input, at, rows, grad);
            if l == 0 {
                break;
            }
            // dL/da = W^T dz, then through SiLU: dz_prev = dL/da * silu'(z_prev)
            self.da.resize(rows * at.n_in, 0.0);
            transpose_times(net.params(), at, &self.dz, rows, &mut self.da);
            self.dz.clear();
            self.dz
                .extend(self.da.iter().zip(&self.slope[l - 1]).map(|(d, s)| d * s));
        }
    }
}

/// `grad_b[o] += dz[r][o]`, rows in order.
#[inline(never)]
fn bias_grad(dz: &[f32], at: LayerAt, rows: usize, grad: &mut [f32]) {
    let gb = &mut grad[at.b..at.b + at.n_out];
    for r in 0..rows {
        for (g, d) in gb.iter_mut().zip(&dz[r * at.n_out..(r + 1) * at.n_out]) {
            *g += d;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mlp::Tape;
    use diffbsdf::Layer;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// Loss `sum(out^2) + out[0]` through both passes.
    fn head(out: &[f32], d: &mut [f32]) {
        for (dv, o) in d.iter_mut().zip(out) {
            *dv = 2.0 * o;
        }
        d[0] += 1.0;
    }

    #[test]
    fn block_matches_the_row_pass() {
        let mut rng = Pcg64::seed_from_u64(3);
        // Shapes with ragged edges everywhere: 21 inputs, 7- and 96-wide layers, 2 outputs.
        for (width, hidden, rows) in [(7usize, 2usize, 13usize), (96, 4, 37), (32, 3, 4)] {
            let layers: Vec<Layer> = (0..=hidden)
                .map(|l| Layer {
                    inputs: if l == 0 { 21 } else { width },
                    outputs: if l == hidden { 2 } else { width },
                    activated: l < hidden,
                })
                .collect();
            let net = Mlp::with_layers(layers, &mut rng);
            let x: Vec<f32> = (0..rows * 21).map(|_| rng.gen_range(-2.0..2.0)).collect();
            let mut grad_rows = vec![0.0f32; net.params().len()];
            let mut out_rows = Vec::new();
            let (mut tape, mut scratch) = (Tape::default(), [Vec::new(), Vec::new()]);
            for xr in x.chunks_exact(21) {
                let out = net.forward_tape(xr, &mut tape).to_vec();
                let mut d = vec![0.0; 2];
                head(&out, &mut d);
                net.backward(xr, &tape, &d, &mut grad_rows, &mut scratch);
                out_rows.extend(out);
            }
            let mut block = Block::default();
            let out = block.forward(&net, &x).to_vec();
            let mut d = vec![0.0; out.len()];
            for (dr, o) in d.chunks_exact_mut(2).zip(out.chunks_exact(2)) {
                head(o, dr);
            }
            let mut grad = vec![0.0f32; net.params().len()];
            block.backward(&net, &x, &d, &mut grad);
            let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&out), bits(&out_rows), "outputs, width {width}");
            assert_eq!(bits(&grad), bits(&grad_rows), "gradient, width {width}");
        }
    }
}
