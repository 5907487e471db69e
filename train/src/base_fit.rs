//! The base net `p0(x0 | wi)` by maximum likelihood of the training pairs (paper §4.1).
//!
//! Outputs `[o0, o1, o2, o3]` are read as the kernel reads them (`BaseDist::from_net`):
//! disk `[mu0, mu1, ln sigma0, ln sigma1]`, sphere `[mu_theta, ln sigma, mu_phi,
//! ln gamma]`, log-scales clamped to `[LN_SCALE_MIN, LN_SCALE_MAX]` (zero gradient where
//! the clamp is active). The loss is the negative log density, differentiated by hand.

use crate::adam::{cosine_lr, Adam};
use crate::batch::{forward_rows, loss_and_grad};
use crate::dataset::TrainingSet;
use crate::mlp::Mlp;
use diffbsdf::internals::base::BaseDist;
use diffbsdf::spec::{BASE_OUTPUTS, LN_4PI, LN_INV_SQRT_2PI, LN_SCALE_MAX, LN_SCALE_MIN};
use diffbsdf::{Domain, ModelDef, Net};
use rand::Rng;
use rand_pcg::Pcg64;

/// Settings of base-net training (its shape is the model definition's `base`).
#[derive(Clone, Copy, Debug)]
pub struct BaseConfig {
    /// Adam iterations.
    pub iters: usize,
    /// Pairs per batch.
    pub batch: usize,
    /// Peak learning rate.
    pub lr: f32,
}

impl Default for BaseConfig {
    fn default() -> Self {
        BaseConfig {
            iters: 1500,
            batch: 2048,
            lr: 3e-3,
        }
    }
}

/// `-ln N(x; mu, e^s)` and its derivatives in `mu` and `s`:
/// `z = (x - mu) e^-s`, `-ln p = z^2/2 + s - LN_INV_SQRT_2PI`, `d/dmu = -z e^-s`,
/// `d/ds = 1 - z^2`.
fn gaussian_nll(x: f64, mu: f64, s: f64) -> (f64, f64, f64) {
    let inv = (-s).exp();
    let z = (x - mu) * inv;
    (
        0.5 * z * z + s - f64::from(LN_INV_SQRT_2PI),
        -z * inv,
        1.0 - z * z,
    )
}

/// `-ln WC(d; gamma)` with `d = phi - mu`, `g = ln gamma`, and its derivatives in `mu` and `g`.
/// `-ln p = -ln sinh(gamma) + LN_4PI + ln(sh^2 + sd^2)`, `sh = sinh(gamma/2)`, `sd = sin(d/2)`;
/// `d/dmu = -sd cd / (sh^2 + sd^2)`, `d/dg = gamma (-coth gamma + sh ch / (sh^2 + sd^2))`.
fn wrapped_cauchy_nll(phi: f64, mu: f64, g: f64) -> (f64, f64, f64) {
    let gamma = g.exp();
    let (sh, ch) = ((0.5 * gamma).sinh(), (0.5 * gamma).cosh());
    let (sd, cd) = (0.5 * (phi - mu)).sin_cos();
    let q = sh * sh + sd * sd;
    let nll = -gamma.sinh().ln() + f64::from(LN_4PI) + q.ln();
    let d_mu = -sd * cd / q;
    let d_g = gamma * (-1.0 / gamma.tanh() + sh * ch / q);
    (nll, d_mu, d_g)
}

/// A log-scale as the kernel clamps it, and whether the clamp let the gradient through.
fn clamp_scale(s: f32) -> (f64, f64) {
    let c = s.clamp(LN_SCALE_MIN, LN_SCALE_MAX);
    (c as f64, if c == s { 1.0 } else { 0.0 })
}

