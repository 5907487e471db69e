//! Structure-aware fuzzing of the RGL `.bsdf` reader (untrusted files).
//!
//! Starts from the real measured files in `shared/data/rgl/` and from a small valid copy of
//! one of them (every table subsampled, about 12 KB, so that one input costs tens of
//! microseconds instead of the milliseconds a 650 KB file takes), and mutates them with
//! the layout of `shared/RGL-FORMAT.md` in hand: the container header (magic, version,
//! field count), each field's header entry (name length, name, ndim, dtype, offset, every
//! extent), the field data (incidence angles out of order or out of range, NaN / Inf /
//! negative / huge / zeroed table values), truncation, extension, bit flips and
//! interesting bytes. Every input goes to `RglMaterial::from_bytes`; every material that
//! loads is evaluated, sampled and asked for PDFs at valid and invalid directions.
//!
//! Checked: no panic (an error is fine); a loaded material gives finite values, a PDF
//! that is finite and >= 0, and samples with a finite unit `wo`, a positive finite PDF
//! and a finite weight.
//!
//! `DIFFBSDF_FUZZ_INPUTS` sets the number of inputs (default 400 000, about 15 s in
//! release on 2 cores; one in 64 is a mutated full-size file), `DIFFBSDF_FUZZ_SEED` the
//! seed. Input `i` depends only on the seed and `i`; a failing input is written to
//! `target/tmp/` and its index printed.

#[path = "../../tests/support/fuzz_driver.rs"]
mod fuzz_driver;
mod tensor_copy;

use diffbsdf_materials::rgl::{RglError, RglMaterial, TensorFile};
use diffbsdf_materials::{DVec3, Material};
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use tensor_copy::{rewrite, spread, Rewrite};

const DEFAULT_INPUTS: usize = 400_000;
const DEFAULT_SEED: u64 = 0x0B5D_F00D;
/// One input in this many starts from a full-size file.
const FULL_SIZE_EVERY: usize = 64;

/// SplitMix64 (std only).
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

    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }

    fn chance(&mut self, p: f64) -> bool {
        self.uniform() < p
    }

    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len())]
    }
}

fn data_dir() -> PathBuf {
    let dir = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/data/rgl"
    ));
    assert!(
        dir.is_dir(),
        "RGL test data missing: expected {dir:?} (the shared/ folder beside the repository)"
    );
    dir
}

// ---------------------------------------------------------------------------------------
// The container layout: where each header entry and each field's data lie
// ---------------------------------------------------------------------------------------

/// Byte positions of one field's header entry and data.
#[derive(Clone, Debug)]
struct Entry {
    name: String,
    name_len_at: usize,
    name_at: usize,
    ndim_at: usize,
    dtype_at: usize,
    offset_at: usize,
    shape_at: Vec<usize>,
    dtype: u8,
    data_at: usize,
    data_len: usize,
}

/// A file with its layout (from the unmutated bytes).
#[derive(Clone, Debug)]
struct Seed {
    label: String,
    bytes: Vec<u8>,
    entries: Vec<Entry>,
}

fn dtype_size(code: u8) -> usize {
    match code {
        1 | 2 => 1,
        3 | 4 | 9 => 2,
        5 | 6 | 10 => 4,
        _ => 8,
    }
}

