//! The PDF integrates to one: quadrature of `pdf_x` over the domain plus the measured
//! mass that leaves the domain equals 1 within 1e-3.

mod support;

use diffbsdf::glam::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};
use support::{
    direction, random_disk, random_isotropic_equatorial, random_isotropic_half_vector,
    random_sphere, random_standardized_half_vector, random_warped_half_vector,
};

/// Allowed error of `integral + lost mass` against 1.
const NORMALIZATION_TOL: f64 = 1e-3;
/// Stratified `u` grid (per axis) for the lost-mass fraction.
const U_GRID: usize = 1000;

/// Fraction of a stratified `u` grid whose sample leaves the domain.
fn lost_mass(valid: impl Fn(Vec2) -> bool) -> f64 {
    let mut lost = 0usize;
    for i in 0..U_GRID {
        for j in 0..U_GRID {
            let u = Vec2::new(
                (i as f32 + 0.5) / U_GRID as f32,
                (j as f32 + 0.5) / U_GRID as f32,
            );
            lost += usize::from(!valid(u));
        }
    }
    lost as f64 / (U_GRID * U_GRID) as f64
}

/// Midpoint quadrature of `pdf_x = pdf_w / cos(theta)` over the disk in polar coordinates.
fn disk_integral(pdf: impl Fn(Vec3) -> f32) -> f64 {
    let (nr, nphi) = (400, 800);
    let mut sum = 0.0f64;
    for i in 0..nr {
        let r = (i as f32 + 0.5) / nr as f32;
        for j in 0..nphi {
            let phi = (j as f32 + 0.5) / nphi as f32 * TAU;
            let wo = Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - r * r).sqrt());
            sum += (pdf(wo) / wo.z) as f64 * r as f64;
        }
    }
    sum * (1.0 / nr as f64) * (std::f64::consts::TAU / nphi as f64)
}

/// Midpoint quadrature of `pdf_x = pdf_w sin(theta)` over (theta, phi) about the z axis.
fn sphere_integral(pdf: impl Fn(Vec3) -> f32) -> f64 {
    chart_integral(pdf, |v| v)
}

/// The same about the y axis (the equatorial chart, whose `1 / sin(theta)` singularities sit
/// at `+-y`, where the z-axis grid would not resolve them).
fn equatorial_integral(pdf: impl Fn(Vec3) -> f32) -> f64 {
    chart_integral(pdf, |v| Vec3::new(v.x, v.z, v.y))
}

/// Midpoint quadrature over (theta, phi) of the sphere turned by `axes`.
fn chart_integral(pdf: impl Fn(Vec3) -> f32, axes: impl Fn(Vec3) -> Vec3) -> f64 {
    let (nt, nphi) = (500, 800);
    let mut sum = 0.0f64;
    for i in 0..nt {
        let theta = (i as f32 + 0.5) / nt as f32 * PI;
        for j in 0..nphi {
            let phi = (j as f32 + 0.5) / nphi as f32 * TAU - PI;
            let wo = axes(Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            ));
            sum += (pdf(wo) * theta.sin()) as f64;
        }
    }
    sum * (std::f64::consts::PI / nt as f64) * (std::f64::consts::TAU / nphi as f64)
}

#[test]
fn disk_pdf_integrates_to_one_minus_lost_mass() {
    for (seed, steps, a, b) in [
        (1u64, 4u32, 0.2f32, 0.1f32),
        (2, 2, 0.9, 0.5),
        (3, 8, 0.02, 0.8),
    ] {
        let m = random_disk(seed, 2);
        let wi = direction(a, b, true);
        let integral = disk_integral(|wo| m.pdf_steps(wi, wo, steps));
        let lost = lost_mass(|u| m.sample_direction_steps(wi, u, steps).is_some());
        check_total(&format!("disk seed {seed}"), integral, lost);
    }
}

