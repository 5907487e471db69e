//! A chunk of rows through an [`Mlp`] layer by layer, in register tiles: a weight is
//! loaded once for several rows (the affine maps and `W^T dz`) and a gradient entry stays
//! in a register across the chunk's rows.
//!
//! Every sum keeps the order of the row-at-a-time pass ([`Mlp::forward_tape`],
//! [`Mlp::backward`]): dot products in [`dot`]'s 8 interleaved partial sums, gradients over
//! the rows in row order, `W^T dz` over the outputs in order, no fused multiply-add. The
//! results are therefore the same bits, only computed with far fewer loads and stores
//! (`block_matches_the_row_pass` below checks it).

use crate::mlp::{LayerAt, Mlp};
use diffbsdf::internals::net::activation::silu_with_slope;
use wide::f32x8;

/// Rows per register tile of `W^T dz`.
const ROWS: usize = 4;
/// Outputs per register tile of the weight gradient.
const GRAD_OUTS: usize = 4;
/// Lanes: [`dot`]'s partial sums, and the inputs of one gradient column block.
const LANES: usize = 8;

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

/// `z[r][o] = b[o] + dot(W[o], a[r])` for every row of `a`, eight outputs at a time:
/// [`dot`]'s partial sum `l` of eight outputs is one vector, and `wt` holds `W` in blocks
/// of eight outputs ([`transpose`]), so each input multiplies one contiguous vector of
/// weights and the final sums are lane-wise, in `dot`'s order.
fn affine(params: &[f32], at: LayerAt, wt: &[f32], a: &[f32], z: &mut [f32]) {
    let (n_in, n_out) = (at.n_in, at.n_out);
    let b = &params[at.b..at.b + n_out];
    let full = n_in - n_in % LANES;
    for (a_row, z_row) in a.chunks_exact(n_in).zip(z.chunks_exact_mut(n_out)) {
        for (block, (z_out, b_out)) in wt
            .chunks_exact(n_in * LANES)
            .zip(z_row.chunks_mut(LANES).zip(b.chunks(LANES)))
        {
            let mut acc = [Lanes::ZERO; LANES];
            for (x8, w8) in a_row[..full]
                .chunks_exact(LANES)
                .zip(block.chunks_exact(LANES * LANES))
            {
                for (l, acc_l) in acc.iter_mut().enumerate() {
                    *acc_l = acc_l.add_product(Lanes::splat(x8[l]), Lanes::load(&w8[l * LANES..]));
                }
            }
            // The last inputs go to the first partial sums, as in `dot`.
            let rest = &block[full * LANES..];
            for (l, (x, w)) in a_row[full..]
                .iter()
                .zip(rest.chunks_exact(LANES))
                .enumerate()
            {
                acc[l] = acc[l].add_product(Lanes::splat(*x), Lanes::load(w));
            }
            let sums = Lanes::reduce8(&acc);
            for ((zv, bv), s) in z_out.iter_mut().zip(b_out).zip(sums.to_array()) {
                *zv = bv + s;
            }
        }
    }
}