/// Walks the header of a valid file (RGL-FORMAT.md, "Container").
fn layout(bytes: &[u8]) -> Vec<Entry> {
    let u16_at = |p: usize| usize::from(u16::from_le_bytes([bytes[p], bytes[p + 1]]));
    let u64_at = |p: usize| u64::from_le_bytes(bytes[p..p + 8].try_into().unwrap()) as usize;
    let count = u32::from_le_bytes(bytes[14..18].try_into().unwrap()) as usize;
    let mut p = 18;
    let mut out = Vec::new();
    for _ in 0..count {
        let name_len = u16_at(p);
        let name = String::from_utf8(bytes[p + 2..p + 2 + name_len].to_vec()).unwrap();
        let ndim_at = p + 2 + name_len;
        let ndim = u16_at(ndim_at);
        let dtype = bytes[ndim_at + 2];
        let offset_at = ndim_at + 3;
        let shape_at: Vec<usize> = (0..ndim).map(|k| offset_at + 8 + 8 * k).collect();
        let count: usize = shape_at.iter().map(|&s| u64_at(s)).product();
        out.push(Entry {
            name,
            name_len_at: p,
            name_at: p + 2,
            ndim_at,
            dtype_at: ndim_at + 2,
            offset_at,
            dtype,
            data_at: u64_at(offset_at),
            data_len: count * dtype_size(dtype),
            shape_at,
        });
        p = offset_at + 8 + 8 * ndim;
    }
    out
}

/// A small valid file from a real one: 4 of the incidences, VNDF 16x16, luminance and RGB
/// 8x8; the other fields as they are.
fn small_copy(bytes: &[u8]) -> Vec<u8> {
    let tf = TensorFile::parse(bytes).unwrap();
    let thetas = spread(tf.field("theta_i").unwrap().shape[0], 4);
    rewrite(bytes, |f| {
        let all = |n: usize| (0..n).collect::<Vec<_>>();
        match f.name.as_str() {
            "theta_i" => Rewrite::Gather(vec![thetas.clone()]),
            "vndf" => Rewrite::Gather(vec![
                all(f.shape[0]),
                thetas.clone(),
                spread(f.shape[2], 16),
                spread(f.shape[3], 16),
            ]),
            "luminance" => Rewrite::Gather(vec![
                all(f.shape[0]),
                thetas.clone(),
                spread(f.shape[2], 8),
                spread(f.shape[3], 8),
            ]),
            "rgb" => Rewrite::Gather(vec![
                all(f.shape[0]),
                thetas.clone(),
                all(f.shape[2]),
                spread(f.shape[3], 8),
                spread(f.shape[4], 8),
            ]),
            _ => Rewrite::Keep,
        }
    })
}

/// The small copies (every file) and the full-size files.
fn seeds() -> (Vec<Seed>, Vec<Seed>) {
    let mut names: Vec<_> = std::fs::read_dir(data_dir())
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "bsdf"))
        .collect();
    names.sort();
    assert!(names.len() >= 6, "expected the six RGL files");
    let mut small = Vec::new();
    let mut full = Vec::new();
    for p in names {
        let label = p.file_name().unwrap().to_string_lossy().into_owned();
        let bytes = std::fs::read(&p).unwrap();
        let s = small_copy(&bytes);
        RglMaterial::from_bytes(&s).unwrap_or_else(|e| panic!("small copy of {label}: {e}"));
        small.push(Seed {
            label: format!("small {label}"),
            entries: layout(&s),
            bytes: s,
        });
        full.push(Seed {
            label,
            entries: layout(&bytes),
            bytes,
        });
    }
    (small, full)
}

// ---------------------------------------------------------------------------------------
// Mutations
// ---------------------------------------------------------------------------------------

fn set_le(b: &mut [u8], at: usize, size: usize, v: u64) {
    if let Some(dst) = b.get_mut(at..at + size) {
        dst.copy_from_slice(&v.to_le_bytes()[..size]);
    }
}

/// Writes `src` at `at` where the (possibly truncated) input still has room.
fn put(b: &mut [u8], at: usize, src: &[u8]) {
    if let Some(dst) = b.get_mut(at..at + src.len()) {
        dst.copy_from_slice(src);
    }
}

fn get_le(b: &[u8], at: usize, size: usize) -> u64 {
    let mut a = [0u8; 8];
    if let Some(src) = b.get(at..at + size) {
        a[..size].copy_from_slice(src);
    }
    u64::from_le_bytes(a)
}

