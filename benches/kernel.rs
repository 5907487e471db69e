//! Samples per second of the kernel's three entry points, for the paper's disk (3x32, N=4)
//! and sphere (4x32, N=8) architectures, with f32 and f16 weights, over 4096 precomputed
//! inputs per iteration (one core). The models are the shipped rough-copper ones: the
//! forward passes cost the same for any weights of a shape, but the inverse's Newton
//! iterations depend on how straight the trained flow is, which random weights are not.
//!
//! `cargo bench --bench kernel`; throughput is reported in elements (samples) per second.

#[path = "../tests/support/mod.rs"]
mod support;

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::{Model, Model3x32, Model4x32, Sample};

const BATCH: usize = 4096;

fn inputs(upper: bool) -> (Vec<Vec3>, Vec<Vec2>) {
    let mut rng = support::Rng::new(99);
    let wi = (0..BATCH)
        .map(|_| support::direction(rng.range(0.05, 1.0), rng.uniform(), upper))
        .collect();
    let u = (0..BATCH)
        .map(|_| Vec2::new(rng.uniform(), rng.uniform()))
        .collect();
    (wi, u)
}

fn bench_model<
    const A: usize,
    const B: usize,
    const C: usize,
    const D: usize,
    const E: usize,
    const F: usize,
>(
    c: &mut Criterion,
    label: &str,
    models: [(&str, Model<A, B, C, D, E, F>); 2],
    upper: bool,
) {
    let (wi, u) = inputs(upper);
    let steps = models[0].1.default_steps();
    let mut group = c.benchmark_group(format!("{label}_n{steps}"));
    group.throughput(Throughput::Elements(BATCH as u64));
    group.sample_size(20);
    for (p, m) in models {
        let mut dirs = vec![Vec3::ZERO; BATCH];
        group.bench_function(BenchmarkId::new("direction_only", p), |b| {
            b.iter(|| {
                m.sample_direction_batch(black_box(&wi), black_box(&u), steps, &mut dirs)
                    .unwrap()
            })
        });
        let mut samples = vec![Sample::INVALID; BATCH];
        group.bench_function(BenchmarkId::new("direction_and_pdf", p), |b| {
            b.iter(|| {
                m.sample_batch(black_box(&wi), black_box(&u), steps, &mut samples)
                    .unwrap()
            })
        });
        let wo: Vec<Vec3> = samples
            .iter()
            .zip(&wi)
            .map(|(s, w)| if s.is_valid() { s.wo } else { *w })
            .collect();
        let mut pdfs = vec![0.0f32; BATCH];
        group.bench_function(BenchmarkId::new("pdf_of_direction", p), |b| {
            b.iter(|| {
                m.pdf_batch(black_box(&wi), black_box(&wo), steps, &mut pdfs)
                    .unwrap()
            })
        });
    }
    group.finish();
}

/// The shipped f32 and f16 blobs of `name` in `models/`.
fn shipped<
    const A: usize,
    const B: usize,
    const C: usize,
    const D: usize,
    const E: usize,
    const F: usize,
>(
    name: &str,
) -> [(&'static str, Model<A, B, C, D, E, F>); 2] {
    let load = |file: String| {
        let path = format!("{}/models/{file}", env!("CARGO_MANIFEST_DIR"));
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
        Model::from_blob(&bytes).unwrap_or_else(|e| panic!("{path}: {e}"))
    };
    [
        ("f32", load(format!("{name}.dbsdf"))),
        ("f16", load(format!("{name}.f16.dbsdf"))),
    ]
}

fn kernel(c: &mut Criterion) {
    let disk: [(&str, Model3x32); 2] = shipped("conductor-ggx-a0.3-cu-disk");
    bench_model(c, "disk_3x32", disk, true);
    let sphere: [(&str, Model4x32); 2] = shipped("conductor-ggx-a0.3-cu-sphere");
    bench_model(c, "sphere_4x32", sphere, true);
    // The half-vector chart (the default for BRDFs), warped standard coordinates and the
    // latent table: a measured material and an analytic one, same shape and step count
    // (their Newton iteration counts in `pdf` differ).
    let measured: [(&str, Model3x32); 2] = shipped("rgl-vch-golden-yellow-hv");
    bench_model(c, "half_vector_3x32_golden_yellow", measured, true);
    let analytic: [(&str, Model3x32); 2] = shipped("conductor-ggx-a0.3-cu-hv");
    bench_model(c, "half_vector_3x32_copper", analytic, true);
}

criterion_group!(benches, kernel);
criterion_main!(benches);
