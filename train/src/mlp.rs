//! A fully connected net for training, laid out as the kernel describes it
//! ([`ModelDef::layer`]): SiLU on the activated (hidden) layers, linear read-out.
//! Parameters are stored in the kernel's blob order: each layer `W` row-major
//! `[out][in]`, then its bias (`docs/blob-format.md`), so a trained student's parameter
//! vector is written to a blob as is.
//!
//! The activation is the kernel's own `silu` (through `exp_poly`), so the trained net
//! evaluates as the kernel will evaluate it.

use diffbsdf::internals::net::activation::silu_with_slope;
use diffbsdf::{Layer, ModelDef, Net};
use rand::Rng;
use rand_pcg::Pcg64;

/// The layers (the kernel's description) and the flat parameter vector.
#[derive(Clone, Debug, PartialEq)]
pub struct Mlp {
    layers: Vec<Layer>,
    params: Vec<f32>,
}

/// Per-sample activations kept by the forward pass for the backward pass.
#[derive(Clone, Debug, Default)]
pub struct Tape {
    /// `z` (pre-activation) of every hidden layer, then the output.
    pre: Vec<Vec<f32>>,
    /// `silu(z)` of every hidden layer.
    post: Vec<Vec<f32>>,
}

/// Offsets of layer `l`'s weights and biases in the parameter vector.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LayerAt {
    /// Inputs (columns of `W`).
    pub(crate) n_in: usize,
    /// Outputs (rows of `W`, entries of `b`).
    pub(crate) n_out: usize,
    /// Offset of `W` (row-major `[out][in]`).
    pub(crate) w: usize,
    /// Offset of `b`.
    pub(crate) b: usize,
}

/// The layers of `net` in `def`, first hidden layer to read-out.
pub fn layers_of(def: &ModelDef, net: Net) -> Vec<Layer> {
    (0..def.layer_count(net))
        .map_while(|i| def.layer(net, i))
        .collect()
}

impl Mlp {
    /// `net` of `def`, initialised like PyTorch's `nn.Linear`: weights and biases uniform
    /// in `+-1/sqrt(fan_in)`.
    pub fn new(def: &ModelDef, net: Net, rng: &mut Pcg64) -> Self {
        Self::with_layers(layers_of(def, net), rng)
    }

    /// A net of the given layers, initialised as [`Mlp::new`].
    pub fn with_layers(layers: Vec<Layer>, rng: &mut Pcg64) -> Self {
        let mut params = Vec::with_capacity(param_count(&layers));
        for layer in &layers {
            let bound = 1.0 / (layer.inputs as f32).sqrt();
            for _ in 0..layer.param_count() {
                params.push(rng.gen_range(-bound..bound));
            }
        }
        Mlp { layers, params }
    }

    /// A net from existing parameters; `None` if the count does not match the layers.
    pub fn from_params(layers: Vec<Layer>, params: Vec<f32>) -> Option<Self> {
        (params.len() == param_count(&layers) && !layers.is_empty())
            .then_some(Mlp { layers, params })
    }

    /// The layers, first hidden layer to read-out.
    pub fn layers(&self) -> &[Layer] {
        &self.layers
    }

    /// Inputs per sample.
    pub fn inputs(&self) -> usize {
        self.layers[0].inputs
    }

    /// Outputs per sample.
    pub fn outputs(&self) -> usize {
        self.layers[self.layers.len() - 1].outputs
    }

    /// The parameters in blob order.
    pub fn params(&self) -> &[f32] {
        &self.params
    }

    /// Mutable parameters (the optimiser updates them in place).
    pub fn params_mut(&mut self) -> &mut [f32] {
        &mut self.params
    }

    /// Scales the last layer's weights and biases (a small read-out at initialisation
    /// starts the flow near the identity map).
    pub fn scale_last_layer(&mut self, factor: f32) {
        let last = self.layer(self.layers.len() - 1);
        for p in &mut self.params[last.w..last.b + last.n_out] {
            *p *= factor;
        }
    }

    /// Where layer `l`'s parameters sit.
    pub(crate) fn layer(&self, l: usize) -> LayerAt {
        let off: usize = self.layers[..l].iter().map(Layer::param_count).sum();
        let (n_in, n_out) = (self.layers[l].inputs, self.layers[l].outputs);
        LayerAt {
            n_in,
            n_out,
            w: off,
            b: off + n_in * n_out,
        }
    }

    /// Output for one input row (no tape).
    pub fn forward(&self, x: &[f32], out: &mut [f32]) {
        let mut tape = Tape::default();
        self.forward_tape(x, &mut tape);
        if let Some(last) = tape.pre.last() {
            out.iter_mut().zip(last).for_each(|(o, v)| *o = *v);
        }
    }

