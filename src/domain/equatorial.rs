//! The equatorial chart: spherical coordinates about the tangent `y` axis,
//! `x = (theta, phi)`, `wo = (sin t cos p, cos t, sin t sin p)` (`docs/math.md`, §4.3).
//!
//! The normal is `(theta, phi) = (pi/2, pi/2)` and, for an isotropic model (whose `wi`
//! lies in the xz-plane), the whole plane of incidence is the equator `theta = pi/2`: the
//! specular and retro-reflection peaks never sit on a pole, where the standard sphere
//! chart pinches (a lobe at the normal loses the base mass with `theta < 0` there). The
//! upper hemisphere is `phi` in `(0, pi)`. Everything but the two maps below (features,
//! base distribution, measure, wrap) is the sphere's.

use super::sphere;
use glam::Vec3;

/// The direction of `(theta, phi)`; `None` unless `sin(theta) > 0` (theta in (0, pi)).
/// The sphere's direction with y and z exchanged (the same operations).
#[inline]
#[must_use]
pub fn to_direction(x: [f32; 2]) -> Option<Vec3> {
    sphere::to_direction(x).map(swap_yz)
}

/// `(theta, phi)` of a unit direction; `None` on the poles `wo = (0, +-1, 0)`.
#[inline]
#[must_use]
pub fn from_direction(wo: Vec3) -> Option<[f32; 2]> {
    sphere::from_direction(swap_yz(wo))
}

/// The reflection that exchanges the y and z axes (its own inverse).
#[inline(always)]
fn swap_yz(v: Vec3) -> Vec3 {
    Vec3::new(v.x, v.z, v.y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::{FRAC_PI_2, PI};

    #[test]
    fn normal_is_on_the_equator() {
        let x = from_direction(Vec3::Z).unwrap();
        assert!((x[0] - FRAC_PI_2).abs() < 1e-6 && (x[1] - FRAC_PI_2).abs() < 1e-6);
        assert!(from_direction(Vec3::Y).is_none() && from_direction(-Vec3::Y).is_none());
    }

    #[test]
    fn charts_round_trip() {
        for i in 1..40 {
            for j in 0..40 {
                let x = [i as f32 * PI / 40.0, -PI + j as f32 * 0.157];
                let wo = to_direction(x).unwrap();
                assert!((wo.length() - 1.0).abs() < 1e-6);
                let back = from_direction(wo).unwrap();
                assert!((back[0] - x[0]).abs() < 2e-5, "{x:?} -> {back:?}");
                let dphi = crate::domain::sphere::wrap(back[1] - x[1]);
                assert!(dphi.abs() < 2e-5, "{x:?} -> {back:?}");
            }
        }
        assert!(to_direction([0.0, 1.0]).is_none() && to_direction([PI, 1.0]).is_none());
        assert!(to_direction([f32::NAN, 1.0]).is_none());
    }
}
