//! The inputs the nets see, computed with the kernel's own functions: the NeRF encoding
//! of `wi` (`diffbsdf::internals::net::encoding::encode_wi`) and the flow-state features (disk:
//! `x, y`; sphere: `theta, sin phi, cos phi`), plus the domain's point arithmetic
//! (phi wrapped, geodesic phi differences).

use diffbsdf::internals::domain::sphere::wrap;
use diffbsdf::internals::net::encoding::encode_wi;
use diffbsdf::Domain;

/// Encoding length of the velocity net (5 frequencies).
pub const VEL_ENC: usize = 33;
/// Encoding length of the base net (3 frequencies).
pub const BASE_ENC: usize = 21;

/// The velocity net's encoding of `wi`.
pub fn velocity_encoding(wi: [f32; 3]) -> [f32; VEL_ENC] {
    encode_wi::<VEL_ENC>(wi)
}

/// The base net's encoding of `wi` (a prefix of the velocity net's).
pub fn base_encoding(wi: [f32; 3]) -> [f32; BASE_ENC] {
    encode_wi::<BASE_ENC>(wi)
}

/// Inputs of the velocity net's first layer: `[features, t, encoding]`.
pub fn velocity_inputs(domain: Domain) -> usize {
    domain.feature_count() + 1 + VEL_ENC
}

/// Appends the velocity-net input row for state `x` at time `t`.
pub fn push_velocity_row(domain: Domain, x: [f32; 2], t: f32, enc: &[f32], row: &mut Vec<f32>) {
    match domain {
        Domain::Disk => row.extend_from_slice(&[x[0], x[1]]),
        Domain::Sphere => row.extend_from_slice(&[x[0], libm::sinf(x[1]), libm::cosf(x[1])]),
    }
    row.push(t);
    row.extend_from_slice(enc);
}

/// `x + d` (phi wrapped on the sphere), as the kernel advances a step.
pub fn advance(domain: Domain, x: [f32; 2], d: [f32; 2]) -> [f32; 2] {
    match domain {
        Domain::Disk => [x[0] + d[0], x[1] + d[1]],
        Domain::Sphere => [x[0] + d[0], wrap(x[1] + d[1])],
    }
}

/// `b - a`, the phi part taken the short way round on the sphere (the geodesic
/// difference of the paper's §4.3).
pub fn difference(domain: Domain, a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
    match domain {
        Domain::Disk => [b[0] - a[0], b[1] - a[1]],
        Domain::Sphere => [b[0] - a[0], wrap(b[1] - a[1])],
    }
}

/// `x_t = x0 + t (x1 - x0)` along the (geodesic) straight path.
pub fn interpolate(domain: Domain, x0: [f32; 2], x1: [f32; 2], t: f32) -> [f32; 2] {
    let d = difference(domain, x0, x1);
    advance(domain, x0, [t * d[0], t * d[1]])
}
