//! Pairs by MCMC that needs only `eval`: the affine-invariant ensemble sampler of Goodman
//! & Weare (2010) ("stretch move", as in emcee), over the 4D joint of `(wi, wo)`, one
//! ensemble per band of `theta_i`.
//!
//! State: `wi` and `wo` each as a point of the equal-area octahedral square `[-1,1]^2`
//! (Clarberg 2008; `dw = pi da db`), so the joint density in state space is proportional
//! to `1[wi in band] Y(f(wi, wo)) |cos theta_o|` on the sphere domain. On the disk domain
//! `wo` is the disk point `(wo.x, wo.y)` and the density is `1[wi in band] Y(f(wi, wo))`
//! (`f cos dw = f dA`). Either way the conditional law of `wo` given `wi` is the
//! normalised target; the marginal of `wi` inside a band is proportional to the albedo
//! `Z(wi)` times the uniform solid-angle measure.
//!
//! Moves: the stretch move (Goodman & Weare 2010 eq. 7, acceptance `z^(d-1) p(Y)/p(X)`),
//! mixed with probability `jump` with an independence proposal uniform over the support
//! (acceptance `p(Y)/p(X)`), which lets walkers cross between separate lobes (reflection
//! and transmission). Both kernels leave the target invariant.

use super::pair::{Band, DomainTarget, Generated, Pair};
use diffbsdf::Domain;
use diffbsdf_materials::warp::{equal_area_sphere_to_square, equal_area_square_to_sphere};
use diffbsdf_materials::{DVec3, Material};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;
use std::time::Instant;

/// Dimension of the state.
const DIM: usize = 4;

/// Settings of the MCMC generator.
#[derive(Clone, Copy, Debug)]
pub struct McmcConfig {
    /// Domain of `wo`.
    pub domain: Domain,
    /// Walkers per ensemble (>= 2 DIM).
    pub walkers: usize,
    /// Sweeps discarded at the start of each band.
    pub burn_in: usize,
    /// Sweeps between recorded states.
    pub thin: usize,
    /// Stretch scale `a` (2 in emcee).
    pub stretch: f64,
    /// Probability of an independence (uniform) proposal instead of a stretch move.
    pub jump: f64,
    /// Seed; band `k` uses `seed + k`.
    pub seed: u64,
}

impl Default for McmcConfig {
    fn default() -> Self {
        Self {
            domain: Domain::Disk,
            walkers: 48,
            burn_in: 1000,
            thin: 60,
            stretch: 2.0,
            jump: 0.2,
            seed: 0,
        }
    }
}

/// Maps a state to `(wi, wo)`; `None` outside the support's chart.
fn decode(x: &[f64; DIM], domain: Domain) -> Option<(DVec3, DVec3)> {
    if x[0].abs() > 1.0 || x[1].abs() > 1.0 {
        return None;
    }
    let wi = equal_area_square_to_sphere([x[0], x[1]]);
    let wo = match domain {
        Domain::Sphere | Domain::Equatorial => {
            if x[2].abs() > 1.0 || x[3].abs() > 1.0 {
                return None;
            }
            equal_area_square_to_sphere([x[2], x[3]])
        }
        Domain::Disk | Domain::HalfVector => {
            let r2 = x[2] * x[2] + x[3] * x[3];
            if r2 >= 1.0 {
                return None;
            }
            DVec3::new(x[2], x[3], (1.0 - r2).sqrt())
        }
    };
    Some((wi, wo))
}

/// Unnormalised density of a state.
fn density(m: &dyn Material, band: &Band, domain: Domain, x: &[f64; DIM]) -> f64 {
    let Some((wi, wo)) = decode(x, domain) else {
        return 0.0;
    };
    if !band.contains(wi) {
        return 0.0;
    }
    match domain {
        Domain::Sphere | Domain::Equatorial => domain.target(m, wi, wo),
        Domain::Disk | Domain::HalfVector => {
            let v = m.eval_luminance(wi, wo);
            if v.is_finite() && v > 0.0 {
                v
            } else {
                0.0
            }
        }
    }
}

