//! The criterion bench behind `diffbsdf tradeoff`: time per call of the shipped rough
//! copper models (disk N = 4 and sphere N = 8 as trained, f32 and f16 weights) at every
//! step count of the sweep, for the three entry points, next to the material's own
//! sampler in the same run.
//!
//! `cargo bench -p diffbsdf-cli --bench tradeoff`; throughput in calls per second.

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::AnyModel;
use diffbsdf_materials::parse_spec;
use diffbsdf_train::ModelExt;

const CALLS: usize = 1024;
const STEPS: [u16; 6] = [1, 2, 4, 8, 16, 32];
const COPPER: &str = "conductor:ggx,alpha=0.3,metal=Cu";

const MODELS: [(&str, &[u8]); 4] = [
    (
        "cu_disk_f32",
        include_bytes!("../../models/conductor-ggx-a0.3-cu-disk.dbsdf"),
    ),
    (
        "cu_disk_f16",
        include_bytes!("../../models/conductor-ggx-a0.3-cu-disk.f16.dbsdf"),
    ),
    (
        "cu_sphere_f32",
        include_bytes!("../../models/conductor-ggx-a0.3-cu-sphere.dbsdf"),
    ),
    (
        "cu_sphere_f16",
        include_bytes!("../../models/conductor-ggx-a0.3-cu-sphere.f16.dbsdf"),
    ),
];

/// `wi` at 45 degrees (as the tradeoff report) and a stratified set of `u`.
fn inputs() -> (Vec3, Vec<Vec2>) {
    let wi = Vec3::new(0.45, 0.57, 0.69).normalize();
    let u = (0..CALLS)
        .map(|k| {
            let a = (k as f32 + 0.5) / CALLS as f32;
            Vec2::new(a, (a * 7919.0).fract())
        })
        .collect();
    (wi, u)
}

fn material_sampler(c: &mut Criterion) {
    let material = parse_spec(COPPER).expect("spec");
    let (wi, u) = inputs();
    let wi = wi.as_dvec3();
    let mut g = c.benchmark_group("material");
    g.throughput(Throughput::Elements(CALLS as u64));
    g.bench_function("cu_ggx_vndf_sample", |b| {
        b.iter(|| {
            for s in &u {
                black_box(material.sample(wi, [s.x as f64, s.y as f64, 0.5]));
            }
        })
    });
    g.finish();
}

fn learned(c: &mut Criterion) {
    let (wi, u) = inputs();
    for (label, blob) in MODELS {
        let model = AnyModel::from_blob(blob).expect("shipped blob");
        let mut g = c.benchmark_group(label);
        g.throughput(Throughput::Elements(CALLS as u64));
        g.sample_size(20);
        for n in STEPS {
            let m = model.with_steps(n);
            g.bench_function(BenchmarkId::new("direction", n), |b| {
                b.iter(|| {
                    for s in &u {
                        black_box(m.sample_direction(black_box(wi), *s));
                    }
                })
            });
            g.bench_function(BenchmarkId::new("direction_and_pdf", n), |b| {
                b.iter(|| {
                    for s in &u {
                        black_box(m.sample(black_box(wi), *s));
                    }
                })
            });
            let wo: Vec<Vec3> = u
                .iter()
                .filter_map(|s| m.sample(wi, *s))
                .map(|s| s.wo)
                .collect();
            g.bench_function(BenchmarkId::new("pdf_of_direction", n), |b| {
                b.iter(|| {
                    for w in &wo {
                        black_box(m.pdf(black_box(wi), *w));
                    }
                })
            });
        }
        g.finish();
    }
}

criterion_group!(benches, material_sampler, learned);
criterion_main!(benches);
