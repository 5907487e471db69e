//! Structure-aware fuzzing of the blob loader, behind the checksum.
//!
//! Starts from valid blobs (the shipped `models/*.dbsdf`, f32 and f16, and small random
//! ones written with `write_blob`), applies stacked mutations that know the layout of
//! `docs/blob-format.md` (bit flips, interesting bytes, header fields set to edge values,
//! special weights, truncation, extension, splicing, resizing the body to a new parameter
//! count), and rewrites the CRC-32 of most inputs so that the mutation reaches the header,
//! shape and weight checks. Every input goes to `Model3x32::from_blob`,
//! `Model4x32::from_blob`, `AnyModel::from_blob` and `load_into`; every input that loads is
//! sampled and evaluated at valid and invalid `wi`, `u` and step counts.
//!
//! Checked: no panic; the four loaders agree with `Blob::parse`; an error leaves the model
//! of `load_into` unchanged; no NaN/Inf output (PDF finite and >= 0, `wo` finite and
//! unit); invalid arguments give no sample and PDF 0.
//!
//! `DIFFBSDF_FUZZ_INPUTS` sets the number of inputs (default 16 000, 15-25 s in release
//! on 2 cores), `DIFFBSDF_FUZZ_SEED` the seed. Input `i` depends only on the seed and `i`;
//! a failing input is written to `target/tmp/` and its index printed.

#[path = "support/fuzz_driver.rs"]
mod fuzz_driver;
mod support;

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::internals::blob::{blob_len, crc32, write_blob, Blob, CHECKSUM_LEN, HEADER_LEN};
use diffbsdf::{
    spec, AnyModel, BlobError, Domain, Model3x32, Model4x32, ModelDef, ModelName, Precision, Sample,
};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

const DEFAULT_INPUTS: usize = 16_000;
const DEFAULT_SEED: u64 = 0x00DB_5DF0;

