//! Shipped models and input rows shared by the C ABI's tests and benchmarks.
#![allow(dead_code)]

use diffbsdf_ffi::*;

/// A shipped model of `models/` by name, loaded through the C ABI.
pub fn shipped(name: &str) -> *mut diffbsdf_model {
    let path = format!("{}/../models/{name}.dbsdf", env!("CARGO_MANIFEST_DIR"));
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut status = -100;
    let m = unsafe { diffbsdf_model_new(bytes.as_ptr(), bytes.len(), &mut status) };
    assert_eq!(status, 0, "{path}");
    m
}

/// `n` incident directions (`cos theta` uniform in [0.02, 1]) and `u` pairs, flat, from a
/// fixed linear congruential sequence. With `invalid`, some rows are invalid: `wi` below
/// the surface (every 97th), not unit (every 89th), `u` outside [0, 1] (every 83rd).
pub fn inputs(n: usize, invalid: bool) -> (Vec<f32>, Vec<f32>) {
    let mut s = 0x2545_f491_u64;
    let mut next = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let every = |i: usize, k: usize| invalid && i.is_multiple_of(k);
    let mut wi = Vec::with_capacity(3 * n);
    let mut u = Vec::with_capacity(2 * n);
    for i in 0..n {
        let z = if every(i, 97) {
            -0.3
        } else {
            0.02 + 0.98 * next()
        };
        let phi = std::f32::consts::TAU * next();
        let r = (1.0 - z * z).sqrt();
        let scale = if every(i, 89) { 1.5 } else { 1.0 };
        wi.extend([scale * r * phi.cos(), scale * r * phi.sin(), scale * z]);
        let shift = if every(i, 83) { 1.25 } else { 0.0 };
        u.extend([next() + shift, next()]);
    }
    (wi, u)
}
