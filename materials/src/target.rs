//! The two normalised-up-to-a-constant target densities the trainer fits.
//!
//! Both describe the same law of `wo`: per unit solid angle it is proportional to
//! `Y(f(wi, wo)) |cos theta_o|` (`Y` = luminance).

use crate::spherical::from_spherical;
use crate::{DVec3, Material};

/// Disk domain: unnormalised density of `x = (wo.x, wo.y)` on the unit disk,
/// `wo.z = sqrt(1 - |x|^2)`. Since `f cos dw = f dA`, it equals `Y(f(wi, wo))`.
/// Zero outside the open disk.
pub fn disk_target(m: &dyn Material, wi: DVec3, x: [f64; 2]) -> f64 {
    let r2 = x[0] * x[0] + x[1] * x[1];
    if !(r2 < 1.0) {
        return 0.0;
    }
    let wo = DVec3::new(x[0], x[1], (1.0 - r2).sqrt());
    m.eval_luminance(wi, wo).max(0.0)
}

/// Sphere domain: unnormalised density of `x = (theta_o, phi_o)`,
/// `Y(f(wi, wo)) |cos theta_o| sin theta_o`. Zero for `theta` outside `(0, pi)`.
pub fn sphere_target(m: &dyn Material, wi: DVec3, theta: f64, phi: f64) -> f64 {
    if !(theta > 0.0 && theta < std::f64::consts::PI) {
        return 0.0;
    }
    let wo = from_spherical(theta, phi);
    (m.eval_luminance(wi, wo) * wo.z.abs() * theta.sin()).max(0.0)
}

/// Target density of `wo` per unit solid angle, unnormalised: `Y(f) |cos theta_o|`.
pub fn solid_angle_target(m: &dyn Material, wi: DVec3, wo: DVec3) -> f64 {
    (m.eval_luminance(wi, wo) * wo.z.abs()).max(0.0)
}