/// SplitMix64: std only, and every input is a function of (seed, index).
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        let mut r = Rng(seed ^ 0x9E37_79B9_7F4A_7C15);
        r.next_u64();
        r
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (`n > 0`).
    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }

    fn chance(&mut self, p: f32) -> bool {
        self.uniform() < p
    }

    /// Uniform in [0, 1).
    fn uniform(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

// ---------------------------------------------------------------------------------------
// Corpus
// ---------------------------------------------------------------------------------------

/// A valid blob of `def` with random weights of magnitude up to `scale`.
fn random_blob(def: &ModelDef, rng: &mut Rng, scale: f32) -> Vec<u8> {
    let params: Vec<f32> = (0..def.param_count())
        .map(|_| (2.0 * rng.uniform() - 1.0) * scale)
        .collect();
    let mut out = vec![0u8; blob_len(def)];
    let n = write_blob(def, &params, &mut out).expect("a valid random blob");
    assert_eq!(n, out.len());
    out
}

/// The shipped models and small random blobs: both compiled shapes on both domains,
/// both precisions, isotropic or not, and shapes no compiled type accepts.
fn corpus() -> Vec<(String, Vec<u8>)> {
    let mut out = support::shipped_blobs();
    let mut rng = Rng::new(7);
    let mut k = 0;
    for base in [ModelDef::paper_disk(), ModelDef::paper_sphere()] {
        for domain in [Domain::Disk, Domain::Sphere, Domain::Equatorial] {
            for precision in [Precision::F32, Precision::F16] {
                for isotropic in [false, true] {
                    let mut def = base;
                    def.domain = domain;
                    def.precision = precision;
                    def.isotropic = isotropic;
                    def.default_steps = 1 + rng.below(8) as u16;
                    def.name = ModelName::new(&format!("fuzz-{k}")).unwrap();
                    let scale = [0.3, 1.0, 3.0][k % 3];
                    out.push((format!("random-{k}"), random_blob(&def, &mut rng, scale)));
                    k += 1;
                }
            }
        }
    }
    // Valid blobs of other shapes: parse, but no compiled model accepts them.
    for (bw, bl, vf, vw, vl) in [(4, 1, 1, 4, 1), (16, 2, 5, 32, 3), (8, 1, 0, 2, 2)] {
        let mut def = ModelDef::paper_disk();
        def.base.width = bw;
        def.base.hidden_layers = bl;
        def.base.freqs = def.base.freqs.min(vf);
        def.velocity.freqs = vf;
        def.velocity.width = vw;
        def.velocity.hidden_layers = vl;
        def.default_steps = spec::MAX_STEPS as u16;
        out.push((format!("other-shape-{k}"), random_blob(&def, &mut rng, 1.0)));
        k += 1;
    }
    for (name, b) in &out {
        Blob::parse(b).unwrap_or_else(|e| panic!("corpus blob {name} is invalid: {e}"));
    }
    out
}

// ---------------------------------------------------------------------------------------
// Mutations
// ---------------------------------------------------------------------------------------

/// Header fields after the version: (offset, size in bytes).
const FIELDS: [(usize, usize); 14] = [
    (10, 1), // domain
    (11, 1), // precision
    (12, 1), // activation
    (13, 1), // base freqs
    (14, 2), // base width
    (16, 1), // base layers
    (17, 1), // velocity freqs
    (18, 2), // velocity width
    (20, 1), // velocity layers
    (21, 1), // name length
    (22, 2), // default steps
    (24, 4), // parameter count
    (28, 4), // flags
    (8, 2),  // version
];

const INTERESTING_BYTES: [u8; 5] = [0, 1, 0x7f, 0x80, 0xff];

fn field_value(rng: &mut Rng, size: usize) -> u64 {
    let max = if size == 8 {
        u64::MAX
    } else {
        (1u64 << (8 * size)) - 1
    };
    let edges = [
        0,
        1,
        2,
        3,
        4,
        5,
        8,
        16,
        17,
        32,
        33,
        u64::from(spec::MAX_STEPS),
        u64::from(spec::MAX_STEPS) + 1,
        u64::from(spec::MAX_WIDTH),
        u64::from(spec::MAX_WIDTH) + 1,
        3782,
        4870,
        max,
        max - 1,
        max / 2,
        max / 2 + 1,
    ];
    match rng.below(3) {
        0 => *rng.pick(&edges) & max,
        1 => rng.next_u64() & max,
        _ => rng.below(40) as u64,
    }
}

fn set_le(bytes: &mut [u8], offset: usize, size: usize, value: u64) {
    if let Some(dst) = bytes.get_mut(offset..offset + size) {
        dst.copy_from_slice(&value.to_le_bytes()[..size]);
    }
}

fn get_le(bytes: &[u8], offset: usize, size: usize) -> Option<u64> {
    let src = bytes.get(offset..offset + size)?;
    let mut b = [0u8; 8];
    b[..size].copy_from_slice(src);
    Some(u64::from_le_bytes(b))
}

/// Bytes per stored weight as the header says (4 for an unknown code).
fn weight_size(bytes: &[u8]) -> usize {
    if bytes.get(11) == Some(&1) {
        2
    } else {
        4
    }
}

const SPECIAL_F32: [f32; 14] = [
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::MAX,
    f32::MIN,
    1e30,
    -1e30,
    1e10,
    -1e10,
    1e-45,
    f32::MIN_POSITIVE,
    0.0,
    -0.0,
    65504.0,
];
const SPECIAL_F16: [u16; 10] = [
    0x7e00, 0x7c00, 0xfc00, 0x7bff, 0xfbff, 0x0001, 0x8000, 0x0000, 0x7a00, 0xfa00,
];

/// Resizes the weight region to `params` weights and writes the count into the header,
/// keeping the length consistent so the input gets past the length checks.
fn resize_body(b: &mut Vec<u8>, params: usize, rng: &mut Rng) {
    let s = weight_size(b);
    b.truncate(HEADER_LEN.min(b.len()));
    b.resize(HEADER_LEN, 0);
    set_le(b, 24, 4, params as u64);
    for _ in 0..params * s {
        b.push(if rng.chance(0.9) {
            0x3c
        } else {
            rng.next_u64() as u8
        });
    }
    b.extend_from_slice(&[0; CHECKSUM_LEN]);
}

fn mutate(b: &mut Vec<u8>, corpus: &[(String, Vec<u8>)], rng: &mut Rng, log: &mut Vec<String>) {
    let len = b.len();
    // Length-changing mutations (truncate, extend, splice) are a sixth of the draws.
    let mut kind = rng.below(15);
    if kind >= 12 {
        kind = *rng.pick(&[0, 1, 4]);
    }
    match kind {
        0 => {
            let at = if rng.chance(0.5) {
                rng.below(HEADER_LEN.min(len).max(1))
            } else {
                rng.below(len.max(1))
            };
            let bit = rng.below(8);
            if let Some(x) = b.get_mut(at) {
                *x ^= 1 << bit;
            }
            log.push(format!("flip byte {at} bit {bit}"));
        }
        1 => {
            let at = if rng.chance(0.6) {
                rng.below(HEADER_LEN)
            } else {
                rng.below(len.max(1))
            };
            let v = *rng.pick(&INTERESTING_BYTES);
            if let Some(x) = b.get_mut(at) {
                *x = v;
            }
            log.push(format!("byte {at} = {v:#x}"));
        }
        2 | 3 => {
            let (offset, size) = *rng.pick(&FIELDS);
            let v = field_value(rng, size);
            set_le(b, offset, size, v);
            log.push(format!("field at {offset} ({size} bytes) = {v}"));
        }
        4 => {
            let s = weight_size(b);
            let n = len.saturating_sub(HEADER_LEN + CHECKSUM_LEN) / s;
            if n > 0 {
                let i = rng.below(n);
                let at = HEADER_LEN + i * s;
                if s == 4 {
                    let v = *rng.pick(&SPECIAL_F32);
                    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
                    log.push(format!("weight {i} = {v:e} (f32)"));
                } else {
                    let v = *rng.pick(&SPECIAL_F16);
                    b[at..at + 2].copy_from_slice(&v.to_le_bytes());
                    log.push(format!("weight {i} = {v:#06x} (f16)"));
                }
            }
        }
        5 => {
            // Scale every weight (finite but huge values reach the nets).
            let s = weight_size(b);
            let k = *rng.pick(&[8.0f32, 1e3, 1e6, 1e20, -1.0, 0.0]);
            let end = len.saturating_sub(CHECKSUM_LEN);
            let mut at = HEADER_LEN;
            while at + s <= end {
                if s == 4 {
                    let w = f32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]]) * k;
                    b[at..at + 4].copy_from_slice(&w.to_le_bytes());
                } else {
                    let w = half::f16::from_bits(u16::from_le_bytes([b[at], b[at + 1]]));
                    let w = half::f16::from_f32(w.to_f32() * k);
                    b[at..at + 2].copy_from_slice(&w.to_bits().to_le_bytes());
                }
                at += s;
            }
            log.push(format!("all weights * {k:e}"));
        }
        6 => {
            let to = if rng.chance(0.5) {
                rng.below(HEADER_LEN + 8)
            } else {
                rng.below(len.max(1))
            };
            b.truncate(to);
            log.push(format!("truncate to {to}"));
        }
        7 => {
            let n = 1 + rng.below(64);
            let zero = rng.chance(0.5);
            for _ in 0..n {
                b.push(if zero { 0 } else { rng.next_u64() as u8 });
            }
            log.push(format!(
                "extend by {n} ({})",
                if zero { "zeros" } else { "random" }
            ));
        }
        8 => {
            let (name, other) = rng.pick(corpus);
            if rng.chance(0.5) {
                // Header of this blob, body of the other.
                let body = other.get(HEADER_LEN..).unwrap_or(&[]);
                b.truncate(HEADER_LEN.min(b.len()));
                b.extend_from_slice(body);
                log.push(format!("body of {name}"));
            } else {
                let k = rng.below(len.max(1));
                b.truncate(k);
                b.extend_from_slice(other.get(k..).unwrap_or(&[]));
                log.push(format!("splice {name} from {k}"));
            }
        }
        9 => {
            // The header's count may already be mutated: stay below 64 Ki weights.
            let declared = (get_le(b, 24, 4).unwrap_or(0) as usize).min(1 << 16);
            let params = match rng.below(4) {
                0 => declared.saturating_sub(1 + rng.below(4)),
                1 => declared + 1 + rng.below(4),
                2 => *rng.pick(&[0, 1, 3782, 4870, 3782 + 32 * 33]),
                _ => rng.below(6000),
            };
            resize_body(b, params, rng);
            log.push(format!("resize body to {params} weights"));
        }
        10 => {
            // Another precision, with the body resized to stay consistent.
            if b.len() >= HEADER_LEN {
                let code = *rng.pick(&[0u8, 1, 2, 0xff]);
                b[11] = code;
                let declared = get_le(b, 24, 4).unwrap_or(0) as usize;
                if declared <= 1 << 16 {
                    resize_body(b, declared, rng);
                }
                log.push(format!("precision code {code}, body resized"));
            }
        }
        _ => {
            let at = rng.below(len.max(1));
            let n = 1 + rng.below(16);
            for i in at..(at + n).min(b.len()) {
                b[i] = rng.next_u64() as u8;
            }
            log.push(format!("random run of {n} at {at}"));
        }
    }
}

