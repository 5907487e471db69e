//! The half-vector chart of a reflection: `x = (h.x, h.y)` on the projected unit disk,
//! `h.z = sqrt(1 - |x|^2)`, and `wo = 2 (wi.h) h - wi` (`docs/math.md`, §4.4).
//!
//! For a fixed `wi` above the surface, `h -> wo` maps the half vectors with `wi.h > 0` one
//! to one onto the sphere, with `dw_o / dw_h = 4 (wi.h)` (Walter et al. 2007, eq. 14), and
//! the disk gives `dw_h = dA / h.z`; so `pdf_w(wo) = pdf_x(x) h.z / (4 wi.h)`. A measured
//! BRDF's specular peak sits at `h = n` (the disk's centre) for every `wi`, and the horizon
//! of `wo` is a curve inside the disk (where `f |cos theta_o|` vanishes) instead of its rim.
//! Points whose `wo` is not above the surface are outside the domain: invalid, never
//! renormalised. `wi` is the incident direction in the model's frame, `wi.z >= 0`.

use crate::math::{ln, sqrt};
use crate::spec::HALF_VECTOR_IDENTITY_SPAN;
use glam::Vec3;

/// The half vector of a disk point; `None` outside the open unit disk.
#[inline(always)]
fn half_vector(x: [f32; 2]) -> Option<Vec3> {
    super::disk::to_direction(x)
}

/// The reflected direction of a disk point; `None` outside the disk or where `wo` is not
/// above the surface.
#[inline]
#[must_use]
pub fn to_direction(x: [f32; 2], wi: Vec3) -> Option<Vec3> {
    let h = half_vector(x)?;
    // wo = 2 (wi.h) h - wi   (Walter et al. 2007, eq. 13 with the reflection's sign)
    let d = wi.dot(h);
    let wo = h * (2.0 * d) - wi;
    (d > 0.0 && wo.z > 0.0).then_some(wo)
}

/// The disk point of a reflected direction: `h = (wi + wo) / |wi + wo|`; `None` unless
/// `wo` is above the surface.
#[inline]
#[must_use]
pub fn from_direction(wo: Vec3, wi: Vec3) -> Option<[f32; 2]> {
    if !(wo.z > 0.0) {
        return None;
    }
    let s = sum(wi, wo);
    let len = sqrt(s.dot(s));
    if !(len > 0.0) {
        return None;
    }
    let h = s * (1.0 / len);
    (h.z > 0.0).then_some([h.x, h.y])
}

/// `s = wi + wo` (`docs/math.md`, (58)), its tangent part computed along `wi`'s azimuth:
/// with `rho = |wi.xy|`, `t` and `p` the components of `wo.xy` along and across `wi.xy / rho`,
/// `s_t = rho + t`, or where `t < 0` and `rho - t > HALF_VECTOR_IDENTITY_SPAN` the unit-vector
/// identity `s_t = (p^2 + (wo.z^2 - wi.z^2)) / (rho - t)`; then `s.xy` from `(s_t, p)`.
/// Near the mirror direction at grazing incidence `rho` and `-t` are about 1 and `|s|`
/// about 0.035: the plain sum keeps the rounding of `wo` along `wi`'s azimuth, which is
/// mostly off the sphere (radial), and `h = s / |s|` amplifies it 30x. The identity holds
/// for the `wo` the forward map computes (whose length is `wi`'s), so the radial rounding
/// drops out; its own error is the rounding of the squares over `rho - t`, which is why
/// small tangent parts keep the plain sum. In the incident frame of an isotropic model
/// `wi.y = 0` and `wi.x = rho`, so `t = wo.x`, `p = wo.y` and nothing is rotated.
#[inline(always)]
fn sum(wi: Vec3, wo: Vec3) -> Vec3 {
    let mut s = wi + wo;
    let rho = sqrt(wi.x * wi.x + wi.y * wi.y);
    if rho > 0.0 {
        let (c, sn) = (wi.x / rho, wi.y / rho);
        let t = c * wo.x + sn * wo.y;
        let p = c * wo.y - sn * wo.x;
        let mut st = rho + t;
        if t < 0.0 && rho - t > HALF_VECTOR_IDENTITY_SPAN {
            st = (p * p + (wo.z * wo.z - wi.z * wi.z)) / (rho - t);
        }
        s.x = c * st - sn * p;
        s.y = sn * st + c * p;
    }
    s
}

