//! The PDF of a sampled direction, computed by the exact inverse, equals the PDF reported
//! when it was sampled; and the direction-only path samples the same direction.

mod support;

use diffbsdf::glam::Vec2;
use diffbsdf::internals::Diagnostics;
use proptest::prelude::*;
use support::{
    direction, random_disk, random_equatorial, random_half_vector, random_isotropic_disk,
    random_isotropic_equatorial, random_isotropic_half_vector, random_isotropic_sphere,
    random_sphere, random_standardized_disk, random_standardized_half_vector,
    random_warped_half_vector, rel,
};

/// Allowed relative difference between `pdf(wi, wo)` and the sampled PDF, or, where one
/// f32 rounding of `wo` or `x0` moves the density by more than that (sharply compressing
/// random flows), the rounding allowance the shipped-model tests use
/// (`Diagnostics::pdf_consistent`, its estimate taken at the model's default N).
const PDF_TOL: f32 = diffbsdf::spec::PDF_CONSISTENCY_TOL;

macro_rules! consistency {
    ($name:ident, $model:ident, $upper:expr) => {
        proptest! {
            #![proptest_config(ProptestConfig::with_cases(1024))]
            #[test]
            fn $name(
                seed in any::<u64>(), a in 0.0f32..1.0, b in 0.0f32..1.0,
                u0 in 0.0f32..1.0, u1 in 0.0f32..1.0, steps in 1u32..=8,
            ) {
                let m = $model(seed, 1);
                let wi = direction(a, b, $upper);
                let u = Vec2::new(u0, u1);
                let dir = m.sample_direction_steps(wi, u, steps);
                match m.sample_steps(wi, u, steps) {
                    Some(s) => {
                        prop_assert_eq!(dir, Some(s.wo));
                        let back = m.pdf_steps(wi, s.wo, steps);
                        let mut points = vec![[0.0f32; 2]; steps as usize + 1];
                        prop_assert!(m.trajectory(wi, u, steps, &mut points).is_some());
                        let x0 = points[0];
                        prop_assert!(
                            rel(back, s.pdf, 0.0) <= PDF_TOL
                                || m.pdf_consistent(wi, s.wo, s.pdf, back, x0),
                            "sampled pdf {} but pdf() gives {} (rel {}, rounding allows {})",
                            s.pdf, back, rel(back, s.pdf, 0.0),
                            diffbsdf::spec::PDF_ROUNDING_SPAN * m.pdf_rounding(wi, s.wo, back, x0)
                        );
                    }
                    // Direction-only validity is geometric; with invertible steps and finite
                    // densities both paths reject the same samples.
                    None => prop_assert!(dir.is_none(), "direction-only gave {:?}, sample gave None", dir),
                }
            }
        }
    };
}

consistency!(disk_pdf_of_sample_matches_sampled_pdf, random_disk, true);
consistency!(
    sphere_pdf_of_sample_matches_sampled_pdf,
    random_sphere,
    false
);
consistency!(
    isotropic_disk_pdf_of_sample_matches_sampled_pdf,
    random_isotropic_disk,
    true
);
consistency!(
    isotropic_sphere_pdf_of_sample_matches_sampled_pdf,
    random_isotropic_sphere,
    false
);
consistency!(
    equatorial_pdf_of_sample_matches_sampled_pdf,
    random_equatorial,
    false
);
consistency!(
    isotropic_equatorial_pdf_of_sample_matches_sampled_pdf,
    random_isotropic_equatorial,
    false
);
consistency!(
    half_vector_pdf_of_sample_matches_sampled_pdf,
    random_half_vector,
    true
);
consistency!(
    isotropic_half_vector_pdf_of_sample_matches_sampled_pdf,
    random_isotropic_half_vector,
    true
);
consistency!(
    standardized_disk_pdf_of_sample_matches_sampled_pdf,
    random_standardized_disk,
    true
);
consistency!(
    standardized_half_vector_pdf_of_sample_matches_sampled_pdf,
    random_standardized_half_vector,
    true
);
consistency!(
    warped_half_vector_pdf_of_sample_matches_sampled_pdf,
    random_warped_half_vector,
    true
);
