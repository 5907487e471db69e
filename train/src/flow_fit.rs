//! Flow matching (paper eq. 3): `L = |v(x_t, t, wi) - (x1 - x0)|^2`, `x_t = (1-t) x0 + t x1`,
//! `t` stratified across the batch, the phi difference geodesic on the sphere.
//!
//! Two couplings: the teacher pairs each data point `x1` with a fresh `x0 ~ p0(. | wi)`;
//! the reflow student trains on fixed pairs `(x0, teacher(x0))`. Optionally the teacher's
//! fresh `x0` are coupled by mini-batch optimal transport at a fixed `wi` (Tong et al.
//! 2023, Pooladian et al. 2023): the batch is drawn as whole runs of pairs that share a
//! `wi` ([`TrainingSet::run`]), and within a run the base draws are permuted to minimise
//! `sum |x1 - x0|^2`. Each `x0` is still a draw of the run's base distribution and each `x1`
//! of its data, so the coupling keeps both conditional laws and only shortens the paths.

use crate::adam::{cosine_lr, Adam};
use crate::assignment::Assignment;
use crate::batch::loss_and_grad;
use crate::dataset::TrainingSet;
use crate::features::{interpolate, push_velocity_row};
use crate::mlp::Mlp;
use crate::start::StartDist;
use diffbsdf::{Domain, ModelDef};
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
    /// Pairs per `wi` coupled by mini-batch optimal transport (see the module; the
    /// training pairs must come in runs of that many per `wi`); 0 or 1 keeps the
    /// independent coupling. Fixed pairs ignore it.
    pub ot_group: usize,
}