/// An edge value for an integer field of `size` bytes that held `orig`.
fn edge(rng: &mut Rng, size: usize, orig: u64, file_len: usize) -> u64 {
    let max = if size == 8 {
        u64::MAX
    } else {
        (1u64 << (8 * size)) - 1
    };
    let v = match rng.below(4) {
        0 => *rng.pick(&[
            0,
            1,
            2,
            3,
            4,
            5,
            16,
            max,
            max - 1,
            max / 2,
            max / 2 + 1,
            1 << 32,
            (1 << 62) + 1,
            u64::MAX / 4 + 1,
        ]),
        1 => orig
            .wrapping_add(*rng.pick(&[1u64, 2, 8, u64::MAX, u64::MAX - 7]))
            .min(max),
        2 => *rng.pick(&[
            file_len as u64,
            (file_len as u64).saturating_sub(1),
            file_len as u64 + 1,
            orig / 2,
            orig * 2,
        ]),
        _ => rng.next_u64(),
    };
    v & max
}

const INTERESTING_BYTES: [u8; 5] = [0, 1, 0x7f, 0x80, 0xff];
const SPECIAL_F32: [f32; 14] = [
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::MAX,
    -f32::MAX,
    1e30,
    -1.0,
    0.0,
    -0.0,
    1e-45,
    1.570_796_4,
    1.571_1,
    -1e-5,
    3.0,
];

fn mutate(b: &mut Vec<u8>, seed: &Seed, seeds: &[Seed], rng: &mut Rng, log: &mut Vec<String>) {
    let len = b.len();
    let e = rng.pick(&seed.entries).clone();
    match rng.below(14) {
        0 => {
            // Container header: magic, version, field count.
            let magic_byte = rng.below(12);
            let (at, size) = *rng.pick(&[(magic_byte, 1), (12, 1), (13, 1), (14, 4)]);
            let v = edge(rng, size, get_le(b, at, size), len);
            set_le(b, at, size, v);
            log.push(format!("container field at {at} = {v}"));
        }
        1 => {
            let v = edge(rng, 2, get_le(b, e.name_len_at, 2), len);
            set_le(b, e.name_len_at, 2, v);
            log.push(format!("{}: name length = {v}", e.name));
        }
        2 => {
            // Rename: another field's name (same length where possible), or a byte.
            let other = &rng.pick(&seed.entries).name;
            let at = e.name_at + rng.below(e.name.len());
            if other.len() == e.name.len() {
                put(b, e.name_at, other.as_bytes());
                log.push(format!("{} renamed {other}", e.name));
            } else {
                let v = *rng.pick(&[0u8, 0xff, 0xc3, b'x']);
                put(b, at, &[v]);
                log.push(format!("{}: name byte {at} = {v:#x}", e.name));
            }
        }
        3 => {
            let v = edge(rng, 2, get_le(b, e.ndim_at, 2), len);
            set_le(b, e.ndim_at, 2, v);
            log.push(format!("{}: ndim = {v}", e.name));
        }
        4 => {
            let v = *rng.pick(&[0u8, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 0xff]);
            put(b, e.dtype_at, &[v]);
            log.push(format!("{}: dtype = {v}", e.name));
        }
        5 => {
            let other = rng.pick(&seed.entries).data_at as u64;
            let v = if rng.chance(0.3) {
                other + rng.below(3) as u64 * 4
            } else {
                edge(rng, 8, get_le(b, e.offset_at, 8), len)
            };
            set_le(b, e.offset_at, 8, v);
            log.push(format!("{}: offset = {v}", e.name));
        }
        6 | 7 => {
            if !e.shape_at.is_empty() {
                let k = rng.below(e.shape_at.len());
                let v = edge(rng, 8, get_le(b, e.shape_at[k], 8), len);
                set_le(b, e.shape_at[k], 8, v);
                log.push(format!("{}: shape[{k}] = {v}", e.name));
            }
        }
        8 | 9 => {
            // Field data: special values, or a run of zeros / negatives / one value.
            if e.dtype == 10 && e.data_len >= 4 {
                let n = e.data_len / 4;
                let i = rng.below(n);
                let run = match rng.below(3) {
                    0 => 1,
                    1 => n - i,
                    _ => 1 + rng.below(64).min(n - i - 1),
                };
                let v = *rng.pick(&SPECIAL_F32);
                for k in i..i + run {
                    put(b, e.data_at + 4 * k, &v.to_le_bytes());
                }
                log.push(format!("{}: {run} values from {i} = {v:e}", e.name));
            } else if e.data_len > 0 {
                let at = e.data_at + rng.below(e.data_len);
                let v = *rng.pick(&INTERESTING_BYTES);
                put(b, at, &[v]);
                log.push(format!("{}: data byte {at} = {v:#x}", e.name));
            }
        }
        10 => {
            let to = if rng.chance(0.5) {
                rng.below(seed.entries.last().map_or(64, |e| e.data_at) + 1)
            } else {
                rng.below(len)
            };
            b.truncate(to);
            log.push(format!("truncate to {to}"));
        }
        11 => {
            let n = 1 + rng.below(64);
            b.extend((0..n).map(|_| rng.next_u64() as u8));
            log.push(format!("extend by {n}"));
        }
        12 => {
            // The header of another file over this one's.
            let other = rng.pick(seeds);
            let h = other.entries.last().map_or(18, |e| e.data_at).min(len);
            let h = h.min(other.bytes.len());
            b[..h].copy_from_slice(&other.bytes[..h]);
            log.push(format!("header of {}", other.label));
        }
        _ => {
            let at = if rng.chance(0.7) {
                rng.below(seed.entries.last().map_or(64, |e| e.data_at).min(len))
            } else {
                rng.below(len)
            };
            if rng.chance(0.5) {
                b[at] ^= 1 << rng.below(8);
                log.push(format!("flip a bit of byte {at}"));
            } else {
                let v = *rng.pick(&INTERESTING_BYTES);
                b[at] = v;
                log.push(format!("byte {at} = {v:#x}"));
            }
        }
    }
}

