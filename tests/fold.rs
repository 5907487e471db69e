//! Folded models (`ModelDef::fold`): the nets see `wi` folded into part of the turn by sign
//! changes and a sample is unfolded by the same signs. So a folded model at `wi` is the
//! unfolded model with the same weights at the folded `wi`, its sample unfolded, bit for
//! bit (sign changes are exact); sampling commutes with the material's symmetries (a half
//! turn; for a quarter fold also either mirror); and the fold travels in the blob's flags.

mod support;

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::internals::blob::{blob_len, crc32, CHECKSUM_LEN};
use diffbsdf::{BlobError, IncidentFold, Model3x32, Precision};
use proptest::prelude::*;
use support::{
    direction, random_folded_half_vector, random_folded_sphere, random_half_vector, random_sphere,
};

/// The symmetries a fold assumes, each as the signs it applies to `x` and `y`.
fn symmetries(fold: IncidentFold) -> &'static [(f32, f32)] {
    match fold {
        IncidentFold::None => &[],
        IncidentFold::HalfTurn => &[(-1.0, -1.0)],
        IncidentFold::Quarter => &[(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0)],
    }
}

fn flip(w: Vec3, (sx, sy): (f32, f32)) -> Vec3 {
    Vec3::new(sx * w.x, sy * w.y, w.z)
}

/// Checks one folded model against its unfolded twin at `wi`, `u`.
fn check(
    fold: IncidentFold,
    folded: impl Fn(Vec3, Vec2) -> (Option<(Vec3, f32)>, Option<Vec3>),
    plain: impl Fn(Vec3, Vec2) -> (Option<(Vec3, f32)>, Option<Vec3>),
    pdf: impl Fn(Vec3, Vec3) -> f32,
    twin_pdf: impl Fn(Vec3, Vec3) -> f32,
    wi: Vec3,
    u: Vec2,
) -> Result<(), TestCaseError> {
    let signs = fold.signs(wi.x, wi.y);
    let (sample, dir) = folded(wi, u);
    let (twin, twin_dir) = plain(flip(wi, signs), u);
    // The folded model is its twin at the folded wi, unfolded.
    prop_assert_eq!(
        sample.map(|s| (s.0, s.1)),
        twin.map(|s| (flip(s.0, signs), s.1))
    );
    prop_assert_eq!(dir, twin_dir.map(|w| flip(w, signs)));
    if let Some((wo, p)) = sample {
        prop_assert!(p > 0.0 && p.is_finite());
        // ... its PDF is the twin's at the folded pair, and the same at the symmetric
        // images.
        prop_assert_eq!(pdf(wi, wo), twin_pdf(flip(wi, signs), flip(wo, signs)));
        for &g in symmetries(fold) {
            prop_assert_eq!(pdf(flip(wi, g), flip(wo, g)), pdf(wi, wo));
        }
    }
    // Sampling commutes with the symmetries (away from the fold's edges, where `-0` and
    // `+0` fold differently).
    if wi.x != 0.0 && wi.y != 0.0 {
        for &g in symmetries(fold) {
            let (image, _) = folded(flip(wi, g), u);
            prop_assert_eq!(image, sample.map(|s| (flip(s.0, g), s.1)));
        }
    }
    Ok(())
}

/// A proptest that a folded model of the given kind matches its unfolded twin (`check`).
macro_rules! twin_test {
    ($name:ident, $folded:ident, $plain:ident, $upper:expr) => {
        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn $name(
                seed in 0u64..32, a in 0.0f32..1.0, b in 0.0f32..1.0,
                u0 in 0.0f32..1.0, u1 in 0.0f32..1.0, steps in 1u32..=8,
                quarter in any::<bool>(),
            ) {
                let fold = if quarter { IncidentFold::Quarter } else { IncidentFold::HalfTurn };
                let m = $folded(seed, 1, fold);
                let twin = $plain(seed, 1);
                let folded = |wi: Vec3, u: Vec2| {
                    (
                        m.sample_steps(wi, u, steps).map(|s| (s.wo, s.pdf)),
                        m.sample_direction_steps(wi, u, steps),
                    )
                };
                let plain = |wi: Vec3, u: Vec2| {
                    (
                        twin.sample_steps(wi, u, steps).map(|s| (s.wo, s.pdf)),
                        twin.sample_direction_steps(wi, u, steps),
                    )
                };
                let pdf = |wi: Vec3, wo: Vec3| m.pdf_steps(wi, wo, steps);
                let twin_pdf = |wi: Vec3, wo: Vec3| twin.pdf_steps(wi, wo, steps);
                let wi = direction(a, b, $upper);
                check(fold, folded, plain, pdf, twin_pdf, wi, Vec2::new(u0, u1))?;
            }
        }
    };
}

twin_test!(
    folded_half_vector_is_its_twin_at_the_folded_wi,
    random_folded_half_vector,
    random_half_vector,
    true
);
twin_test!(
    folded_sphere_is_its_twin_at_the_folded_wi,
    random_folded_sphere,
    random_sphere,
    false
);

/// The blob of `m` (f32).
fn blob(m: &Model3x32) -> Vec<u8> {
    let mut out = vec![0u8; blob_len(m.def())];
    m.write_blob(Precision::F32, &mut out).unwrap();
    out
}

/// `bytes` with the flags' second byte (bits 8..16) set to `v`, checksum resealed.
fn with_flag_byte(bytes: &[u8], v: u8) -> Vec<u8> {
    let mut b = bytes.to_vec();
    b[29] = v;
    let n = b.len() - CHECKSUM_LEN;
    let crc = crc32(&b[..n]);
    b[n..].copy_from_slice(&crc.to_le_bytes());
    b
}

#[test]
fn the_fold_round_trips_through_the_blob_flags() {
    for (fold, bits) in [
        (IncidentFold::None, 0),
        (IncidentFold::HalfTurn, 1),
        (IncidentFold::Quarter, 2),
    ] {
        let bytes = blob(&random_folded_half_vector(3, 1, fold));
        assert_eq!(bytes[29], bits, "{fold:?}");
        assert_eq!(Model3x32::from_blob(&bytes).unwrap().def().fold, fold);
    }
    let plain = blob(&random_half_vector(3, 1));
    // Both folds, or a fold on an isotropic model, are header errors.
    assert!(matches!(
        Model3x32::from_blob(&with_flag_byte(&plain, 3)),
        Err(BlobError::BadHeader(_))
    ));
    let mut iso = plain.clone();
    iso[28] |= 1;
    for bits in [1, 2] {
        assert!(matches!(
            Model3x32::from_blob(&with_flag_byte(&iso, bits)),
            Err(BlobError::BadHeader(_))
        ));
    }
    // An unfolded blob with bit 8 set reads as folded by a half turn.
    assert_eq!(
        Model3x32::from_blob(&with_flag_byte(&plain, 1))
            .unwrap()
            .def()
            .fold,
        IncidentFold::HalfTurn
    );
}
