//! Flow matching (paper eq. 3): `L = |v(x_t, t, wi) - (x1 - x0)|^2`, `x_t = (1-t) x0 + t x1`,
//! `t` stratified across the batch, the phi difference geodesic on the sphere.
//!
//! Two couplings: the teacher pairs each data point `x1` with a fresh `x0 ~ p0(. | wi)`;
//! the reflow student trains on fixed pairs `(x0, teacher(x0))`.

use crate::adam::{cosine_lr, Adam};
use crate::batch::loss_and_grad;
use crate::dataset::TrainingSet;
use crate::features::{interpolate, push_velocity_row};
use crate::mlp::Mlp;
use diffbsdf::internals::base::BaseDist;
use diffbsdf::ModelDef;
use rand::Rng;
use rand_pcg::Pcg64;

/// Settings of one flow-matching run (the net's shape is its model definition's).
#[derive(Clone, Copy, Debug)]
pub struct FlowConfig {
    /// Adam iterations.
    pub iters: usize,
    /// Rows per batch.
    pub batch: usize,
    /// Peak learning rate (cosine decay to 5 %).
    pub lr: f32,
    /// Decay of the exponential moving average of the weights that is kept as the
    /// result (0 keeps the last iterate).
    pub ema: f32,
    /// When `n > 0`, `t` takes only the Euler times `k / n` (the student is evaluated
    /// nowhere else); 0 draws `t` uniformly.
    pub t_grid: usize,
}

/// Where `(wi, x0, x1)` triples come from.
#[derive(Clone, Copy, Debug)]
pub enum Coupling<'a> {
    /// `x1` from the data, `x0` drawn afresh from the base distribution of its `wi`.
    Independent {
        /// One base distribution per training pair.
        base: &'a [BaseDist],
    },
    /// Fixed pairs: `pairs[k] = (index of wi in the data, x0, x1)`.
    Fixed {
        /// The coupled pairs.
        pairs: &'a [(u32, [f32; 2], [f32; 2])],
    },
}

impl Coupling<'_> {
    fn draw(&self, data: &TrainingSet, rng: &mut Pcg64) -> (usize, [f32; 2], [f32; 2]) {
        match self {
            Coupling::Independent { base } => {
                let i = rng.gen_range(0..data.len());
                let u = [rng.gen::<f32>(), rng.gen::<f32>()];
                (i, base[i].sample(u), data.x1[i])
            }
            Coupling::Fixed { pairs } => {
                let (i, x0, x1) = pairs[rng.gen_range(0..pairs.len())];
                (i as usize, x0, x1)
            }
        }
    }
}

/// Trains `net`, the velocity net of `def`, by flow matching; calls `progress(iter, mean
/// loss)` after each iteration.
pub fn train_flow(
    net: &mut Mlp,
    def: &ModelDef,
    data: &TrainingSet,
    coupling: Coupling<'_>,
    cfg: &FlowConfig,
    rng: &mut Pcg64,
    progress: &mut dyn FnMut(usize, f64),
) {
    let domain = def.domain;
    let freqs = def.velocity.freqs;
    let mut adam = Adam::new(net.params().len());
    let batch = cfg.batch.max(1);
    let mut inputs = Vec::with_capacity(batch * net.inputs());
    let mut targets = Vec::with_capacity(batch);
    let mut ema = net.params().to_vec();
    for it in 0..cfg.iters {
        inputs.clear();
        targets.clear();
        for b in 0..batch {
            let (i, x0, x1) = coupling.draw(data, rng);
            // t stratified: one uniform draw per stratum [b/B, (b+1)/B), or the Euler times.
            let t = if cfg.t_grid > 0 {
                (b % cfg.t_grid) as f32 / cfg.t_grid as f32
            } else {
                (b as f32 + rng.gen::<f32>()) / batch as f32
            };
            let xt = interpolate(domain, x0, x1, t);
            push_velocity_row(def, xt, t, data.encoding(i, freqs), &mut inputs);
            // The target velocity x1 - x0 (phi the short way round).
            targets.push(domain.difference(x1, x0));
        }
        let scale = 1.0 / batch as f32;
        let (loss, grad) = loss_and_grad(net, &inputs, |r, v, d| {
            // eq. 3: |v - (x1 - x0)|^2, gradient 2 (v - (x1 - x0)) / B
            let e = [v[0] - targets[r][0], v[1] - targets[r][1]];
            d[0] = 2.0 * e[0] * scale;
            d[1] = 2.0 * e[1] * scale;
            ((e[0] * e[0] + e[1] * e[1]) * scale) as f64
        });
        let lr = cosine_lr(cfg.lr, 0.05, it, cfg.iters);
        adam.update(net.params_mut(), &grad, lr);
        // Weight average: ema <- d ema + (1 - d) params, with a warm-up of the decay.
        let d = cfg.ema.min((1.0 + it as f32) / (10.0 + it as f32));
        ema.iter_mut()
            .zip(net.params())
            .for_each(|(e, p)| *e = d * *e + (1.0 - d) * p);
        progress(it, loss);
    }
    net.params_mut().copy_from_slice(&ema);
}