fn make_input(seed: u64, index: usize, small: &[Seed], full: &[Seed]) -> (Vec<u8>, Vec<String>) {
    let mut rng = Rng::new(seed ^ (index as u64).wrapping_mul(0xA24B_AED4_963E_E407));
    let pool = if index % FULL_SIZE_EVERY == FULL_SIZE_EVERY - 1 {
        full
    } else {
        small
    };
    let s = rng.pick(pool);
    let mut b = s.bytes.clone();
    let mut log = vec![format!("start {}", s.label)];
    let n = if rng.chance(0.6) { 1 } else { 2 + rng.below(3) };
    for _ in 0..n {
        if b.is_empty() {
            break;
        }
        mutate(&mut b, s, pool, &mut rng, &mut log);
    }
    (b, log)
}

// ---------------------------------------------------------------------------------------
// Checks
// ---------------------------------------------------------------------------------------

#[derive(Default)]
struct Counts {
    inputs: AtomicUsize,
    loaded: AtomicUsize,
    calls: AtomicUsize,
    outcomes: Mutex<BTreeMap<String, usize>>,
}

fn outcome(r: &Result<RglMaterial, RglError>) -> String {
    match r {
        Ok(_) => "loaded".into(),
        Err(e) => {
            let s = format!("{e:?}");
            s.split(['(', ' ', '{']).next().unwrap_or("").to_string()
        }
    }
}

fn dir(theta_deg: f64, phi: f64) -> DVec3 {
    let t = theta_deg.to_radians();
    DVec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos())
}

