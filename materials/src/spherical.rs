//! Spherical coordinates of directions in the local shading frame (z = normal), and the
//! mirror reflection in pbrt's convention (both directions pointing away).

use diffbsdf::glam::DVec3;

/// Polar and azimuthal angles of a direction.
pub trait Spherical {
    /// Polar angle `theta` in `[0, pi]` (from +z); assumes a unit vector.
    fn theta(self) -> f64;

    /// Azimuth `phi` in `(-pi, pi]`.
    fn phi(self) -> f64;
}

impl Spherical for DVec3 {
    fn theta(self) -> f64 {
        self.z.clamp(-1.0, 1.0).acos()
    }

    fn phi(self) -> f64 {
        self.y.atan2(self.x)
    }
}

/// Unit vector from spherical angles: `theta` from +z, `phi` from +x.
pub fn from_spherical(theta: f64, phi: f64) -> DVec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    DVec3::new(st * cp, st * sp, ct)
}

/// Mirror reflection of `w` (pointing away) about the unit normal `m`: `2 (w.m) m - w`
/// (pbrt's convention; glam's `DVec3::reflect` takes an incoming direction instead).
pub fn reflect(w: DVec3, m: DVec3) -> DVec3 {
    m * (2.0 * w.dot(m)) - w
}