/// `W` of layer `at` in blocks of [`LANES`] outputs, each block `[in][LANES]`:
/// `wt[(k n_in + i) LANES + j] = W[k LANES + j][i]`, outputs past the last zero.
fn transpose(params: &[f32], at: LayerAt, wt: &mut Vec<f32>) {
    let blocks = at.n_out.div_ceil(LANES);
    wt.clear();
    wt.resize(blocks * at.n_in * LANES, 0.0);
    for o in 0..at.n_out {
        let (k, j) = (o / LANES, o % LANES);
        for i in 0..at.n_in {
            wt[(k * at.n_in + i) * LANES + j] = params[at.w + o * at.n_in + i];
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

/// `grad_W[o][i] += dz[r][o] a[r][i]`, rows in order, each entry in a register across
/// the rows.
#[inline(never)]
fn weight_grad(dz: &[f32], a: &[f32], at: LayerAt, rows: usize, grad: &mut [f32]) {
    let (n_in, n_out) = (at.n_in, at.n_out);
    let gw = &mut grad[at.w..at.b];
    let full = n_in - n_in % LANES;
    let mut o = 0;
    while o + GRAD_OUTS <= n_out {
        for c in (0..full).step_by(LANES) {
            let mut acc: [Lanes; GRAD_OUTS] =
                core::array::from_fn(|j| Lanes::load(&gw[(o + j) * n_in + c..]));
            for r in 0..rows {
                let av = Lanes::load(&a[r * n_in + c..]);
                let d = &dz[r * n_out + o..r * n_out + o + GRAD_OUTS];
                for j in 0..GRAD_OUTS {
                    acc[j] = acc[j].add_product(av, Lanes::splat(d[j]));
                }
            }
            for (j, acc_o) in acc.iter().enumerate() {
                acc_o.store(&mut gw[(o + j) * n_in + c..]);
            }
        }
        o += GRAD_OUTS;
    }
    // The ragged edges (last outputs, last inputs) one entry at a time, rows in order.
    for oo in 0..n_out {
        let first = if oo < o { full } else { 0 };
        for i in first..n_in {
            let mut g = gw[oo * n_in + i];
            for r in 0..rows {
                g += dz[r * n_out + oo] * a[r * n_in + i];
            }
            gw[oo * n_in + i] = g;
        }
    }
}

/// `da[r][i] = sum_o dz[r][o] W[o][i]`, outputs in order, a weight row loaded once for a
/// tile of rows.
#[inline(never)]
fn transpose_times(params: &[f32], at: LayerAt, dz: &[f32], rows: usize, da: &mut [f32]) {
    let (n_in, n_out) = (at.n_in, at.n_out);
    let w = &params[at.w..at.b];
    let full = n_in - n_in % LANES;
    let mut r = 0;
    while r + ROWS <= rows {
        for c in (0..full).step_by(LANES) {
            let mut acc = [Lanes::ZERO; ROWS];
            for o in 0..n_out {
                let wv = Lanes::load(&w[o * n_in + c..]);
                for k in 0..ROWS {
                    acc[k] = acc[k].add_product(Lanes::splat(dz[(r + k) * n_out + o]), wv);
                }
            }
            for (k, acc_r) in acc.iter().enumerate() {
                acc_r.store(&mut da[(r + k) * n_in + c..]);
            }
        }
        r += ROWS;
    }
    // The ragged edges (last rows, last inputs) one entry at a time, outputs in order.
    for k in 0..rows {
        let first = if k < r { full } else { 0 };
        for i in first..n_in {
            let mut s = 0.0f32;
            for o in 0..n_out {
                s += dz[k * n_out + o] * w[o * n_in + i];
            }
            da[k * n_in + i] = s;
        }
    }
}

/// [`LANES`] floats that travel together (one AVX register, two SSE registers).
#[derive(Clone, Copy, Debug)]
struct Lanes(f32x8);

impl Lanes {
    const ZERO: Lanes = Lanes(f32x8::ZERO);

    /// The first [`LANES`] entries of `v`.
    #[inline(always)]
    fn load(v: &[f32]) -> Lanes {
        let v = &v[..LANES];
        Lanes(f32x8::new(core::array::from_fn(|l| v[l])))
    }

    /// [`reduce8`] lane by lane over eight vectors.
    #[inline(always)]
    fn reduce8(v: &[Lanes; LANES]) -> Lanes {
        Lanes(((v[0].0 + v[4].0) + (v[2].0 + v[6].0)) + ((v[1].0 + v[5].0) + (v[3].0 + v[7].0)))
    }

    /// `x` in every lane.
    #[inline(always)]
    fn splat(x: f32) -> Lanes {
        Lanes(f32x8::splat(x))
    }

    /// `self + a b`, lane by lane, rounded twice (no fused multiply-add).
    #[inline(always)]
    fn add_product(self, a: Lanes, b: Lanes) -> Lanes {
        Lanes(self.0 + a.0 * b.0)
    }

    /// The lanes as floats.
    #[inline(always)]
    fn to_array(self) -> [f32; LANES] {
        self.0.to_array()
    }

    /// Writes the lanes to the first [`LANES`] entries of `v`.
    #[inline(always)]
    fn store(&self, v: &mut [f32]) {
        v[..LANES].copy_from_slice(&self.to_array());
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
