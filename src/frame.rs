//! The incident frame of an isotropic model: the rotation about the normal that turns `wi`
//! into the xz-plane (`phi_i = 0`, `wi.x >= 0`).
//!
//! An isotropic BSDF is unchanged by rotations about the normal, so an isotropic model is
//! trained and evaluated with `wi` in that plane: its nets are conditioned on `theta_i`
//! alone, and a sample is turned back by the same rotation. A rotation about `z` keeps solid
//! angle, the projected disk's area and `phi` differences, so every density is unchanged
//! and the reported PDF stays exact.

use crate::math::sqrt;
use crate::spec::NORMAL_INCIDENCE_RHO;
use glam::Vec3;

/// A rotation about the normal by `phi_i`: `cos`/`sin` of the angle of `wi` in the xy-plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IncidentFrame {
    cos: f32,
    sin: f32,
}

impl IncidentFrame {
    /// No rotation (anisotropic models, normal incidence).
    pub const IDENTITY: IncidentFrame = IncidentFrame { cos: 1.0, sin: 0.0 };

    /// The frame in which `wi` (unit) has `phi = 0`.
    #[inline]
    #[must_use]
    pub fn aligning(wi: Vec3) -> Self {
        // rho = |wi.xy|, (cos phi_i, sin phi_i) = wi.xy / rho
        let rho = sqrt(wi.x * wi.x + wi.y * wi.y);
        if !(rho > NORMAL_INCIDENCE_RHO) {
            return Self::IDENTITY;
        }
        let inv = 1.0 / rho;
        IncidentFrame {
            cos: wi.x * inv,
            sin: wi.y * inv,
        }
    }

    /// `R(-phi_i) v`: a world vector in the frame.
    #[inline(always)]
    #[must_use]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(
            self.cos * v.x + self.sin * v.y,
            self.cos * v.y - self.sin * v.x,
            v.z,
        )
    }

    /// `R(phi_i) v`: a frame vector back in the world.
    #[inline(always)]
    #[must_use]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        Vec3::new(
            self.cos * v.x - self.sin * v.y,
            self.sin * v.x + self.cos * v.y,
            v.z,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aligned_wi_lies_in_the_xz_plane_and_round_trips() {
        let wi = Vec3::new(-0.3, 0.5, 0.8124038);
        let f = IncidentFrame::aligning(wi);
        let l = f.to_local(wi);
        assert!(l.y.abs() < 1e-7 && l.x > 0.0, "{l:?}");
        assert!((f.to_world(l) - wi).length() < 1e-6);
    }

    #[test]
    fn normal_incidence_is_the_identity() {
        assert_eq!(
            IncidentFrame::aligning(Vec3::new(1e-20, -1e-20, 1.0)),
            IncidentFrame::IDENTITY
        );
    }
}
