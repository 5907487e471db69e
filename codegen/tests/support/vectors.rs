//! Shared conformance vectors and helpers, used by the codegen tests and (through
//! `#[path]`) by the FFI tests: the random-weight models, the `(wi, u)` and `(wi, wo)`
//! vectors with their edge cases, the tolerance checks and the tools (gcc, g++) runners.
#![allow(dead_code)]

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::internals::blob::{blob_len, write_blob};
use diffbsdf::internals::Diagnostics;
use diffbsdf::{AnyModel, Domain, IncidentFold, ModelDef, ModelName, Net, Precision, TableGrid};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The f32 conformance tolerance of the issue: 1e-5 relative (directions are unit
/// vectors, so their error is relative to 1).
pub const TOL_F32: f32 = 1e-5;

/// 1 - 2^-24: the largest f32 below 1.
pub const ONE_MINUS_EPS: f32 = 1.0 - 1.0 / 16_777_216.0;

/// A model under test: a name and its blob.
pub struct TestModel {
    pub name: String,
    pub blob: Vec<u8>,
}

/// SplitMix64: a seeded generator, so tests need no extra crate.
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
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        let u = (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32);
        lo + (hi - lo) * u
    }
}

/// Parameters of a random model in blob order: hidden layers with weights uniform in
/// +-1.7/sqrt(fan-in) (the `wi` columns of the first velocity layer damped by 0.3), the
/// base readout biased so that p0 sits inside the domain with scales in [0.08, 0.4], and
/// the velocity readout scaled by `stretch` so every Euler step stays invertible while
/// deforming p0 visibly.
pub fn random_params(def: &ModelDef, seed: u64, stretch: f32) -> Vec<f32> {
    let mut rng = Rng::new(seed);
    let mut p = Vec::with_capacity(def.param_count());
    for net in Net::ALL {
        for i in 0..def.layer_count(net) {
            let Some(layer) = def.layer(net, i) else {
                continue;
            };
            let readout = !layer.activated;
            let fan = (layer.inputs as f32).sqrt();
            let scale = match (net, readout) {
                (_, false) => 1.7 / fan,
                (Net::Base, true) => 0.17 / fan,
                (Net::Velocity, true) => stretch / fan,
            };
            // The `wi` columns of the first velocity layer follow the features and `t`.
            let damp_from = if net == Net::Velocity && i == 0 {
                def.domain.feature_count() + 1
            } else {
                usize::MAX
            };
            for _ in 0..layer.outputs {
                for c in 0..layer.inputs {
                    let damp = if c >= damp_from { 0.3 } else { 1.0 };
                    p.push(damp * rng.range(-scale, scale));
                }
            }
            for r in 0..layer.outputs {
                p.push(match (net, readout) {
                    (Net::Base, false) => rng.range(-0.1, 0.1),
                    (Net::Base, true) => base_bias(def.domain, r, &mut rng),
                    (Net::Velocity, false) => rng.range(-0.2, 0.2),
                    (Net::Velocity, true) => rng.range(-0.1, 0.1),
                });
            }
        }
    }
    // The latent table's node values: positive, a 60x range.
    for _ in 0..def.table_len() {
        p.push(rng.range(0.05, 3.0));
    }
    assert_eq!(p.len(), def.param_count());
    p
}

/// A base readout bias: locations inside the domain, log-scales in [ln 0.08, ln 0.4].
fn base_bias(domain: Domain, r: usize, rng: &mut Rng) -> f32 {
    let ln_scale = rng.range(0.08f32.ln(), 0.4f32.ln());
    match (domain, r) {
        (Domain::Disk | Domain::HalfVector, 0 | 1) => rng.range(-0.4, 0.4),
        (Domain::Sphere | Domain::Equatorial, 0) => rng.range(0.3, 2.8),
        (Domain::Sphere | Domain::Equatorial, 2) => rng.range(-3.0, 3.0),
        _ => ln_scale,
    }
}

/// A blob of `def` with random parameters.
pub fn random_blob(def: &ModelDef, seed: u64, stretch: f32) -> Vec<u8> {
    let params = random_params(def, seed, stretch);
    let mut out = vec![0u8; blob_len(def)];
    write_blob(def, &params, &mut out).expect("write blob");
    out
}

