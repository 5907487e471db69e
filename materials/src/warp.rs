//! Square-to-direction warps with their densities (per unit solid angle) and inverses.

use crate::DVec3;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Concentric map of `[0,1]^2` to the unit disk (Shirley & Chiu 1997).
pub fn square_to_disk_concentric(u: [f64; 2]) -> [f64; 2] {
    let a = 2.0 * u[0] - 1.0;
    let b = 2.0 * u[1] - 1.0;
    if a == 0.0 && b == 0.0 {
        return [0.0, 0.0];
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, FRAC_PI_4 * (b / a))
    } else {
        (b, FRAC_PI_2 - FRAC_PI_4 * (a / b))
    };
    [r * phi.cos(), r * phi.sin()]
}

/// Cosine-weighted hemisphere (Malley's method); density `cos theta / pi`.
pub fn square_to_cosine_hemisphere(u: [f64; 2]) -> DVec3 {
    let d = square_to_disk_concentric(u);
    let z = (1.0 - d[0] * d[0] - d[1] * d[1]).max(0.0).sqrt();
    DVec3::new(d[0], d[1], z)
}

/// Density of [`square_to_cosine_hemisphere`] per unit solid angle.
pub fn cosine_hemisphere_pdf(w: DVec3) -> f64 {
    if w.z > 0.0 {
        w.z / PI
    } else {
        0.0
    }
}

/// Equal-area octahedral map of the square `[-1,1]^2` onto the unit sphere (Clarberg 2008).
/// The upper hemisphere is the diamond `|a| + |b| <= 1`. `dw = pi da db`.
pub fn equal_area_square_to_sphere(p: [f64; 2]) -> DVec3 {
    let (a, b) = (p[0], p[1]);
    let (ap, bp) = (a.abs(), b.abs());
    let signed_distance = 1.0 - (ap + bp);
    let r = 1.0 - signed_distance.abs();
    let phi = if r == 0.0 {
        FRAC_PI_4
    } else {
        ((bp - ap) / r + 1.0) * FRAC_PI_4
    };
    let z = (1.0 - r * r).copysign(signed_distance);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    DVec3::new(phi.cos().copysign(a) * s, phi.sin().copysign(b) * s, z)
}

/// Inverse of [`equal_area_square_to_sphere`].
pub fn equal_area_sphere_to_square(d: DVec3) -> [f64; 2] {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let a = x.max(y);
    let b = if a == 0.0 { 0.0 } else { x.min(y) / a };
    let mut phi = b.atan() / FRAC_PI_2;
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        std::mem::swap(&mut u, &mut v);
        u = 1.0 - u;
        v = 1.0 - v;
    }
    [u.copysign(d.x), v.copysign(d.y)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_area_round_trip() {
        for i in 0..50 {
            for j in 0..50 {
                let p = [
                    -0.99 + 1.98 * i as f64 / 49.0,
                    -0.99 + 1.98 * j as f64 / 49.0,
                ];
                let w = equal_area_square_to_sphere(p);
                assert!((w.length() - 1.0).abs() < 1e-12);
                let q = equal_area_sphere_to_square(w);
                assert!(
                    (p[0] - q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9,
                    "{p:?} {q:?}"
                );
            }
        }
    }
}
