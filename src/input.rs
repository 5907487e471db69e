//! Checks on what callers pass in. Renderers pass unit vectors, but the kernel must answer
//! non-unit, zero, NaN and infinite inputs with an invalid result, never NaN or a panic.

use crate::spec::UNIT_TOLERANCE;
use glam::{Vec2, Vec3};

/// `w` normalised, or `None` if it is not finite or not close to unit length.
#[inline]
#[must_use]
pub fn unit_direction(w: Vec3) -> Option<Vec3> {
    if !w.is_finite() {
        return None;
    }
    let l2 = w.length_squared();
    if !((l2 - 1.0).abs() <= UNIT_TOLERANCE) {
        return None;
    }
    Some(w * (1.0 / crate::math::sqrt(l2)))
}

/// `u` as an array, or `None` unless both numbers lie in [0, 1].
#[inline]
#[must_use]
pub fn uniform_pair(u: Vec2) -> Option<[f32; 2]> {
    let ok = |x: f32| (0.0..=1.0).contains(&x);
    (ok(u.x) && ok(u.y)).then_some([u.x, u.y])
}
