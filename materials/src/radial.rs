//! A hemisphere material seen through a radial warp of the projected disk built from the
//! material's own profile ([`crate::disk_view`]): `R` flattens the radial profile of the
//! inner material's target `Y(f) |cos|`, mixed with a share `eps` of the uniform disk.
//!
//! The profile is tabulated on `BINS` rings with edges `r_b = (b / BINS)^2` (fine at the
//! centre, where a specular spike sits) from the inner material's own samples,
//! importance-weighted: at normal incidence (`theta_max = 0`), or averaged over
//! `INCIDENCES` incidences `theta_i` in `[0, theta_max]` (each normalised, so each counts
//! alike) for a profile of where the target lies at every incidence. Within a ring the
//! map has constant areal density: `|y|^2 = C_b + a_b (|x|^2 - r_b^2)`, with `C_b` the
//! mixture's mass inside `r_b` and `a_b` its mass in the ring over the ring's area; so
//! the map's determinant is `J = dA_x / dA_y = 1 / a_b`, constant per ring, and a target
//! that follows the profile has a flat density in `y`.

use crate::disk_view::{DiskView, RadialMap};
use crate::{DVec3, Material};

/// Rings of the profile.
const BINS: usize = 256;
/// Samples of the inner material that estimate the profile, over all incidences.
const PROFILE_SAMPLES: usize = 1 << 20;
/// Incidences of an averaged profile, `theta_i` at the midpoints of equal bands of
/// `[0, theta_max]`.
const INCIDENCES: usize = 16;

/// The radially warped view of a reflection-only material.
pub type Radial = DiskView<ProfileMap>;

/// The warp's radial map, built from a material's profile.
#[derive(Clone, Debug)]
pub struct ProfileMap {
    eps: f64,
    /// Largest incidence of the profile (degrees; 0: normal incidence alone).
    theta_max_deg: f64,
    /// Ring edges `r_b`, `BINS + 1` of them, from 0 to 1.
    edges: Vec<f64>,
    /// The mixture's mass inside each edge, `BINS + 1` values from 0 to 1.
    mass: Vec<f64>,
    /// Areal density of the mixture in each ring, `a_b`.
    density: Vec<f64>,
}

/// The `i`-th point of the three-dimensional Kronecker sequence with the plastic-number
/// ratios (deterministic, evenly spread).
fn kronecker(i: usize) -> [f64; 3] {
    // phi_3 = 1.2207..., the real root of x^4 = x + 1
    const G: f64 = 1.220_744_084_605_759_5;
    let a = [1.0 / G, 1.0 / (G * G), 1.0 / (G * G * G)];
    a.map(|a| (0.5 + a * i as f64).fract())
}

impl Radial {
    /// Wraps `inner` with a uniform share `eps` in (0, 1] and the profile's largest
    /// incidence `theta_max_deg` in [0, 90) degrees; `None` for a transmissive material,
    /// a value out of range, or a material that reflects nothing at those incidences.
    pub fn new(inner: Box<dyn Material>, eps: f64, theta_max_deg: f64) -> Option<Radial> {
        let in_range = eps > 0.0 && eps <= 1.0 && (0.0..90.0).contains(&theta_max_deg);
        if inner.is_transmissive() || !in_range {
            return None;
        }
        let ring = ring_profile(inner.as_ref(), theta_max_deg);
        let edges: Vec<f64> = (0..=BINS)
            .map(|b| (b as f64 / BINS as f64).powi(2))
            .collect();
        let total: f64 = ring.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut mass = vec![0.0f64; BINS + 1];
        let mut density = vec![0.0f64; BINS];
        for b in 0..BINS {
            let area = edges[b + 1] * edges[b + 1] - edges[b] * edges[b];
            let m = (1.0 - eps) * ring[b] / total + eps * area;
            mass[b + 1] = mass[b] + m;
            density[b] = m / area;
        }
        // The last edge holds all of the mass (rounding aside).
        let end = mass[BINS];
        mass.iter_mut().for_each(|m| *m /= end);
        density.iter_mut().for_each(|d| *d /= end);
        let map = ProfileMap {
            eps,
            theta_max_deg,
            edges,
            mass,
            density,
        };
        DiskView::with_map(inner, map)
    }
}

