//! Reflow (Liu et al. 2023; paper §4.1): couple `x0 ~ p0(. | wi)` with the teacher's
//! endpoint from `x0` (classical RK4, `steps` steps, i.e. `4 steps` teacher evaluations,
//! more accurate than as many Euler steps), so the student learns straight paths.

use crate::block::Block;
use crate::dataset::TrainingSet;
use crate::features::push_velocity_row;
use crate::mlp::Mlp;
use crate::start::StartDist;
use diffbsdf::ModelDef;
use rand::Rng;
use rand_pcg::Pcg64;
use rayon::prelude::*;

/// `(wi index, x0, x1)` reflow pairs.
pub type ReflowPairs = Vec<(u32, [f32; 2], [f32; 2])>;

/// Draws `count` start points (serially, from `rng`) and integrates the teacher (the
/// velocity net of `def`) from each.
#[allow(clippy::too_many_arguments)]
pub fn reflow_pairs(
    teacher: &Mlp,
    def: &ModelDef,
    data: &TrainingSet,
    base: &[StartDist],
    count: usize,
    steps: usize,
    rng: &mut Pcg64,
    progress: &(dyn Fn(usize) + Sync),
) -> ReflowPairs {
    let starts: Vec<(u32, [f32; 2])> = (0..count)
        .map(|_| {
            let i = rng.gen_range(0..data.len());
            let u = [rng.gen::<f32>(), rng.gen::<f32>()];
            (i as u32, def.domain.advance(base[i].sample(u), [0.0, 0.0]))
        })
        .collect();
    starts
        .par_chunks(512)
        .flat_map_iter(|chunk| {
            let mut block = Block::default();
            let x1 = integrate(teacher, def, data, chunk, steps, &mut block);
            progress(chunk.len());
            chunk
                .iter()
                .zip(x1)
                .map(|(&(i, x0), x1)| (i, x0, x1))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The teacher's ODE from `t = 0` to 1 by RK4, for a chunk of start points at once
/// (each evaluation of the teacher is one [`Block`] pass over the chunk; every trajectory
/// is computed exactly as it would be alone).
fn integrate(
    net: &Mlp,
    def: &ModelDef,
    data: &TrainingSet,
    starts: &[(u32, [f32; 2])],
    steps: usize,
    block: &mut Block,
) -> Vec<[f32; 2]> {
    let domain = def.domain;
    let h = 1.0 / steps.max(1) as f32;
    let mut rows = Vec::with_capacity(starts.len() * net.inputs());
    let mut v = |points: &[[f32; 2]], t: f32| -> Vec<[f32; 2]> {
        rows.clear();
        for (x, &(i, _)) in points.iter().zip(starts) {
            let enc = data.encoding(i as usize, def.velocity.freqs);
            push_velocity_row(def, *x, t, enc, &mut rows);
        }
        block
            .forward(net, &rows)
            .chunks_exact(net.outputs())
            .map(|o| [o[0], o[1]])
            .collect()
    };
    // x + s k, the point where RK4 evaluates its next stage.
    let step = |x: &[[f32; 2]], k: &[[f32; 2]], s: f32| -> Vec<[f32; 2]> {
        x.iter()
            .zip(k)
            .map(|(x, k)| domain.advance(*x, [s * k[0], s * k[1]]))
            .collect()
    };
    let mut x: Vec<[f32; 2]> = starts.iter().map(|s| s.1).collect();
    for k in 0..steps.max(1) {
        let t = k as f32 * h;
        let k1 = v(&x, t);
        let k2 = v(&step(&x, &k1, 0.5 * h), t + 0.5 * h);
        let k3 = v(&step(&x, &k2, 0.5 * h), t + 0.5 * h);
        let k4 = v(&step(&x, &k3, h), t + h);
        for (j, xj) in x.iter_mut().enumerate() {
            let d = |c: usize| h / 6.0 * (k1[j][c] + 2.0 * k2[j][c] + 2.0 * k3[j][c] + k4[j][c]);
            *xj = domain.advance(*xj, [d(0), d(1)]);
        }
    }
    x
}
