//! Shared helpers of the kernel tests: random models with invertible steps, a seeded
//! generator, and tolerance checks that print what they allowed.
#![allow(dead_code)]

use diffbsdf::internals::Diagnostics;
use diffbsdf::{Domain, IncidentFold, Model3x32, Model4x32, ModelDef, Net};

/// A small seeded generator (SplitMix64) so tests need no extra crate.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x9E37_79B9_7F4A_7C15)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.uniform()
    }
}

/// Largest `h * |dv/dx|_2` allowed over the probe grid: keeps steps far from folding.
const STEP_STRETCH: f32 = 0.6;

/// Weight-matrix sizes of `net` in blob order, `(rows, cols)` = `(outputs, inputs)`, from the
/// kernel's layer description.
fn weight_shapes(def: &ModelDef, net: Net) -> Vec<(usize, usize)> {
    (0..def.layer_count(net))
        .filter_map(|i| def.layer(net, i))
        .map(|l| (l.outputs, l.inputs))
        .collect()
}

/// Parameters of a random model in blob order.
///
/// The base net's outputs are biased so that `p0` sits inside the domain with scales in
/// [`min_scale`, 0.4].
/// The velocity net is left unscaled here; [`scale_to_invertible`] scales its readout.
pub fn random_params(def: &ModelDef, rng: &mut Rng, min_scale: f32) -> Vec<f32> {
    let mut params = Vec::with_capacity(def.param_count());
    // Base net: small weights, biases of the readout set the distribution.
    let layers = weight_shapes(def, Net::Base);
    for (li, &(rows, cols)) in layers.iter().enumerate() {
        let last = li + 1 == layers.len();
        let scale = if last { 0.1 } else { 1.0 } / (cols as f32).sqrt();
        for _ in 0..rows * cols {
            params.push(rng.range(-scale, scale) * 1.7);
        }
        for r in 0..rows {
            params.push(if last {
                base_bias(def.domain, r, rng, min_scale)
            } else {
                rng.range(-0.1, 0.1)
            });
        }
    }
    // Velocity net.
    let features = def.domain.feature_count();
    for (li, &(rows, cols)) in weight_shapes(def, Net::Velocity).iter().enumerate() {
        let scale = 1.7 / (cols as f32).sqrt();
        for _ in 0..rows {
            for c in 0..cols {
                // The `wi` columns of the first layer are damped: the flow should deform
                // p0 for every wi, not carry it away.
                let damp = if li == 0 && c > features { 0.3 } else { 1.0 };
                params.push(damp * rng.range(-scale, scale));
            }
        }
        for _ in 0..rows {
            params.push(rng.range(-0.2, 0.2));
        }
    }
    assert_eq!(params.len(), def.param_count());
    params
}

fn base_bias(domain: Domain, r: usize, rng: &mut Rng, min_scale: f32) -> f32 {
    let ln_scale = rng.range(min_scale.ln(), 0.4f32.ln());
    match (domain, r) {
        (Domain::Disk | Domain::HalfVector, 0 | 1) => rng.range(-0.4, 0.4),
        (Domain::Sphere | Domain::Equatorial, 0) => rng.range(0.3, 2.8),
        (Domain::Sphere | Domain::Equatorial, 2) => rng.range(-3.0, 3.0),
        _ => ln_scale,
    }
}

/// Spectral norm of a 2x2 matrix.
fn spectral_norm(j: [[f32; 2]; 2]) -> f32 {
    let (a, b, c, d) = (j[0][0], j[0][1], j[1][0], j[1][1]);
    let s = a * a + b * b + c * c + d * d;
    let det = a * d - b * c;
    ((s + (s * s - 4.0 * det * det).max(0.0).sqrt()) / 2.0).sqrt()
}

/// Scales the velocity readout (the last `2 * width + 2` parameters) so that the largest
/// `|dv/dx|_2` seen on a grid of points, times `h = 1/min_steps`, is `STEP_STRETCH`. The
/// steps stay strongly deforming but invertible (the bijectivity tests check that).
/// Then shifts the readout bias so the mean velocity over the grid is zero (the flow
/// deforms `p0` rather than carrying all of it out of the domain).
type Probe = (diffbsdf::glam::Vec3, [f32; 2], f32);
type Velocity = ([f32; 2], [[f32; 2]; 2]);