fn reseal(b: &mut [u8]) {
    if b.len() >= CHECKSUM_LEN {
        let n = b.len() - CHECKSUM_LEN;
        let crc = crc32(&b[..n]);
        b[n..].copy_from_slice(&crc.to_le_bytes());
    }
}

/// Input `index`: a corpus blob, 1 to 4 stacked mutations, usually resealed.
fn make_input(seed: u64, index: usize, corpus: &[(String, Vec<u8>)]) -> (Vec<u8>, Vec<String>) {
    let mut rng = Rng::new(seed ^ (index as u64).wrapping_mul(0xA24B_AED4_963E_E407));
    let (name, start) = rng.pick(corpus);
    let mut b = start.clone();
    let mut log = vec![format!("start {name}")];
    // Mostly one mutation (it reaches deeper checks), up to four stacked.
    let n = if rng.chance(0.5) { 1 } else { 2 + rng.below(3) };
    for _ in 0..n {
        mutate(&mut b, corpus, &mut rng, &mut log);
    }
    if rng.chance(0.92) {
        reseal(&mut b);
        log.push("resealed".into());
    }
    (b, log)
}

// ---------------------------------------------------------------------------------------
// Checks
// ---------------------------------------------------------------------------------------

#[derive(Default)]
struct Counts {
    inputs: AtomicUsize,
    past_checksum: AtomicUsize,
    loaded: AtomicUsize,
    loaded_3x32: AtomicUsize,
    loaded_4x32: AtomicUsize,
    calls: AtomicUsize,
    /// Inputs per outcome (`BlobError` variant or "loaded" / "shape mismatch").
    outcomes: Mutex<std::collections::BTreeMap<&'static str, usize>>,
}