/// The target's mass per ring `(r_b, r_{b+1})`, `r_b = (b / BINS)^2` (unnormalised): from
/// the material's own samples, importance-weighted, at normal incidence (`theta_max_deg`
/// = 0) or summed over `INCIDENCES` incidences up to `theta_max_deg`, each normalised.
fn ring_profile(inner: &dyn Material, theta_max_deg: f64) -> Vec<f64> {
    let incidences = if theta_max_deg > 0.0 { INCIDENCES } else { 1 };
    let theta_max = theta_max_deg.to_radians();
    let mut ring = vec![0.0f64; BINS];
    for j in 0..incidences {
        let theta = theta_max * (j as f64 + 0.5) / incidences as f64;
        let wi = DVec3::new(theta.sin(), 0.0, theta.cos());
        let mut here = vec![0.0f64; BINS];
        for i in 0..PROFILE_SAMPLES / incidences {
            let Some(s) = inner.sample(wi, kronecker(i)) else {
                continue;
            };
            let w = s.weight.luminance();
            if !(s.wo.z > 0.0 && w > 0.0 && w.is_finite()) {
                continue;
            }
            let r = (s.wo.x * s.wo.x + s.wo.y * s.wo.y).sqrt().min(1.0);
            let b = ((r.sqrt() * BINS as f64) as usize).min(BINS - 1);
            here[b] += w;
        }
        // every incidence counts alike
        let sum: f64 = here.iter().sum();
        if sum > 0.0 && sum.is_finite() {
            ring.iter_mut().zip(&here).for_each(|(r, h)| *r += h / sum);
        }
    }
    ring
}

impl ProfileMap {
    /// The ring of inner radius `r` (`r_b <= r < r_{b+1}`, the last ring for `r = 1`).
    fn ring_of_radius(&self, r: f64) -> usize {
        self.edges[1..].partition_point(|&e| e <= r).min(BINS - 1)
    }

    /// The ring holding the mass `c` (`C_b <= c < C_{b+1}`).
    fn ring_of_mass(&self, c: f64) -> usize {
        self.mass[1..].partition_point(|&m| m <= c).min(BINS - 1)
    }

    /// `|x|` of the point `|y| = rho`, and `a_b`.
    fn radius_of_mass(&self, rho: f64) -> (f64, f64) {
        let c = (rho * rho).min(1.0);
        let b = self.ring_of_mass(c);
        let r2 = self.edges[b] * self.edges[b] + (c - self.mass[b]) / self.density[b];
        (r2.clamp(0.0, 1.0).sqrt(), self.density[b])
    }

    /// `|y|` of the inner point `|x| = r`, and `a_b`.
    fn mass_radius(&self, r: f64) -> (f64, f64) {
        let b = self.ring_of_radius(r);
        let c = self.mass[b] + self.density[b] * (r * r - self.edges[b] * self.edges[b]);
        (c.clamp(0.0, 1.0).sqrt(), self.density[b])
    }
}

impl RadialMap for ProfileMap {
    fn name(&self) -> &'static str {
        "radial"
    }

    fn spec_prefix(&self) -> String {
        format!("radial:{}:{}", self.eps, self.theta_max_deg)
    }

    fn inner_radius(&self, rho: f64) -> (f64, f64) {
        let (r, a) = self.radius_of_mass(rho);
        (r, 1.0 / a)
    }

    fn outer_radius(&self, r: f64) -> (f64, f64) {
        let (rho, a) = self.mass_radius(r);
        (rho, 1.0 / a)
    }

    fn centre_ratio(&self) -> f64 {
        1.0 / self.density[0].sqrt()
    }
}

#[cfg(test)]
mod tests {
    use crate::disk_view::checks::assert_view_keeps_weights;
    use crate::parse_spec;
    use crate::DVec3;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// The sampler's PDF and weights agree with `pdf` and `eval` in the warped chart (the
    /// warp inverts itself), and the mean weight (the albedo) is the inner material's.
    #[test]
    fn weights_densities_and_albedo_survive_the_warp() {
        let copper = "halfway:conductor:ggx,alpha=0.05,metal=Cu";
        for (spec, inner) in [
            (format!("radial:0.25:0:{copper}"), copper),
            (format!("radial:0.05:89.5:{copper}"), copper),
            ("radial:0.5:60:lambertian".to_string(), "lambertian"),
        ] {
            assert_view_keeps_weights(&spec, inner, 1e-7);
        }
    }

    /// At normal incidence the warped target of a narrow lobe is spread out: its samples'
    /// mean radius in the warped chart is far larger than in the inner one.
    #[test]
    fn the_warp_spreads_a_narrow_lobe() {
        let m = parse_spec("radial:0.25:0:halfway:conductor:ggx,alpha=0.05,metal=Cu").unwrap();
        let inner = parse_spec("halfway:conductor:ggx,alpha=0.05,metal=Cu").unwrap();
        let n = DVec3::new(0.0, 0.0, 1.0);
        let mut rng = Pcg64::seed_from_u64(3);
        let (mut rm, mut ri) = (0.0, 0.0);
        for _ in 0..5_000 {
            let u: [f64; 3] = [rng.gen(), rng.gen(), rng.gen()];
            let (Some(s), Some(t)) = (m.sample(n, u), inner.sample(n, u)) else {
                continue;
            };
            rm += (s.wo.x * s.wo.x + s.wo.y * s.wo.y).sqrt();
            ri += (t.wo.x * t.wo.x + t.wo.y * t.wo.y).sqrt();
        }
        assert!(rm > 5.0 * ri, "{rm} vs {ri}");
    }
}
