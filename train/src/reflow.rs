//! Reflow (Liu et al. 2023; paper §4.1): couple `x0 ~ p0(. | wi)` with the teacher's
//! endpoint from `x0` (classical RK4, `steps` steps, i.e. `4 steps` teacher evaluations,
//! more accurate than as many Euler steps), so the student learns straight paths.

use crate::dataset::TrainingSet;
use crate::features::push_velocity_row;
use crate::mlp::{Mlp, Tape};
use diffbsdf::internals::base::BaseDist;
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
    base: &[BaseDist],
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
            let mut tape = Tape::default();
            let mut row = Vec::with_capacity(teacher.inputs());
            let out: Vec<_> = chunk
                .iter()
                .map(|&(i, x0)| {
                    let enc = data.encoding(i as usize, def.velocity.freqs);
                    let x1 = integrate(teacher, def, x0, enc, steps, &mut tape, &mut row);
                    (i, x0, x1)
                })
                .collect();
            progress(chunk.len());
            out.into_iter()
        })
        .collect()
}

/// The teacher's ODE from `t = 0` to 1 by RK4.
fn integrate(
    net: &Mlp,
    def: &ModelDef,
    x0: [f32; 2],
    enc: &[f32],
    steps: usize,
    tape: &mut Tape,
    row: &mut Vec<f32>,
) -> [f32; 2] {
    let domain = def.domain;
    let h = 1.0 / steps.max(1) as f32;
    let mut v = |x: [f32; 2], t: f32| -> [f32; 2] {
        row.clear();
        push_velocity_row(def, x, t, enc, row);
        let o = net.forward_tape(row, tape);
        [o[0], o[1]]
    };
    let mut x = x0;
    for k in 0..steps.max(1) {
        let t = k as f32 * h;
        let k1 = v(x, t);
        let k2 = v(
            domain.advance(x, [0.5 * h * k1[0], 0.5 * h * k1[1]]),
            t + 0.5 * h,
        );
        let k3 = v(
            domain.advance(x, [0.5 * h * k2[0], 0.5 * h * k2[1]]),
            t + 0.5 * h,
        );
        let k4 = v(domain.advance(x, [h * k3[0], h * k3[1]]), t + h);
        let d = |c: usize| h / 6.0 * (k1[c] + 2.0 * k2[c] + 2.0 * k3[c] + k4[c]);
        x = domain.advance(x, [d(0), d(1)]);
    }
    x
}
