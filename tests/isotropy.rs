//! Isotropic models: the nets see `wi` turned about the normal to `phi = 0` and the sample
//! is turned back. So sampling commutes with rotations about the normal (same `u`, rotated
//! `wi` -> rotated `wo`, same PDF), and an isotropic model at any `wi` is the anisotropic
//! model with the same weights at the aligned `wi`, turned back; both to the rounding of
//! `wi` times the flow's sensitivity to it.

mod support;

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::internals::frame::IncidentFrame;
use diffbsdf::{Model3x32, Precision};
use proptest::prelude::*;
use support::{
    direction, random_disk, random_isotropic_disk, random_isotropic_sphere, random_sphere, rel,
};

/// Direction agreement where the flow does not amplify differences of `wi`.
const DIR_TOL: f32 = 2e-5;
/// Relative PDF agreement there.
const PDF_TOL: f32 = 2e-4;
/// How far the `wi` the nets see may differ between two paths that should agree: the
/// iso model normalises `wi` and then turns it, the reference turns and then normalises,
/// and `turn` rounds too; a few f32 ulps of a unit vector.
const WI_ROUNDING: f32 = 1e-6;

/// PDF tolerance at `wo` for a direction difference `d`: the measure change
/// `1/sin(theta)` (sphere) or `cos(theta)` (disk) turns `d` into a relative PDF difference
/// of about `d / sin` or `d / cos`, which is large next to the pole and the horizon.
fn pdf_tol(wo: Vec3, d: f32) -> f32 {
    let rho = (wo.x * wo.x + wo.y * wo.y).sqrt();
    PDF_TOL + d / rho.min(wo.z.abs()).max(1e-6)
}

/// How strongly a sample reacts to `wi` (by central differences along two tangents,
/// 1e-4 apart): `(|d wo / d wi|, |d ln pdf / d wi|)`. Random flows near the domain's
/// edge amplify a difference of `wi` a hundredfold, so two paths whose `wi` differ by
/// rounding can only agree to rounding times this.
fn wi_sensitivity(sample: impl Fn(Vec3) -> Option<(Vec3, f32)>, wi: Vec3) -> (f32, f32) {
    let t1 = wi.any_orthonormal_vector();
    let t2 = wi.cross(t1);
    let h = 1e-4f32;
    let (mut kd, mut kp) = (0.0f32, 0.0f32);
    for t in [t1, t2] {
        match (
            sample((wi + h * t).normalize()),
            sample((wi - h * t).normalize()),
        ) {
            (Some(a), Some(b)) => {
                kd = kd.max((a.0 - b.0).length() / (2.0 * h));
                kp = kp.max((a.1.ln() - b.1.ln()).abs() / (2.0 * h));
            }
            _ => return (f32::INFINITY, f32::INFINITY),
        }
    }
    (kd, kp)
}

fn turn(w: Vec3, angle: f32) -> Vec3 {
    let (s, c) = angle.sin_cos();
    Vec3::new(c * w.x - s * w.y, s * w.x + c * w.y, w.z)
}

macro_rules! equivariance {
    ($name:ident, $iso:ident, $plain:ident, $upper:expr) => {
        proptest! {
            #![proptest_config(ProptestConfig::with_cases(512))]
            #[test]
            fn $name(
                seed in 0u64..64, a in 0.0f32..1.0, b in 0.0f32..1.0, angle in -3.2f32..3.2,
                u0 in 0.0f32..1.0, u1 in 0.0f32..1.0, steps in 1u32..=8,
            ) {
                let iso = $iso(seed, 1);
                let plain = $plain(seed, 1);
                let wi = direction(a, b, $upper);
                let u = Vec2::new(u0, u1);
                let (kd, kp) = wi_sensitivity(
                    |w| iso.sample_steps(w, u, steps).map(|s| (s.wo, s.pdf)),
                    wi,
                );
                // Differences of wi by rounding can move the sample across the domain's
                // edge only where it is that sensitive; elsewhere validity must agree.
                let (dir_tol, ln_tol) = (DIR_TOL + kd * WI_ROUNDING, kp * WI_ROUNDING);
                // Same model at the aligned wi, turned back.
                let frame = IncidentFrame::aligning(wi);
                let aligned = plain.sample_steps(frame.to_local(wi), u, steps);
                let got = iso.sample_steps(wi, u, steps);
                prop_assert!(aligned.is_some() == got.is_some() || !kd.is_finite());
                if let (Some(a), Some(g)) = (aligned, got) {
                    prop_assert!((frame.to_world(a.wo) - g.wo).length() <= dir_tol,
                        "{:?} vs {:?}", frame.to_world(a.wo), g.wo);
                    prop_assert!(rel(g.pdf, a.pdf, 0.0) <= pdf_tol(g.wo, dir_tol) + ln_tol);
                    prop_assert!(rel(iso.pdf_steps(wi, g.wo, steps), g.pdf, 0.0) <= 1e-4);
                }
                // Turning wi turns the sample.
                let wr = turn(wi, angle);
                if let (Some(g), Some(r)) = (got, iso.sample_steps(wr, u, steps)) {
                    prop_assert!((turn(g.wo, angle) - r.wo).length() <= dir_tol,
                        "{:?} vs {:?}", turn(g.wo, angle), r.wo);
                    prop_assert!(rel(r.pdf, g.pdf, 0.0) <= pdf_tol(g.wo, dir_tol) + ln_tol);
                    let q = iso.pdf_steps(wr, r.wo, steps);
                    prop_assert!(rel(q, r.pdf, 0.0) <= 1e-4);
                }
            }
        }
    };
}

equivariance!(
    isotropic_disk_commutes_with_rotations,
    random_isotropic_disk,
    random_disk,
    true
);
equivariance!(
    isotropic_sphere_commutes_with_rotations,
    random_isotropic_sphere,
    random_sphere,
    false
);

#[test]
fn the_isotropic_flag_survives_the_blob_and_changes_the_samples() {
    let iso = random_isotropic_disk(3, 2);
    for precision in [Precision::F32, Precision::F16] {
        let mut out = vec![
            0u8;
            diffbsdf::internals::blob::blob_len(&{
                let mut d = *iso.def();
                d.precision = precision;
                d
            })
        ];
        let n = iso.write_blob(precision, &mut out).unwrap();
        let back = Model3x32::from_blob(&out[..n]).unwrap();
        assert!(back.def().isotropic);
    }
    // Away from phi = 0 the flag matters: the plain model gives another direction.
    let plain = random_disk(3, 2);
    let mut compared = 0;
    for k in 0..256 {
        let wi = direction(
            0.3 + 0.6 * (k % 4) as f32 / 4.0,
            0.1 + (k % 16) as f32 / 20.0,
            true,
        );
        let u = Vec2::new((k % 8) as f32 / 8.0 + 0.06, (k / 32) as f32 / 8.0 + 0.06);
        if let (Some(a), Some(b)) = (iso.sample_direction(wi, u), plain.sample_direction(wi, u)) {
            assert!((a - b).length() > 1e-3, "{a:?} {b:?}");
            compared += 1;
        }
    }
    assert!(compared >= 32, "only {compared} valid pairs");
}

#[test]
fn normal_incidence_uses_no_rotation() {
    let iso = random_isotropic_sphere(5, 2);
    let plain = random_sphere(5, 2);
    let u = Vec2::new(0.7, 0.2);
    assert_eq!(
        iso.sample(Vec3::Z, u),
        plain.sample(Vec3::Z, u),
        "at wi = z the frame is the identity"
    );
}
