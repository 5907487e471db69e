//! Samples per second of the C ABI's batch calls on 1 and 2 threads (and every core, if
//! more), for the shipped copper disk (3x32, N = 4) and sphere (4x32, N = 8) models:
//! `cargo bench -p diffbsdf-ffi --bench parallel`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use diffbsdf_ffi::*;

#[path = "../tests/support/rows.rs"]
mod rows;

const BATCH: usize = 16_384;

fn bench_model(c: &mut Criterion, label: &str, name: &str) {
    let m = rows::shipped(name);
    let (wi, u) = rows::inputs(BATCH, false);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as u32;
    let mut threads = vec![1, 2];
    if cores > 2 {
        threads.push(cores);
    }
    let mut group = c.benchmark_group(label);
    group.throughput(Throughput::Elements(BATCH as u64));
    group.sample_size(20);
    let mut dirs = vec![0.0f32; 3 * BATCH];
    let mut samples = vec![diffbsdf_sample_result::default(); BATCH];
    let mut pdfs = vec![0.0f32; BATCH];
    let st = unsafe {
        diffbsdf_sample_batch(m, wi.as_ptr(), u.as_ptr(), BATCH, 0, samples.as_mut_ptr())
    };
    assert_eq!(st as i32, 0);
    let wo: Vec<f32> = samples.iter().flat_map(|s| s.wo).collect();
    for &t in &threads {
        group.bench_function(BenchmarkId::new("direction_only", t), |b| {
            b.iter(|| unsafe {
                diffbsdf_sample_direction_batch_parallel(
                    m,
                    wi.as_ptr(),
                    u.as_ptr(),
                    BATCH,
                    0,
                    t,
                    dirs.as_mut_ptr(),
                )
            })
        });
        group.bench_function(BenchmarkId::new("direction_and_pdf", t), |b| {
            b.iter(|| unsafe {
                diffbsdf_sample_batch_parallel(
                    m,
                    wi.as_ptr(),
                    u.as_ptr(),
                    BATCH,
                    0,
                    t,
                    samples.as_mut_ptr(),
                )
            })
        });
        group.bench_function(BenchmarkId::new("pdf_of_direction", t), |b| {
            b.iter(|| unsafe {
                diffbsdf_pdf_batch_parallel(
                    m,
                    wi.as_ptr(),
                    wo.as_ptr(),
                    BATCH,
                    0,
                    t,
                    pdfs.as_mut_ptr(),
                )
            })
        });
    }
    group.finish();
    unsafe { diffbsdf_model_free(m) };
}

fn parallel(c: &mut Criterion) {
    bench_model(c, "c_abi_disk_3x32_n4", "conductor-ggx-a0.3-cu-disk");
    bench_model(c, "c_abi_sphere_4x32_n8", "conductor-ggx-a0.3-cu-sphere");
}

criterion_group!(benches, parallel);
criterion_main!(benches);
