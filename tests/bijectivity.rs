//! Every Euler step is a bijection: `det > 0` along every trajectory, and the exact
//! inverse returns the start point.

mod support;

use diffbsdf::glam::Vec2;
use diffbsdf::internals::Diagnostics;
use proptest::prelude::*;
use support::{direction, random_disk, random_sphere};

/// Allowed error of the recovered `x0`, relative to `max(1, |x0|)`.
const INVERSE_TOL: f32 = 1e-4;

fn wrapped(d: f32) -> f32 {
    let tau = std::f32::consts::TAU;
    d - tau * ((d + std::f32::consts::PI) / tau).floor()
}

fn check(
    points: &[[f32; 2]],
    min_det: f32,
    back: Option<[f32; 2]>,
    sphere: bool,
) -> Result<(), TestCaseError> {
    prop_assert!(min_det > 0.0, "det {min_det} <= 0 along {points:?}");
    let x0 = points[0];
    let back = back.ok_or_else(|| TestCaseError::fail(format!("inverse failed for {points:?}")))?;
    let d1 = if sphere {
        wrapped(back[1] - x0[1])
    } else {
        back[1] - x0[1]
    };
    let err = (back[0] - x0[0]).abs().max(d1.abs());
    let scale = 1f32.max(x0[0].abs()).max(x0[1].abs());
    prop_assert!(
        err <= INVERSE_TOL * scale,
        "x0 {x0:?} came back as {back:?} (error {err})"
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn disk_steps_are_bijective(
        seed in any::<u64>(), a in 0.0f32..1.0, b in 0.0f32..1.0,
        u0 in 0.0f32..1.0, u1 in 0.0f32..1.0, steps in 1u32..=8,
    ) {
        let m = random_disk(seed, 1);
        let wi = direction(a, b, true);
        let mut pts = [[0.0; 2]; 9];
        let min_det = m.trajectory(wi, Vec2::new(u0, u1), steps, &mut pts).unwrap();
        let back = m.invert_flow(wi, pts[steps as usize], steps);
        check(&pts[..=steps as usize], min_det, back, false)?;
    }

    #[test]
    fn sphere_steps_are_bijective(
        seed in any::<u64>(), a in 0.0f32..1.0, b in 0.0f32..1.0,
        u0 in 0.0f32..1.0, u1 in 0.0f32..1.0, steps in 1u32..=8,
    ) {
        let m = random_sphere(seed, 1);
        let wi = direction(a, b, false);
        let mut pts = [[0.0; 2]; 9];
        let min_det = m.trajectory(wi, Vec2::new(u0, u1), steps, &mut pts).unwrap();
        let back = m.invert_flow(wi, pts[steps as usize], steps);
        check(&pts[..=steps as usize], min_det, back, true)?;
    }
}
