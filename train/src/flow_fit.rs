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
use rayon::prelude::*;

/// Rows of a batch built per parallel task.
const ROWS_PER_TASK: usize = 256;

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

/// One row's random draws, made serially from the run's generator (they fix the bits);
/// [`Draw::resolve`] does the rest of the work, in parallel.
#[derive(Clone, Copy, Debug)]
enum Draw<'a> {
    /// Data row `i`, its base distribution and the uniform numbers of its `x0`.
    Independent {
        i: usize,
        base: &'a BaseDist,
        u: [f32; 2],
    },
    /// A fixed pair.
    Fixed((u32, [f32; 2], [f32; 2])),
}

impl<'a> Coupling<'a> {
    fn draw(&self, data: &TrainingSet, rng: &mut Pcg64) -> Draw<'a> {
        match *self {
            Coupling::Independent { base } => {
                let i = rng.gen_range(0..data.len());
                let u = [rng.gen::<f32>(), rng.gen::<f32>()];
                Draw::Independent {
                    i,
                    base: &base[i],
                    u,
                }
            }
            Coupling::Fixed { pairs } => Draw::Fixed(pairs[rng.gen_range(0..pairs.len())]),
        }
    }
}

impl Draw<'_> {
    /// `(wi index, x0, x1)`.
    fn resolve(self, data: &TrainingSet) -> (usize, [f32; 2], [f32; 2]) {
        match self {
            Draw::Independent { i, base, u } => (i, base.sample(u), data.x1[i]),
            Draw::Fixed((i, x0, x1)) => (i as usize, x0, x1),
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
    let n_in = net.inputs();
    let mut inputs = Vec::with_capacity(batch * n_in);
    let mut targets = Vec::with_capacity(batch);
    let mut draws = Vec::with_capacity(batch);
    let mut ema = net.params().to_vec();
    for it in 0..cfg.iters {
        // The random numbers in order (they fix the bits), then the rows in parallel.
        draws.clear();
        for b in 0..batch {
            let d = coupling.draw(data, rng);
            // t stratified: one uniform draw per stratum [b/B, (b+1)/B), or the Euler times.
            let t = if cfg.t_grid > 0 {
                (b % cfg.t_grid) as f32 / cfg.t_grid as f32
            } else {
                (b as f32 + rng.gen::<f32>()) / batch as f32
            };
            draws.push((d, t));
        }
        inputs.resize(batch * n_in, 0.0);
        targets.resize(batch, [0.0; 2]);
        inputs
            .par_chunks_mut(ROWS_PER_TASK * n_in)
            .zip(targets.par_chunks_mut(ROWS_PER_TASK))
            .zip(draws.par_chunks(ROWS_PER_TASK))
            .for_each(|((rows, target), draws)| {
                let mut row = Vec::with_capacity(n_in);
                for ((dst, target), &(d, t)) in rows.chunks_exact_mut(n_in).zip(target).zip(draws) {
                    let (i, x0, x1) = d.resolve(data);
                    let xt = interpolate(domain, x0, x1, t);
                    row.clear();
                    push_velocity_row(def, xt, t, data.encoding(i, freqs), &mut row);
                    dst.copy_from_slice(&row);
                    // The target velocity x1 - x0 (phi the short way round).
                    *target = domain.difference(x1, x0);
                }
            });
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