fn outcome(r: &Result<AnyModel, BlobError>) -> &'static str {
    match r {
        Ok(_) => "loaded",
        Err(BlobError::BadMagic) => "BadMagic",
        Err(BlobError::UnsupportedVersion(_)) => "UnsupportedVersion",
        Err(BlobError::Truncated { .. }) => "Truncated",
        Err(BlobError::TrailingBytes { .. }) => "TrailingBytes",
        Err(BlobError::UnknownPrecision(_)) => "UnknownPrecision",
        Err(BlobError::ChecksumMismatch { .. }) => "ChecksumMismatch",
        Err(BlobError::UnknownDomain(_)) => "UnknownDomain",
        Err(BlobError::UnknownActivation(_)) => "UnknownActivation",
        Err(BlobError::BadHeader(_)) => "BadHeader",
        Err(BlobError::ParamCountMismatch { .. }) => "ParamCountMismatch",
        Err(BlobError::NonFiniteWeight { .. }) => "NonFiniteWeight",
        Err(BlobError::ShapeMismatch) => "ShapeMismatch",
        Err(_) => "other",
    }
}

fn before_checksum(e: &BlobError) -> bool {
    matches!(
        e,
        BlobError::BadMagic
            | BlobError::UnsupportedVersion(_)
            | BlobError::Truncated { .. }
            | BlobError::TrailingBytes { .. }
            | BlobError::UnknownPrecision(_)
            | BlobError::ChecksumMismatch { .. }
    )
}

