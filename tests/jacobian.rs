//! The hand-derived input Jacobian of the velocity net equals finite differences.

mod support;

use diffbsdf::glam::Vec3;
use diffbsdf::internals::Diagnostics;
use proptest::prelude::*;
use support::{direction, random_disk, random_sphere};

/// Allowed relative error of the hand-derived Jacobian (max entry norm).
const JACOBIAN_TOL: f32 = 1e-3;
/// Finite-difference step (4th-order central differences).
const FD_STEP: f32 = 1e-2;

type Velocity<'a> = dyn Fn([f32; 2]) -> [f32; 2] + 'a;

/// `dv/dx` by 4th-order central differences: `(8 (f(x+e) - f(x-e)) - (f(x+2e) - f(x-2e))) / 12e`.
fn finite_difference(v: &Velocity<'_>, x: [f32; 2]) -> [[f32; 2]; 2] {
    let mut j = [[0.0; 2]; 2];
    for c in 0..2 {
        let at = |s: f32| {
            let mut p = x;
            p[c] += s;
            v(p)
        };
        let (p1, m1, p2, m2) = (
            at(FD_STEP),
            at(-FD_STEP),
            at(2.0 * FD_STEP),
            at(-2.0 * FD_STEP),
        );
        for r in 0..2 {
            j[r][c] = (8.0 * (p1[r] - m1[r]) - (p2[r] - m2[r])) / (12.0 * FD_STEP);
        }
    }
    j
}

fn check(hand: [[f32; 2]; 2], fd: [[f32; 2]; 2]) -> Result<(), TestCaseError> {
    let scale = hand.iter().flatten().fold(1e-2f32, |m, v| m.max(v.abs()));
    let err = (0..4).fold(0.0f32, |m, i| {
        m.max((hand[i / 2][i % 2] - fd[i / 2][i % 2]).abs())
    });
    prop_assert!(
        err <= JACOBIAN_TOL * scale,
        "hand {hand:?} vs finite differences {fd:?}: error {err}, allowed {}",
        JACOBIAN_TOL * scale
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn disk_jacobian_matches_finite_differences(
        seed in any::<u64>(), a in 0.0f32..1.0, b in 0.0f32..1.0,
        x0 in -0.95f32..0.95, x1 in -0.95f32..0.95, t in 0.0f32..1.0,
    ) {
        let m = random_disk(seed, 0);
        let wi: Vec3 = direction(a, b, true);
        let (v, hand) = m.velocity_at(wi, [x0, x1], t).unwrap();
        prop_assert!(v.iter().all(|c| c.is_finite()));
        let f = |x: [f32; 2]| m.velocity_only_at(wi, x, t).unwrap();
        check(hand, finite_difference(&f, [x0, x1]))?;
    }

    #[test]
    fn sphere_jacobian_matches_finite_differences(
        seed in any::<u64>(), a in 0.0f32..1.0, b in 0.0f32..1.0,
        theta in 0.05f32..3.1, phi in -3.1f32..3.1, t in 0.0f32..1.0,
    ) {
        let m = random_sphere(seed, 0);
        let wi = direction(a, b, false);
        let (_, hand) = m.velocity_at(wi, [theta, phi], t).unwrap();
        let f = |x: [f32; 2]| m.velocity_only_at(wi, x, t).unwrap();
        check(hand, finite_difference(&f, [theta, phi]))?;
    }
}

/// The velocity-only and the velocity-with-Jacobian paths run the same float operations
/// in the same order (no fused multiply-adds are formed), so `v` agrees bit for bit.
#[test]
fn jacobian_and_velocity_paths_agree_bit_for_bit() {
    for seed in 0..8 {
        let m = random_disk(seed, 0);
        let wi = direction(0.3, 0.6, true);
        for k in 0..100 {
            let x = [k as f32 * 0.017 - 0.8, 0.5 - k as f32 * 0.009];
            let (v, _) = m.velocity_at(wi, x, 0.25).unwrap();
            assert_eq!(v, m.velocity_only_at(wi, x, 0.25).unwrap());
        }
    }
}
