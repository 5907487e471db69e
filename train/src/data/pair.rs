//! A training pair, its domain coordinates, and incidence bands.

use diffbsdf::spec::NORMAL_INCIDENCE_RHO;
use diffbsdf::Domain;
use diffbsdf_materials::symmetry::{apply_signs, fold_signs};
use diffbsdf_materials::{DVec3, IncidentFold, Material, Spherical};
use std::f64::consts::PI;

/// What the trainer needs of the kernel's [`Domain`] beyond its flow maps: which
/// directions it holds and the target density there.
pub trait DomainTarget {
    /// True when `wo` belongs to the domain (disk: `wo.z > 0`; sphere: off the horizon).
    fn contains(self, wo: DVec3) -> bool;

    /// Unnormalised target per unit solid angle: `Y(f) |cos theta_o|` inside the domain.
    fn target(self, m: &dyn Material, wi: DVec3, wo: DVec3) -> f64;
}

impl DomainTarget for Domain {
    fn contains(self, wo: DVec3) -> bool {
        match self {
            Domain::Disk | Domain::HalfVector => wo.z > 0.0,
            Domain::Sphere | Domain::Equatorial => wo.z != 0.0,
        }
    }

    fn target(self, m: &dyn Material, wi: DVec3, wo: DVec3) -> f64 {
        if !self.contains(wo) {
            return 0.0;
        }
        let v = m.eval_luminance(wi, wo) * wo.z.abs();
        if v.is_finite() && v > 0.0 {
            v
        } else {
            0.0
        }
    }
}

/// A band of incidence `theta_i` in radians, `0 <= min < max <= pi`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    /// Lower polar angle of `wi`.
    pub theta_min: f64,
    /// Upper polar angle of `wi`.
    pub theta_max: f64,
}

impl Band {
    /// `count` equal bands covering `[0, pi/2]` (or `[0, pi]` when `both_sides`).
    pub fn split(count: usize, both_sides: bool) -> Vec<Band> {
        let top = if both_sides { PI } else { PI / 2.0 };
        let n = count.max(1);
        (0..n)
            .map(|i| Band {
                theta_min: top * i as f64 / n as f64,
                theta_max: top * (i + 1) as f64 / n as f64,
            })
            .collect()
    }

    /// True when `w` has its polar angle inside the band.
    pub fn contains(&self, w: DVec3) -> bool {
        let t = w.theta();
        t >= self.theta_min && t <= self.theta_max
    }

    /// A direction uniform in solid angle inside the band, from `u` in `[0,1)^2`.
    pub fn sample_uniform(&self, u: [f64; 2]) -> DVec3 {
        let (c0, c1) = (self.theta_min.cos(), self.theta_max.cos());
        let z = c0 + (c1 - c0) * u[0];
        let s = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * u[1];
        DVec3::new(s * phi.cos(), s * phi.sin(), z)
    }
}

impl Band {
    /// A direction with `theta` uniform in angle inside the band and `phi` uniform, from
    /// `u` in `[0,1)^2`. For isotropic fits, whose nets see `theta_i` alone: solid-angle
    /// sampling would give `theta_i` the density `sin(theta_i)`, starving normal incidence.
    pub fn sample_uniform_angle(&self, u: [f64; 2]) -> DVec3 {
        let theta = self.theta_min + (self.theta_max - self.theta_min) * u[0];
        let phi = 2.0 * PI * u[1];
        let s = theta.sin();
        DVec3::new(s * phi.cos(), s * phi.sin(), theta.cos())
    }
}

/// One training pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair {
    /// Fixed direction.
    pub wi: DVec3,
    /// Direction drawn from the target given `wi`.
    pub wo: DVec3,
}

impl Pair {
    /// The pair turned about the normal so that `wi` has `phi = 0`: the kernel's
    /// `diffbsdf::internals::frame::IncidentFrame` (same rotation `R(-phi_i)`, same
    /// normal-incidence threshold `spec::NORMAL_INCIDENCE_RHO`) in f64, so that training
    /// pairs are rounded to f32 once.
    pub fn in_incident_frame(&self) -> Pair {
        let rho = (self.wi.x * self.wi.x + self.wi.y * self.wi.y).sqrt();
        if !(rho > f64::from(NORMAL_INCIDENCE_RHO)) {
            return *self;
        }
        let (c, s) = (self.wi.x / rho, self.wi.y / rho);
        // R(-phi_i) w = (c x + s y, c y - s x, z), as IncidentFrame::to_local.
        let turn = |w: DVec3| DVec3::new(c * w.x + s * w.y, c * w.y - s * w.x, w.z);
        Pair {
            wi: turn(self.wi),
            wo: turn(self.wo),
        }
    }
}