fn unit(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z).normalize()
}

/// Incident directions the contract calls invalid on every model: no sample, PDF 0.
fn invalid_wi() -> [Vec3; 6] {
    [
        Vec3::new(f32::NAN, 0.0, 1.0),
        Vec3::new(0.0, f32::INFINITY, 1.0),
        Vec3::ZERO,
        Vec3::new(0.0, 0.0, 2.0),
        Vec3::new(0.3, 0.0, 0.5),
        Vec3::new(0.0, 0.0, f32::NEG_INFINITY),
    ]
}

/// Unit incident directions: normal, oblique, grazing, below the surface (valid for some
/// sphere models, otherwise no sample), and unit within the tolerance.
fn valid_wi() -> [Vec3; 8] {
    [
        Vec3::Z,
        Vec3::new(0.3, 0.0, 0.953_939_2),
        unit(0.6, -0.8, 0.3),
        unit(1.0, 0.0, 1e-6),
        Vec3::X,
        unit(0.3, 0.2, -0.9),
        -Vec3::Z,
        Vec3::new(0.0, 0.0, 1.000_4),
    ]
}

const INVALID_U: [Vec2; 5] = [
    Vec2::new(-0.1, 0.5),
    Vec2::new(0.5, 1.5),
    Vec2::new(f32::NAN, 0.5),
    Vec2::new(0.5, f32::INFINITY),
    Vec2::new(-1e-3, -1e-3),
];
const VALID_U: [Vec2; 6] = [
    Vec2::new(0.5, 0.5),
    Vec2::new(0.0, 0.0),
    Vec2::new(1.0, 1.0),
    Vec2::new(1e-30, 1.0 - 6e-8),
    Vec2::new(0.25, 0.75),
    Vec2::new(0.999, 0.001),
];

fn check_sample(s: Option<Sample>, what: &str) {
    if let Some(s) = s {
        assert!(
            s.wo.is_finite() && (s.wo.length() - 1.0).abs() < 1e-3,
            "{what}: wo {:?}",
            s.wo
        );
        assert!(s.pdf.is_finite() && s.pdf >= 0.0, "{what}: pdf {}", s.pdf);
    }
}

fn check_dir(d: Option<Vec3>, what: &str) {
    if let Some(wo) = d {
        assert!(
            wo.is_finite() && (wo.length() - 1.0).abs() < 1e-3,
            "{what}: wo {wo:?}"
        );
    }
}

fn check_pdf(p: f32, what: &str) {
    assert!(p.is_finite() && p >= 0.0, "{what}: pdf {p}");
}

