//! A hemisphere material seen through a radial warp of the projected disk built from the
//! material's own profile: the disk point `y` of this material's direction stands for the
//! inner material's disk point `x = y R(|y|) / |y|`, where `R` flattens the radial profile
//! of the inner material's target `Y(f) |cos|` at normal incidence, mixed with a share
//! `eps` of the uniform disk.
//!
//! The profile is tabulated on `BINS` rings with edges `r_b = (b / BINS)^2` (fine at the
//! centre, where a specular spike sits) from the inner material's own samples,
//! importance-weighted: at normal incidence (`theta_max = 0`), or averaged over
//! `INCIDENCES` incidences `theta_i` in `[0, theta_max]` (each normalised, so each counts
//! alike) for a profile of where the target lies at every incidence. Within a ring the map has constant areal density:
//! `|y|^2 = C_b + a_b (|x|^2 - r_b^2)`, with `C_b` the mixture's mass inside `r_b` and
//! `a_b` its mass in the ring over the ring's area; so the map's determinant is
//! `dA_x / dA_y = 1 / a_b`, constant per ring, and a target that follows the profile has
//! a flat density in `y`.
//!
//! Densities per unit solid angle change by `F = (d.z / d'.z) / a_b` (`d` this material's
//! direction, `d'` the inner one), and `f_d(wi, d) = f(wi, d') / a_b`, so importance
//! weights are unchanged.

use crate::{DVec3, Material, MaterialSample, Rgb};

/// Rings of the profile.
const BINS: usize = 256;
/// Samples of the inner material that estimate the profile, over all incidences.
const PROFILE_SAMPLES: usize = 1 << 20;
/// Incidences of an averaged profile, `theta_i` at the midpoints of equal bands of
/// `[0, theta_max]`.
const INCIDENCES: usize = 16;

/// The radially warped view of a reflection-only material.
#[derive(Debug)]
pub struct Radial {
    inner: Box<dyn Material>,
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
        let incidences = if theta_max_deg > 0.0 { INCIDENCES } else { 1 };
        let theta_max = theta_max_deg.to_radians();
        let edges: Vec<f64> = (0..=BINS)
            .map(|b| (b as f64 / BINS as f64).powi(2))
            .collect();
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
        Some(Radial {
            inner,
            eps,
            theta_max_deg,
            edges,
            mass,
            density,
        })
    }

    /// The ring of inner radius `r` (`r_b <= r < r_{b+1}`, the last ring for `r = 1`).
    fn ring_of_radius(&self, r: f64) -> usize {
        self.edges[1..].partition_point(|&e| e <= r).min(BINS - 1)
    }

    /// The ring holding the mass `c` (`C_b <= c < C_{b+1}`).
    fn ring_of_mass(&self, c: f64) -> usize {
        self.mass[1..].partition_point(|&m| m <= c).min(BINS - 1)
    }

    /// `|x|` of the point `|y| = rho`, and `a_b`.
    fn inner_radius(&self, rho: f64) -> (f64, f64) {
        let c = (rho * rho).min(1.0);
        let b = self.ring_of_mass(c);
        let r2 = self.edges[b] * self.edges[b] + (c - self.mass[b]) / self.density[b];
        (r2.clamp(0.0, 1.0).sqrt(), self.density[b])
    }

    /// `|y|` of the inner point `|x| = r`, and `a_b`.
    fn outer_radius(&self, r: f64) -> (f64, f64) {
        let b = self.ring_of_radius(r);
        let c = self.mass[b] + self.density[b] * (r * r - self.edges[b] * self.edges[b]);
        (c.clamp(0.0, 1.0).sqrt(), self.density[b])
    }

    /// The direction on the disk point `p` scaled to radius `to` from radius `from`.
    fn rescale(d: DVec3, from: f64, to: f64) -> Option<DVec3> {
        let s = if from > 1e-300 { to / from } else { 0.0 };
        let (x, y) = (d.x * s, d.y * s);
        let z = (1.0 - x * x - y * y).max(0.0).sqrt();
        (z > 0.0).then_some(DVec3::new(x, y, z))
    }

    /// The inner direction of `d` and `a_b`; `None` below the surface.
    fn inner_of(&self, d: DVec3) -> Option<(DVec3, f64)> {
        if !(d.z > 0.0) {
            return None;
        }
        let rho = (d.x * d.x + d.y * d.y).sqrt().min(1.0);
        let (r, a) = self.inner_radius(rho);
        Some((Radial::rescale(d, rho, r)?, a))
    }
}

