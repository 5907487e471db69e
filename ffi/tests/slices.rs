//! `diffbsdf_ffi::slices` (the batch calls the Python package makes): the kernel's own
//! batch calls, bit for bit, in the AVX2 copy and in the baseline one, invalid rows
//! included, and the same error for slices of different lengths.

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::{AnyModel, BatchError, Sample};
use diffbsdf_ffi::{force_baseline, slices};

#[path = "support/rows.rs"]
mod rows;

const N: usize = 2003;

fn load(name: &str) -> AnyModel {
    let path = format!("{}/../models/{name}.dbsdf", env!("CARGO_MANIFEST_DIR"));
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    AnyModel::from_blob(&bytes).expect("shipped blob")
}

/// Bits of every output of the three slice calls.
fn slice_outputs(m: &AnyModel, wi: &[Vec3], u: &[Vec2]) -> Vec<u32> {
    let mut dirs = vec![Vec3::ONE; wi.len()];
    slices::sample_direction_batch(m, wi, u, 0, &mut dirs).expect("lengths");
    let mut samples = vec![Sample::INVALID; wi.len()];
    slices::sample_batch(m, wi, u, 0, &mut samples).expect("lengths");
    let wo: Vec<Vec3> = samples.iter().map(|s| s.wo).collect();
    let mut pdfs = vec![1.0; wi.len()];
    slices::pdf_batch(m, wi, &wo, 0, &mut pdfs).expect("lengths");
    bits(&dirs, &samples, &pdfs)
}

/// Bits of every output of the kernel's own batch calls.
fn kernel_outputs(m: &AnyModel, wi: &[Vec3], u: &[Vec2]) -> Vec<u32> {
    let mut dirs = vec![Vec3::ONE; wi.len()];
    m.sample_direction_batch(wi, u, 0, &mut dirs)
        .expect("lengths");
    let mut samples = vec![Sample::INVALID; wi.len()];
    m.sample_batch(wi, u, 0, &mut samples).expect("lengths");
    let wo: Vec<Vec3> = samples.iter().map(|s| s.wo).collect();
    let mut pdfs = vec![1.0; wi.len()];
    m.pdf_batch(wi, &wo, 0, &mut pdfs).expect("lengths");
    bits(&dirs, &samples, &pdfs)
}

fn bits(dirs: &[Vec3], samples: &[Sample], pdfs: &[f32]) -> Vec<u32> {
    let v3 = |v: &Vec3| v.to_array().map(f32::to_bits);
    dirs.iter()
        .flat_map(v3)
        .chain(samples.iter().flat_map(|s| v3(&s.wo)))
        .chain(samples.iter().map(|s| s.pdf.to_bits()))
        .chain(pdfs.iter().map(|p| p.to_bits()))
        .collect()
}

#[test]
fn slice_batches_equal_the_kernel_batches_bit_for_bit() {
    let (wi, u) = rows::inputs(N, true);
    let wi: Vec<Vec3> = wi.chunks_exact(3).map(Vec3::from_slice).collect();
    let u: Vec<Vec2> = u.chunks_exact(2).map(Vec2::from_slice).collect();
    for name in [
        "conductor-ggx-a0.3-cu-disk",
        "dielectric-beckmann-a0.3-sphere",
    ] {
        let m = load(name);
        let want = kernel_outputs(&m, &wi, &u);
        let valid = want[3 * N..6 * N]
            .chunks(3)
            .filter(|d| d != &[0, 0, 0])
            .count();
        assert!(valid > N / 2, "{name}: only {valid} valid samples");
        for baseline in [false, true] {
            force_baseline(baseline);
            let got = slice_outputs(&m, &wi, &u);
            force_baseline(false);
            let differ = got.iter().zip(&want).filter(|(a, b)| a != b).count();
            assert_eq!(
                (got.len(), differ),
                (want.len(), 0),
                "{name}, baseline copy {baseline}"
            );
        }
    }
}

#[test]
fn slice_batches_reject_slices_of_different_lengths_and_write_nothing() {
    let m = load("conductor-ggx-a0.3-cu-disk");
    let wi = vec![Vec3::Z; 4];
    let u = vec![Vec2::splat(0.5); 3];
    let mut dirs = vec![Vec3::ONE; 4];
    let got = slices::sample_direction_batch(&m, &wi, &u, 0, &mut dirs);
    assert_eq!(got, Err(BatchError::LengthMismatch));
    assert!(dirs.iter().all(|d| *d == Vec3::ONE));
    let mut samples = vec![Sample::INVALID; 3];
    let got = slices::sample_batch(&m, &wi, &u, 0, &mut samples);
    assert_eq!(got, Err(BatchError::LengthMismatch));
    let mut pdfs = vec![7.0f32; 4];
    let got = slices::pdf_batch(&m, &wi, &wi[..3], 0, &mut pdfs);
    assert_eq!(got, Err(BatchError::LengthMismatch));
    assert!(pdfs.iter().all(|p| *p == 7.0));
}
