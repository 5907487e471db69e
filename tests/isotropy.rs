//! Isotropic models: the nets see `wi` turned about the normal to `phi = 0` and the sample
//! is turned back. So sampling commutes with rotations about the normal (same `u`, rotated
//! `wi` -> rotated `wo`, same PDF), and an isotropic model at any `wi` is the anisotropic
//! model with the same weights at the aligned `wi`, turned back.

mod support;

use diffbsdf::frame::IncidentFrame;
use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::{Model3x32, Precision};
use proptest::prelude::*;
use support::{
    direction, random_disk, random_isotropic_disk, random_isotropic_sphere, random_sphere, rel,
};

/// Direction agreement (rotations in f32 differ from the aligned path by a few ulps, which
/// the flow can amplify a little).
const DIR_TOL: f32 = 2e-5;
/// Relative PDF agreement.
const PDF_TOL: f32 = 2e-4;

/// PDF tolerance at `wo`: the measure change `1/sin(theta)` (sphere) or `cos(theta)` (disk)
/// turns a direction difference `d` into a relative PDF difference of about `d / sin` or
/// `d / cos`, which is large next to the pole and the horizon.
fn pdf_tol(wo: Vec3) -> f32 {
    let rho = (wo.x * wo.x + wo.y * wo.y).sqrt();
    PDF_TOL + DIR_TOL / rho.min(wo.z.abs()).max(1e-6)
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
                // Same model at the aligned wi, turned back.
                let frame = IncidentFrame::aligning(wi);
                let aligned = plain.sample_steps(frame.to_local(wi), u, steps);
                let got = iso.sample_steps(wi, u, steps);
                prop_assert_eq!(aligned.is_some(), got.is_some());
                if let (Some(a), Some(g)) = (aligned, got) {
                    prop_assert!((frame.to_world(a.wo) - g.wo).length() <= DIR_TOL);
                    prop_assert!(rel(g.pdf, a.pdf, 0.0) <= pdf_tol(g.wo));
                    prop_assert!(rel(iso.pdf_steps(wi, g.wo, steps), g.pdf, 0.0) <= 1e-4);
                }
                // Turning wi turns the sample.
                let wr = turn(wi, angle);
                if let (Some(g), Some(r)) = (got, iso.sample_steps(wr, u, steps)) {
                    prop_assert!((turn(g.wo, angle) - r.wo).length() <= DIR_TOL,
                        "{:?} vs {:?}", turn(g.wo, angle), r.wo);
                    prop_assert!(rel(r.pdf, g.pdf, 0.0) <= pdf_tol(g.wo));
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
            diffbsdf::blob::blob_len(&{
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