fn named(mut def: ModelDef, name: &str, precision: Precision) -> ModelDef {
    def.name = ModelName::new(name).expect("name");
    def.precision = precision;
    def
}

/// The random-weight models every conformance test runs (the paper's disk and sphere
/// architectures, f32 and f16 weights, isotropic and not), and every shipped model in
/// `models/`. The GPU test (`tests/gpu.rs`) compiles one pipeline per architecture and
/// runs every model of that shape through it.
pub fn test_models() -> Vec<TestModel> {
    let iso = |mut d: ModelDef| {
        d.isotropic = true;
        d
    };
    let disk = ModelDef::paper_disk();
    let sphere = ModelDef::paper_sphere();
    let equatorial = ModelDef {
        domain: Domain::Equatorial,
        ..sphere
    };
    let upper = |mut d: ModelDef| {
        d.incident = diffbsdf::IncidentRange::UpperHemisphere;
        d
    };
    let half_vector = ModelDef {
        domain: Domain::HalfVector,
        ..disk
    };
    // The flow in the base's standard coordinates (docs/math.md, §6.3).
    let standard = |mut d: ModelDef| {
        d.standardized = true;
        d
    };
    // ... compressed by K asinh(z / K) (docs/math.md, §6.4).
    let warped = |mut d: ModelDef| {
        d.standardized = true;
        d.standard_warp = true;
        d
    };
    let mut models = vec![
        TestModel {
            name: "random_disk".into(),
            blob: random_blob(&named(iso(disk), "random_disk", Precision::F32), 11, 1.2),
        },
        TestModel {
            name: "random_sphere".into(),
            blob: random_blob(&named(sphere, "random_sphere", Precision::F32), 12, 1.2),
        },
        TestModel {
            name: "random_disk_f16".into(),
            blob: random_blob(
                &named(iso(disk), "random_disk_f16", Precision::F16),
                13,
                1.2,
            ),
        },
        TestModel {
            name: "random_disk_aniso".into(),
            blob: random_blob(&named(disk, "random_disk_aniso", Precision::F32), 14, 1.2),
        },
        TestModel {
            name: "random_sphere_iso".into(),
            blob: random_blob(
                &named(iso(sphere), "random_sphere_iso", Precision::F32),
                15,
                1.2,
            ),
        },
        TestModel {
            name: "random_equatorial_iso".into(),
            blob: random_blob(
                &named(
                    upper(iso(equatorial)),
                    "random_equatorial_iso",
                    Precision::F32,
                ),
                16,
                1.2,
            ),
        },
        TestModel {
            name: "random_half_vector_iso".into(),
            blob: random_blob(
                &named(iso(half_vector), "random_half_vector_iso", Precision::F32),
                17,
                1.2,
            ),
        },
        TestModel {
            name: "random_half_vector_aniso".into(),
            blob: random_blob(
                &named(half_vector, "random_half_vector_aniso", Precision::F32),
                18,
                1.2,
            ),
        },
        TestModel {
            name: "random_half_vector_f16".into(),
            blob: random_blob(
                &named(iso(half_vector), "random_half_vector_f16", Precision::F16),
                19,
                1.2,
            ),
        },
        TestModel {
            name: "random_half_vector_std".into(),
            blob: random_blob(
                &named(
                    standard(iso(half_vector)),
                    "random_half_vector_std",
                    Precision::F32,
                ),
                20,
                1.2,
            ),
        },
        TestModel {
            name: "random_half_vector_warp".into(),
            blob: random_blob(
                &named(
                    warped(iso(half_vector)),
                    "random_half_vector_warp",
                    Precision::F32,
                ),
                21,
                1.2,
            ),
        },
        TestModel {
            name: "random_half_vector_warp_f16".into(),
            blob: random_blob(
                &named(
                    warped(iso(half_vector)),
                    "random_half_vector_warp_f16",
                    Precision::F16,
                ),
                22,
                1.2,
            ),
        },
        // A latent table in front of the warped flow (docs/math.md, §6.5), anisotropic
        // and folded into a quarter of the turn (83), on the 32 slices with warped axes
        // (81) (the shipped anisotropic copper has the table on even cells and no fold, the
        // other shipped tables the blended layout's 40 slices).
        TestModel {
            name: "random_half_vector_table".into(),
            blob: random_blob(
                &named(
                    ModelDef {
                        latent_table: Some(TableGrid::WarpedCodes),
                        fold: IncidentFold::Quarter,
                        ..warped(half_vector)
                    },
                    "random_half_vector_table",
                    Precision::F32,
                ),
                24,
                1.2,
            ),
        },
        // The 16-cell table of blob-precision values (blobs written before the coded
        // table), f16.
        TestModel {
            name: "random_hv_value_table_f16".into(),
            blob: random_blob(
                &named(
                    ModelDef {
                        latent_table: Some(TableGrid::Values),
                        ..warped(iso(half_vector))
                    },
                    "random_hv_value_table_f16",
                    Precision::F16,
                ),
                25,
                1.2,
            ),
        },
        // Anisotropic and folded by a half turn (83), on the sphere, declared for the upper
        // hemisphere, f16 weights: no shipped model has this combination.
        TestModel {
            name: "random_sphere_aniso_upper_f16".into(),
            blob: random_blob(
                &named(
                    ModelDef {
                        fold: IncidentFold::HalfTurn,
                        ..upper(sphere)
                    },
                    "random_sphere_aniso_upper_f16",
                    Precision::F16,
                ),
                23,
                1.2,
            ),
        },
    ];
    models.extend(shipped_models());
    models
}