/// `-ln p0(x1)` and `dL/d outputs` for one pair.
pub fn base_nll(domain: Domain, out: &[f32], x1: [f32; 2], d_out: &mut [f32]) -> f64 {
    let x = [x1[0] as f64, x1[1] as f64];
    match domain {
        Domain::Disk | Domain::HalfVector => {
            let (s0, m0) = clamp_scale(out[2]);
            let (s1, m1) = clamp_scale(out[3]);
            let (l0, dmu0, ds0) = gaussian_nll(x[0], out[0] as f64, s0);
            let (l1, dmu1, ds1) = gaussian_nll(x[1], out[1] as f64, s1);
            d_out[0] = dmu0 as f32;
            d_out[1] = dmu1 as f32;
            d_out[2] = (ds0 * m0) as f32;
            d_out[3] = (ds1 * m1) as f32;
            l0 + l1
        }
        Domain::Sphere | Domain::Equatorial => {
            let (s, ms) = clamp_scale(out[1]);
            let (g, mg) = clamp_scale(out[3]);
            let (l0, dmu, ds) = gaussian_nll(x[0], out[0] as f64, s);
            let (l1, dphi, dg) = wrapped_cauchy_nll(x[1], out[2] as f64, g);
            d_out[0] = dmu as f32;
            d_out[1] = (ds * ms) as f32;
            d_out[2] = dphi as f32;
            d_out[3] = (dg * mg) as f32;
            l0 + l1
        }
    }
}

/// Trains the base net of `def`; calls `progress(iter, mean NLL)` after each iteration.
pub fn train_base(
    data: &TrainingSet,
    def: &ModelDef,
    cfg: &BaseConfig,
    rng: &mut Pcg64,
    progress: &mut dyn FnMut(usize, f64),
) -> Mlp {
    let mut net = Mlp::new(def, Net::Base, rng);
    // Start wide: mean 0, log-scale 0 (sigma = 1) whatever the input.
    net.scale_last_layer(0.01);
    let mut adam = Adam::new(net.params().len());
    let batch = cfg.batch.min(data.len()).max(1);
    let freqs = def.base.freqs;
    let mut inputs = Vec::with_capacity(batch * net.inputs());
    let mut idx = Vec::with_capacity(batch);
    for it in 0..cfg.iters {
        inputs.clear();
        idx.clear();
        for _ in 0..batch {
            let i = rng.gen_range(0..data.len());
            idx.push(i);
            inputs.extend_from_slice(data.encoding(i, freqs));
        }
        let scale = 1.0 / batch as f64;
        let (loss, grad) = loss_and_grad(&net, &inputs, |r, out, d| {
            let l = base_nll(data.domain, out, data.x1[idx[r]], d);
            d.iter_mut().for_each(|v| *v *= scale as f32);
            l * scale
        });
        let lr = cosine_lr(cfg.lr, 0.05, it, cfg.iters);
        adam.update(net.params_mut(), &grad, lr);
        progress(it, loss);
    }
    net
}

/// The kernel's base distribution for each pair's `wi` (`net` is the base net of `def`).
pub fn base_distributions(net: &Mlp, def: &ModelDef, data: &TrainingSet) -> Vec<BaseDist> {
    let inputs: Vec<f32> = (0..data.len())
        .flat_map(|i| data.encoding(i, def.base.freqs).iter().copied())
        .collect();
    forward_rows(net, &inputs)
        .chunks_exact(BASE_OUTPUTS)
        .map(|o| BaseDist::from_net(data.domain, [o[0], o[1], o[2], o[3]]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nll_gradients_match_finite_differences() {
        for domain in [Domain::Disk, Domain::Sphere] {
            let out = [0.3f32, -0.4, 0.2, -0.7];
            let x1 = [0.5f32, 2.9];
            let mut d = [0.0f32; 4];
            base_nll(domain, &out, x1, &mut d);
            for k in 0..4 {
                let (mut p, mut m) = (out, out);
                p[k] += 1e-3;
                m[k] -= 1e-3;
                let mut tmp = [0.0f32; 4];
                let fd = (base_nll(domain, &p, x1, &mut tmp) - base_nll(domain, &m, x1, &mut tmp))
                    / 2e-3;
                assert!(
                    (fd - d[k] as f64).abs() < 1e-2 * (1.0 + fd.abs()),
                    "{domain:?} {k}: {fd} vs {}",
                    d[k]
                );
            }
        }
    }

    #[test]
    fn nll_matches_the_kernel_density() {
        let mut d = [0.0f32; 4];
        for (domain, out) in [
            (Domain::Disk, [0.1f32, 0.2, -1.0, -0.5]),
            (Domain::Sphere, [1.0, -0.3, 2.0, -1.2]),
        ] {
            let x1 = [0.3f32, -2.5];
            let nll = base_nll(domain, &out, x1, &mut d);
            let kernel = BaseDist::from_net(domain, out).ln_pdf(x1) as f64;
            assert!((nll + kernel).abs() < 1e-4, "{domain:?}: {nll} vs {kernel}");
        }
    }
}