/// Samples and evaluates a loaded model at valid and invalid arguments.
fn exercise(m: &AnyModel, rng: &mut Rng, counts: &Counts) {
    let mut calls = 0;
    let too_many = spec::MAX_STEPS + 1;
    let mut steps = vec![0, 1, *rng.pick(&[2, 3, 4, 8, 16])];
    if rng.chance(1.0 / 64.0) {
        steps.push(spec::MAX_STEPS);
    }
    let random_wi = unit(
        2.0 * rng.uniform() - 1.0,
        2.0 * rng.uniform() - 1.0,
        2.0 * rng.uniform() - 1.0 + 1e-3,
    );
    let wis = [*rng.pick(&valid_wi()), *rng.pick(&valid_wi()), random_wi];
    for wi in wis {
        let us = [*rng.pick(&VALID_U), Vec2::new(rng.uniform(), rng.uniform())];
        for &s in &steps {
            for u in us {
                let what = format!("wi {wi:?} u {u:?} steps {s}");
                let d = m.sample_direction_steps(wi, u, s);
                check_dir(d, &what);
                let smp = m.sample_steps(wi, u, s);
                check_sample(smp, &what);
                calls += 2;
                if let Some(smp) = smp {
                    check_pdf(m.pdf_steps(wi, smp.wo, s), &what);
                    calls += 1;
                }
            }
            for wo in [random_wi, -wi, Vec3::Z] {
                check_pdf(m.pdf_steps(wi, wo, s), &format!("pdf wi {wi:?} wo {wo:?}"));
                calls += 1;
            }
        }
        // Steps above spec::MAX_STEPS: nothing.
        let u = Vec2::new(0.5, 0.5);
        assert_eq!(m.sample_direction_steps(wi, u, too_many), None);
        assert_eq!(m.sample_steps(wi, u, too_many), None);
        assert_eq!(m.pdf_steps(wi, Vec3::Z, too_many), 0.0);
        assert_eq!(m.sample_steps(wi, u, u32::MAX), None);
        // u outside [0, 1]^2: nothing.
        let bad_u = *rng.pick(&INVALID_U);
        assert_eq!(m.sample_direction(wi, bad_u), None, "u {bad_u:?}");
        assert_eq!(m.sample(wi, bad_u), None, "u {bad_u:?}");
        // An invalid wo: PDF 0.
        let bad = *rng.pick(&invalid_wi());
        assert_eq!(m.pdf(wi, bad), 0.0, "wo {bad:?}");
        calls += 7;
    }
    // Invalid wi: nothing, PDF 0.
    let bad = *rng.pick(&invalid_wi());
    let u = *rng.pick(&VALID_U);
    assert_eq!(m.sample_direction(bad, u), None, "wi {bad:?}");
    assert_eq!(m.sample(bad, u), None, "wi {bad:?}");
    assert_eq!(m.pdf(bad, Vec3::Z), 0.0, "wi {bad:?}");
    // Batch forms: the same rules on each element.
    let wi = [wis[0], bad, wis[2]];
    let uu = [u, Vec2::new(0.3, 0.6), *rng.pick(&INVALID_U)];
    let mut out = [Sample {
        wo: Vec3::ONE,
        pdf: -1.0,
    }; 3];
    m.sample_batch(&wi, &uu, 0, &mut out).unwrap();
    for s in out {
        // An invalid element is written as wo = 0, pdf = 0.
        if s.wo != Vec3::ZERO || s.pdf != 0.0 {
            check_sample(Some(s), "batch");
        }
    }
    let mut pdfs = [-1.0f32; 3];
    m.pdf_batch(&wi, &[Vec3::Z, Vec3::Z, random_wi], 0, &mut pdfs)
        .unwrap();
    for p in pdfs {
        check_pdf(p, "pdf batch");
    }
    calls += 9;
    counts.calls.fetch_add(calls, Ordering::Relaxed);
}

