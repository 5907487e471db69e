//! Samples per second of the kernel's three entry points, for the paper's disk (3x32, N=4)
//! and sphere (4x32, N=8) architectures, with f32 and f16 weights, over 4096 precomputed
//! inputs per iteration (one core).
//!
//! `cargo bench --bench kernel`; throughput is reported in elements (samples) per second.

#[path = "../tests/support/mod.rs"]
mod support;

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::{internals::blob::blob_len, Model, Precision, Sample};

const BATCH: usize = 4096;

fn round_trip<
    const A: usize,
    const B: usize,
    const C: usize,
    const D: usize,
    const E: usize,
    const F: usize,
>(
    m: &Model<A, B, C, D, E, F>,
    precision: Precision,
) -> Model<A, B, C, D, E, F> {
    let mut def = *m.def();
    def.precision = precision;
    let mut bytes = vec![0u8; blob_len(&def)];
    m.write_blob(precision, &mut bytes).unwrap();
    Model::from_blob(&bytes).unwrap()
}

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
    model: &Model<A, B, C, D, E, F>,
    upper: bool,
) {
    let (wi, u) = inputs(upper);
    let steps = model.default_steps();
    let mut group = c.benchmark_group(format!("{label}_n{steps}"));
    group.throughput(Throughput::Elements(BATCH as u64));
    group.sample_size(20);
    for precision in [Precision::F32, Precision::F16] {
        let m = round_trip(model, precision);
        let p = format!("{precision:?}").to_lowercase();
        let mut dirs = vec![Vec3::ZERO; BATCH];
        group.bench_function(BenchmarkId::new("direction_only", &p), |b| {
            b.iter(|| {
                m.sample_direction_batch(black_box(&wi), black_box(&u), steps, &mut dirs)
                    .unwrap()
            })
        });
        let mut samples = vec![Sample::INVALID; BATCH];
        group.bench_function(BenchmarkId::new("direction_and_pdf", &p), |b| {
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
        group.bench_function(BenchmarkId::new("pdf_of_direction", &p), |b| {
            b.iter(|| {
                m.pdf_batch(black_box(&wi), black_box(&wo), steps, &mut pdfs)
                    .unwrap()
            })
        });
    }
    group.finish();
}

fn kernel(c: &mut Criterion) {
    bench_model(c, "disk_3x32", &support::random_disk(1, 2), true);
    bench_model(c, "sphere_4x32", &support::random_sphere(1, 4), false);
}

criterion_group!(benches, kernel);
criterion_main!(benches);
