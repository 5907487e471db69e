//! The batch calls against the calls they stand for: every output bit for bit the single
//! call's, whatever the batch's length, with invalid inputs among valid ones; the flow in
//! lanes is checked in every build (the batch call takes it with the `fma` feature, which
//! `scripts/test.sh` runs this file with too).

mod support;

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::internals::sample_direction_lanes;
use diffbsdf::{AnyModel, Model};
use support::{
    direction, random_disk, random_equatorial, random_isotropic_half_vector, random_sphere,
    random_warped_half_vector, shipped_blobs,
};

/// `n` inputs: mostly valid pairs, every seventh `wi` and every eleventh `u` invalid.
fn inputs(n: usize, upper: bool) -> (Vec<Vec3>, Vec<Vec2>) {
    let mut wi = Vec::with_capacity(n);
    let mut u = Vec::with_capacity(n);
    for i in 0..n {
        let a = ((i * 37) % 101) as f32 / 101.0;
        let b = ((i * 53) % 97) as f32 / 97.0;
        wi.push(match i % 7 {
            3 => Vec3::new(f32::NAN, 0.0, 1.0),
            5 if i % 2 == 0 => Vec3::ZERO,
            _ => direction(0.02 + 0.97 * a, b, upper),
        });
        u.push(if i % 11 == 4 {
            Vec2::new(1.5, 0.5)
        } else {
            Vec2::new(b, a)
        });
    }
    (wi, u)
}

/// `sample_direction_batch` against `sample_direction_steps`, bit for bit, for lengths
/// around the lane count and step counts including the default and one above the limit.
fn check<
    const BE: usize,
    const BW: usize,
    const BM: usize,
    const VE: usize,
    const VW: usize,
    const VM: usize,
>(
    name: &str,
    m: &Model<BE, BW, BM, VE, VW, VM>,
) {
    let upper = !m.def().accepts_incident_z(-0.5);
    for n in [0, 1, 3, 4, 5, 8, 103] {
        let (wi, u) = inputs(n, upper);
        for steps in [0, 3, diffbsdf::spec::MAX_STEPS + 1] {
            let mut out = vec![Vec3::splat(7.0); n];
            m.sample_direction_batch(&wi, &u, steps, &mut out).unwrap();
            let mut lanes = vec![Vec3::splat(7.0); n];
            sample_direction_lanes(m, &wi, &u, steps, &mut lanes).unwrap();
            let mut valid = 0;
            for i in 0..n {
                let one = m
                    .sample_direction_steps(wi[i], u[i], steps)
                    .unwrap_or(Vec3::ZERO);
                valid += usize::from(one != Vec3::ZERO);
                let b = one.to_array();
                for (what, got) in [("batch", out[i]), ("lanes", lanes[i])] {
                    let a = got.to_array();
                    assert!(
                        a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                        "{name}: n {n}, steps {steps}, input {i}: {what} {a:?} vs alone {b:?}"
                    );
                }
            }
            if n == 103 && steps != diffbsdf::spec::MAX_STEPS + 1 {
                assert!(valid >= 20, "{name}: only {valid} valid samples of {n}");
            }
        }
    }
}

#[test]
fn batch_directions_are_the_single_calls_bit_for_bit() {
    check("random disk", &random_disk(3, 2));
    check("random sphere", &random_sphere(2, 2));
    check("random equatorial", &random_equatorial(5, 2));
    check(
        "random isotropic half-vector",
        &random_isotropic_half_vector(5, 2),
    );
    check(
        "random warped half-vector",
        &random_warped_half_vector(6, 2),
    );
    for (name, blob) in shipped_blobs() {
        match AnyModel::from_blob(&blob).unwrap() {
            AnyModel::Velocity3x32(m) => check(&name, &m),
            AnyModel::Velocity4x32(m) => check(&name, &m),
        }
    }
}
