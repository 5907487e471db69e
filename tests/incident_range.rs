//! The incident range a model declares (blob flag bit 1 on the sphere): the model answers
//! only for those `wi`, in every entry point, and old sphere blobs keep meaning "every wi".

mod support;

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::internals::blob::{blob_len, write_blob};
use diffbsdf::{AnyModel, BlobError, IncidentRange, Model4x32, ModelDef, Precision};
use support::{random_sphere, Rng};

fn blob(def: &ModelDef, params: &[f32]) -> Vec<u8> {
    let mut out = vec![0u8; blob_len(def)];
    let n = write_blob(def, params, &mut out).expect("writes");
    out.truncate(n);
    out
}

fn params_of(m: &Model4x32) -> Vec<f32> {
    let mut p = vec![0.0; m.def().param_count()];
    m.params(&mut p).expect("params");
    p
}

#[test]
fn upper_hemisphere_sphere_model_rejects_wi_below_the_surface() {
    let whole = random_sphere(3, 0);
    let mut def = *whole.def();
    def.incident = IncidentRange::UpperHemisphere;
    let bytes = blob(&def, &params_of(&whole));
    let upper = AnyModel::from_blob(&bytes).expect("loads");
    assert_eq!(upper.def().incident, IncidentRange::UpperHemisphere);
    let mut rng = Rng::new(9);
    let (mut below, mut above_valid) = (0, 0);
    for _ in 0..400 {
        let wi = support::direction(rng.uniform(), rng.uniform(), false);
        let u = Vec2::new(rng.uniform(), rng.uniform());
        if wi.z < 0.0 {
            below += 1;
            assert!(upper.sample(wi, u).is_none());
            assert!(upper.sample_direction(wi, u).is_none());
            assert_eq!(upper.pdf(wi, Vec3::Z), 0.0);
            assert_eq!(upper.pdf(wi, -Vec3::Z), 0.0);
        } else {
            // Above the surface both declarations answer alike.
            assert_eq!(upper.sample(wi, u), whole.sample(wi, u));
            above_valid += usize::from(upper.sample(wi, u).is_some());
        }
    }
    assert!(below > 100 && above_valid > 100, "{below} {above_valid}");
}

#[test]
fn the_flag_round_trips_and_old_sphere_blobs_mean_every_wi() {
    let whole = random_sphere(4, 0);
    let params = params_of(&whole);
    for incident in [IncidentRange::UpperHemisphere, IncidentRange::WholeSphere] {
        for precision in [Precision::F32, Precision::F16] {
            let mut def = *whole.def();
            def.incident = incident;
            def.precision = precision;
            let bytes = blob(&def, &params);
            // Flag bit 1 at offset 28, set only for the upper hemisphere.
            assert_eq!(
                bytes[28] & 2 != 0,
                incident == IncidentRange::UpperHemisphere
            );
            assert_eq!(
                Model4x32::from_blob(&bytes).map(|m| m.def().incident),
                Ok(incident)
            );
        }
    }
    // A disk blob is always upper-hemisphere, flag or not.
    let mut disk = ModelDef::paper_disk();
    disk.incident = IncidentRange::WholeSphere;
    let bytes = blob(&disk, &vec![0.01; disk.param_count()]);
    assert_eq!(
        AnyModel::from_blob(&bytes).map(|m| m.def().incident),
        Ok(IncidentRange::UpperHemisphere)
    );
    assert!(!disk.accepts_incident_z(-0.5));
    // Unknown flag bits are still rejected.
    let mut bad = blob(whole.def(), &params);
    bad[28] |= 8;
    let n = bad.len() - 4;
    let crc = diffbsdf::internals::blob::crc32(&bad[..n]);
    bad[n..].copy_from_slice(&crc.to_le_bytes());
    assert!(matches!(
        Model4x32::from_blob(&bad),
        Err(BlobError::BadHeader(_))
    ));
}
