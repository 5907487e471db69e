//! The inputs the nets see, computed with the kernel's own functions: the NeRF encoding
//! of `wi` (`diffbsdf::internals::net::encoding::encode_wi`) and the flow-state features
//! and point arithmetic of [`Domain`] (phi wrapped, geodesic phi differences).

use diffbsdf::internals::net::encoding::encode_wi;
use diffbsdf::spec::MAX_FREQS;
use diffbsdf::{encoding_len, Domain, ModelDef};

/// Length of the encoding at [`MAX_FREQS`]; every shorter encoding is a prefix of it.
const MAX_ENCODING: usize = encoding_len(MAX_FREQS);

/// Appends the encoding of `wi` with `freqs` frequencies (at most [`MAX_FREQS`]) to `out`.
pub fn push_encoding(wi: [f32; 3], freqs: u8, out: &mut Vec<f32>) {
    let len = encoding_len(freqs.min(MAX_FREQS));
    out.extend_from_slice(&encode_wi::<MAX_ENCODING>(wi)[..len]);
}

/// The encoding of `wi` with `freqs` frequencies (at most [`MAX_FREQS`]).
pub fn encoding(wi: [f32; 3], freqs: u8) -> Vec<f32> {
    let mut out = Vec::with_capacity(encoding_len(freqs));
    push_encoding(wi, freqs, &mut out);
    out
}

/// Appends the velocity-net input row of `def` for state `x` at time `t`:
/// `[features, t, encoding]`; `enc` holds at least the velocity net's encoding (only that
/// prefix is used).
pub fn push_velocity_row(def: &ModelDef, x: [f32; 2], t: f32, enc: &[f32], row: &mut Vec<f32>) {
    let domain = def.domain;
    row.extend_from_slice(&domain.features(x)[..domain.feature_count()]);
    row.push(t);
    row.extend_from_slice(&enc[..def.velocity.encoding_len()]);
}

/// `x_t = x0 + t (x1 - x0)` along the (geodesic) straight path.
pub fn interpolate(domain: Domain, x0: [f32; 2], x1: [f32; 2], t: f32) -> [f32; 2] {
    let d = domain.difference(x1, x0);
    domain.advance(x0, [t * d[0], t * d[1]])
}
