//! The relative variance pooled over incidences off the fixed grid.
//!
//! The grid's seven polar angles are few, and a model whose quality varies along `theta_i`
//! (a latent table mixes two incidence slices linearly, and is at its best on a slice) can
//! look better or worse there than between them. This measure draws `theta_i` in equal
//! strata over the range a model is trained on, each jittered within its stratum, `phi_i`
//! uniform, and reports the learned sampler's and the material's own sampler's mean
//! relative variance over them, side by side on the same incidences.

use super::sampler::{draw, learned_weights, weight, SamplerKind};
use super::stats::WeightStats;
use diffbsdf::AnyModel;
use diffbsdf_materials::{from_spherical, Material};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;
use serde::Serialize;

/// The polar angles the strata cover above the surface, in degrees (the trainer's range).
pub const THETA_RANGE_DEG: (f64, f64) = (0.0, 89.5);

/// One incidence off the grid.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct OffGridRow {
    /// Polar angle of `wi` in degrees.
    pub theta_deg: f64,
    /// Azimuth of `wi` in degrees.
    pub phi_deg: f64,
    /// The learned model's weights.
    pub learned: WeightStats,
    /// The material's own sampler's weights.
    pub material: WeightStats,
}

/// The pooled figures and the rows they come from.
#[derive(Clone, Debug, Serialize)]
pub struct OffGrid {
    /// Incidences (strata).
    pub incidences: usize,
    /// Samples per incidence and sampler.
    pub samples_per_wi: usize,
    /// Mean relative variance of the learned model over the incidences.
    pub learned_rv_mean: f64,
    /// The same for the material's own sampler.
    pub material_rv_mean: f64,
    /// `learned_rv_mean / material_rv_mean`.
    pub rv_ratio_to_material: f64,
    /// Worst firefly ratio of the learned model over the incidences.
    pub learned_firefly_worst: f64,
    /// Per incidence, in stratum order (upper hemisphere first).
    pub rows: Vec<OffGridRow>,
}

/// `(theta_i, phi_i)` in degrees: `theta_i` in `incidences` equal strata of
/// [`THETA_RANGE_DEG`], one jittered point in each, in order (then mirrored below the
/// surface when `both_sides`), `phi_i` uniform.
fn strata(incidences: usize, both_sides: bool, seed: u64) -> Vec<(f64, f64)> {
    let mut rng = Pcg64::seed_from_u64(seed ^ 0x0FF6_41D0);
    let (lo, hi) = THETA_RANGE_DEG;
    let mut points = Vec::new();
    for side in 0..if both_sides { 2 } else { 1 } {
        for k in 0..incidences {
            let theta = lo + (hi - lo) * (k as f64 + rng.gen::<f64>()) / incidences as f64;
            let theta = if side == 0 { theta } else { 180.0 - theta };
            points.push((theta, rng.gen::<f64>() * 360.0));
        }
    }
    points
}

/// Measures `model` and the material's sampler at `incidences` strata of `theta_i` (per
/// hemisphere: the lower one too when `both_sides`), `samples` draws each.
pub fn measure(
    model: &AnyModel,
    material: &dyn Material,
    incidences: usize,
    samples: usize,
    both_sides: bool,
    seed: u64,
) -> OffGrid {
    let points = strata(incidences, both_sides, seed);
    let rows: Vec<OffGridRow> = points
        .par_iter()
        .enumerate()
        .map(|(k, &(theta_deg, phi_deg))| {
            let wi = from_spherical(theta_deg.to_radians(), phi_deg.to_radians());
            let seed = seed.wrapping_mul(2_000_003).wrapping_add(k as u64);
            let mut rng = Pcg64::seed_from_u64(seed);
            let mut w = learned_weights(material, model, wi, samples, &mut rng);
            let learned = WeightStats::from_weights(&mut w);
            let mut rng = Pcg64::seed_from_u64(seed ^ 1);
            let kind = SamplerKind::Material;
            let mut w: Vec<f64> = (0..samples)
                .map(|_| {
                    weight(
                        material,
                        wi,
                        draw(kind, material, Some(model), wi, &mut rng),
                    )
                })
                .collect();
            OffGridRow {
                theta_deg,
                phi_deg,
                learned,
                material: WeightStats::from_weights(&mut w),
            }
        })
        .collect();
    let n = rows.len().max(1) as f64;
    let learned_rv_mean = rows.iter().map(|r| r.learned.rv).sum::<f64>() / n;
    let material_rv_mean = rows.iter().map(|r| r.material.rv).sum::<f64>() / n;
    OffGrid {
        incidences: rows.len(),
        samples_per_wi: samples,
        learned_rv_mean,
        material_rv_mean,
        rv_ratio_to_material: learned_rv_mean / material_rv_mean,
        learned_firefly_worst: rows.iter().map(|r| r.learned.firefly).fold(0.0, f64::max),
        rows,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One point in each stratum of the range, in order, `phi_i` spread over the circle;
    /// below the surface the same strata mirrored.
    #[test]
    fn strata_cover_the_range_once_each() {
        let (lo, hi) = THETA_RANGE_DEG;
        for both in [false, true] {
            let n = 50;
            let p = strata(n, both, 3);
            assert_eq!(p.len(), if both { 2 * n } else { n });
            let width = (hi - lo) / n as f64;
            for (k, &(theta, phi)) in p.iter().enumerate() {
                let (side, k) = (k / n, k % n);
                let theta = if side == 0 { theta } else { 180.0 - theta };
                let at = (theta - lo) / width;
                assert!(
                    at >= k as f64 && at < (k + 1) as f64,
                    "stratum {k}: {theta}"
                );
                assert!((0.0..360.0).contains(&phi), "{phi}");
            }
            let east = p.iter().filter(|q| q.1 < 180.0).count() as f64 / p.len() as f64;
            assert!((east - 0.5).abs() < 0.2, "{east}");
        }
    }
}