    /// Forward pass for one input row, keeping the activations; the output is the last
    /// entry of the tape's `pre`.
    pub fn forward_tape<'t>(&self, x: &[f32], tape: &'t mut Tape) -> &'t [f32] {
        let layers = self.layers.len();
        tape.pre.resize(layers, Vec::new());
        tape.post.resize(layers - 1, Vec::new());
        for l in 0..layers {
            let at = self.layer(l);
            let (pre_done, pre_rest) = tape.pre.split_at_mut(l);
            let _ = pre_done;
            let input: &[f32] = if l == 0 { x } else { &tape.post[l - 1] };
            let z = &mut pre_rest[0];
            z.resize(at.n_out, 0.0);
            let w = &self.params[at.w..at.b];
            let b = &self.params[at.b..at.b + at.n_out];
            for o in 0..at.n_out {
                z[o] = b[o] + dot(&w[o * at.n_in..(o + 1) * at.n_in], input);
            }
            if self.layers[l].activated {
                let h = &mut tape.post[l];
                h.resize(at.n_out, 0.0);
                for (hv, zv) in h.iter_mut().zip(z.iter()) {
                    *hv = silu_with_slope(*zv).0;
                }
            }
        }
        &tape.pre[layers - 1]
    }

    /// Backward pass for one row: adds `dL/dparams` to `grad` given `dL/doutput`.
    /// `scratch` holds two buffers reused across calls.
    pub fn backward(
        &self,
        x: &[f32],
        tape: &Tape,
        d_out: &[f32],
        grad: &mut [f32],
        scratch: &mut [Vec<f32>; 2],
    ) {
        let layers = self.layers.len();
        let [dz, da] = scratch;
        dz.clear();
        dz.extend_from_slice(d_out);
        for l in (0..layers).rev() {
            let at = self.layer(l);
            let input: &[f32] = if l == 0 { x } else { &tape.post[l - 1] };
            // dL/db = dz, dL/dW[o][i] = dz[o] * a[i]
            for o in 0..at.n_out {
                let g = dz[o];
                grad[at.b + o] += g;
                if g != 0.0 {
                    axpy(
                        g,
                        input,
                        &mut grad[at.w + o * at.n_in..at.w + (o + 1) * at.n_in],
                    );
                }
            }
            if l == 0 {
                break;
            }
            // dL/da = W^T dz, then through SiLU: dz_prev = dL/da * silu'(z_prev)
            da.clear();
            da.resize(at.n_in, 0.0);
            let w = &self.params[at.w..at.b];
            for o in 0..at.n_out {
                axpy(dz[o], &w[o * at.n_in..(o + 1) * at.n_in], da);
            }
            let z_prev = &tape.pre[l - 1];
            dz.clear();
            dz.extend(
                da.iter()
                    .zip(z_prev)
                    .map(|(d, z)| d * silu_with_slope(*z).1),
            );
        }
    }
}

/// Number of parameters of a net with these layers.
pub fn param_count(layers: &[Layer]) -> usize {
    layers.iter().map(Layer::param_count).sum()
}

/// `y += a x`.
#[inline]
fn axpy(a: f32, x: &[f32], y: &mut [f32]) {
    for (yv, xv) in y.iter_mut().zip(x) {
        *yv += a * xv;
    }
}

/// Partial sums of [`dot`] (`spec::DOT_PARTIAL_SUMS`; [`reduce8`] names all eight).
const PARTIAL_SUMS: usize = diffbsdf::spec::DOT_PARTIAL_SUMS;
const _: () = assert!(PARTIAL_SUMS == 8);

/// Dot product with the kernel's 8 interleaved partial sums (vectorises without
/// reassociation).
#[inline]
pub(crate) fn dot(a: &[f32], b: &[f32]) -> f32 {
    let mut acc = [0.0f32; PARTIAL_SUMS];
    let mut ca = a.chunks_exact(PARTIAL_SUMS);
    let mut cb = b.chunks_exact(PARTIAL_SUMS);
    for (xa, xb) in (&mut ca).zip(&mut cb) {
        for l in 0..PARTIAL_SUMS {
            acc[l] += xa[l] * xb[l];
        }
    }
    for (l, (x, y)) in ca.remainder().iter().zip(cb.remainder()).enumerate() {
        acc[l] += x * y;
    }
    reduce8(&acc)
}

/// The sum of [`dot`]'s 8 partial sums, in its fixed order.
#[inline(always)]
pub(crate) fn reduce8(acc: &[f32; 8]) -> f32 {
    ((acc[0] + acc[4]) + (acc[2] + acc[6])) + ((acc[1] + acc[5]) + (acc[3] + acc[7]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn gradient_matches_finite_differences() {
        let mut rng = Pcg64::seed_from_u64(1);
        let mut def = ModelDef::paper_disk();
        def.base = diffbsdf::NetShape {
            freqs: 0,
            width: 7,
            hidden_layers: 2,
        };
        let net = Mlp::new(&def, Net::Base, &mut rng);
        assert_eq!(net.inputs(), 3);
        let x: Vec<f32> = (0..3).map(|i| 0.3 * i as f32 - 0.5).collect();
        let loss = |n: &Mlp| {
            let mut o = [0.0; 4];
            n.forward(&x, &mut o);
            (o[0] as f64).powi(2) + 3.0 * o[1] as f64
        };
        let mut tape = Tape::default();
        let out = net.forward_tape(&x, &mut tape).to_vec();
        let d = [2.0 * out[0], 3.0, 0.0, 0.0];
        let mut grad = vec![0.0; net.params().len()];
        let mut scratch = [Vec::new(), Vec::new()];
        net.backward(&x, &tape, &d, &mut grad, &mut scratch);
        for k in (0..grad.len()).step_by(7) {
            let mut p = net.clone();
            p.params_mut()[k] += 1e-3;
            let mut m = net.clone();
            m.params_mut()[k] -= 1e-3;
            let fd = (loss(&p) - loss(&m)) / 2e-3;
            assert!(
                (fd - grad[k] as f64).abs() < 2e-3 * (1.0 + fd.abs()),
                "{k}: {fd} vs {}",
                grad[k]
            );
        }
    }
}
