//! Variance refinement of the student (docs/math.md, §11, (67)-(70)). Distillation
//! teaches the student its teacher's coupling; what a renderer pays for is the relative
//! variance of `w = Y(f) |cos theta_o| / pdf`. This stage tunes the student's weights to
//! lower `ln(1 + RV(wi))` itself, averaged over incidences, by reparameterised gradients:
//! for a fixed start point the end point and the log-density move with the weights, so
//! `d ln w = d ln q(x_N) + d sum_k ln det(I + h J_k)` (the submodules `target`, `path`
//! and `net`), and `d ln(1 + RV) = 2 E[(w^2 / E[w^2] - w / E[w]) d ln w]`; half of the
//! gradient is estimated from the material's own samples instead, which reach where the
//! flow's density is too low (70).
//!
//! The base net, the shape, the step count and so the blob format are unchanged: the
//! refined student is exported and checked for exactness like any other. The stage keeps
//! the refined weights only where they lower the loss on a fixed validation set.
//! Every chart: flat (disk, half-vector) and spherical (sphere, equatorial), whose
//! velocity net sees `(theta, sin phi, cos phi)` and whose steps wrap `phi`.

mod net;
mod path;
mod target;

use crate::adam::{cosine_lr, Adam};
use crate::data::DomainTarget;
use crate::error::TrainError;
use crate::features::encoding;
use crate::mlp::{layers_of, param_count, Mlp};
use crate::progress::Progress;
use diffbsdf::glam::Vec3;
use diffbsdf::internals::base::BaseDist;
use diffbsdf::spec::BASE_OUTPUTS;
use diffbsdf::{AnyModel, IncidentFold, IncidentRange, ModelDef, Net};
use diffbsdf_materials::{DVec3, Material};
use net::Transposed;
use path::{Paths, BATCH};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;
use target::Incidence;

/// Settings of the refinement.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RefineConfig {
    /// Adam iterations (0: no refinement).
    pub iters: usize,
    /// Incidences per iteration, `theta_i` uniform in angle.
    pub incidences: usize,
    /// Samples per incidence (jittered on a square grid of `u`).
    pub samples: usize,
    /// Peak learning rate (cosine decay to 5 %).
    pub lr: f32,
    /// Share of the gradient estimated from target samples (the material's own sampler,
    /// importance-weighted; they see where the flow's density is too low, which its own
    /// samples rarely reach); the rest from the flow's samples. As many target samples
    /// as flow samples per incidence when above 0.
    pub target_share: f32,
    /// Share of the incidences drawn from the grazing band `[THETA_GRAZING, THETA_MAX]`
    /// instead of the whole range (where the variance of the measured files sits).
    pub grazing_share: f32,
}

impl RefineConfig {
    /// The standard recipe's: 1 800 iterations at a peak rate of 8e-4, half the gradient
    /// from target samples (measured in docs/measured-materials.md, "Variance
    /// refinement": 600 iterations took 6-9 % more off every measured file than 300, 900
    /// another 4-11 % on the glossy ones; "Twice the peak rate of the refinement": 4e-4
    /// took another 3-8 % off all six RGL files against 2e-4; "1 800 iterations at
    /// 4e-4": twice the iterations, affordable since the refinement runs its points in
    /// batches, another 8-12 % off all six; within the 15-minute budget of a fit;
    /// "Twice the peak rate again": 8e-4 another 2-9 % off all six, at the same cost).
    pub const STANDARD: RefineConfig = RefineConfig {
        iters: 1800,
        incidences: 32,
        samples: 256,
        lr: 8e-4,
        target_share: 0.5,
        grazing_share: 0.0,
    };

    /// No refinement (the standard settings, no iterations).
    pub const OFF: RefineConfig = RefineConfig {
        iters: 0,
        ..Self::STANDARD
    };
}

impl Default for RefineConfig {
    fn default() -> Self {
        Self::STANDARD
    }
}

/// What the stage did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Refined {
    /// Validation loss (mean `ln(1 + RV)`) of the student as distilled.
    pub loss_before: f64,
    /// Validation loss of the refined weights.
    pub loss_after: f64,
    /// Whether the refined weights were kept (they lowered the validation loss).
    pub kept: bool,
}

