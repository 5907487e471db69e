//! Microfacet normal distributions (GGX / Trowbridge-Reitz and Beckmann, anisotropic),
//! Smith masking and visible-normal sampling, shared by the conductor, dielectric, plastic
//! and principled models.
//!
//! Microfacet normals `m` live in the upper hemisphere (`m.z > 0`). `D(m)` is normalised
//! so that `int D(m) cos theta_m dm = 1` (Walter 2007 eq. 4).

use crate::special::{erf, erf_inv};
use crate::spherical::Spherical;
use crate::DVec3;
use std::f64::consts::PI;

/// Smallest roughness accepted; smaller values are clamped (the lobe is then numerically a
/// delta and nothing downstream can integrate it).
pub const MIN_ALPHA: f64 = 1e-4;

/// The normal distribution family.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Distribution {
    /// GGX / Trowbridge-Reitz (Walter 2007 eq. 33).
    Ggx,
    /// Beckmann (Walter 2007 eq. 25).
    Beckmann,
}

impl Distribution {
    /// The spec keyword (`ggx` or `beckmann`).
    pub fn keyword(self) -> &'static str {
        match self {
            Distribution::Ggx => "ggx",
            Distribution::Beckmann => "beckmann",
        }
    }
}

/// An anisotropic microfacet distribution with roughness `alpha_x`, `alpha_y` along the
/// tangent axes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    /// Distribution family.
    pub dist: Distribution,
    /// Roughness along x.
    pub alpha_x: f64,
    /// Roughness along y.
    pub alpha_y: f64,
}

impl Microfacet {
    /// True when `alpha_x == alpha_y` (the distribution is unchanged by rotations about z).
    pub fn is_isotropic(&self) -> bool {
        self.alpha_x == self.alpha_y
    }

    /// A distribution; roughness values are clamped to `[MIN_ALPHA, inf)`.
    pub fn new(dist: Distribution, alpha_x: f64, alpha_y: f64) -> Self {
        Self {
            dist,
            alpha_x: alpha_x.max(MIN_ALPHA),
            alpha_y: alpha_y.max(MIN_ALPHA),
        }
    }

    /// `D(m)`: GGX (Walter 2007 eq. 33 / Heitz 2014 eq. 85) or Beckmann (Walter 2007
    /// eq. 25 / Heitz 2014 eq. 84), anisotropic. Zero for `m.z <= 0`.
    pub fn d(&self, m: DVec3) -> f64 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let z2 = m.z * m.z;
        let e = (m.x * m.x / (self.alpha_x * self.alpha_x)
            + m.y * m.y / (self.alpha_y * self.alpha_y))
            / z2;
        let norm = PI * self.alpha_x * self.alpha_y * z2 * z2;
        let v = match self.dist {
            Distribution::Ggx => 1.0 / (norm * (1.0 + e) * (1.0 + e)),
            Distribution::Beckmann => (-e).exp() / norm,
        };
        if v.is_finite() {
            v
        } else {
            0.0
        }
    }

    /// Smith `Lambda(w)` (Heitz 2014 eqs. 72 and 86), using the projected roughness
    /// `alpha_0 = sqrt(cos^2 phi alpha_x^2 + sin^2 phi alpha_y^2)`.
    pub fn lambda(&self, w: DVec3) -> f64 {
        let t2 = self.alpha_x * self.alpha_x * w.x * w.x + self.alpha_y * self.alpha_y * w.y * w.y;
        if t2 <= 0.0 {
            return 0.0;
        }
        let z2 = w.z * w.z;
        if z2 == 0.0 {
            return f64::INFINITY;
        }
        match self.dist {
            Distribution::Ggx => 0.5 * (-1.0 + (1.0 + t2 / z2).sqrt()),
            Distribution::Beckmann => {
                // a = 1 / (alpha_0 tan theta)
                let a = (z2 / t2).sqrt();
                if a > 8.0 {
                    return 0.0;
                }
                0.5 * (erf(a) - 1.0) + (-a * a).exp() / (2.0 * a * PI.sqrt())
            }
        }
    }

    /// Smith monodirectional masking `G1(w, m) = chi+(w.m / w.n) / (1 + Lambda(w))`
    /// (Walter 2007 eq. 27 for Beckmann's rational form, eq. 34 for GGX).
    pub fn g1(&self, w: DVec3, m: DVec3) -> f64 {
        if w.dot(m) * w.z <= 0.0 {
            return 0.0;
        }
        1.0 / (1.0 + self.lambda(w))
    }

    /// Separable shadowing-masking `G(wi, wo, m) = G1(wi, m) G1(wo, m)` (Walter 2007
    /// eq. 23). Reciprocal.
    pub fn g(&self, wi: DVec3, wo: DVec3, m: DVec3) -> f64 {
        self.g1(wi, m) * self.g1(wo, m)
    }

    /// Density of visible normals `D_w(m) = G1(w, m) |w.m| D(m) / |w.z|` (Heitz 2014
    /// eq. 2), per unit solid angle of `m`. `w` may be on either side: the distribution is
    /// that of normals visible from `w` mirrored into the upper hemisphere.
    pub fn visible_pdf(&self, w: DVec3, m: DVec3) -> f64 {
        let wu = if w.z < 0.0 { -w } else { w };
        if wu.z <= 0.0 {
            return 0.0;
        }
        self.g1(wu, m) * wu.dot(m).max(0.0) * self.d(m) / wu.z
    }

    /// Samples a normal visible from `w` (either side; see [`Self::visible_pdf`]).
    /// GGX: Heitz 2018 "Sampling the GGX distribution of visible normals"; Beckmann:
    /// Heitz & d'Eon 2014 stretched-slope sampling with a Newton-bisection inversion of the
    /// visible-slope CDF.
    pub fn sample_visible(&self, w: DVec3, u: [f64; 2]) -> DVec3 {
        let wu = if w.z < 0.0 { -w } else { w };
        match self.dist {
            Distribution::Ggx => self.sample_visible_ggx(wu, u),
            Distribution::Beckmann => self.sample_visible_beckmann(wu, u),
        }
    }

    fn sample_visible_ggx(&self, w: DVec3, u: [f64; 2]) -> DVec3 {
        // Heitz 2018, listing 1: stretch, sample the projected hemisphere, unstretch.
        let vh = DVec3::new(self.alpha_x * w.x, self.alpha_y * w.y, w.z)
            .try_normalize()
            .unwrap_or(DVec3::Z);
        let lensq = vh.x * vh.x + vh.y * vh.y;
        let t1 = if lensq > 0.0 {
            DVec3::new(-vh.y, vh.x, 0.0) * (1.0 / lensq.sqrt())
        } else {
            DVec3::new(1.0, 0.0, 0.0)
        };
        let t2 = vh.cross(t1);
        let r = u[0].sqrt();
        let phi = 2.0 * PI * u[1];
        let p1 = r * phi.cos();
        let mut p2 = r * phi.sin();
        let s = 0.5 * (1.0 + vh.z);
        p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
        let nh = t1 * p1 + t2 * p2 + vh * (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        DVec3::new(self.alpha_x * nh.x, self.alpha_y * nh.y, nh.z.max(0.0))
            .try_normalize()
            .unwrap_or(DVec3::Z)
    }

    fn sample_visible_beckmann(&self, w: DVec3, u: [f64; 2]) -> DVec3 {
        // Heitz & d'Eon 2014, section 4: stretch, sample unit-roughness slopes, rotate,
        // unstretch.
        let ws = DVec3::new(self.alpha_x * w.x, self.alpha_y * w.y, w.z)
            .try_normalize()
            .unwrap_or(DVec3::Z);
        let theta = ws.theta();
        let phi = if ws.x == 0.0 && ws.y == 0.0 {
            0.0
        } else {
            ws.phi()
        };
        let (sx, sy) = beckmann_visible_slopes(theta, u);
        let (sp, cp) = phi.sin_cos();
        let (rx, ry) = (cp * sx - sp * sy, sp * sx + cp * sy);
        DVec3::new(-rx * self.alpha_x, -ry * self.alpha_y, 1.0)
            .try_normalize()
            .unwrap_or(DVec3::Z)
    }
}