/// Where `(wi, x0, x1)` triples come from.
#[derive(Clone, Copy, Debug)]
pub enum Coupling<'a> {
    /// `x1` from the data, `x0` drawn afresh from the base distribution of its `wi`.
    Independent {
        /// One start distribution per training pair.
        base: &'a [StartDist],
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
        base: &'a StartDist,
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

/// Re-couples each group of draws `draws[ends[g-1]..ends[g]]` (rows of one `wi`) by optimal
/// transport: the group's base uniforms `u` are assigned to its rows to minimise `sum
/// |x1 - x0(u)|^2` (the domain's difference, phi the short way round). Every row keeps its
/// slot, hence its `t`. Deterministic for any number of threads.
fn transport_coupling(
    draws: &mut [(Draw<'_>, f32)],
    ends: &[usize],
    data: &TrainingSet,
    domain: Domain,
) {
    let mut groups = Vec::with_capacity(ends.len());
    let mut rest = draws;
    let mut start = 0;
    for &end in ends {
        let (g, tail) = rest.split_at_mut(end - start);
        groups.push(g);
        rest = tail;
        start = end;
    }
    groups.into_par_iter().for_each(|g| {
        let n = g.len();
        let rows: Vec<(usize, &StartDist, [f32; 2])> = g
            .iter()
            .filter_map(|(d, _)| match *d {
                Draw::Independent { i, base, u } => Some((i, base, u)),
                Draw::Fixed(_) => None,
            })
            .collect();
        if rows.len() != n || n < 2 {
            return;
        }
        // One wi, so one base distribution: each x0(u) once.
        let x0: Vec<[f32; 2]> = rows.iter().map(|&(_, _, u)| rows[0].1.sample(u)).collect();
        let mut cost = Vec::with_capacity(n * n);
        for &(i, _, _) in &rows {
            for &x0 in &x0 {
                let d = domain.difference(data.x1[i], x0);
                let c = f64::from(d[0] * d[0] + d[1] * d[1]);
                cost.push(if c.is_finite() { c } else { f64::MAX / 4.0 });
            }
        }
        let mut perm = vec![0; n];
        Assignment::default().solve(n, &cost, &mut perm);
        for ((d, _), (&(i, base, _), &p)) in g.iter_mut().zip(rows.iter().zip(&perm)) {
            *d = Draw::Independent {
                i,
                base,
                u: rows[p].2,
            };
        }
    });
}

/// The batch as whole runs of pairs that share a `wi` (a run cut short at the batch's
/// end), `x0` drawn independently. Runs are `group` long; when `group` divides the batch,
/// row `k` takes the `t` stratum `(k mod group) * (batch / group) + k / group`, so the rows
/// of one `wi` spread over `[0, 1]`.
fn draw_runs<'a>(
    data: &TrainingSet,
    base: &'a [StartDist],
    batch: usize,
    group: usize,
    time: &mut dyn FnMut(usize, &mut Pcg64) -> f32,
    rng: &mut Pcg64,
    draws: &mut Vec<(Draw<'a>, f32)>,
) {
    while draws.len() < batch {
        let run = data.run(rng.gen_range(0..data.runs()));
        for i in run.take(batch - draws.len()) {
            let u = [rng.gen::<f32>(), rng.gen::<f32>()];
            let k = draws.len();
            let stratum = if batch.is_multiple_of(group) {
                (k % group) * (batch / group) + k / group
            } else {
                k
            };
            let t = time(stratum, rng);
            draws.push((
                Draw::Independent {
                    i,
                    base: &base[i],
                    u,
                },
                t,
            ));
        }
    }
}

/// Where each run drawn by [`draw_runs`] ends (a run's rows are consecutive data indices
/// with one `wi`, so a row that does not follow its predecessor's index, or has another
/// `wi`, starts a new one): the groups [`transport_coupling`] couples.
fn group_ends(draws: &[(Draw<'_>, f32)], data: &TrainingSet) -> Vec<usize> {
    let index = |d: &Draw<'_>| match *d {
        Draw::Independent { i, .. } => Some(i),
        Draw::Fixed(_) => None,
    };
    let mut ends: Vec<usize> = (1..draws.len())
        .filter(|&k| {
            let (prev, this) = (index(&draws[k - 1].0), index(&draws[k].0));
            let bits = |i: usize| data.wi[i].map(f32::to_bits);
            prev.zip(this)
                .is_none_or(|(p, t)| t != p + 1 || bits(t) != bits(p))
        })
        .collect();
    ends.push(draws.len());
    ends
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
        // t stratified: one uniform draw per stratum [b/B, (b+1)/B), or the Euler times.
        let mut time = |b: usize, rng: &mut Pcg64| {
            if cfg.t_grid > 0 {
                (b % cfg.t_grid) as f32 / cfg.t_grid as f32
            } else {
                (b as f32 + rng.gen::<f32>()) / batch as f32
            }
        };
        draws.clear();
        match coupling {
            Coupling::Independent { base } if cfg.ot_group > 1 => {
                draw_runs(data, base, batch, cfg.ot_group, &mut time, rng, &mut draws);
                let ends = group_ends(&draws, data);
                transport_coupling(&mut draws, &ends, data, domain);
            }
            _ => {
                for b in 0..batch {
                    let d = coupling.draw(data, rng);
                    let t = time(b, rng);
                    draws.push((d, t));
                }
            }
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

#[cfg(test)]
mod tests {
    use super::*;
    use diffbsdf::internals::base::BaseDist;
    use rand::SeedableRng;

    fn length2(draws: &[(Draw<'_>, f32)], data: &TrainingSet) -> f64 {
        draws
            .iter()
            .map(|&(d, _)| {
                let (_, x0, x1) = d.resolve(data);
                let e = Domain::Sphere.difference(x1, x0);
                f64::from(e[0] * e[0] + e[1] * e[1])
            })
            .sum()
    }

    #[test]
    fn transport_coupling_shortens_the_pairs_and_keeps_every_row() {
        let mut rng = Pcg64::seed_from_u64(7);
        let group = 32;
        let mut pairs = Vec::new();
        for _ in 0..128 {
            let z: f32 = rng.gen_range(0.05..1.0);
            let wi = [(1.0 - z * z).sqrt(), 0.0, z];
            for _ in 0..group {
                // A lobe about theta = acos(z), phi = 0, of width 0.3.
                let x1 = [
                    z.acos() + 0.3 * (rng.gen::<f32>() - 0.5),
                    rng.gen_range(-0.3..0.3),
                ];
                pairs.push((wi, x1));
            }
        }
        let data = TrainingSet::new(Domain::Sphere, 0, &pairs);
        assert_eq!(data.runs(), 128);
        let base: Vec<StartDist> = data
            .wi
            .iter()
            .map(|wi| {
                StartDist::Chart(BaseDist::Sphere {
                    mu_theta: wi[2].acos(),
                    ln_sigma: 0.2f32.ln(),
                    mu_phi: 0.0,
                    ln_gamma: 0.2f32.ln(),
                })
            })
            .collect();
        let batch = 1024;
        let mut time = |b: usize, _: &mut Pcg64| b as f32 / batch as f32;
        let mut draws = Vec::new();
        draw_runs(&data, &base, batch, group, &mut time, &mut rng, &mut draws);
        let ends = group_ends(&draws, &data);
        // Whole runs of 32 (two of one wi drawn back to back make one group of 64).
        let mut prev = 0;
        for &end in &ends {
            assert!(
                end > prev && (end - prev) % group == 0,
                "groups end at {ends:?}"
            );
            prev = end;
        }
        let before = draws.clone();
        transport_coupling(&mut draws, &ends, &data, Domain::Sphere);
        let (l0, l1) = (length2(&before, &data), length2(&draws, &data));
        // Measured 0.63 (the wrapped Cauchy's heavy tails keep some long pairs); a random
        // permutation would give about 1.
        assert!(l1 < 0.8 * l0, "sum |x1 - x0|^2 {l0} -> {l1}");
        let mut start = 0;
        for &end in &ends {
            let (mut us_before, mut us_after) = (Vec::new(), Vec::new());
            for ((a, ta), (b, tb)) in before[start..end].iter().zip(&draws[start..end]) {
                assert_eq!(ta, tb, "a row left its slot");
                match (a, b) {
                    (
                        Draw::Independent { i: ia, u: ua, .. },
                        Draw::Independent { i: ib, u: ub, .. },
                    ) => {
                        assert_eq!(ia, ib, "a row changed its data point");
                        us_before.push((ua[0].to_bits(), ua[1].to_bits()));
                        us_after.push((ub[0].to_bits(), ub[1].to_bits()));
                    }
                    _ => panic!("the coupling changed kind"),
                }
            }
            let wi = |d: &Draw<'_>| match *d {
                Draw::Independent { i, .. } => data.wi[i],
                Draw::Fixed(_) => unreachable!(),
            };
            assert!(
                draws[start..end]
                    .iter()
                    .all(|(d, _)| wi(d) == wi(&draws[start].0)),
                "a group mixes incidences"
            );
            us_before.sort_unstable();
            us_after.sort_unstable();
            assert_eq!(us_before, us_after, "the base draws left their group");
            start = end;
        }
        // The rows of one wi spread over t.
        let ts: Vec<f32> = draws[..group].iter().map(|d| d.1).collect();
        assert!(ts[group - 1] - ts[0] > 0.9, "{ts:?}");
    }
}
