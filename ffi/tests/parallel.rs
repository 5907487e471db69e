//! The `_parallel` batch calls: bit for bit the one-thread batch at every thread count
//! (contiguous ranges, the same per-element body), in place as well, with the same
//! pointer errors; and the AVX2 copy of the kernel the library picks at run time gives the
//! same bits as its baseline x86-64 copy.

use diffbsdf_ffi::diffbsdf_status::*;
use diffbsdf_ffi::*;
use rows::shipped;
use std::ptr::null;

#[path = "support/rows.rs"]
mod rows;

/// The shipped copper disk model (3x32, N = 4).
fn model() -> *mut diffbsdf_model {
    shipped("conductor-ggx-a0.3-cu-disk")
}

/// `n` rows, some of them invalid.
fn inputs(n: usize) -> (Vec<f32>, Vec<f32>) {
    rows::inputs(n, true)
}

const N: usize = 3001;
const THREADS: [u32; 6] = [0, 1, 2, 3, 7, 1000];

#[test]
fn parallel_batches_equal_the_one_thread_batch_bit_for_bit() {
    let m = model();
    let (wi, u) = inputs(N);
    unsafe {
        let mut dirs = vec![0.0f32; 3 * N];
        assert_eq!(
            diffbsdf_sample_direction_batch(m, wi.as_ptr(), u.as_ptr(), N, 0, dirs.as_mut_ptr()),
            DIFFBSDF_OK
        );
        let mut samples = vec![diffbsdf_sample_result::default(); N];
        assert_eq!(
            diffbsdf_sample_batch(m, wi.as_ptr(), u.as_ptr(), N, 0, samples.as_mut_ptr()),
            DIFFBSDF_OK
        );
        let wo: Vec<f32> = samples.iter().flat_map(|s| s.wo).collect();
        let mut pdfs = vec![0.0f32; N];
        assert_eq!(
            diffbsdf_pdf_batch(m, wi.as_ptr(), wo.as_ptr(), N, 0, pdfs.as_mut_ptr()),
            DIFFBSDF_OK
        );
        let valid = samples.iter().filter(|s| s.pdf > 0.0).count();
        assert!(
            valid > N * 9 / 10 && valid < N,
            "valid and invalid rows: {valid}"
        );
        assert!(pdfs.iter().filter(|&&p| p > 0.0).count() >= valid);
        for threads in THREADS {
            let mut d = vec![-1.0f32; 3 * N];
            let st = diffbsdf_sample_direction_batch_parallel(
                m,
                wi.as_ptr(),
                u.as_ptr(),
                N,
                0,
                threads,
                d.as_mut_ptr(),
            );
            assert_eq!(st, DIFFBSDF_OK);
            assert!(
                d.iter().zip(&dirs).all(|(a, b)| a.to_bits() == b.to_bits()),
                "directions, {threads} threads"
            );
            let mut s = vec![
                diffbsdf_sample_result {
                    wo: [-1.0; 3],
                    pdf: -1.0
                };
                N
            ];
            let st = diffbsdf_sample_batch_parallel(
                m,
                wi.as_ptr(),
                u.as_ptr(),
                N,
                0,
                threads,
                s.as_mut_ptr(),
            );
            assert_eq!(st, DIFFBSDF_OK);
            assert!(
                s.iter()
                    .zip(&samples)
                    .all(|(a, b)| a.pdf.to_bits() == b.pdf.to_bits()
                        && a.wo.map(f32::to_bits) == b.wo.map(f32::to_bits)),
                "samples, {threads} threads"
            );
            let mut p = vec![-1.0f32; N];
            let st = diffbsdf_pdf_batch_parallel(
                m,
                wi.as_ptr(),
                wo.as_ptr(),
                N,
                0,
                threads,
                p.as_mut_ptr(),
            );
            assert_eq!(st, DIFFBSDF_OK);
            assert!(
                p.iter().zip(&pdfs).all(|(a, b)| a.to_bits() == b.to_bits()),
                "pdfs, {threads} threads"
            );
        }
        diffbsdf_model_free(m);
    }
}

