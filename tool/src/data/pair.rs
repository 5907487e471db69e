//! A training pair, its domain coordinates, and incidence bands.

use crate::material::{Material, Vec3};
use std::f64::consts::PI;

/// The sampling domain of the learned model (DESIGN.md, "The math").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// `x = (wo.x, wo.y)` on the unit disk (BRDFs); `wo.z > 0`.
    Disk,
    /// `x = (theta_o, phi_o)` on the whole sphere.
    Sphere,
}

impl Domain {
    /// True when `wo` belongs to the domain.
    pub fn contains(self, wo: Vec3) -> bool {
        match self {
            Domain::Disk => wo.z > 0.0,
            Domain::Sphere => wo.z != 0.0,
        }
    }

    /// Unnormalised target per unit solid angle: `Y(f) |cos theta_o|` inside the domain.
    pub fn target(self, m: &dyn Material, wi: Vec3, wo: Vec3) -> f64 {
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
    pub fn contains(&self, w: Vec3) -> bool {
        let t = w.theta();
        t >= self.theta_min && t <= self.theta_max
    }

    /// A direction uniform in solid angle inside the band, from `u` in `[0,1)^2`.
    pub fn sample_uniform(&self, u: [f64; 2]) -> Vec3 {
        let (c0, c1) = (self.theta_min.cos(), self.theta_max.cos());
        let z = c0 + (c1 - c0) * u[0];
        let s = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * u[1];
        Vec3::new(s * phi.cos(), s * phi.sin(), z)
    }
}

impl Band {
    /// A direction with `theta` uniform in angle inside the band and `phi` uniform, from
    /// `u` in `[0,1)^2`. For isotropic fits, whose nets see `theta_i` alone: solid-angle
    /// sampling would give `theta_i` the density `sin(theta_i)`, starving normal incidence.
    pub fn sample_uniform_angle(&self, u: [f64; 2]) -> Vec3 {
        let theta = self.theta_min + (self.theta_max - self.theta_min) * u[0];
        let phi = 2.0 * PI * u[1];
        let s = theta.sin();
        Vec3::new(s * phi.cos(), s * phi.sin(), theta.cos())
    }
}

/// One training pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair {
    /// Fixed direction.
    pub wi: Vec3,
    /// Direction drawn from the target given `wi`.
    pub wo: Vec3,
}

impl Pair {
    /// The pair turned about the normal so that `wi` has `phi = 0` (the frame of an
    /// isotropic model, `diffbsdf::internals::frame::IncidentFrame`); unchanged at normal incidence.
    pub fn in_incident_frame(&self) -> Pair {
        let rho = (self.wi.x * self.wi.x + self.wi.y * self.wi.y).sqrt();
        if !(rho > f64::from(diffbsdf::spec::NORMAL_INCIDENCE_RHO)) {
            return *self;
        }
        let (c, s) = (self.wi.x / rho, self.wi.y / rho);
        // R(-phi_i) w = (c x + s y, c y - s x, z)
        let turn = |w: Vec3| Vec3::new(c * w.x + s * w.y, c * w.y - s * w.x, w.z);
        Pair {
            wi: turn(self.wi),
            wo: turn(self.wo),
        }
    }

    /// Disk coordinates `(wo.x, wo.y)`.
    pub fn disk(&self) -> [f64; 2] {
        [self.wo.x, self.wo.y]
    }

    /// Sphere coordinates `(theta_o, phi_o)`, `phi_o` in `(-pi, pi]`.
    pub fn sphere(&self) -> [f64; 2] {
        [self.wo.theta(), self.wo.phi()]
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