/// Every blob under `models/` (any file starting with the blob magic).
pub fn shipped_models() -> Vec<TestModel> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models");
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return out;
    };
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for p in paths {
        let Ok(bytes) = std::fs::read(&p) else {
            continue;
        };
        if bytes.starts_with(b"DIFFBSDF") {
            let name = p
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            out.push(TestModel { name, blob: bytes });
        }
    }
    out
}

/// The kernel's answers for one model (whichever compiled shape it has).
pub struct Kernel(Box<AnyModel>);

impl Kernel {
    pub fn load(blob: &[u8]) -> Kernel {
        Kernel(Box::new(AnyModel::from_blob(blob).expect("blob loads")))
    }
    /// The kernel holding the weights a shader reads: the blob's, rounded to f16 for f16
    /// output (`half`), as its parameter block holds them (docs/codegen.md). The f16 bounds
    /// then measure the f16 arithmetic, not the rounding of the weights.
    pub fn load_for(blob: &[u8], half: bool) -> Kernel {
        if !half {
            return Kernel::load(blob);
        }
        let model = AnyModel::from_blob(blob).expect("blob loads");
        let mut def = *model.def();
        def.precision = Precision::F16;
        let mut out = vec![0u8; blob_len(&def)];
        model
            .write_blob(Precision::F16, &mut out)
            .expect("f16 blob");
        Kernel::load(&out)
    }
    pub fn domain(&self) -> Domain {
        self.0.def().domain
    }
    pub fn default_steps(&self) -> u32 {
        self.0.def().default_steps as u32
    }
    pub fn direction(&self, wi: [f32; 3], u: [f32; 2], steps: u32) -> Option<[f32; 3]> {
        let (wi, u, s) = (Vec3::from(wi), Vec2::from(u), steps);
        self.0
            .sample_direction_steps(wi, u, s)
            .map(|v| v.to_array())
    }
    pub fn sample(&self, wi: [f32; 3], u: [f32; 2], steps: u32) -> Option<([f32; 3], f32)> {
        let (wi, u, s) = (Vec3::from(wi), Vec2::from(u), steps);
        self.0
            .sample_steps(wi, u, s)
            .map(|s| (s.wo.to_array(), s.pdf))
    }
    /// How much the sampling map `x0 -> wo` amplifies a perturbation of the flow's start
    /// point near `u` (finite differences along both `u` axes, 1e-3 and 1e-4 apart): rounding
    /// differences of order 1e-7 injected along the flow (the kernel's build contracts
    /// multiply-adds into FMAs, gcc and the shader compilers may not) reach the direction
    /// multiplied by about this much. 1 or less for gentle flows; large for the sharp lobes
    /// of trained models.
    pub fn amplification(&self, wi: [f32; 3], u: [f32; 2], steps: u32) -> f32 {
        let base = self.0.base_distribution(Vec3::from(wi));
        let (Some(base), Some(wo)) = (base, self.direction(wi, u, steps)) else {
            return 1.0;
        };
        let x0 = base.sample(u);
        let mut amp = 1.0f32;
        // Two spacings: where the base's quantile is steep (a wrapped Cauchy's far side,
        // near u = 0 or 1) 1e-3 in u is already a large, nonlinear move in x0.
        for (j, du) in [(0, 1e-3f32), (1, 1e-3), (0, 1e-4), (1, 1e-4)] {
            let mut v = u;
            v[j] = if u[j] > 0.5 { u[j] - du } else { u[j] + du };
            let x1 = base.sample(v);
            let dx = ((x1[0] - x0[0]).powi(2) + (x1[1] - x0[1]).powi(2)).sqrt();
            if let Some(w1) = self.direction(wi, v, steps) {
                let dw = (0..3).map(|i| (w1[i] - wo[i]).powi(2)).sum::<f32>().sqrt();
                if dx > 0.0 && (dw / dx).is_finite() {
                    amp = amp.max(dw / dx);
                }
            }
        }
        amp
    }