fn exercise(m: &RglMaterial, rng: &mut Rng, counts: &Counts) {
    let wis = [
        dir(0.0, 0.0),
        dir(30.0, 0.4),
        dir(89.9, -2.0),
        dir(rng.uniform() * 90.0, rng.uniform() * 7.0 - 3.5),
        DVec3::new(0.3, 0.1, -0.9).normalize(),
        DVec3::new(f64::NAN, 0.0, 1.0),
        DVec3::ZERO,
        DVec3::new(0.0, 0.0, 2.0),
    ];
    let wos = [
        dir(30.0, std::f64::consts::PI + 0.4),
        dir(rng.uniform() * 90.0, rng.uniform() * 7.0 - 3.5),
        DVec3::Z,
        DVec3::new(0.0, 0.0, f64::INFINITY),
        -DVec3::Z,
    ];
    let mut calls = 0;
    for (i, &wi) in wis.iter().enumerate() {
        // Valid incidences everywhere; the invalid ones against two outgoing directions.
        let wos = if i < 4 { &wos[..] } else { &wos[..2] };
        for &wo in wos {
            let f = m.eval(wi, wo);
            assert!(f.is_finite(), "eval({wi:?}, {wo:?}) = {f:?}");
            let fc = m.eval_cos(wi, wo);
            assert!(fc.is_finite(), "eval_cos({wi:?}, {wo:?}) = {fc:?}");
            let p = m.pdf(wi, wo);
            assert!(p.is_finite() && p >= 0.0, "pdf({wi:?}, {wo:?}) = {p}");
            calls += 3;
        }
        let us = [
            [rng.uniform(), rng.uniform(), rng.uniform()],
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 1.0],
            [-0.5, 1.5, f64::NAN],
        ];
        for u in us {
            if let Some(s) = m.sample(wi, u) {
                assert!(
                    s.wo.is_finite() && (s.wo.length() - 1.0).abs() < 1e-9,
                    "sample({wi:?}, {u:?}).wo = {:?}",
                    s.wo
                );
                assert!(
                    s.pdf.is_finite() && s.pdf > 0.0,
                    "sample({wi:?}, {u:?}).pdf = {}",
                    s.pdf
                );
                assert!(
                    s.weight.is_finite(),
                    "sample({wi:?}, {u:?}).weight = {:?}",
                    s.weight
                );
            }
            calls += 1;
        }
    }
    counts.calls.fetch_add(calls, Ordering::Relaxed);
}

fn check_input(bytes: &[u8], index: usize, seed: u64, counts: &Counts) {
    let r = RglMaterial::from_bytes(bytes);
    counts.inputs.fetch_add(1, Ordering::Relaxed);
    *counts
        .outcomes
        .lock()
        .unwrap()
        .entry(outcome(&r))
        .or_default() += 1;
    if let Ok(m) = &r {
        counts.loaded.fetch_add(1, Ordering::Relaxed);
        let mut rng = Rng::new(seed ^ 0x5EED ^ (index as u64).wrapping_mul(0x9FB2_1C65_1E98_DF25));
        exercise(m, &mut rng, counts);
    }
}

#[test]
fn mutated_rgl_files_never_panic() {
    let (inputs, seed) = fuzz_driver::inputs_and_seed(DEFAULT_INPUTS, DEFAULT_SEED);
    let (small, full) = seeds();
    let counts = Counts::default();
    let (threads, secs) = fuzz_driver::run(
        "fuzz_rgl",
        "bsdf",
        env!("CARGO_TARGET_TMPDIR"),
        seed,
        inputs,
        |index| make_input(seed, index, &small, &full),
        |bytes, index| check_input(bytes, index, seed, &counts),
    );
    let n = counts.inputs.load(Ordering::Relaxed);
    println!(
        "fuzz_rgl: seed {seed}, {n} inputs in {secs:.1} s on {threads} threads ({:.0}/s): {} loaded, {} eval/pdf/sample calls",
        n as f64 / secs,
        counts.loaded.load(Ordering::Relaxed),
        counts.calls.load(Ordering::Relaxed),
    );
    println!("fuzz_rgl: outcomes {:?}", counts.outcomes.lock().unwrap());
    if inputs >= 1000 {
        assert!(
            counts.loaded.load(Ordering::Relaxed) * 10 > n,
            "too few inputs load"
        );
    }
}
