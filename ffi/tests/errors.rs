//! Error paths of the C API called from Rust: every blob error has its own status, bad
//! pointers and lengths are errors, and invalid numeric input is not.

use diffbsdf::internals::blob::{blob_len, write_blob};
use diffbsdf::{ModelDef, Precision};
use diffbsdf_ffi::*;
use std::ptr::{null, null_mut};

fn blob(def: &ModelDef) -> Vec<u8> {
    let params: Vec<f32> = (0..def.param_count())
        .map(|i| ((i % 7) as f32 - 3.0) * 0.01)
        .collect();
    let mut out = vec![0u8; blob_len(def)];
    write_blob(def, &params, &mut out).expect("blob");
    out
}

fn load(bytes: &[u8]) -> diffbsdf_status {
    let mut st = 0;
    let m = unsafe { diffbsdf_model_new(bytes.as_ptr(), bytes.len(), &mut st) };
    unsafe { diffbsdf_model_free(m) };
    assert_eq!(m.is_null(), st != 0);
    diffbsdf_ffi::diffbsdf_status::ALL
        .into_iter()
        .find(|s| *s as i32 == st)
        .expect("known status")
}

/// Re-seals a modified blob with a correct checksum, so the header check is what fails.
fn reseal(mut b: Vec<u8>) -> Vec<u8> {
    let n = b.len() - 4;
    let crc = diffbsdf::internals::blob::crc32(&b[..n]);
    b[n..].copy_from_slice(&crc.to_le_bytes());
    b
}

#[test]
fn every_blob_error_has_its_status() {
    use diffbsdf_status::*;
    let good = blob(&ModelDef::paper_disk());
    assert_eq!(load(&good), DIFFBSDF_OK);
    assert_eq!(load(&blob(&ModelDef::paper_sphere())), DIFFBSDF_OK);
    let mut b = good.clone();
    b[0] = b'x';
    assert_eq!(load(&b), DIFFBSDF_ERR_BAD_MAGIC);
    let mut b = good.clone();
    b[8] = 9;
    assert_eq!(load(&b), DIFFBSDF_ERR_UNSUPPORTED_VERSION);
    assert_eq!(load(&good[..good.len() - 1]), DIFFBSDF_ERR_TRUNCATED);
    assert_eq!(load(&good[..10]), DIFFBSDF_ERR_TRUNCATED);
    let mut b = good.clone();
    b.push(0);
    assert_eq!(load(&b), DIFFBSDF_ERR_TRAILING_BYTES);
    let mut b = good.clone();
    b[100] ^= 1;
    assert_eq!(load(&b), DIFFBSDF_ERR_CHECKSUM);
    let mut b = good.clone();
    b[10] = 7;
    assert_eq!(load(&reseal(b)), DIFFBSDF_ERR_UNKNOWN_DOMAIN);
    let mut b = good.clone();
    b[11] = 7;
    assert_eq!(load(&reseal(b)), DIFFBSDF_ERR_UNKNOWN_PRECISION);
    let mut b = good.clone();
    b[12] = 7;
    assert_eq!(load(&reseal(b)), DIFFBSDF_ERR_UNKNOWN_ACTIVATION);
    let mut b = good.clone();
    b[28] = 8; // an unknown flag bit (0: isotropic, 1: upper hemisphere, 2: standard coordinates)
    assert_eq!(load(&reseal(b)), DIFFBSDF_ERR_BAD_HEADER);
    // Standard coordinates (flag bit 2) exist on the disk, not on the sphere.
    let mut b = good.clone();
    b[28] = 4;
    assert_eq!(load(&reseal(b)), DIFFBSDF_OK);
    let mut b = blob(&ModelDef::paper_sphere());
    b[28] |= 4;
    assert_eq!(load(&reseal(b)), DIFFBSDF_ERR_BAD_HEADER);
    let mut b = good.clone();
    b[24] ^= 1; // declared parameter count (the length check sees it first)
    assert_eq!(load(&reseal(b)), DIFFBSDF_ERR_TRUNCATED);
    let mut b = good.clone();
    b[64..68].copy_from_slice(&f32::NAN.to_le_bytes());
    assert_eq!(load(&reseal(b)), DIFFBSDF_ERR_NON_FINITE_WEIGHT);
    let mut def = ModelDef::paper_disk();
    def.velocity.hidden_layers = 2;
    assert_eq!(load(&blob(&def)), DIFFBSDF_ERR_SHAPE_MISMATCH);
    let mut def = ModelDef::paper_disk();
    def.precision = Precision::F16;
    assert_eq!(load(&blob(&def)), DIFFBSDF_OK);
}

