//! Pairs by sampling-importance-resampling (SIR, Rubin 1988) of the material's own sampler.
//!
//! For each pair, `candidates` directions are drawn from `material.sample(wi, .)` and one
//! is kept with probability proportional to `w = target / pdf`. The law of the kept
//! direction tends to the normalised target as `candidates` grows; its relative deviation
//! is of order `RV / candidates` (`RV` = the sampler's relative variance against the
//! target), which the tests cannot detect at the default 64.

use super::pair::{Band, DomainTarget, Generated, Pair};
use diffbsdf::Domain;
use diffbsdf_materials::{DVec3, Material};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;
use std::time::Instant;

/// Settings of the exact generator.
#[derive(Clone, Copy, Debug)]
pub struct ExactConfig {
    /// Domain of `wo`.
    pub domain: Domain,
    /// Candidates per pair.
    pub candidates: usize,
    /// Seed; the output is a deterministic function of it.
    pub seed: u64,
    /// Consecutive pairs that share one `wi` (1: a fresh `wi` for every pair). Groups
    /// let the teacher couple `x0` and `x1` by optimal transport at a fixed `wi`.
    pub group: usize,
}

impl Default for ExactConfig {
    fn default() -> Self {
        Self {
            domain: Domain::Disk,
            candidates: 64,
            seed: 0,
            group: 1,
        }
    }
}

/// One SIR draw; `None` when no candidate has positive weight.
fn resample_one(
    m: &dyn Material,
    wi: DVec3,
    cfg: &ExactConfig,
    rng: &mut Pcg64,
) -> (Option<DVec3>, u64) {
    let mut total = 0.0;
    let mut chosen = None;
    let mut valid = 0;
    for _ in 0..cfg.candidates.max(1) {
        let u = [rng.gen::<f64>(), rng.gen::<f64>(), rng.gen::<f64>()];
        let Some(s) = m.sample(wi, u) else { continue };
        let w = cfg.domain.target(m, wi, s.wo) / s.pdf;
        if !(w > 0.0 && w.is_finite()) {
            continue;
        }
        valid += 1;
        total += w;
        // Reservoir form of SIR: keep the new candidate with probability w / total.
        if rng.gen::<f64>() * total < w {
            chosen = Some(s.wo);
        }
    }
    (chosen, valid)
}

/// `n` pairs at a fixed `wi`, in chunks run in parallel (chunk `k` seeded with `seed + k`).
pub fn exact_pairs_for_wi(m: &dyn Material, wi: DVec3, n: usize, cfg: &ExactConfig) -> Generated {
    generate(m, n, cfg, |_| wi)
}

/// `n` pairs with `wi` uniform in solid angle within `band`.
pub fn exact_pairs(m: &dyn Material, band: Band, n: usize, cfg: &ExactConfig) -> Generated {
    generate(m, n, cfg, |rng| band.sample_uniform([rng.gen(), rng.gen()]))
}

/// `n` pairs for isotropic fits: a fraction `angle` of the `wi` with `theta_i` uniform in
/// angle within `band`, the rest uniform in solid angle (`angle = 1`: all in angle, and
/// no extra random draw, so the stream matches earlier fits).
pub fn exact_pairs_uniform_angle(
    m: &dyn Material,
    band: Band,
    n: usize,
    cfg: &ExactConfig,
    angle: f64,
) -> Generated {
    generate(m, n, cfg, |rng| {
        if angle >= 1.0 || rng.gen::<f64>() < angle {
            band.sample_uniform_angle([rng.gen(), rng.gen()])
        } else {
            band.sample_uniform([rng.gen(), rng.gen()])
        }
    })
}

fn generate<F>(m: &dyn Material, n: usize, cfg: &ExactConfig, draw_wi: F) -> Generated
where
    F: Fn(&mut Pcg64) -> DVec3 + Sync,
{
    const CHUNK: usize = 4096;
    let start = Instant::now();
    let chunks = n.div_ceil(CHUNK);
    let results: Vec<(Vec<Pair>, u64, u64)> = (0..chunks)
        .into_par_iter()
        .map(|k| {
            let mut rng = Pcg64::seed_from_u64(cfg.seed.wrapping_add(k as u64));
            let want = CHUNK.min(n - k * CHUNK);
            let mut out = Vec::with_capacity(want);
            let (mut evals, mut valid) = (0u64, 0u64);
            let mut tries = 0usize;
            let group = cfg.group.max(1);
            let (mut wi, mut in_group) = (DVec3::ZERO, group);
            while out.len() < want && tries < want * 100 + 100 {
                tries += 1;
                // A fresh wi for every try (the random stream of ungrouped fits), or for
                // groups whenever the current one is full.
                if group == 1 || in_group == group {
                    wi = draw_wi(&mut rng);
                    in_group = 0;
                }
                let (wo, v) = resample_one(m, wi, cfg, &mut rng);
                evals += cfg.candidates.max(1) as u64;
                valid += v;
                if let Some(wo) = wo {
                    out.push(Pair { wi, wo });
                    in_group += 1;
                }
            }
            (out, evals, valid)
        })
        .collect();
    let mut pairs = Vec::with_capacity(n);
    let (mut evals, mut valid) = (0, 0);
    for (p, e, v) in results {
        pairs.extend(p);
        evals += e;
        valid += v;
    }
    Generated {
        pairs,
        seconds: start.elapsed().as_secs_f64(),
        evaluations: evals,
        acceptance: if evals > 0 {
            valid as f64 / evals as f64
        } else {
            0.0
        },
    }
}
