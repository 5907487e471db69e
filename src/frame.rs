//! The incident frame: the orthogonal map of the xy-plane in which the nets see `wi`.
//!
//! An isotropic BSDF is unchanged by rotations about the normal, so an isotropic model is
//! trained and evaluated with `wi` turned into the xz-plane (`phi_i = 0`, `wi.x >= 0`): its
//! nets are conditioned on `theta_i` alone, and a sample is turned back by the same
//! rotation. An anisotropic BSDF unchanged by a half turn, or by mirroring either axis,
//! is learned on part of the turn only: `wi` is folded into it by sign changes
//! ([`IncidentFold`]) and a sample unfolded by the same signs. Rotations and mirrors keep
//! solid angle, the projected disk's area and `phi` differences up to sign, so every
//! density is unchanged and the reported PDF stays exact.

use crate::def::IncidentFold;
use crate::math::sqrt;
use crate::spec::NORMAL_INCIDENCE_RHO;
use glam::Vec3;

/// An orthogonal map of the xy-plane, `z` unchanged: a rotation by `(c, s) = (cos, sin)`
/// of `phi_i`, or (`fold`) the sign changes `(c, s) = (sx, sy)`, each its own inverse.
/// The fields are the generated code's `Frame`, and both compute the same products.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IncidentFrame {
    c: f32,
    s: f32,
    fold: bool,
}

impl IncidentFrame {
    /// No rotation (anisotropic models without a fold, normal incidence).
    pub const IDENTITY: IncidentFrame = IncidentFrame {
        c: 1.0,
        s: 0.0,
        fold: false,
    };

    /// The rotation `R(-phi_i)` in which `wi` (unit) has `phi = 0`.
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
            c: wi.x * inv,
            s: wi.y * inv,
            fold: false,
        }
    }

    /// The sign changes that fold `wi` into the part of the turn `fold` keeps
    /// ([`IncidentFold::signs`]; docs/math.md, (83)).
    #[inline]
    #[must_use]
    pub fn folding(wi: Vec3, fold: IncidentFold) -> Self {
        if fold == IncidentFold::None {
            return Self::IDENTITY;
        }
        let (c, s) = fold.signs(wi.x, wi.y);
        IncidentFrame { c, s, fold: true }
    }

    /// A world vector in the frame: `R(-phi_i) v`, or `v` with its signs changed.
    #[inline(always)]
    #[must_use]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        if self.fold {
            return Vec3::new(self.c * v.x, self.s * v.y, v.z);
        }
        Vec3::new(
            self.c * v.x + self.s * v.y,
            self.c * v.y - self.s * v.x,
            v.z,
        )
    }

    /// A frame vector back in the world: `R(phi_i) v`, or `v` with its signs changed.
    #[inline(always)]
    #[must_use]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        if self.fold {
            return Vec3::new(self.c * v.x, self.s * v.y, v.z);
        }
        Vec3::new(
            self.c * v.x - self.s * v.y,
            self.s * v.x + self.c * v.y,
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
    fn folded_wi_lies_in_the_kept_part_and_round_trips() {
        for (x, y) in [
            (0.3, 0.5),
            (-0.3, 0.5),
            (0.3, -0.5),
            (-0.3, -0.5),
            (0.6, 0.0),
        ] {
            let wi = Vec3::new(x, y, 0.8124038);
            // A half turn for `wi.y >= 0`, nothing otherwise.
            let half = IncidentFrame::folding(wi, IncidentFold::HalfTurn).to_local(wi);
            let turned = if y >= 0.0 { (-x, -y) } else { (x, y) };
            assert_eq!((half.x, half.y), turned);
            let quarter = IncidentFrame::folding(wi, IncidentFold::Quarter);
            let l = quarter.to_local(wi);
            assert!(l.x <= 0.0 && l.y <= 0.0, "{l:?}");
            assert_eq!(quarter.to_world(l), wi);
            assert_eq!(
                IncidentFrame::folding(wi, IncidentFold::None),
                IncidentFrame::IDENTITY
            );
        }
    }

    #[test]
    fn normal_incidence_is_the_identity() {
        assert_eq!(
            IncidentFrame::aligning(Vec3::new(1e-20, -1e-20, 1.0)),
            IncidentFrame::IDENTITY
        );
    }
}
