//! NeRF-style encoding of `wi`: the raw direction, then for each frequency `k` the sines and
//! cosines of `2^k * pi * wi` (per axis):
//!
//! `enc = [wi, sin(pi wi), cos(pi wi), sin(2 pi wi), cos(2 pi wi), ...]`
//!
//! Higher frequencies come from the double-angle formulas (`sin 2a = 2 sin a cos a`,
//! `cos 2a = 1 - 2 sin^2 a`), so one `sin` and one `cos` per axis serve every frequency.
//! The trainer and the generated shaders use the same recurrence.

use crate::math::sin_cos;
use core::f32::consts::PI;

/// The encoding of `wi` into `E = 3 + 6 * freqs` values (`E` fixes the frequency count).
#[inline]
#[must_use]
pub fn encode_wi<const E: usize>(wi: [f32; 3]) -> [f32; E] {
    let mut enc = [0.0; E];
    let (mut s, mut c) = ([0.0; 3], [0.0; 3]);
    for a in 0..3 {
        (s[a], c[a]) = sin_cos(PI * wi[a]);
    }
    for (slot, w) in enc.iter_mut().zip(wi) {
        *slot = w;
    }
    let mut k = 3;
    while k + 6 <= E {
        for a in 0..3 {
            enc[k + a] = s[a];
            enc[k + 3 + a] = c[a];
        }
        for a in 0..3 {
            let (sa, ca) = (s[a], c[a]);
            s[a] = 2.0 * sa * ca;
            c[a] = 1.0 - 2.0 * sa * sa;
        }
        k += 6;
    }
    enc
}

/// The first `P` values of `enc` (the base net's encoding is a prefix of the velocity
/// net's; the loader checks `P <= E`).
#[inline]
#[must_use]
pub fn prefix<const P: usize, const E: usize>(enc: &[f32; E]) -> [f32; P] {
    let mut out = [0.0; P];
    for (o, e) in out.iter_mut().zip(enc.iter()) {
        *o = *e;
    }
    out
}