    /// `|d ln pdf / d angle|` at `wo` (per radian, largest over two tangent directions),
    /// by central differences through the kernel: the PDF of a given direction amplifies
    /// rounding differences of the inverse (libm's vs the C library's sin, cos, exp) by
    /// about this much, as [`measure_condition`] does for the measure alone.
    pub fn pdf_condition(&self, wi: [f32; 3], wo: [f32; 3], steps: u32) -> f32 {
        let w = Vec3::from(wo);
        let t1 = w.any_orthonormal_vector();
        let t2 = w.cross(t1);
        let delta = 1e-3f32;
        let ln = |v: Vec3| self.pdf(wi, v.normalize().to_array(), steps).ln();
        let mut c = 0.0f32;
        for t in [t1, t2] {
            let g = (ln(w + t * delta) - ln(w - t * delta)) / (2.0 * delta);
            if g.is_finite() {
                c = c.max(g.abs());
            }
        }
        c
    }

    pub fn pdf(&self, wi: [f32; 3], wo: [f32; 3], steps: u32) -> f32 {
        let (wi, wo, s) = (Vec3::from(wi), Vec3::from(wo), steps);
        self.0.pdf_steps(wi, wo, s)
    }
}

fn dir(theta: f32, phi: f32) -> [f32; 3] {
    [
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    ]
}

/// Incident directions: normal, a spread of angles, grazing (`z = 1e-3` and exactly 0),
/// and on the sphere the lower hemisphere too.
pub fn incident_directions(domain: Domain) -> Vec<[f32; 3]> {
    let half_pi = std::f32::consts::FRAC_PI_2;
    let mut v = vec![[0.0, 0.0, 1.0]];
    for (k, theta) in [0.3f32, 0.8, 1.2, 1.5, half_pi - 1e-3]
        .into_iter()
        .enumerate()
    {
        v.push(dir(theta, 0.7 + 1.9 * k as f32));
    }
    v.push([1.0, 0.0, 0.0]); // exactly grazing: z = 0
    if domain.is_spherical() {
        v.push(dir(2.0, -2.5));
        v.push(dir(std::f32::consts::PI - 0.1, 1.0));
        v.push([0.0, 0.0, -1.0]);
    }
    v
}

/// Whether a coordinate of `u` is at an end of [0, 1] (0, 1 - 2^-24 or 1): the base
/// distribution's extreme tails, where the networks run far outside what they were
/// trained on and the kernel itself amplifies rounding most.
pub fn u_at_edge(u: [f32; 2]) -> bool {
    u.iter().any(|&x| x <= 0.0 || x >= ONE_MINUS_EPS)
}