impl Pair {
    /// The pair folded into the part of the turn `fold` keeps: both directions' signs
    /// changed by [`diffbsdf_materials::symmetry::fold_signs`] of `wi` (the kernel's
    /// `IncidentFrame::folding`), for a material with that symmetry.
    pub fn folded(&self, fold: IncidentFold) -> Pair {
        let signs = fold_signs(fold, self.wi);
        Pair {
            wi: apply_signs(signs, self.wi),
            wo: apply_signs(signs, self.wo),
        }
    }
}

/// Generated pairs with throughput figures.
#[derive(Clone, Debug)]
pub struct Generated {
    /// The pairs.
    pub pairs: Vec<Pair>,
    /// Wall-clock seconds spent.
    pub seconds: f64,
    /// Number of `eval` calls (MCMC) or sampler calls (exact).
    pub evaluations: u64,
    /// Mean acceptance rate (MCMC) or fraction of valid candidates (exact).
    pub acceptance: f64,
}

impl Generated {
    /// Pairs per second of wall-clock time.
    pub fn pairs_per_second(&self) -> f64 {
        if self.seconds > 0.0 {
            self.pairs.len() as f64 / self.seconds
        } else {
            f64::INFINITY
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use diffbsdf::glam;
    use diffbsdf::internals::frame::IncidentFrame;

    #[test]
    fn incident_frame_is_the_kernels() {
        let f32s = |w: DVec3| glam::Vec3::new(w.x as f32, w.y as f32, w.z as f32);
        for (wi, wo) in [
            (
                DVec3::new(-0.3, 0.5, 0.812_403_8),
                DVec3::new(0.6, 0.0, 0.8),
            ),
            (DVec3::new(0.0, -0.6, -0.8), DVec3::new(-0.48, 0.64, 0.6)),
            (DVec3::new(1e-20, -1e-20, 1.0), DVec3::new(0.0, 0.6, 0.8)),
        ] {
            let p = Pair { wi, wo }.in_incident_frame();
            let frame = IncidentFrame::aligning(f32s(wi));
            for (mine, w) in [(p.wi, wi), (p.wo, wo)] {
                let kernel = frame.to_local(f32s(w));
                assert!((f32s(mine) - kernel).length() < 1e-6, "{mine:?} {kernel:?}");
            }
        }
    }

    /// Folded pairs are the kernel's folding of them, bit for bit after rounding (sign
    /// changes are exact), and `wi` lands in the kept azimuths.
    #[test]
    fn folded_pair_is_the_kernels() {
        let f32s = |w: DVec3| glam::Vec3::new(w.x as f32, w.y as f32, w.z as f32);
        for fold in [IncidentFold::HalfTurn, IncidentFold::Quarter] {
            let (start, span) = fold.kept_azimuths();
            for (wi, wo) in [
                (DVec3::new(-0.3, 0.5, 0.8124), DVec3::new(0.6, 0.0, 0.8)),
                (DVec3::new(0.3, -0.5, 0.8124), DVec3::new(-0.48, 0.64, 0.6)),
                (DVec3::new(0.3, 0.5, -0.8124), DVec3::new(0.0, 0.6, 0.8)),
                (DVec3::new(-0.3, -0.5, 0.8124), DVec3::new(0.0, -0.6, 0.8)),
            ] {
                let p = Pair { wi, wo }.folded(fold);
                let frame = IncidentFrame::folding(f32s(wi), fold);
                assert_eq!(f32s(p.wi), frame.to_local(f32s(wi)));
                assert_eq!(f32s(p.wo), frame.to_local(f32s(wo)));
                let phi = p.wi.y.atan2(p.wi.x) as f32;
                assert!((start..=start + span).contains(&phi), "{fold:?} {phi}");
            }
        }
    }
}
