//! The exactness sweep: the samples on which a model's promise "`pdf(wi, sample.wo)` is
//! the density `sample` drew from" is checked before a model ships (`diffbsdf fit`), when
//! it is evaluated (`diffbsdf eval`) and by the shipped-model tests. One definition, so
//! that the fit refuses exactly what the tests would catch.
//!
//! The sweep covers normal to grazing incidence (below the surface too for models declared
//! for the whole sphere) and puts two thirds of its `u` in thin strips at 0 and 1, where the
//! base quantile is steepest and the inverse's line search has most to do.

use crate::any_model::AnyModel;
use crate::def::IncidentRange;
use crate::diagnostics::Diagnostics;
use crate::math::sin_cos;
use crate::spec;
use glam::{Vec2, Vec3};

/// Incident polar angles of the sweep above the surface, degrees.
pub const THETAS_ABOVE_DEG: [f32; 9] = [0.0, 10.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.0, 89.9];
/// Incident polar angles added below the surface for models declared for the whole sphere.
pub const THETAS_BELOW_DEG: [f32; 5] = [90.1, 100.0, 135.0, 170.0, 180.0];
/// Width of the strips of `u` at 0 and 1.
pub const EDGE_STRIP: f32 = 5e-4;

/// `u` of sample `k` from four uniform numbers `r` in `[0, 1)`: `k % 3 == 0` uniform,
/// `1` with `u.y` and `2` with `u.x` in a strip of width [`EDGE_STRIP`] at 0 or 1
/// (`r[3] < 0.5` picks 0).
pub fn sweep_u(k: usize, r: [f32; 4]) -> Vec2 {
    let edge = if r[3] < 0.5 {
        r[2] * EDGE_STRIP
    } else {
        1.0 - r[2] * EDGE_STRIP
    };
    match k % 3 {
        1 => Vec2::new(r[0], edge),
        2 => Vec2::new(edge, r[1]),
        _ => Vec2::new(r[0], r[1]),
    }
}

/// `wi` at polar angle `theta` (radians) and azimuth `phi`.
pub fn incident(theta: f32, phi: f32) -> Vec3 {
    let ((st, ct), (sp, cp)) = (sin_cos(theta), sin_cos(phi));
    Vec3::new(st * cp, st * sp, ct)
}

/// What one `(wi, u)` of the sweep gave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome {
    /// No sample (outside the domain's support, or `wi` outside the incident range).
    Invalid,
    /// A sample whose `pdf()` agrees: within [`spec::PDF_CONSISTENCY_TOL`] relative, or
    /// within `span` times the density's change over one f32 rounding
    /// ([`Diagnostics::pdf_rounding`]; the kernel's promise is `span` =
    /// [`spec::PDF_ROUNDING_SPAN`], see [`Diagnostics::pdf_consistent`]).
    Exact {
        /// `|pdf() - sampled| / sampled`.
        rel: f32,
        /// `rel` over the rounding change where `rel` is past the plain tolerance, else 0.
        over_rounding: f32,
        /// The smallest step determinant along the trajectory.
        min_det: f32,
    },
    /// A failure: the sample and the broken promise.
    Broken(Broken),
}

/// How a sample breaks the contract.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Failure {
    /// `sample_direction` and `sample` disagree (validity or direction) on a trajectory
    /// without a folding step.
    PathsDisagree,
    /// A non-finite or non-positive sampled PDF.
    BadPdf,
    /// A step along the trajectory with determinant <= 0 (the map folds): `sample` drops
    /// such a trajectory, `sample_direction` returns its direction.
    Folded,
    /// `pdf(wi, wo)` is 0 for a valid sample.
    ZeroPdf,
    /// `pdf(wi, wo)` disagrees beyond what f32 rounding allows.
    Inexact,
}

/// A failing sample, for the message that reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Broken {
    /// What failed.
    pub failure: Failure,
    /// The input.
    pub wi: Vec3,
    /// The input.
    pub u: Vec2,
    /// The sampled PDF (0 where there is none).
    pub sampled: f32,
    /// `pdf(wi, wo)` (0 where not reached).
    pub back: f32,
    /// The smallest step determinant (infinity where not reached).
    pub min_det: f32,
}