/// `(wi, u)` vectors: a grid of `u` with 0, 1/2, 1 - 2^-24 and 1 on each axis for every
/// incident direction, then invalid inputs (non-unit, zero, NaN and infinite `wi`, `u`
/// outside [0, 1] or NaN, and for disk models `wi` below the horizon).
pub fn sample_vectors(domain: Domain) -> Vec<([f32; 3], [f32; 2])> {
    let us = [0.0, 0.137, 0.5, 0.731, ONE_MINUS_EPS, 1.0];
    let mut v = Vec::new();
    for wi in incident_directions(domain) {
        for &a in &us {
            for &b in &us {
                v.push((wi, [a, b]));
            }
        }
    }
    let n = [0.0, 0.0, 1.0];
    let bad_wi = [
        [0.0, 0.0, 2.0],
        [0.0, 0.0, 0.0],
        [f32::NAN, 0.0, 1.0],
        [f32::INFINITY, 0.0, 0.0],
    ];
    for wi in bad_wi {
        v.push((wi, [0.5, 0.5]));
    }
    for u in [[-0.1, 0.5], [0.5, 1.5], [f32::NAN, 0.5]] {
        v.push((n, u));
    }
    v.push(([0.0, 0.6, -0.8], [0.5, 0.5])); // below the horizon (invalid on the disk)
    v.push(([0.0, 0.0, 1.0004], [0.3, 0.3])); // non-unit within tolerance: accepted
    v
}

/// `(wi, wo)` vectors: the kernel's own samples (so most PDFs are positive), a grid of
/// outgoing directions including grazing ones, the poles, below-horizon and non-unit `wo`.
pub fn pdf_vectors(kernel: &Kernel, samples: &[([f32; 3], [f32; 2])]) -> Vec<([f32; 3], [f32; 3])> {
    let mut v = Vec::new();
    for &(wi, u) in samples {
        if let Some(wo) = kernel.direction(wi, u, 0) {
            v.push((wi, wo));
        }
    }
    let wi = dir(0.6, 0.4);
    for theta in [
        0.05f32,
        0.5,
        1.0,
        1.45,
        std::f32::consts::FRAC_PI_2 - 1e-3,
        2.2,
    ] {
        for phi in [-3.0f32, -1.0, 0.0, 1.3, 3.1] {
            v.push((wi, dir(theta, phi)));
        }
    }
    v.push((wi, [0.0, 0.0, 1.0]));
    v.push((wi, [0.0, 0.0, -1.0]));
    v.push((wi, [1.0, 0.0, 0.0]));
    v.push((wi, [0.0, 0.0, 0.5]));
    v.push((wi, [f32::NAN, 0.0, 1.0]));
    v.push(([0.0, 0.0, 3.0], [0.0, 0.0, 1.0]));
    v
}

/// Largest error seen by a comparison, and every vector past its own allowance. The
/// comparisons record; [`Errors::assert_allowances`] (also called by
/// [`Errors::assert_raw_bounds`]) fails on them, after a whole run has been reported.
#[derive(Default, Debug, Clone)]
pub struct Errors {
    pub max_dir: f32,
    /// Largest PDF error relative to the PDF, divided by its allowance's scale
    /// (`max(1, |ln pdf|)` plus the condition of the measure and of the inverse).
    pub max_pdf_rel: f32,
    /// Largest PDF error relative to the PDF, as is.
    pub max_pdf_raw: f32,
    pub compared: usize,
    /// Comparisons where the kernel's answer was a valid sample or a positive PDF.
    pub valid: usize,
    /// Comparisons past their allowance (or whose validity differs from the kernel's).
    pub over: usize,
    /// The largest error over its allowance (infinite for a validity difference), and the
    /// vector it was seen on.
    pub worst: Option<(f32, String)>,
}