/// `ln(pdf_w / pdf_x) = ln(h.z / (4 wi.h)) = ln(s.z / (2 s.s))` with `s = wi + wo`
/// (`h = s / |s|`; `docs/math.md`, (57)): a function of the direction that is well
/// conditioned where the pieces are not. `sqrt(1 - |x|^2)` for `h.z` loses a relative 1e-4
/// to one rounding of `x` near the disk's rim (half vectors near the horizon, reached at
/// grazing `wi`), and `sqrt((1 + wi.wo) / 2)` for `wi.h` as much near the mirror direction
/// at grazing `wi`; `s.z` (a sum of two positive numbers) and `s.s` lose only what the
/// rounding of `wo` itself moves. The argument `x` is not used: the point is implied by `wo`.
#[inline]
#[must_use]
pub fn ln_measure(wo: Vec3, wi: Vec3) -> f32 {
    let s = sum(wi, wo);
    ln(s.z / (2.0 * s.dot(s)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflection_round_trips_and_keeps_the_peak_at_the_centre() {
        let wi = Vec3::new(0.6, 0.0, 0.8);
        let mirror = Vec3::new(-0.6, 0.0, 0.8);
        let x = from_direction(mirror, wi).unwrap();
        assert!(x[0].abs() < 1e-7 && x[1].abs() < 1e-7, "{x:?}");
        for i in 0..30 {
            for j in 0..30 {
                let x = [-0.9 + 0.06 * i as f32, -0.9 + 0.06 * j as f32];
                let Some(wo) = to_direction(x, wi) else {
                    continue;
                };
                assert!((wo.length() - 1.0).abs() < 1e-5);
                let back = from_direction(wo, wi).unwrap();
                assert!((back[0] - x[0]).abs() < 1e-5 && (back[1] - x[1]).abs() < 1e-5);
            }
        }
        assert!(
            to_direction([0.99, 0.0], wi).is_none(),
            "h near the rim reflects below"
        );
    }

    /// The measure integrates: a uniform density on the disk (1/pi) carried to `wo` by the
    /// measure change integrates over the upper hemisphere to the disk area whose `wo` is
    /// valid (checked against counting on a fine grid).
    #[test]
    fn measure_change_integrates_to_the_valid_disk_area() {
        let wi = Vec3::new(0.5, 0.3, 0.812_404);
        let n = 400;
        let (mut valid, mut integral) = (0.0f64, 0.0f64);
        for i in 0..n {
            for j in 0..n {
                let x = [
                    -1.0 + (i as f32 + 0.5) * 2.0 / n as f32,
                    -1.0 + (j as f32 + 0.5) * 2.0 / n as f32,
                ];
                if to_direction(x, wi).is_some() {
                    valid += 1.0;
                }
                // Same integral over wo: theta in (0, pi/2), phi in (-pi, pi).
                let th = (i as f64 + 0.5) / n as f64 * core::f64::consts::FRAC_PI_2;
                let ph =
                    -core::f64::consts::PI + (j as f64 + 0.5) / n as f64 * core::f64::consts::TAU;
                let wo = Vec3::new(
                    (th.sin() * ph.cos()) as f32,
                    (th.sin() * ph.sin()) as f32,
                    th.cos() as f32,
                );
                if from_direction(wo, wi).is_some() {
                    let pdf_w = (ln_measure(wo, wi) as f64).exp();
                    let dw = th.sin() * core::f64::consts::FRAC_PI_2 * core::f64::consts::TAU
                        / (n * n) as f64;
                    integral += pdf_w * dw;
                }
            }
        }
        let area = valid * 4.0 / (n * n) as f64;
        assert!(
            (integral - area).abs() < 0.01 * area,
            "{integral} vs {area}"
        );
    }
}
