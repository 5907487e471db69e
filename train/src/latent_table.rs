//! Fitting the latent table (docs/math.md, §6.5): per incidence slice, where in `u` the
//! trained flow's samples carry too much or too little weight.
//!
//! For a draw `u` the flow's importance weight is `q(u) = Y(f) |cos theta_o| / pdf`; a
//! density `p(u)` in front of the flow turns it into `q / p`, whose second moment
//! `E[q^2 / p]` is least for `p` proportional to `sqrt(E[q^2 | u])`. Each slice's node
//! values are that root mean square, estimated from draws spread over the node's
//! bilinear hat in `u` and over its slice's hat in incidence (so that the mixed density a
//! `wi` between two slices sees is fitted too), normalised to integral 1 and mixed with
//! the uniform density (`floor`), which bounds every weight and keeps the map bijective.

use crate::error::TrainError;
use crate::metrics::sampler::{from_glam, to_glam, weight, Drawn};
use diffbsdf::internals::base::table::{slice_incidence, NODES, SLICE_LEN, TABLE_LEN};
use diffbsdf::spec::{LATENT_TABLE_CELLS as C, LATENT_TABLE_SLICES as S, LATENT_TABLE_VALUE_MAX};
use diffbsdf::{AnyModel, ModelDef};
use diffbsdf_materials::{DVec3, Material};
use rand::Rng;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use rayon::prelude::*;

/// How the table is fitted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableConfig {
    /// Draws per slice (0: no table).
    pub draws_per_slice: usize,
    /// Weight of the uniform density in every slice.
    pub floor: f64,
}

impl TableConfig {
    /// The default: 300 000 draws per slice (about a thousand per node), a uniform share
    /// of 5 % (docs/measured-materials.md, "The latent table").
    pub const DEFAULT: TableConfig = TableConfig {
        draws_per_slice: 300_000,
        floor: 0.05,
    };
    /// No table.
    pub const OFF: TableConfig = TableConfig {
        draws_per_slice: 0,
        floor: 0.05,
    };
}

/// `model` with a latent table fitted against `material` (a model that has one gets a new
/// one fitted to its flow alone). Needs standard coordinates.
pub fn with_latent_table(
    model: &AnyModel,
    material: &dyn Material,
    cfg: &TableConfig,
    seed: u64,
) -> Result<AnyModel, TrainError> {
    let def = *model.def();
    if !def.standardized {
        return Err(TrainError::Mismatch);
    }
    let flow = without_table(model)?;
    let slices: Vec<Vec<f32>> = (0..S)
        .into_par_iter()
        .map(|k| fit_slice(&flow, material, cfg, seed, k))
        .collect();
    let mut params = vec![0.0f32; flow.def().param_count()];
    flow.params(&mut params).map_err(TrainError::Blob)?;
    params.extend(slices.into_iter().flatten());
    debug_assert_eq!(params.len(), flow.def().param_count() + TABLE_LEN);
    let table_def = ModelDef {
        latent_table: true,
        ..def
    };
    AnyModel::from_params(table_def, &params).map_err(TrainError::Blob)
}

/// The same model without its latent table (itself where it has none).
pub fn without_table(model: &AnyModel) -> Result<AnyModel, TrainError> {
    let def = *model.def();
    let mut params = vec![0.0f32; def.param_count()];
    model.params(&mut params).map_err(TrainError::Blob)?;
    params.truncate(def.param_count() - def.table_len());
    let flow_def = ModelDef {
        latent_table: false,
        ..def
    };
    AnyModel::from_params(flow_def, &params).map_err(TrainError::Blob)
}

/// One slice's node values: RMS of the flow's weights around each node, normalised and
/// mixed with the uniform density.
fn fit_slice(
    flow: &AnyModel,
    material: &dyn Material,
    cfg: &TableConfig,
    seed: u64,
    k: usize,
) -> Vec<f32> {
    let mut rng = Pcg64::seed_from_u64(seed ^ (0x7AB1_E000 + k as u64));
    let mut second = vec![0.0f64; SLICE_LEN];
    let mut mass = vec![0.0f64; SLICE_LEN];
    let isotropic = flow.def().isotropic;
    for _ in 0..cfg.draws_per_slice {
        // The slice's hat in incidence, reflected at the ends.
        let s = k as f64 + rng.gen::<f64>() - rng.gen::<f64>();
        let s = (s.abs()).min(2.0 * (S - 1) as f64 - s.abs());
        let z = slice_incidence(s).max(1e-4);
        let phi = if isotropic {
            0.0
        } else {
            rng.gen::<f64>() * std::f64::consts::TAU
        };
        let r = (1.0 - z * z).max(0.0).sqrt();
        let wi = DVec3::new(r * phi.cos(), r * phi.sin(), z);
        let u = [rng.gen::<f64>(), rng.gen::<f64>()];
        let q = flow_weight(flow, material, wi, u);
        let (x, y) = (u[0] * C as f64, u[1] * C as f64);
        let (i, j) = ((x as usize).min(C - 1), (y as usize).min(C - 1));
        let (a, b) = (x - i as f64, y - j as f64);
        for (di, dj, w) in [
            (0, 0, (1.0 - a) * (1.0 - b)),
            (1, 0, a * (1.0 - b)),
            (0, 1, (1.0 - a) * b),
            (1, 1, a * b),
        ] {
            let n = (i + di) * NODES + j + dj;
            second[n] += w * q * q;
            mass[n] += w;
        }
    }
    let rms: Vec<f64> = (0..SLICE_LEN)
        .map(|n| {
            if mass[n] > 0.0 {
                (second[n] / mass[n]).sqrt()
            } else {
                0.0
            }
        })
        .collect();
    // The bilinear surface's integral: trapezoid weights over C^2 cells.
    let trapezoid = |i: usize| if i == 0 || i == C { 0.5 } else { 1.0 };
    let mut integral = 0.0;
    for i in 0..NODES {
        for j in 0..NODES {
            integral += trapezoid(i) * trapezoid(j) * rms[i * NODES + j];
        }
    }
    integral /= (C * C) as f64;
    rms.iter()
        .map(|&v| {
            let shaped = if integral > 0.0 { v / integral } else { 1.0 };
            let mixed = (1.0 - cfg.floor) * shaped + cfg.floor;
            (mixed as f32).clamp(f32::MIN_POSITIVE, LATENT_TABLE_VALUE_MAX)
        })
        .collect()
}

/// The flow's importance weight `Y(f) |cos theta_o| / pdf` for `u`; 0 where it draws
/// nothing.
fn flow_weight(flow: &AnyModel, material: &dyn Material, wi: DVec3, u: [f64; 2]) -> f64 {
    let u = diffbsdf::glam::Vec2::new(u[0] as f32, u[1] as f32);
    let drawn = flow.sample(to_glam(wi), u).map(|s| Drawn {
        wo: from_glam(s.wo),
        pdf: f64::from(s.pdf),
    });
    weight(material, wi, drawn)
}