/// Bounds on the raw errors over a whole conformance run (every model, step count and
/// vector), on top of the per-vector allowances: the largest absolute direction error and
/// the largest `|pdf - pdf_kernel| / pdf_kernel`, not divided by any condition number. The
/// maxima sit at vectors where the kernel itself amplifies rounding (grazing `wi`, `u` at
/// the ends of [0, 1], sharply compressing random models); docs/codegen.md lists them.
pub const RAW_DIR_F32: f32 = 2e-3;
/// See [`RAW_DIR_F32`].
pub const RAW_PDF_F32: f32 = 2e-2;
/// f16 networks (about 3 decimal digits), on every vector whose `u` is inside (0, 1) (not
/// [`u_at_edge`]): a direction within 0.1 of the kernel's, a PDF within a factor 3
/// (measured 0.065 and 1.94 on lavapipe, both on the iridescent paint's sphere model,
/// whose map compresses more than 300x at grazing `wi`; docs/codegen.md).
pub const RAW_DIR_F16: f32 = 0.1;
/// See [`RAW_DIR_F16`].
pub const RAW_PDF_F16: f32 = 2.0;
/// [`RAW_PDF_F16`] on a hardware driver (`DIFFBSDF_GPU_ADAPTER`), whose f16 arithmetic
/// rounds otherwise than lavapipe's: a factor 4 (measured 2.49 on an NVIDIA H200).
pub const RAW_PDF_F16_HARDWARE: f32 = 3.0;
/// f16 networks at the ends of [0, 1] ([`u_at_edge`]: the base distribution's extreme
/// tails): a direction within 1 of the kernel's (measured 0.69 on lavapipe, 0.66 on an NVIDIA H200); the PDF there is held to
/// each vector's own allowance only (its raw error is reported: docs/codegen.md).
pub const RAW_DIR_F16_EDGE: f32 = 1.0;

impl Errors {
    /// Records a comparison past its allowance (`ratio` = error / allowance).
    fn record_over(&mut self, ratio: f32, message: String) {
        self.over += 1;
        if self.worst.as_ref().is_none_or(|(r, _)| ratio > *r) {
            self.worst = Some((ratio, message));
        }
    }

    /// Asserts that every comparison was within its own allowance.
    pub fn assert_allowances(&self, label: &str) {
        if let Some((ratio, message)) = &self.worst {
            panic!(
                "{label}: {} of {} comparisons past their allowance; the worst ({ratio:.3}x): {message}",
                self.over, self.compared
            );
        }
    }

    /// Asserts bounds on the raw errors of a whole run: the largest direction error and the
    /// largest raw relative PDF error (`None`: reported, not bounded); and, first, that
    /// every comparison was within its own allowance.
    pub fn assert_raw_bounds(&self, label: &str, dir: f32, pdf: Option<f32>) {
        self.assert_allowances(label);
        assert!(
            self.max_dir <= dir,
            "{label}: largest direction error {:e} > {dir:e}",
            self.max_dir
        );
        if let Some(pdf) = pdf {
            assert!(
                self.max_pdf_raw <= pdf,
                "{label}: largest raw relative PDF error {:e} > {pdf:e}",
                self.max_pdf_raw
            );
        }
    }

    /// Adds another run's comparisons (largest errors, counts).
    pub fn merge(&mut self, e: &Errors) {
        self.max_dir = self.max_dir.max(e.max_dir);
        self.max_pdf_rel = self.max_pdf_rel.max(e.max_pdf_rel);
        self.max_pdf_raw = self.max_pdf_raw.max(e.max_pdf_raw);
        self.compared += e.compared;
        self.valid += e.valid;
        if let Some((ratio, message)) = &e.worst {
            self.record_over(*ratio, message.clone());
            self.over += e.over - 1;
        }
    }
}

/// Compares an optional direction (`None` written as zeros) with the kernel's.
pub fn check_dir(what: &str, got: [f32; 3], want: Option<[f32; 3]>, tol: f32, e: &mut Errors) {
    e.compared += 1;
    match want {
        None if got != [0.0; 3] => e.record_over(
            f32::INFINITY,
            format!("{what}: kernel says invalid, got {got:?}"),
        ),
        None => {}
        Some(w) => {
            e.valid += 1;
            let d = (0..3).map(|i| (got[i] - w[i]).abs()).fold(0.0f32, f32::max);
            e.max_dir = e.max_dir.max(d);
            // NaN is past any allowance.
            let within = d <= tol;
            if !within {
                e.record_over(
                    d / tol,
                    format!(
                        "{what}: direction {got:?} vs kernel {w:?}: error {d:e} > allowed {tol:e}"
                    ),
                );
            }
        }
    }
}