/// Largest `theta_i` drawn (radians): 89.5 degrees.
const THETA_MAX: f32 = 89.5 * std::f32::consts::PI / 180.0;
/// Lower end of the grazing band of `RefineConfig::grazing_share` (radians): 60 degrees.
const THETA_GRAZING: f32 = 60.0 * std::f32::consts::PI / 180.0;
/// Incidences of the validation set (`theta_i` at the midpoints of equal bands).
const VALIDATION_INCIDENCES: usize = 24;
/// Samples per validation incidence.
const VALIDATION_SAMPLES: usize = 4096;

/// Whether `def` answers for `wi` below the surface too (a transmissive model on the
/// sphere): its incidences are drawn on both sides.
fn both_sides(def: &ModelDef) -> bool {
    def.incident == IncidentRange::WholeSphere
}

/// The two nets of a model, as the trainer holds them.
struct Nets {
    base: Mlp,
    velocity: Mlp,
}

impl Nets {
    fn of(model: &AnyModel) -> Result<Nets, TrainError> {
        let def = model.def();
        let (base_layers, velocity_layers) =
            (layers_of(def, Net::Base), layers_of(def, Net::Velocity));
        let n_base = param_count(&base_layers);
        let mut params = vec![0.0f32; n_base + param_count(&velocity_layers)];
        model.params(&mut params)?;
        let velocity = params.split_off(n_base);
        Ok(Nets {
            base: Mlp::from_params(base_layers, params).ok_or(TrainError::Mismatch)?,
            velocity: Mlp::from_params(velocity_layers, velocity).ok_or(TrainError::Mismatch)?,
        })
    }

    fn model(&self, def: ModelDef) -> Result<AnyModel, TrainError> {
        crate::export::model_from_nets(def, &self.base, &self.velocity)
    }
}

/// Refines `model`'s student against `material` (see the module); returns the model to
/// ship (the refined one, or `model` itself where refinement did not lower the
/// validation loss) and what happened.
pub fn refine(
    model: &AnyModel,
    material: &dyn Material,
    cfg: &RefineConfig,
    seed: u64,
    progress: &dyn Progress,
) -> Result<(AnyModel, Refined), TrainError> {
    // The flow alone: a latent table fitted to the old flow would not fit the new one.
    let flow = crate::latent_table::without_table(model)?;
    let model = &flow;
    let def = *model.def();
    let mut nets = Nets::of(model)?;
    let before = validation_loss(&def, &nets, material);
    if cfg.iters == 0 {
        let same = Refined {
            loss_before: before,
            loss_after: before,
            kept: false,
        };
        return Ok((*model, same));
    }
    progress.stage("refine", cfg.iters as u64);
    let mut adam = Adam::new(nets.velocity.params().len());
    let mut rng = Pcg64::seed_from_u64(seed ^ 0x5eed_2ef1_9e00_0001);
    for it in 0..cfg.iters {
        let jobs: Vec<(Vec3, u64)> = (0..cfg.incidences)
            .map(|_| (draw_incidence(&def, cfg.grazing_share, &mut rng), rng.gen()))
            .collect();
        let (grad, loss) = batch_gradient(&def, &nets, material, &jobs, cfg);
        let lr = cosine_lr(cfg.lr, 0.05, it, cfg.iters);
        adam.update(nets.velocity.params_mut(), &grad, lr);
        progress.advance(1, Some(loss));
    }
    let after = validation_loss(&def, &nets, material);
    let kept = after < before;
    let out = if kept { nets.model(def)? } else { *model };
    Ok((
        out,
        Refined {
            loss_before: before,
            loss_after: after,
            kept,
        },
    ))
}

/// A training incidence: `theta_i` uniform in angle on `[0, THETA_MAX]` (with probability
/// `grazing_share` on `[THETA_GRAZING, THETA_MAX]`), mirrored below the surface half the
/// time for a model of both sides; `phi_i` 0 for an isotropic model (its frame) and
/// uniform otherwise.
fn draw_incidence(def: &ModelDef, grazing_share: f32, rng: &mut Pcg64) -> Vec3 {
    let lowest = if grazing_share > 0.0 && rng.gen::<f32>() < grazing_share {
        THETA_GRAZING
    } else {
        0.0
    };
    let theta = lowest + (THETA_MAX - lowest) * rng.gen::<f32>();
    let theta = if both_sides(def) && rng.gen::<bool>() {
        std::f32::consts::PI - theta
    } else {
        theta
    };
    let (start, span) = def.fold.kept_azimuths();
    let phi = if def.isotropic {
        0.0
    } else {
        start + span * rng.gen::<f32>()
    };
    incidence(theta, phi)
}

