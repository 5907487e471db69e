//! No input makes the kernel return NaN or infinity, or panic: NaN, +-Inf, zero, denormal,
//! huge and non-unit directions; `u` at 0, 1 - eps, 1 and outside; any step count.

mod support;

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::internals::Diagnostics;
use proptest::prelude::*;
use support::{random_disk, random_sphere};

const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;

fn special() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(0.0),
        Just(-0.0),
        Just(f32::MIN_POSITIVE / 4.0),
        Just(-f32::MIN_POSITIVE / 4.0),
        Just(1e30),
        Just(-1e30),
        Just(f32::MAX),
        Just(1.0),
        Just(-1.0),
        Just(ONE_MINUS_EPS),
        any::<f32>(),
        -1.0f32..1.0,
    ]
}

fn unit_or_special() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        (special(), special(), special()).prop_map(|(x, y, z)| Vec3::new(x, y, z)),
        (0.0f32..1.0, 0.0f32..1.0).prop_map(|(a, b)| support::direction(a, b, false)),
        (special(), 0.0f32..1.0).prop_map(
            |(a, b)| support::direction(b, 0.3, true) * if a.is_finite() { a } else { 1.0 }
        ),
    ]
}

fn uniform_or_special() -> impl Strategy<Value = Vec2> {
    let u = prop_oneof![
        Just(0.0f32),
        Just(ONE_MINUS_EPS),
        Just(1.0),
        0.0f32..1.0,
        special()
    ];
    (u.clone(), u).prop_map(|(a, b)| Vec2::new(a, b))
}

fn steps() -> impl Strategy<Value = u32> {
    prop_oneof![Just(0u32), Just(1), Just(2), Just(4), Just(8), Just(64)]
}

macro_rules! never_nan {
    ($name:ident, $model:ident) => {
        proptest! {
            #![proptest_config(ProptestConfig::with_cases(3000))]
            #[test]
            fn $name(seed in 0u64..4, wi in unit_or_special(), wo in unit_or_special(),
                     u in uniform_or_special(), n in steps()) {
                let m = $model(seed, 1);
                if let Some(d) = m.sample_direction_steps(wi, u, n) {
                    prop_assert!(d.is_finite() && (d.length() - 1.0).abs() < 1e-5, "{d:?}");
                }
                if let Some(s) = m.sample_steps(wi, u, n) {
                    prop_assert!(s.wo.is_finite() && s.pdf.is_finite() && s.pdf > 0.0, "{s:?}");
                }
                let p = m.pdf_steps(wi, wo, n);
                prop_assert!(p.is_finite() && p >= 0.0, "pdf {p}");
                let wis = [wi, wi];
                let us = [u, u];
                let mut out = [diffbsdf::Sample::INVALID; 2];
                m.sample_batch(&wis, &us, n, &mut out).unwrap();
                prop_assert!(out.iter().all(|s| s.wo.is_finite() && s.pdf.is_finite() && s.pdf >= 0.0));
            }
        }
    };
}

never_nan!(disk_never_returns_nan, random_disk);
never_nan!(sphere_never_returns_nan, random_sphere);

#[test]
fn invalid_inputs_are_invalid_results() {
    let m = random_disk(1, 1);
    let wi = support::direction(0.5, 0.2, true);
    let u = Vec2::new(0.3, 0.6);
    assert!(m.sample(wi, u).is_some());
    for bad in [
        Vec3::ZERO,
        Vec3::NAN,
        Vec3::INFINITY,
        wi * 2.0,
        wi * 0.5,
        Vec3::new(0.0, 0.0, -1.0),
    ] {
        assert!(m.sample(bad, u).is_none(), "{bad:?}");
        assert!(m.sample_direction(bad, u).is_none(), "{bad:?}");
        assert_eq!(m.pdf(bad, Vec3::Z), 0.0, "{bad:?}");
        assert_eq!(m.pdf(wi, bad), 0.0, "{bad:?}");
    }
    for bad_u in [
        Vec2::new(-0.1, 0.5),
        Vec2::new(0.5, 1.5),
        Vec2::new(f32::NAN, 0.5),
    ] {
        assert!(m.sample(wi, bad_u).is_none());
    }
    // steps = 0 is the model's default; above MAX_STEPS a call gives nothing.
    assert_eq!(m.sample_steps(wi, u, 0), m.sample(wi, u));
    assert_eq!(
        m.sample_direction_steps(wi, u, 0),
        m.sample_direction(wi, u)
    );
    let wo = m.sample(wi, u).map(|s| s.wo).unwrap_or(Vec3::Z);
    assert_eq!(m.pdf_steps(wi, wo, 0), m.pdf(wi, wo));
    let over = diffbsdf::spec::MAX_STEPS + 1;
    assert!(m.sample_steps(wi, u, over).is_none());
    assert!(m.sample_direction_steps(wi, u, over).is_none());
    assert_eq!(m.pdf_steps(wi, wo, over), 0.0);
    assert!(m.sample_steps(wi, u, diffbsdf::spec::MAX_STEPS).is_some());
    // Slightly non-unit input (renderer rounding) is accepted.
    assert!(m.sample(wi * 1.0004, u).is_some());
}

#[test]
fn u_at_the_ends_of_the_unit_square_gives_finite_samples() {
    for seed in 0..4 {
        let (d, s) = (random_disk(seed, 1), random_sphere(seed, 1));
        for (a, b) in [
            (0.0, 0.0),
            (0.0, ONE_MINUS_EPS),
            (ONE_MINUS_EPS, 0.0),
            (ONE_MINUS_EPS, ONE_MINUS_EPS),
            (1.0, 1.0),
        ] {
            let u = Vec2::new(a, b);
            let wi = support::direction(0.7, 0.1, true);
            for x0 in [
                d.base_distribution(wi).unwrap().sample([a, b]),
                s.base_distribution(wi).unwrap().sample([a, b]),
            ] {
                assert!(
                    x0[0].is_finite() && x0[1].is_finite(),
                    "x0 {x0:?} for u {u:?}"
                );
            }
            if let Some(smp) = d.sample(wi, u) {
                assert!(smp.pdf.is_finite() && smp.pdf > 0.0);
            }
            if let Some(smp) = s.sample(wi, u) {
                assert!(smp.pdf.is_finite() && smp.pdf > 0.0);
            }
        }
    }
}

#[test]
fn batch_length_mismatch_is_an_error() {
    let m = random_disk(1, 1);
    let wi = [Vec3::Z; 3];
    let u = [Vec2::splat(0.5); 2];
    let mut out = [Vec3::ZERO; 3];
    assert_eq!(
        m.sample_direction_batch(&wi, &u, 4, &mut out),
        Err(diffbsdf::BatchError::LengthMismatch)
    );
}