/// Compares a PDF with the kernel's (`0` for invalid on both sides). The relative error
/// allowed is `tol * max(1, |ln want|)`: a density is `exp` of a sum of terms of the size
/// of `ln want`, whose f32 rounding (and FMA contraction in the kernel build) scales with
/// them; for PDFs between 1/e and e this is exactly `tol`.
///
/// `measure` is [`measure_condition`] of the direction: `pdf_w = pdf_x / sin(theta)` on
/// the sphere and `pdf_x cos(theta)` on the disk are ill-conditioned at the poles and the
/// horizon, where a direction error far below 1e-5 moves the density by much more.
pub fn check_pdf(what: &str, got: f32, want: f32, measure: f32, tol: f32, e: &mut Errors) {
    e.compared += 1;
    if want == 0.0 {
        if got != 0.0 {
            e.record_over(f32::INFINITY, format!("{what}: kernel PDF 0, got {got:e}"));
        }
        return;
    }
    if want < f32::MIN_POSITIVE && (0.0..f32::MIN_POSITIVE).contains(&got) {
        // A subnormal density: GPUs may flush it to zero (Vulkan allows it), and it is
        // zero for every practical purpose. Where only one side is subnormal the two are
        // compared as any other PDFs (an f16 network's answer may round across the edge).
        return;
    }
    e.valid += 1;
    let scale = want.ln().abs().max(1.0) + measure;
    let r = (got - want).abs() / want.abs();
    e.max_pdf_rel = e.max_pdf_rel.max(r / scale);
    e.max_pdf_raw = e.max_pdf_raw.max(r);
    let tol = tol * scale;
    let within = r <= tol;
    if !within {
        e.record_over(
            r / tol,
            format!(
                "{what}: PDF {got:e} vs kernel {want:e}: relative error {r:e} > allowed {tol:e}"
            ),
        );
    }
}

/// `|d ln(pdf_w / pdf_x) / d theta|` at `wo` for incident `wi`: `|cot theta|` on the
/// sphere, `tan theta` on the disk, `tan theta_h + tan theta_d` on the half-vector chart
/// (`h` the half vector, `theta_d` the angle between `wi` and `h`; the measure is
/// `h.z / (4 wi.h)`), 0 when `wo` is not a direction.
pub fn measure_condition(domain: Domain, wi: [f32; 3], wo: [f32; 3]) -> f32 {
    let rho = (wo[0] * wo[0] + wo[1] * wo[1]).sqrt();
    let z = wo[2].abs();
    let c = match domain {
        Domain::Sphere => z / rho,
        Domain::Disk => rho / z,
        // The chart's theta is measured from the y axis.
        Domain::Equatorial => wo[1].abs() / (wo[0] * wo[0] + wo[2] * wo[2]).sqrt(),
        Domain::HalfVector => {
            let s = [wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]];
            let len = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
            let h = [s[0] / len, s[1] / len, s[2] / len];
            let cd = wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2];
            (h[0] * h[0] + h[1] * h[1]).sqrt() / h[2].abs() + (1.0 - cd * cd).max(0.0).sqrt() / cd
        }
    };
    if c.is_finite() {
        c
    } else {
        0.0
    }
}

/// Writes little-endian f32s.
pub fn write_f32s(path: &Path, data: &[f32]) {
    let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
    std::fs::write(path, bytes).expect("write test vectors");
}

/// Reads little-endian f32s.
pub fn read_f32s(path: &Path) -> Vec<f32> {
    let bytes = std::fs::read(path).expect("read results");
    bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// A fresh scratch directory under cargo's per-target temp dir (tests), or the system's
/// temp dir (examples, for which cargo sets none).
pub fn scratch(name: &str) -> PathBuf {
    let root = option_env!("CARGO_TARGET_TMPDIR").map_or_else(std::env::temp_dir, PathBuf::from);
    let d = root.join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch dir");
    d
}

/// The strict C flags of the issue.
pub const C_FLAGS: [&str; 5] = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"];

/// Runs a tool; fails the test with what to install if it is missing, and with its output
/// if it fails.
pub fn run_tool(cmd: &mut Command, install_hint: &str) -> String {
    let out = match cmd.output() {
        Ok(o) => o,
        Err(e) => panic!(
            "cannot run {:?} ({e}): install it with `{install_hint}`",
            cmd.get_program()
        ),
    };
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.status.success(),
        "{cmd:?} failed ({}):\n{text}",
        out.status
    );
    text
}

pub const GCC_HINT: &str = "apt-get install -y gcc g++";