fn scale_to_invertible(
    def: &ModelDef,
    params: &mut [f32],
    min_steps: u32,
    eval_all: impl Fn(&[f32], &[Probe]) -> Vec<Velocity>,
) {
    if min_steps == 0 {
        return;
    }
    let mut probes = Vec::new();
    for k in 0..4 {
        let wi = direction(
            0.1 + 0.27 * k as f32,
            0.37 * k as f32,
            !def.domain.is_spherical(),
        );
        for i in 0..13 {
            for j in 0..13 {
                let x = match def.domain {
                    Domain::Disk | Domain::HalfVector => {
                        [-2.0 + i as f32 / 3.0, -2.0 + j as f32 / 3.0]
                    }
                    Domain::Sphere | Domain::Equatorial => {
                        [-1.0 + i as f32 * 0.4, -3.1 + j as f32 * 0.52]
                    }
                };
                for t in [0.0, 0.5, 1.0] {
                    probes.push((wi, x, t));
                }
            }
        }
    }
    let results = eval_all(params, &probes);
    let worst = results
        .iter()
        .fold(0.0f32, |m, (_, j)| m.max(spectral_norm(*j)));
    let count = results.len() as f32;
    let mean = results
        .iter()
        .fold([0.0f32; 2], |m, (v, _)| [m[0] + v[0], m[1] + v[1]]);
    let s = STEP_STRETCH * min_steps as f32 / worst;
    let w = def.velocity.width as usize;
    let n = params.len();
    for p in &mut params[n - 2 * w - 2..] {
        *p *= s;
    }
    params[n - 2] -= s * mean[0] / count;
    params[n - 1] -= s * mean[1] / count;
}

/// A random disk model (paper shape 3x32), invertible for `steps >= min_steps`
/// (`min_steps = 0`: unscaled, possibly not invertible).
pub fn random_disk(seed: u64, min_steps: u32) -> Model3x32 {
    let def = ModelDef::paper_disk();
    let mut params = random_params(&def, &mut Rng::new(seed), 0.08);
    scale_to_invertible(&def, &mut params, min_steps, |p, probes| {
        let m = Model3x32::from_params(def, p).unwrap();
        probes
            .iter()
            .map(|&(wi, x, t)| m.velocity_at(wi, x, t).unwrap())
            .collect()
    });
    Model3x32::from_params(def, &params).unwrap()
}

/// A random sphere model (paper shape 4x32), invertible for `steps >= min_steps`.
pub fn random_sphere(seed: u64, min_steps: u32) -> Model4x32 {
    let def = ModelDef::paper_sphere();
    let mut params = random_params(&def, &mut Rng::new(seed), 0.08);
    scale_to_invertible(&def, &mut params, min_steps, |p, probes| {
        let m = Model4x32::from_params(def, p).unwrap();
        probes
            .iter()
            .map(|&(wi, x, t)| m.velocity_at(wi, x, t).unwrap())
            .collect()
    });
    Model4x32::from_params(def, &params).unwrap()
}

/// `def` with the isotropic flag set, and the parameters `write` puts in blob order.
fn flagged_isotropic(def: &ModelDef, write: impl FnOnce(&mut [f32])) -> (ModelDef, Vec<f32>) {
    let mut def = *def;
    def.isotropic = true;
    let mut p = vec![0.0; def.param_count()];
    write(&mut p);
    (def, p)
}

/// A random disk model as [`random_disk`], flagged isotropic (nets see `wi` at `phi = 0`).
pub fn random_isotropic_disk(seed: u64, min_steps: u32) -> Model3x32 {
    let m = random_disk(seed, min_steps);
    let (def, p) = flagged_isotropic(m.def(), |p| {
        m.params(p).unwrap();
    });
    Model3x32::from_params(def, &p).unwrap()
}

/// A random sphere model as [`random_sphere`], flagged isotropic.
pub fn random_isotropic_sphere(seed: u64, min_steps: u32) -> Model4x32 {
    let m = random_sphere(seed, min_steps);
    let (def, p) = flagged_isotropic(m.def(), |p| {
        m.params(p).unwrap();
    });
    Model4x32::from_params(def, &p).unwrap()
}

/// A unit direction from two uniforms, over the upper hemisphere (`upper`) or the sphere.
pub fn direction(u0: f32, u1: f32, upper: bool) -> diffbsdf::glam::Vec3 {
    let z = if upper { u0 } else { 2.0 * u0 - 1.0 };
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u1;
    diffbsdf::glam::Vec3::new(r * phi.cos(), r * phi.sin(), z).normalize()
}

/// Relative difference `|a - b| / max(|b|, floor)`.
pub fn rel(a: f32, b: f32, floor: f32) -> f32 {
    (a - b).abs() / b.abs().max(floor)
}

/// Every shipped blob (`models/*.dbsdf`, f32 and f16) with its file name, sorted.
pub fn shipped_blobs() -> Vec<(String, Vec<u8>)> {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("models");
    let mut out: Vec<_> = std::fs::read_dir(&dir)
        .expect("models/ exists")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "dbsdf"))
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    out.sort();
    assert!(out.len() >= 10, "expected the shipped models in {dir:?}");
    out
}

