//! Where the flow lives: the map between flow points `x` and directions, the measure
//! change to solid angle, the features the velocity net sees and how a step moves `x`.

pub mod disk;
pub mod equatorial;
pub mod half_vector;
pub mod sphere;

use crate::def::Domain;
use crate::spec::MAX_FEATURES;
use glam::Vec3;

impl Domain {
    /// Velocity-net features of `x`.
    #[inline(always)]
    #[must_use]
    pub fn features(self, x: [f32; 2]) -> [f32; MAX_FEATURES] {
        match self {
            Domain::Disk | Domain::HalfVector => [x[0], x[1], 0.0],
            Domain::Sphere | Domain::Equatorial => {
                let (s, c) = crate::math::sin_cos(x[1]);
                [x[0], s, c]
            }
        }
    }

    /// Features of `x` and their derivatives along `x_0` and `x_1`.
    #[inline(always)]
    #[must_use]
    pub fn features_with_derivative(
        self,
        x: [f32; 2],
    ) -> ([f32; MAX_FEATURES], [[f32; MAX_FEATURES]; 2]) {
        match self {
            Domain::Disk | Domain::HalfVector => {
                ([x[0], x[1], 0.0], [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
            }
            Domain::Sphere | Domain::Equatorial => {
                let (s, c) = crate::math::sin_cos(x[1]);
                ([x[0], s, c], [[1.0, 0.0, 0.0], [0.0, c, -s]])
            }
        }
    }

    /// `x + d`, with phi wrapped on the sphere.
    #[inline(always)]
    #[must_use]
    pub fn advance(self, x: [f32; 2], d: [f32; 2]) -> [f32; 2] {
        match self {
            Domain::Disk | Domain::HalfVector => [x[0] + d[0], x[1] + d[1]],
            Domain::Sphere | Domain::Equatorial => [x[0] + d[0], sphere::wrap(x[1] + d[1])],
        }
    }

    /// `a - b`, with the phi difference taken the short way round on the sphere.
    #[inline(always)]
    #[must_use]
    pub fn difference(self, a: [f32; 2], b: [f32; 2]) -> [f32; 2] {
        match self {
            Domain::Disk | Domain::HalfVector => [a[0] - b[0], a[1] - b[1]],
            Domain::Sphere | Domain::Equatorial => [a[0] - b[0], sphere::wrap(a[1] - b[1])],
        }
    }

    /// The direction of a flow point for incident `wi` (in the model's frame; only the
    /// half-vector chart depends on it); `None` outside the domain.
    #[inline]
    #[must_use]
    pub fn to_direction(self, x: [f32; 2], wi: Vec3) -> Option<Vec3> {
        match self {
            Domain::Disk => disk::to_direction(x),
            Domain::HalfVector => half_vector::to_direction(x, wi),
            Domain::Sphere => sphere::to_direction(x),
            Domain::Equatorial => equatorial::to_direction(x),
        }
    }

    /// `ln(pdf_w / pdf_x)` at a flow point already known to be in the domain.
    #[inline]
    #[must_use]
    pub fn ln_measure(self, x: [f32; 2], wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Domain::Disk => disk::ln_measure(wo),
            Domain::HalfVector => half_vector::ln_measure(wo, wi),
            Domain::Sphere | Domain::Equatorial => sphere::ln_measure(x[0]),
        }
    }

    /// The flow point of a unit direction for incident `wi`; `None` where the domain has
    /// no density.
    #[inline]
    #[must_use]
    pub fn point_of(self, wo: Vec3, wi: Vec3) -> Option<[f32; 2]> {
        match self {
            Domain::Disk => disk::from_direction(wo),
            Domain::HalfVector => half_vector::from_direction(wo, wi),
            Domain::Sphere => sphere::from_direction(wo),
            Domain::Equatorial => equatorial::from_direction(wo),
        }
    }
}