/// Checks one `(wi, u)` at the model's default steps, allowing `span` times the density's
/// change over one f32 rounding where the difference is past the plain tolerance (the
/// kernel promises [`spec::PDF_ROUNDING_SPAN`]; a stricter `span` leaves a margin);
/// `points` must hold `default_steps + 1` points (else the sample counts as
/// [`Failure::Folded`]).
pub fn check(model: &AnyModel, wi: Vec3, u: Vec2, points: &mut [[f32; 2]], span: f32) -> Outcome {
    let broken = |failure, sampled, back, min_det| {
        Outcome::Broken(Broken {
            failure,
            wi,
            u,
            sampled,
            back,
            min_det,
        })
    };
    let dir = model.sample_direction(wi, u);
    let Some(s) = model.sample(wi, u) else {
        if dir.is_none() {
            return Outcome::Invalid;
        }
        // `sample` drops a trajectory through a folding step (its PDF would be wrong);
        // `sample_direction` does not evaluate determinants and returns it.
        let min_det = model
            .trajectory(wi, u, model.default_steps(), points)
            .unwrap_or(f32::NAN);
        let failure = if min_det > 0.0 {
            Failure::PathsDisagree
        } else {
            Failure::Folded
        };
        return broken(failure, 0.0, 0.0, min_det);
    };
    if dir != Some(s.wo) {
        return broken(Failure::PathsDisagree, s.pdf, 0.0, f32::INFINITY);
    }
    if !(s.pdf.is_finite() && s.pdf > 0.0) {
        return broken(Failure::BadPdf, s.pdf, 0.0, f32::INFINITY);
    }
    let min_det = model
        .trajectory(wi, u, model.default_steps(), points)
        .unwrap_or(f32::NAN);
    if !(min_det > 0.0) {
        return broken(Failure::Folded, s.pdf, 0.0, min_det);
    }
    let back = model.pdf(wi, s.wo);
    if !(back > 0.0) {
        return broken(Failure::ZeroPdf, s.pdf, back, min_det);
    }
    let rel = (back - s.pdf).abs() / s.pdf;
    let over_rounding = if rel <= spec::PDF_CONSISTENCY_TOL {
        0.0
    } else {
        rel / model.pdf_rounding(wi, s.wo, back, points[0])
    };
    // Written so that a NaN fails.
    if !(over_rounding <= span) {
        return broken(Failure::Inexact, s.pdf, back, min_det);
    }
    Outcome::Exact {
        rel,
        over_rounding,
        min_det,
    }
}

/// The incident polar angles (radians) of the sweep for a model: below the surface too
/// where it is declared for the whole sphere. Returns the angles in a fixed array and how
/// many are used.
pub fn thetas(
    model: &AnyModel,
) -> (
    [f32; THETAS_ABOVE_DEG.len() + THETAS_BELOW_DEG.len()],
    usize,
) {
    let mut out = [0.0; THETAS_ABOVE_DEG.len() + THETAS_BELOW_DEG.len()];
    let below = model.def().incident == IncidentRange::WholeSphere;
    let mut n = 0;
    for &d in THETAS_ABOVE_DEG
        .iter()
        .chain(THETAS_BELOW_DEG.iter().filter(|_| below))
    {
        out[n] = d * (core::f32::consts::PI / 180.0);
        n += 1;
    }
    (out, n)
}

/// Whether the relative difference of an exact sample is within the plain tolerance
/// ([`spec::PDF_CONSISTENCY_TOL`]; beyond it a sample may still be exact where f32
/// rounding allows, see [`spec::PDF_ROUNDING_SPAN`]).
pub fn within_plain_tolerance(rel: f32) -> bool {
    rel <= spec::PDF_CONSISTENCY_TOL
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_third_of_u_is_uniform_and_two_thirds_sit_in_the_edge_strips() {
        let r = [0.3, 0.6, 0.5, 0.2];
        assert_eq!(sweep_u(0, r), Vec2::new(0.3, 0.6));
        // r[3] < 0.5: the strip at 0; r[2] = 0.5 puts u at half the strip's width.
        assert_eq!(sweep_u(1, r), Vec2::new(0.3, 0.5 * EDGE_STRIP));
        assert_eq!(sweep_u(2, r), Vec2::new(0.5 * EDGE_STRIP, 0.6));
        let top = sweep_u(4, [0.3, 0.6, 0.5, 0.7]);
        assert_eq!(top, Vec2::new(0.3, 1.0 - 0.5 * EDGE_STRIP));
        for k in 0..3 {
            let u = sweep_u(k, [0.999, 0.999, 0.999, 0.999]);
            assert!(u.x < 1.0 && u.y < 1.0 && u.x >= 0.0 && u.y >= 0.0, "{u:?}");
        }
    }

    #[test]
    fn incident_directions_are_unit_and_at_the_polar_angle() {
        for d in THETAS_ABOVE_DEG.iter().chain(THETAS_BELOW_DEG.iter()) {
            let theta = d * (core::f32::consts::PI / 180.0);
            let wi = incident(theta, 1.3);
            assert!((wi.length() - 1.0).abs() < 1e-6);
            assert!((wi.z - crate::math::sin_cos(theta).1).abs() < 1e-6, "{d}");
        }
    }
}
