//! Symmetries of an anisotropic BSDF in the incident azimuth (the kernel's
//! [`IncidentFold`]: a half turn about the normal, or a mirror of either tangent axis). A
//! material with one can be learned (or, measured, stored) on part of the turn only: a
//! direction pair is folded into that part by sign changes of `x` and `y`, and a sampled
//! direction unfolded by the same signs.

use crate::DVec3;
pub use diffbsdf::IncidentFold;

/// The signs `(sx, sy)` that fold `wi` into the part `fold` keeps: the kernel's
/// [`IncidentFold::signs`] on `wi`'s tangent part rounded to f32, so that the two decide
/// alike for every `wi`.
pub fn fold_signs(fold: IncidentFold, wi: DVec3) -> (f64, f64) {
    let (sx, sy) = fold.signs(wi.x as f32, wi.y as f32);
    (f64::from(sx), f64::from(sy))
}

/// `w` with its `x` and `y` multiplied by `signs`.
pub fn apply_signs(signs: (f64, f64), w: DVec3) -> DVec3 {
    DVec3::new(w.x * signs.0, w.y * signs.1, w.z)
}
