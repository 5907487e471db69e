//! The projected unit disk: `x = (wo.x, wo.y)`, `wo.z = sqrt(1 - |x|^2)`.
//!
//! `f cos(theta) dw = f dA`, so `pdf_w(wo) = pdf_x(x) cos(theta_o)`. Points with
//! `|x| >= 1` are outside the domain: invalid, never renormalised.

use glam::Vec3;

/// The direction of a disk point; `None` outside the open unit disk.
#[inline]
#[must_use]
pub fn to_direction(x: [f32; 2]) -> Option<Vec3> {
    let r2 = x[0] * x[0] + x[1] * x[1];
    if !(r2 < 1.0) {
        return None;
    }
    let z = crate::math::sqrt(1.0 - r2);
    (z > 0.0).then_some(Vec3::new(x[0], x[1], z))
}

/// The disk point of a unit direction; `None` below or on the horizon.
#[inline]
#[must_use]
pub fn from_direction(wo: Vec3) -> Option<[f32; 2]> {
    (wo.z > 0.0).then_some([wo.x, wo.y])
}

/// `ln(pdf_w / pdf_x) = ln cos(theta_o)`.
#[inline]
#[must_use]
pub fn ln_measure(wo: Vec3) -> f32 {
    crate::math::ln(wo.z)
}