/// A state drawn uniformly over the chart of the support (the independence proposal).
fn uniform_state(band: &Band, domain: Domain, rng: &mut Pcg64) -> [f64; DIM] {
    let wi = band.sample_uniform([rng.gen(), rng.gen()]);
    let a = equal_area_sphere_to_square(wi);
    let b = match domain {
        Domain::Sphere | Domain::Equatorial => [rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)],
        Domain::Disk | Domain::HalfVector => loop {
            let p = [rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)];
            if p[0] * p[0] + p[1] * p[1] < 1.0 {
                break p;
            }
        },
    };
    [a[0], a[1], b[0], b[1]]
}

/// One band: an ensemble run for `n` recorded pairs.
fn run_band(
    m: &dyn Material,
    band: Band,
    n: usize,
    cfg: &McmcConfig,
    seed: u64,
) -> (Vec<Pair>, u64, u64) {
    let mut rng = Pcg64::seed_from_u64(seed);
    let k = cfg.walkers.max(2 * DIM);
    let mut evals = 0u64;
    let mut walkers = Vec::with_capacity(k);
    let mut dens = Vec::with_capacity(k);
    for _ in 0..k {
        let mut x = uniform_state(&band, cfg.domain, &mut rng);
        let mut p = density(m, &band, cfg.domain, &x);
        evals += 1;
        for _ in 0..10_000 {
            if p > 0.0 {
                break;
            }
            x = uniform_state(&band, cfg.domain, &mut rng);
            p = density(m, &band, cfg.domain, &x);
            evals += 1;
        }
        walkers.push(x);
        dens.push(p);
    }
    if dens.iter().all(|p| *p <= 0.0) {
        return (Vec::new(), evals, 0);
    }
    let a = cfg.stretch.max(1.0 + 1e-6);
    let mut out = Vec::with_capacity(n);
    let mut accepted = 0u64;
    let mut sweep = 0usize;
    let max_sweeps = cfg.burn_in + (n.div_ceil(k) + 1) * cfg.thin.max(1) + 1;
    while out.len() < n && sweep < max_sweeps {
        for i in 0..k {
            let (y, factor) = if rng.gen::<f64>() < cfg.jump {
                (uniform_state(&band, cfg.domain, &mut rng), 1.0)
            } else {
                let mut j = rng.gen_range(0..k - 1);
                if j >= i {
                    j += 1;
                }
                let z = ((a - 1.0) * rng.gen::<f64>() + 1.0).powi(2) / a;
                let (xi, xj) = (walkers[i], walkers[j]);
                let mut y = [0.0; DIM];
                for d in 0..DIM {
                    y[d] = xj[d] + z * (xi[d] - xj[d]);
                }
                (y, z.powi(DIM as i32 - 1))
            };
            let py = density(m, &band, cfg.domain, &y);
            evals += 1;
            let accept = if dens[i] > 0.0 {
                rng.gen::<f64>() * dens[i] < factor * py
            } else {
                py > 0.0
            };
            if accept {
                walkers[i] = y;
                dens[i] = py;
                accepted += 1;
            }
        }
        sweep += 1;
        if sweep > cfg.burn_in && (sweep - cfg.burn_in).is_multiple_of(cfg.thin.max(1)) {
            for x in &walkers {
                if out.len() >= n {
                    break;
                }
                if let Some((wi, wo)) = decode(x, cfg.domain) {
                    out.push(Pair { wi, wo });
                }
            }
        }
    }
    (out, evals, accepted)
}

/// `n` pairs split evenly over `bands`, each band an independent ensemble (run in
/// parallel; deterministic for a given seed).
pub fn mcmc_pairs(m: &dyn Material, bands: &[Band], n: usize, cfg: &McmcConfig) -> Generated {
    let start = Instant::now();
    let nb = bands.len().max(1);
    let results: Vec<(Vec<Pair>, u64, u64)> = bands
        .par_iter()
        .enumerate()
        .map(|(b, band)| {
            let share = n / nb + usize::from(b < n % nb);
            run_band(m, *band, share, cfg, cfg.seed.wrapping_add(b as u64))
        })
        .collect();
    let mut pairs = Vec::with_capacity(n);
    let (mut evals, mut acc) = (0u64, 0u64);
    for (p, e, a) in results {
        pairs.extend(p);
        evals += e;
        acc += a;
    }
    Generated {
        pairs,
        seconds: start.elapsed().as_secs_f64(),
        evaluations: evals,
        acceptance: if evals > 0 {
            acc as f64 / evals as f64
        } else {
            0.0
        },
    }
}