#[test]
fn parallel_batches_work_in_place_and_report_pointer_errors() {
    let m = model();
    let (wi, u) = inputs(N);
    unsafe {
        let mut dirs = vec![0.0f32; 3 * N];
        let st = diffbsdf_sample_direction_batch_parallel(
            m,
            wi.as_ptr(),
            u.as_ptr(),
            N,
            0,
            2,
            dirs.as_mut_ptr(),
        );
        assert_eq!(st, DIFFBSDF_OK);
        // In place: the directions overwritten by their own samples.
        let mut expected = vec![0.0f32; 3 * N];
        assert_eq!(
            diffbsdf_sample_direction_batch(
                m,
                wi.as_ptr(),
                u.as_ptr(),
                N,
                0,
                expected.as_mut_ptr()
            ),
            DIFFBSDF_OK
        );
        let mut buf = wi.clone();
        let st = diffbsdf_sample_direction_batch_parallel(
            m,
            buf.as_ptr(),
            u.as_ptr(),
            N,
            0,
            2,
            buf.as_mut_ptr(),
        );
        assert_eq!(st, DIFFBSDF_OK);
        assert!(buf
            .iter()
            .zip(&expected)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        // Errors: nothing written.
        let mut out = vec![9.0f32; 3 * N];
        let st = diffbsdf_sample_direction_batch_parallel(
            m,
            null(),
            u.as_ptr(),
            N,
            0,
            2,
            out.as_mut_ptr(),
        );
        assert_eq!(st, DIFFBSDF_ERR_NULL);
        let st = diffbsdf_pdf_batch_parallel(
            m,
            wi.as_ptr(),
            wi.as_ptr(),
            usize::MAX / 2,
            0,
            2,
            out.as_mut_ptr(),
        );
        assert_eq!(st, DIFFBSDF_ERR_LENGTH);
        let st = diffbsdf_sample_batch_parallel(
            m,
            wi.as_ptr(),
            u.as_ptr(),
            0,
            0,
            4,
            std::ptr::null_mut(),
        );
        assert_eq!(st, DIFFBSDF_ERR_NULL);
        assert!(out.iter().all(|&x| x == 9.0));
        // An empty batch on many threads is fine.
        let st =
            diffbsdf_pdf_batch_parallel(m, wi.as_ptr(), wi.as_ptr(), 0, 0, 64, out.as_mut_ptr());
        assert_eq!(st, DIFFBSDF_OK);
        diffbsdf_model_free(m);
    }
}

/// Every entry point's outputs on the shipped disk model, single and batch calls.
fn all_outputs(m: *mut diffbsdf_model, wi: &[f32], u: &[f32]) -> Vec<u32> {
    let n = wi.len() / 3;
    let mut bits = Vec::new();
    unsafe {
        let mut dirs = vec![0.0f32; 3 * n];
        let st =
            diffbsdf_sample_direction_batch(m, wi.as_ptr(), u.as_ptr(), n, 0, dirs.as_mut_ptr());
        assert_eq!(st, DIFFBSDF_OK);
        let mut samples = vec![diffbsdf_sample_result::default(); n];
        let st = diffbsdf_sample_batch(m, wi.as_ptr(), u.as_ptr(), n, 0, samples.as_mut_ptr());
        assert_eq!(st, DIFFBSDF_OK);
        let wo: Vec<f32> = samples.iter().flat_map(|s| s.wo).collect();
        let mut pdfs = vec![0.0f32; n];
        let st = diffbsdf_pdf_batch(m, wi.as_ptr(), wo.as_ptr(), n, 0, pdfs.as_mut_ptr());
        assert_eq!(st, DIFFBSDF_OK);
        for i in (0..n).step_by(7) {
            let mut s = diffbsdf_sample_result::default();
            diffbsdf_sample(m, wi[3 * i..].as_ptr(), u[2 * i..].as_ptr(), 0, &mut s);
            let mut p = 0.0f32;
            diffbsdf_pdf(m, wi[3 * i..].as_ptr(), s.wo.as_ptr(), 0, &mut p);
            bits.extend(s.wo.map(f32::to_bits));
            bits.extend([s.pdf.to_bits(), p.to_bits()]);
        }
        bits.extend(dirs.iter().map(|x| x.to_bits()));
        bits.extend(samples.iter().flat_map(|s| s.wo.map(f32::to_bits)));
        bits.extend(samples.iter().map(|s| s.pdf.to_bits()));
        bits.extend(pdfs.iter().map(|x| x.to_bits()));
    }
    bits
}

#[test]
#[cfg(target_arch = "x86_64")]
fn avx2_and_baseline_copies_give_the_same_bits() {
    assert!(
        std::arch::is_x86_feature_detected!("avx2"),
        "this CPU has no AVX2: the AVX2 copy cannot be compared with the baseline one here"
    );
    let (wi, u) = inputs(N);
    // The disk, and the sphere chart's trigonometry.
    for name in [
        "conductor-ggx-a0.3-cu-disk",
        "dielectric-beckmann-a0.3-sphere",
    ] {
        let m = shipped(name);
        let fast = all_outputs(m, &wi, &u);
        force_baseline(true);
        let baseline = all_outputs(m, &wi, &u);
        force_baseline(false);
        let differ = fast.iter().zip(&baseline).filter(|(a, b)| a != b).count();
        assert_eq!(
            (fast.len(), differ),
            (baseline.len(), 0),
            "{name}: AVX2 and baseline outputs differ"
        );
        unsafe { diffbsdf_model_free(m) };
    }
}