#[test]
fn param_count_and_buffer_statuses_map() {
    use diffbsdf::BlobError;
    use diffbsdf_status::*;
    let pc = BlobError::ParamCountMismatch {
        declared: 1,
        from_shape: 2,
    };
    assert_eq!(diffbsdf_status::from(pc), DIFFBSDF_ERR_PARAM_COUNT);
    let bt = BlobError::BufferTooSmall { needed: 2, got: 1 };
    assert_eq!(diffbsdf_status::from(bt), DIFFBSDF_ERR_BUFFER_TOO_SMALL);
    let tv = BlobError::TableValueOutOfRange { index: 3 };
    assert_eq!(diffbsdf_status::from(tv), DIFFBSDF_ERR_TABLE_VALUE);
    for s in diffbsdf_status::ALL {
        let msg = unsafe { std::ffi::CStr::from_ptr(diffbsdf_status_message(s as i32)) };
        assert!(!msg.to_bytes().is_empty());
    }
}

#[test]
fn bad_pointers_and_lengths_are_errors() {
    use diffbsdf_status::*;
    let b = blob(&ModelDef::paper_disk());
    let mut mem = vec![0u64; diffbsdf_model_size() / 8 + 2];
    let m = mem.as_mut_ptr().cast::<diffbsdf_model>();
    unsafe {
        assert_eq!(
            diffbsdf_model_init(m, diffbsdf_model_size() - 1, b.as_ptr(), b.len()),
            DIFFBSDF_ERR_LENGTH
        );
        assert_eq!(
            diffbsdf_model_init(null_mut(), 1 << 20, b.as_ptr(), b.len()),
            DIFFBSDF_ERR_NULL
        );
        let odd = mem
            .as_mut_ptr()
            .cast::<u8>()
            .add(1)
            .cast::<diffbsdf_model>();
        if diffbsdf_model_align() > 1 {
            assert_eq!(
                diffbsdf_model_init(odd, 1 << 20, b.as_ptr(), b.len()),
                DIFFBSDF_ERR_MISALIGNED
            );
        }
        assert_eq!(
            diffbsdf_model_init(m, diffbsdf_model_size(), null(), 0),
            DIFFBSDF_ERR_NULL
        );
        assert_eq!(
            diffbsdf_model_init(m, diffbsdf_model_size(), b.as_ptr(), b.len()),
            DIFFBSDF_OK
        );
        let wi = [0.0f32, 0.0, 1.0, 0.0];
        let u = [0.5f32, 0.5];
        let mut wo = [9.0f32; 4];
        let mut pdf = 9.0f32;
        let mut s = diffbsdf_sample_result::default();
        assert_eq!(
            diffbsdf_sample_direction(null(), wi.as_ptr(), u.as_ptr(), 0, wo.as_mut_ptr()),
            DIFFBSDF_ERR_NULL
        );
        let mis = wi.as_ptr().cast::<u8>().add(2).cast::<f32>();
        assert_eq!(
            diffbsdf_sample_direction(m, mis, u.as_ptr(), 0, wo.as_mut_ptr()),
            DIFFBSDF_ERR_MISALIGNED
        );
        assert_eq!(
            diffbsdf_sample(m, wi.as_ptr(), u.as_ptr(), 0, null_mut()),
            DIFFBSDF_ERR_NULL
        );
        assert_eq!(wo, [9.0; 4], "nothing written on error");
        assert_eq!(
            diffbsdf_pdf_batch(m, wi.as_ptr(), wi.as_ptr(), usize::MAX / 2, 0, &mut pdf),
            DIFFBSDF_ERR_LENGTH
        );
        assert_eq!(
            diffbsdf_sample_batch(m, wi.as_ptr(), u.as_ptr(), 1, 0, null_mut()),
            DIFFBSDF_ERR_NULL
        );
        // Invalid numbers are not errors.
        let bad = [0.0f32, 0.0, 2.0];
        assert_eq!(
            diffbsdf_sample(m, bad.as_ptr(), u.as_ptr(), 0, &mut s),
            DIFFBSDF_NO_SAMPLE
        );
        assert_eq!(s, diffbsdf_sample_result::default());
        assert_eq!(
            diffbsdf_pdf(m, bad.as_ptr(), wi.as_ptr(), 0, &mut pdf),
            DIFFBSDF_OK
        );
        assert_eq!(pdf, 0.0);
        let nan_u = [f32::NAN, 0.5];
        assert_eq!(
            diffbsdf_sample_direction(m, wi.as_ptr(), nan_u.as_ptr(), 3, wo.as_mut_ptr()),
            DIFFBSDF_NO_SAMPLE
        );
        assert_eq!(&wo[..3], &[0.0; 3]);
        // In-place batch: outputs may alias inputs.
        let mut buf = [0.0f32, 0.0, 1.0, 0.3, 0.0, 0.954_339_3];
        assert_eq!(
            diffbsdf_pdf_batch(m, buf.as_ptr(), buf.as_ptr().add(3), 1, 0, buf.as_mut_ptr()),
            DIFFBSDF_OK
        );
        assert!(buf[0].is_finite() && buf[0] >= 0.0);
        let mut info = std::mem::MaybeUninit::<diffbsdf_info>::uninit();
        assert_eq!(diffbsdf_model_info(m, info.as_mut_ptr()), DIFFBSDF_OK);
        let info = info.assume_init();
        assert_eq!(
            (info.domain, info.velocity_hidden_layers, info.default_steps),
            (0, 3, 4)
        );
    }
}