/// The unit `wi` at polar angle `theta` and azimuth `phi`.
fn incidence(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// Mean over `jobs` of the gradient of `ln(1 + RV)` and the mean loss.
fn batch_gradient(
    def: &ModelDef,
    nets: &Nets,
    material: &dyn Material,
    jobs: &[(Vec3, u64)],
    cfg: &RefineConfig,
) -> (Vec<f32>, f64) {
    let parts: Vec<(Vec<f32>, f64)> = jobs
        .par_iter()
        .map(|&(wi, seed)| incidence_loss(def, nets, material, wi, seed, cfg, true))
        .collect();
    let n = parts.len().max(1) as f32;
    let mut grad = vec![0.0f32; nets.velocity.params().len()];
    let mut loss = 0.0;
    for (g, l) in &parts {
        grad.iter_mut().zip(g).for_each(|(a, b)| *a += b / n);
        loss += l / n as f64;
    }
    (grad, loss)
}

/// Mean `ln(1 + RV)` over the fixed validation incidences (and their mirror images
/// below the surface for a model of both sides).
fn validation_loss(def: &ModelDef, nets: &Nets, material: &dyn Material) -> f64 {
    let sides = if both_sides(def) { 2 } else { 1 };
    let losses: Vec<f64> = (0..VALIDATION_INCIDENCES * sides)
        .into_par_iter()
        .map(|i| {
            let k = i % VALIDATION_INCIDENCES;
            let theta = THETA_MAX * (k as f32 + 0.5) / VALIDATION_INCIDENCES as f32;
            let theta = if i < VALIDATION_INCIDENCES {
                theta
            } else {
                std::f32::consts::PI - theta
            };
            let phi = match (def.isotropic, def.fold) {
                (true, _) => 0.0,
                (false, IncidentFold::None) => 2.4 * k as f32,
                // Spread over the kept azimuths by the same golden-ish step.
                (false, fold) => {
                    let (start, span) = fold.kept_azimuths();
                    start + span * (2.4 * k as f32 / std::f32::consts::TAU).fract()
                }
            };
            let wi = incidence(theta, phi);
            let seed = 0x7a11_da7e ^ i as u64;
            let cfg = RefineConfig {
                samples: VALIDATION_SAMPLES,
                ..RefineConfig::OFF
            };
            incidence_loss(def, nets, material, wi, seed, &cfg, false).1
        })
        .collect();
    losses.iter().sum::<f64>() / losses.len().max(1) as f64
}

/// `ln(1 + RV)` of one incidence from `cfg.samples` jittered `u`, and (when
/// `with_gradient`) its gradient: (69) over the flow's samples, mixed with the same over
/// target samples, (70) (`cfg.target_share`).
fn incidence_loss(
    def: &ModelDef,
    nets: &Nets,
    material: &dyn Material,
    wi: Vec3,
    seed: u64,
    cfg: &RefineConfig,
    with_gradient: bool,
) -> (Vec<f32>, f64) {
    let samples = cfg.samples;
    let net = &nets.velocity;
    let mut base_out = [0.0f32; BASE_OUTPUTS];
    nets.base
        .forward(&encoding(wi.to_array(), def.base.freqs), &mut base_out);
    let inc = Incidence {
        def,
        material,
        wi,
        base: BaseDist::from_net(def.domain, base_out),
    };
    let enc = encoding(wi.to_array(), def.velocity.freqs);
    let cond = net::condition(def.domain, net, &enc);
    let weights = (net, &Transposed::of(net));
    let steps = usize::from(def.default_steps.max(1));
    let mut paths = Paths::new(def.domain);
    let mut rng = Pcg64::seed_from_u64(seed);
    let side = (samples as f64).sqrt().ceil().max(1.0) as usize;
    // Pass 1: every sample's start point and ln w (None: lost or zero weight).
    let starts: Vec<([f32; 2], f64)> = (0..side * side)
        .map(|i| {
            let u = [
                ((i % side) as f32 + rng.gen::<f32>()) / side as f32,
                ((i / side) as f32 + rng.gen::<f32>()) / side as f32,
            ];
            inc.start(u.map(|v| v.clamp(1e-7, 1.0 - 1e-7)))
        })
        .collect();
    // (end point, ln w) per sample, and (for the gradient) each batch's paths
    let mut draws: Vec<(Option<[f32; 2]>, Option<f64>)> = Vec::with_capacity(starts.len());
    let mut ran: Vec<Paths> = Vec::new();
    for chunk in starts.chunks(BATCH) {
        let y0: Vec<[f32; 2]> = chunk.iter().map(|s| s.0).collect();
        let ends = paths.run(weights, &cond, &y0, steps);
        draws.extend(chunk.iter().zip(ends).map(|(&(_, ln_p0), end)| {
            let ln_w = end.and_then(|(end, ln_det)| Some(inc.ln_target(end)? - ln_p0 + ln_det));
            (end.map(|e| e.0), ln_w.filter(|v| v.is_finite()))
        }));
        if with_gradient {
            ran.push(std::mem::replace(&mut paths, Paths::new(def.domain)));
        }
    }
    let top = draws
        .iter()
        .filter_map(|d| d.1)
        .fold(f64::NEG_INFINITY, f64::max);
    let w: Vec<f64> = draws
        .iter()
        .map(|d| d.1.map_or(0.0, |l| (l - top).exp()))
        .collect();
    let (s1, s2) = (w.iter().sum::<f64>(), w.iter().map(|v| v * v).sum::<f64>());
    let mut grad = vec![0.0f32; net.params().len()];
    if !(s1 > 0.0) {
        return (grad, 0.0);
    }
    // ln(1 + RV) = ln(n E[w^2] / E[w]^2), the lost samples counted with w = 0
    let loss = (w.len() as f64 * s2 / (s1 * s1)).ln();
    if !with_gradient {
        return (grad, loss);
    }
    // Pass 2: d ln(1 + RV) = sum_s 2 (w_s^2 / S2 - w_s / S1) d ln w_s
    let mut cond_grad = vec![0.0f32; cond.len()];
    let share = cfg.target_share.clamp(0.0, 1.0);
    if share > 0.0 {
        let mut target_rng = Pcg64::seed_from_u64(seed ^ 0x7a26_e75a);
        let ctx = (&inc, weights, cond.as_slice(), steps);
        target_gradient(
            ctx,
            &mut target_rng,
            samples,
            share,
            &mut grad,
            &mut cond_grad,
        );
    }
    let own = 1.0 - share;
    let batches = draws.chunks(BATCH).zip(w.chunks(BATCH)).zip(&mut ran);
    for ((chunk, w), paths) in batches {
        for (row, (draw, ws)) in chunk.iter().zip(w).enumerate() {
            let c = own * (2.0 * (ws * ws / s2 - ws / s1)) as f32;
            if *ws == 0.0 || c == 0.0 {
                continue;
            }
            let Some(g) = draw.0.and_then(|end| inc.ln_target_gradient(end)) else {
                continue;
            };
            paths.backward(
                (net, row),
                [c * g[0], c * g[1]],
                c,
                &mut grad,
                &mut cond_grad,
            );
        }
    }
    net::condition_backward(def.domain, net, &enc, &cond_grad, &mut grad);
    (grad, loss)
}

/// Adds `share` times the gradient of `ln(1 + RV)` estimated from `count` target samples:
/// `1 + RV = E_q[q / p]`, so `grad = -E_s[r grad ln p(x)] / E_s[r]` with
/// `r = (q / s)(q / p)` for samples of the material's own sampler `s`, and `grad ln p(x)`
/// at the fixed sample (`Paths::fixed_end_backward`).
fn target_gradient(
    (inc, weights, cond, steps): (&Incidence<'_>, (&Mlp, &Transposed), &[f32], usize),
    rng: &mut Pcg64,
    count: usize,
    share: f32,
    grad: &mut [f32],
    cond_grad: &mut [f32],
) {
    let as64 = |w: Vec3| DVec3::new(f64::from(w.x), f64::from(w.y), f64::from(w.z));
    let wi64 = as64(inc.wi);
    // (end point, ln(target / s)) of every target sample inside the chart
    let drawn: Vec<([f32; 2], f64)> = (0..count)
        .filter_map(|_| {
            let s = inc
                .material
                .sample(wi64, [rng.gen(), rng.gen(), rng.gen()])?;
            let target = inc.def.domain.target(inc.material, wi64, s.wo);
            if !(target > 0.0 && s.pdf > 0.0) {
                return None;
            }
            let wo = Vec3::new(s.wo.x as f32, s.wo.y as f32, s.wo.z as f32);
            Some((inc.end_point(wo)?, (target / s.pdf).ln()))
        })
        .collect();
    // (start point, ln r, batch, row) of every inverted one; each batch's paths as the
    // inverse left them (run from the starts found)
    let mut kept: Vec<([f32; 2], f64, usize, usize)> = Vec::with_capacity(drawn.len());
    let mut inverted: Vec<Paths> = Vec::new();
    for (batch, chunk) in drawn.chunks(BATCH).enumerate() {
        let ends: Vec<[f32; 2]> = chunk.iter().map(|d| d.0).collect();
        let mut paths = Paths::new(inc.def.domain);
        let starts = paths.invert(weights, cond, &ends, steps);
        let rows = chunk.iter().zip(starts).enumerate();
        kept.extend(rows.filter_map(|(row, (&(end, ln_q_s), start))| {
            let (y0, ln_det) = start?;
            let ln_p = inc.ln_start(y0) - ln_det;
            let ln_r = ln_q_s + inc.ln_target(end)? - ln_p;
            ln_r.is_finite().then_some((y0, ln_r, batch, row))
        }));
        inverted.push(paths);
    }
    let top = kept.iter().map(|k| k.1).fold(f64::NEG_INFINITY, f64::max);
    let total: f64 = kept.iter().map(|k| (k.1 - top).exp()).sum();
    if !(total > 0.0) {
        return;
    }
    for (y0, ln_r, batch, row) in kept {
        let a = -share * ((ln_r - top).exp() / total) as f32;
        if a == 0.0 {
            continue;
        }
        let net = (weights.0, row);
        let paths = &mut inverted[batch];
        let _ = paths.fixed_end_backward(net, inc.ln_start_gradient(y0), a, grad, cond_grad);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::FitConfig;
    use diffbsdf::Domain;

    /// An isotropic model's definition (its incidences use one random number each).
    fn isotropic() -> ModelDef {
        let mut def = FitConfig::tiny(Domain::HalfVector, 3).def;
        def.isotropic = true;
        def
    }

    fn thetas(share: f32) -> Vec<f32> {
        let def = isotropic();
        let mut rng = Pcg64::seed_from_u64(7);
        (0..4000)
            .map(|_| {
                draw_incidence(&def, share, &mut rng)
                    .z
                    .clamp(-1.0, 1.0)
                    .acos()
            })
            .collect()
    }

    /// A grazing share of 0 draws what the refinement drew before the option existed
    /// (uniform in angle, one random number per incidence); a share of 1 draws only the
    /// grazing band; 0.5 about half of its draws there, plus the uniform draws' share.
    #[test]
    fn grazing_share_moves_the_incidences_to_the_grazing_band() {
        let mut rng = Pcg64::seed_from_u64(7);
        let plain: Vec<f32> = (0..4000).map(|_| THETA_MAX * rng.gen::<f32>()).collect();
        let none = thetas(0.0);
        for (a, b) in none.iter().zip(&plain) {
            assert!((a - b).abs() < 1e-3, "{a} vs {b}");
        }
        let all = thetas(1.0);
        assert!(all
            .iter()
            .all(|t| (THETA_GRAZING - 1e-3..=THETA_MAX + 1e-3).contains(t)));
        let half = thetas(0.5);
        let band = half.iter().filter(|&&t| t >= THETA_GRAZING).count() as f64 / 4000.0;
        // 0.5 + 0.5 (THETA_MAX - THETA_GRAZING) / THETA_MAX = 0.665
        assert!((band - 0.665).abs() < 0.03, "{band}");
    }
}
