//! Time per sample of the learned model (with and without PDF, and the PDF of a given
//! direction) next to the material's own sampler, measured in the same run on one thread.
//! Ratios are what to read; bare times depend on the machine and its load.

use super::sampler::to_glam;
use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::AnyModel;
use diffbsdf_materials::{DVec3, Material};
use serde::{Deserialize, Serialize};
use std::hint::black_box;
use std::time::Instant;

/// Nanoseconds per call.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct Cost {
    /// Learned: direction only.
    pub learned_direction_ns: f64,
    /// Learned: direction and PDF.
    pub learned_sample_ns: f64,
    /// Learned: PDF of a given direction (exact inverse).
    pub learned_pdf_ns: f64,
    /// The material's own sampler (direction, PDF and weight).
    pub material_sample_ns: f64,
    /// `learned_sample_ns / material_sample_ns`.
    pub ratio_sample: f64,
}

/// Rounds the timed calls are split into: the four entry points take turns round by round,
/// and each one's figure is its median round, so a burst of another process's work moves
/// one round, not the figure (single passes of 20 000 calls differed by up to 1.5x between
/// neighbouring points of `diffbsdf tradeoff` on a shared 2-core machine).
pub const TIMING_ROUNDS: usize = 7;

/// Times `n` calls of each at a fixed `wi`, in [`TIMING_ROUNDS`] interleaved rounds.
pub fn measure(model: &AnyModel, material: &dyn Material, wi: DVec3, n: usize) -> Cost {
    let g = to_glam(wi);
    let us: Vec<Vec2> = (0..n)
        .map(|k| {
            let a = (k as f32 + 0.5) / n as f32;
            Vec2::new(a, (a * 7919.0).fract())
        })
        .collect();
    let wos: Vec<Vec3> = us
        .iter()
        .filter_map(|&u| model.sample(g, u))
        .map(|s| s.wo)
        .collect();
    let mut rounds: [Vec<f64>; 4] = Default::default();
    for r in 0..TIMING_ROUNDS {
        let (u_round, wo_round) = (round(&us, r), round(&wos, r));
        if !u_round.is_empty() {
            rounds[0].push(per_call(u_round, |u| {
                black_box(model.sample_direction(g, u));
            }));
            rounds[1].push(per_call(u_round, |u| {
                black_box(model.sample(g, u));
            }));
        }
        if !wo_round.is_empty() {
            rounds[2].push(per_call(wo_round, |wo| {
                black_box(model.pdf(g, wo));
            }));
        }
        if !u_round.is_empty() {
            rounds[3].push(per_call(u_round, |u| {
                black_box(material.sample(wi, [u.x as f64, u.y as f64, 0.5]));
            }));
        }
    }
    let [dir, sample, pdf, mat] = rounds.map(median);
    Cost {
        learned_direction_ns: dir,
        learned_sample_ns: sample,
        learned_pdf_ns: pdf,
        material_sample_ns: mat,
        ratio_sample: sample / mat.max(1e-9),
    }
}

/// Round `r` of [`TIMING_ROUNDS`] near-equal consecutive parts of `all` (empty past its end).
fn round<T>(all: &[T], r: usize) -> &[T] {
    let edge = |k: usize| (k.min(TIMING_ROUNDS) * all.len()) / TIMING_ROUNDS;
    &all[edge(r)..edge(r + 1)]
}

/// Nanoseconds per call of `f` over `inputs`.
fn per_call<T: Copy>(inputs: &[T], mut f: impl FnMut(T)) -> f64 {
    let t = Instant::now();
    for &x in inputs {
        f(x);
    }
    t.elapsed().as_secs_f64() * 1e9 / inputs.len().max(1) as f64
}

/// The middle value (the upper of the two middle ones for an even count; 0 for none).
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_ignores_one_slow_round() {
        assert_eq!(median(vec![3.0, 100.0, 2.0, 4.0, 1.0]), 3.0);
        assert_eq!(median(vec![]), 0.0);
    }

    #[test]
    fn rounds_cover_every_call_once() {
        for len in [0, 1, 6, 7, 8, 20_000, 19_997] {
            let all: Vec<usize> = (0..len).collect();
            let joined: Vec<usize> = (0..TIMING_ROUNDS)
                .flat_map(|r| round(&all, r).iter().copied())
                .collect();
            assert_eq!(joined, all, "{len}");
            if len >= TIMING_ROUNDS {
                assert!(
                    (0..TIMING_ROUNDS).all(|r| !round(&all, r).is_empty()),
                    "{len}"
                );
            }
        }
    }
}