/// Samples the slopes of unit-roughness Beckmann normals visible from a direction at polar
/// angle `theta` in the xz half-plane with positive x.
///
/// The visible-slope density in x is `exp(-x^2) (1 - x tan theta)` on `x < cot theta`; its
/// CDF is `sqrt(pi)/2 (1 + erf x) + tan theta / 2 exp(-x^2)` (Heitz & d'Eon 2014 eq. 11).
/// The y slope is an independent Gaussian `exp(-y^2)/sqrt(pi)`.
fn beckmann_visible_slopes(theta: f64, u: [f64; 2]) -> (f64, f64) {
    let uy = u[1].clamp(1e-12, 1.0 - 1e-12);
    let sy = erf_inv(2.0 * uy - 1.0);
    if theta < 1e-6 {
        // Normal incidence: the x slope is Gaussian as well.
        let ux = u[0].clamp(1e-12, 1.0 - 1e-12);
        return (erf_inv(2.0 * ux - 1.0), sy);
    }
    let tan_t = theta.tan();
    let cot_t = 1.0 / tan_t;
    let sqrt_pi = PI.sqrt();
    let cdf = |x: f64| 0.5 * sqrt_pi * (1.0 + erf(x)) + 0.5 * tan_t * (-x * x).exp();
    let total = cdf(cot_t);
    let target = u[0].clamp(1e-12, 1.0 - 1e-12) * total;
    // Bracket: density vanishes below about -6.
    let (mut lo, mut hi) = (-7.0_f64, cot_t);
    let mut x = 0.5 * (lo + hi);
    for _ in 0..100 {
        let v = cdf(x) - target;
        if v > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        if (hi - lo) < 1e-13 * (1.0 + x.abs()) {
            break;
        }
        let d = (-x * x).exp() * (1.0 - x * tan_t);
        let mut nx = if d > 0.0 { x - v / d } else { f64::NAN };
        if !(nx > lo && nx < hi) {
            nx = 0.5 * (lo + hi);
        }
        if (nx - x).abs() < 1e-14 * (1.0 + x.abs()) {
            x = nx;
            break;
        }
        x = nx;
    }
    (x, sy)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spherical::from_spherical;

    /// `int D(m) cos theta_m dm = 1` by midpoint quadrature in (theta, phi).
    #[test]
    fn ndf_is_normalised() {
        for dist in [Distribution::Ggx, Distribution::Beckmann] {
            for (ax, ay) in [(0.1, 0.1), (0.5, 0.2), (1.0, 1.0)] {
                let mf = Microfacet::new(dist, ax, ay);
                let (nt, np) = (2000, 200);
                let mut s = 0.0;
                for i in 0..nt {
                    let t = (i as f64 + 0.5) / nt as f64 * PI / 2.0;
                    for j in 0..np {
                        let p = (j as f64 + 0.5) / np as f64 * 2.0 * PI;
                        let m = from_spherical(t, p);
                        s += mf.d(m) * m.z * t.sin();
                    }
                }
                s *= (PI / 2.0 / nt as f64) * (2.0 * PI / np as f64);
                assert!((s - 1.0).abs() < 2e-3, "{dist:?} {ax} {ay}: {s}");
            }
        }
    }
}