fn check_input(bytes: &[u8], index: usize, seed: u64, counts: &Counts) {
    let parsed = Blob::parse(bytes).map(|b| b.def);
    let r3 = Model3x32::from_blob(bytes);
    let r4 = Model4x32::from_blob(bytes);
    let ra = AnyModel::from_blob(bytes);
    counts.inputs.fetch_add(1, Ordering::Relaxed);
    *counts
        .outcomes
        .lock()
        .unwrap()
        .entry(outcome(&ra))
        .or_default() += 1;
    match &parsed {
        Err(e) => {
            assert_eq!(r3.as_ref().err(), Some(e));
            assert_eq!(r4.as_ref().err(), Some(e));
            assert_eq!(ra.as_ref().err(), Some(e));
            if !before_checksum(e) {
                counts.past_checksum.fetch_add(1, Ordering::Relaxed);
            }
        }
        Ok(def) => {
            counts.past_checksum.fetch_add(1, Ordering::Relaxed);
            for r in [r3.as_ref().err(), r4.as_ref().err(), ra.as_ref().err()] {
                assert!(matches!(r, None | Some(BlobError::ShapeMismatch)), "{r:?}");
            }
            assert!(!(r3.is_ok() && r4.is_ok()), "two shapes accepted one blob");
            assert_eq!(ra.is_ok(), r3.is_ok() || r4.is_ok());
            if let Ok(m) = &r3 {
                assert_eq!(m.def(), def);
                assert!(ra.as_ref().ok() == Some(&AnyModel::Velocity3x32(*m)));
            }
            if let Ok(m) = &r4 {
                assert_eq!(m.def(), def);
                assert!(ra.as_ref().ok() == Some(&AnyModel::Velocity4x32(*m)));
            }
        }
    }
    // load_into: the same result, and an error keeps the model bit for bit.
    let mut rng = Rng::new(seed ^ 0x5EED ^ (index as u64).wrapping_mul(0x9FB2_1C65_1E98_DF25));
    let (before3, before4) = baselines();
    let mut m3 = *before3;
    match (m3.load_into(bytes), &r3) {
        (Ok(()), Ok(m)) => assert!(m3 == *m, "load_into and from_blob differ"),
        (Err(e), Err(f)) => {
            assert_eq!(&e, f);
            assert!(&m3 == before3, "load_into changed the model on {e:?}");
        }
        (got, want) => panic!("load_into {got:?} but from_blob {:?}", want.as_ref().err()),
    }
    let mut m4 = *before4;
    match (m4.load_into(bytes), &r4) {
        (Ok(()), Ok(m)) => assert!(m4 == *m, "load_into and from_blob differ"),
        (Err(e), Err(f)) => {
            assert_eq!(&e, f);
            assert!(&m4 == before4, "load_into changed the model on {e:?}");
        }
        (got, want) => panic!("load_into {got:?} but from_blob {:?}", want.as_ref().err()),
    }
    if let Ok(m) = &ra {
        counts.loaded.fetch_add(1, Ordering::Relaxed);
        match m {
            AnyModel::Velocity3x32(_) => counts.loaded_3x32.fetch_add(1, Ordering::Relaxed),
            AnyModel::Velocity4x32(_) => counts.loaded_4x32.fetch_add(1, Ordering::Relaxed),
        };
        exercise(m, &mut rng, counts);
    }
}

/// Models that `load_into` starts from (distinct from every corpus blob).
fn baselines() -> &'static (Model3x32, Model4x32) {
    static B: std::sync::OnceLock<(Model3x32, Model4x32)> = std::sync::OnceLock::new();
    B.get_or_init(|| {
        let mut rng = Rng::new(99);
        let d = ModelDef::paper_disk();
        let s = ModelDef::paper_sphere();
        let p3: Vec<f32> = (0..d.param_count()).map(|_| rng.uniform() - 0.5).collect();
        let p4: Vec<f32> = (0..s.param_count()).map(|_| rng.uniform() - 0.5).collect();
        (
            Model3x32::from_params(d, &p3).unwrap(),
            Model4x32::from_params(s, &p4).unwrap(),
        )
    })
}

#[test]
fn mutated_blobs_never_panic_and_loaded_models_stay_finite() {
    let (inputs, seed) = fuzz_driver::inputs_and_seed(DEFAULT_INPUTS, DEFAULT_SEED);
    let corpus = corpus();
    let counts = Counts::default();
    let (threads, secs) = fuzz_driver::run(
        "fuzz_blob",
        "dbsdf",
        env!("CARGO_TARGET_TMPDIR"),
        seed,
        inputs,
        |index| make_input(seed, index, &corpus),
        |bytes, index| check_input(bytes, index, seed, &counts),
    );
    let n = counts.inputs.load(Ordering::Relaxed);
    println!(
        "fuzz_blob: seed {seed}, {n} inputs in {secs:.1} s on {threads} threads ({:.0}/s): {} past the checksum, {} loaded ({} as 3x32, {} as 4x32), {} sample/pdf calls",
        n as f64 / secs,
        counts.past_checksum.load(Ordering::Relaxed),
        counts.loaded.load(Ordering::Relaxed),
        counts.loaded_3x32.load(Ordering::Relaxed),
        counts.loaded_4x32.load(Ordering::Relaxed),
        counts.calls.load(Ordering::Relaxed),
    );
    println!("fuzz_blob: outcomes {:?}", counts.outcomes.lock().unwrap());
    // The mutations must reach the checks behind the checksum, and models must load.
    if inputs >= 1000 {
        assert!(counts.past_checksum.load(Ordering::Relaxed) * 2 > n);
        assert!(counts.loaded.load(Ordering::Relaxed) * 5 > n);
    }
}