#[test]
fn sphere_pdf_integrates_to_one_minus_lost_mass() {
    for (seed, steps, a, b) in [
        (11u64, 8u32, 0.3f32, 0.1f32),
        (12, 4, 0.7, 0.5),
        (13, 2, 0.01, 0.9),
    ] {
        let m = random_sphere(seed, 2);
        let wi = direction(a, b, false);
        let integral = sphere_integral(|wo| m.pdf_steps(wi, wo, steps));
        let lost = lost_mass(|u| m.sample_direction_steps(wi, u, steps).is_some());
        check_total(&format!("sphere seed {seed}"), integral, lost);
    }
}

/// `integral + lost = 1` within the tolerance, with enough mass kept for a useful test.
fn check_total(label: &str, integral: f64, lost: f64) {
    let total = integral + lost;
    println!("{label}: integral {integral:.6} + lost {lost:.6} = {total:.6}");
    assert!(
        (total - 1.0).abs() <= NORMALIZATION_TOL,
        "{label}: {integral} + {lost} = {total}"
    );
    assert!(
        integral > 0.2,
        "{label}: too much mass lost for a useful test"
    );
}

#[test]
fn equatorial_pdf_integrates_to_one_minus_lost_mass() {
    for (seed, steps, a, b) in [(21u64, 8u32, 0.3f32, 0.1f32), (22, 4, 0.97, 0.5)] {
        let m = random_isotropic_equatorial(seed, 2);
        let wi = direction(a, b, false);
        let integral = equatorial_integral(|wo| m.pdf_steps(wi, wo, steps));
        let lost = lost_mass(|u| m.sample_direction_steps(wi, u, steps).is_some());
        check_total(&format!("equatorial seed {seed}"), integral, lost);
    }
}

/// The half-vector chart: its density per solid angle of `wo` (the measure change
/// `h.z / (4 wi.h)` included) integrates to the kept mass. Quadrature in (theta, phi): unlike
/// the disk's, this density does not vanish at the horizon, so `pdf_w / cos(theta)` on the
/// projected disk would have an integrable singularity at the rim.
#[test]
fn half_vector_pdf_integrates_to_one_minus_lost_mass() {
    half_vector_totals(
        "half vector",
        random_isotropic_half_vector,
        [(31, 4, 0.2, 0.1), (32, 2, 0.8, 0.5), (33, 8, 0.02, 0.8)],
    );
}

/// The same with the flow in the base's standard coordinates (docs/math.md, §6.3): the map
/// `x = mu + sigma z` and its constant Jacobian are accounted for exactly.
#[test]
fn standardized_half_vector_pdf_integrates_to_one_minus_lost_mass() {
    half_vector_totals(
        "standardized half vector",
        random_standardized_half_vector,
        [(41, 4, 0.2, 0.1), (42, 2, 0.7, 0.5), (43, 8, 0.05, 0.8)],
    );
}

/// The same in the compressed standard coordinates (docs/math.md, §6.4): the warp's
/// Jacobian at both ends of the flow is accounted for exactly.
#[test]
fn warped_half_vector_pdf_integrates_to_one_minus_lost_mass() {
    half_vector_totals(
        "warped half vector",
        random_warped_half_vector,
        [(51, 4, 0.2, 0.1), (52, 2, 0.7, 0.5), (53, 8, 0.05, 0.8)],
    );
}

/// [`check_total`] for half-vector models made by `model(seed, 2)`, one per
/// `(seed, steps, a, b)` (`wi = direction(a, b)` above the surface).
fn half_vector_totals(
    label: &str,
    model: fn(u64, u32) -> diffbsdf::Model3x32,
    cases: [(u64, u32, f32, f32); 3],
) {
    for (seed, steps, a, b) in cases {
        let m = model(seed, 2);
        let wi = direction(a, b, true);
        let integral = sphere_integral(|wo| m.pdf_steps(wi, wo, steps));
        let lost = lost_mass(|u| m.sample_direction_steps(wi, u, steps).is_some());
        check_total(&format!("{label} seed {seed}"), integral, lost);
    }
}