impl Material for Radial {
    fn name(&self) -> &'static str {
        "radial"
    }

    fn spec(&self) -> String {
        format!(
            "radial:{}:{}:{}",
            self.eps,
            self.theta_max_deg,
            self.inner.spec()
        )
    }

    fn eval(&self, wi: DVec3, d: DVec3) -> Rgb {
        match self.inner_of(d) {
            Some((dp, a)) => self.inner.eval(wi, dp) * (1.0 / a),
            None => Rgb::ZERO,
        }
    }

    fn sample(&self, wi: DVec3, u: [f64; 3]) -> Option<MaterialSample> {
        let s = self.inner.sample(wi, u)?;
        if !(s.wo.z > 0.0) {
            return None;
        }
        let r = (s.wo.x * s.wo.x + s.wo.y * s.wo.y).sqrt().min(1.0);
        let (rho, a) = self.outer_radius(r);
        let d = Radial::rescale(s.wo, r, rho)?;
        let pdf = s.pdf * (d.z / s.wo.z) / a;
        (pdf > 0.0 && pdf.is_finite()).then_some(MaterialSample {
            wo: d,
            pdf,
            weight: s.weight,
        })
    }

    fn pdf(&self, wi: DVec3, d: DVec3) -> f64 {
        match self.inner_of(d) {
            Some((dp, a)) => self.inner.pdf(wi, dp) * (d.z / dp.z) / a,
            None => 0.0,
        }
    }

    fn is_transmissive(&self) -> bool {
        false
    }

    fn is_isotropic(&self) -> bool {
        self.inner.is_isotropic()
    }
}

#[cfg(test)]
mod tests {
    use crate::parse_spec;
    use crate::DVec3;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// The sampler's PDF and weights agree with `pdf` and `eval` in the warped chart, the
    /// warp inverts itself, and the mean weight (the albedo) is the inner material's.
    #[test]
    fn weights_densities_and_albedo_survive_the_warp() {
        for spec in [
            "radial:0.25:0:halfway:conductor:ggx,alpha=0.05,metal=Cu",
            "radial:0.05:89.5:halfway:conductor:ggx,alpha=0.05,metal=Cu",
            "radial:0.5:60:lambertian",
        ] {
            let m = parse_spec(spec).unwrap();
            let inner = parse_spec(spec.splitn(4, ':').nth(3).unwrap()).unwrap();
            let wi = DVec3::new(0.6, 0.0, 0.8);
            let mut rng = Pcg64::seed_from_u64(7);
            let (mut a, mut b) = (0.0, 0.0);
            for _ in 0..20_000 {
                let u: [f64; 3] = [rng.gen(), rng.gen(), rng.gen()];
                if let Some(s) = m.sample(wi, u) {
                    let pdf = m.pdf(wi, s.wo);
                    assert!(
                        (pdf - s.pdf).abs() <= 1e-7 * s.pdf,
                        "{spec}: {pdf} vs {}",
                        s.pdf
                    );
                    let w = m.eval_cos(wi, s.wo).luminance() / s.pdf;
                    assert!(
                        (w - s.weight.luminance()).abs() <= 1e-7 * w.max(1.0),
                        "{spec}"
                    );
                    a += w;
                }
                if let Some(s) = inner.sample(wi, u) {
                    b += s.weight.luminance();
                }
            }
            assert!((a - b).abs() < 0.02 * b, "{spec}: {a} vs {b}");
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
