//! Spherical coordinates: `x = (theta, phi)`, `wo = (sin t cos p, sin t sin p, cos t)`.
//!
//! `dw = sin(theta) dtheta dphi`, so `pdf_w(wo) = pdf_x(x) / sin(theta_o)`. `phi` is
//! periodic (the flow wraps it into [-pi, pi)); `theta` outside (0, pi) is invalid.

use crate::math::{atan2, floor, ln, sin, sin_cos, sqrt};
use core::f32::consts::{PI, TAU};
use glam::Vec3;

/// `phi` wrapped into [-pi, pi).
#[inline(always)]
#[must_use]
pub fn wrap(phi: f32) -> f32 {
    phi - TAU * floor((phi + PI) * (1.0 / TAU))
}

/// The direction of `(theta, phi)`; `None` unless `sin(theta) > 0` (theta in (0, pi)).
#[inline]
#[must_use]
pub fn to_direction(x: [f32; 2]) -> Option<Vec3> {
    let (st, ct) = sin_cos(x[0]);
    if !(st > 0.0 && x[0] > 0.0 && x[0] < PI) {
        return None;
    }
    let (sp, cp) = sin_cos(x[1]);
    Some(Vec3::new(st * cp, st * sp, ct))
}

/// `(theta, phi)` of a unit direction; `None` on the poles, where `phi` is undefined and
/// the density in solid angle is singular.
#[inline]
#[must_use]
pub fn from_direction(wo: Vec3) -> Option<[f32; 2]> {
    let rho = sqrt(wo.x * wo.x + wo.y * wo.y);
    if !(rho > 0.0) {
        return None;
    }
    Some([atan2(rho, wo.z), atan2(wo.y, wo.x)])
}

/// `ln(pdf_w / pdf_x) = -ln sin(theta_o)`.
#[inline]
#[must_use]
pub fn ln_measure(theta: f32) -> f32 {
    -ln(sin(theta))
}