/// A random sphere model as [`random_sphere`], on the equatorial chart (the same nets).
pub fn random_equatorial(seed: u64, min_steps: u32) -> Model4x32 {
    let mut m = random_sphere(seed, min_steps);
    let mut def = *m.def();
    def.domain = Domain::Equatorial;
    let mut p = vec![0.0; def.param_count()];
    m.params(&mut p).unwrap();
    m = Model4x32::from_params(def, &p).unwrap();
    m
}

/// [`random_equatorial`], flagged isotropic.
pub fn random_isotropic_equatorial(seed: u64, min_steps: u32) -> Model4x32 {
    let m = random_equatorial(seed, min_steps);
    let (def, p) = flagged_isotropic(m.def(), |p| {
        m.params(p).unwrap();
    });
    Model4x32::from_params(def, &p).unwrap()
}

/// A random disk model as [`random_disk`], on the half-vector chart (the same nets).
pub fn random_half_vector(seed: u64, min_steps: u32) -> Model3x32 {
    let m = random_disk(seed, min_steps);
    let mut def = *m.def();
    def.domain = Domain::HalfVector;
    let mut p = vec![0.0; def.param_count()];
    m.params(&mut p).unwrap();
    Model3x32::from_params(def, &p).unwrap()
}

/// [`random_isotropic_half_vector`] with its flow in the base's standard coordinates
/// (docs/math.md, §6.3), the base narrowed to `sigma` about 0.14 and moved off the centre so
/// that the map from the flow to the chart is far from the identity.
pub fn random_standardized_half_vector(seed: u64, min_steps: u32) -> Model3x32 {
    standardized(&random_isotropic_half_vector(seed, min_steps))
}

/// [`random_disk`] with its flow in the base's standard coordinates, as
/// [`random_standardized_half_vector`].
pub fn random_standardized_disk(seed: u64, min_steps: u32) -> Model3x32 {
    standardized(&random_disk(seed, min_steps))
}

/// [`random_standardized_half_vector`] with the flow in the compressed standard
/// coordinates `K asinh(z / K)` (docs/math.md, §6.4).
pub fn random_warped_half_vector(seed: u64, min_steps: u32) -> Model3x32 {
    let m = standardized(&random_isotropic_half_vector(seed, min_steps));
    let mut def = *m.def();
    def.standard_warp = true;
    let mut p = vec![0.0; def.param_count()];
    m.params(&mut p).unwrap();
    Model3x32::from_params(def, &p).unwrap()
}

fn standardized(m: &Model3x32) -> Model3x32 {
    let mut def = *m.def();
    def.standardized = true;
    let mut p = vec![0.0; def.param_count()];
    m.params(&mut p).unwrap();
    // The base readout (rows mu_0, mu_1, ln sigma_0, ln sigma_1 of `width` weights, then
    // the four biases): a tenth of its dependence on `wi`, centred at (0.1, -0.05) with
    // sigma about 0.14.
    let outputs = diffbsdf::spec::BASE_OUTPUTS;
    let bias = def.net_param_count(Net::Base) - outputs;
    let weights = bias - outputs * def.base.width as usize;
    for w in &mut p[weights..bias] {
        *w *= 0.1;
    }
    p[bias..bias + outputs].copy_from_slice(&[0.1, -0.05, -2.0, -2.0]);
    Model3x32::from_params(def, &p).unwrap()
}

/// [`random_half_vector`], flagged isotropic.
pub fn random_isotropic_half_vector(seed: u64, min_steps: u32) -> Model3x32 {
    let m = random_half_vector(seed, min_steps);
    let (def, p) = flagged_isotropic(m.def(), |p| {
        m.params(p).unwrap();
    });
    Model3x32::from_params(def, &p).unwrap()
}

/// [`random_half_vector`] folded by `fold` (anisotropic: the nets see `wi` folded into
/// part of the turn).
pub fn random_folded_half_vector(seed: u64, min_steps: u32, fold: IncidentFold) -> Model3x32 {
    let m = random_half_vector(seed, min_steps);
    let mut def = *m.def();
    def.fold = fold;
    let mut p = vec![0.0; def.param_count()];
    m.params(&mut p).unwrap();
    Model3x32::from_params(def, &p).unwrap()
}

/// [`random_sphere`] folded by `fold`.
pub fn random_folded_sphere(seed: u64, min_steps: u32, fold: IncidentFold) -> Model4x32 {
    let m = random_sphere(seed, min_steps);
    let mut def = *m.def();
    def.fold = fold;
    let mut p = vec![0.0; def.param_count()];
    m.params(&mut p).unwrap();
    Model4x32::from_params(def, &p).unwrap()
}
