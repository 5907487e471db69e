//! The trainer's inner loop: loss and gradient of one batch of the standard teacher
//! (sphere, 4x96, 1024 rows), the step that takes most of a fit's time.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use diffbsdf::{ModelDef, Net, NetShape};
use diffbsdf_train::batch::loss_and_grad;
use diffbsdf_train::mlp::Mlp;
use diffbsdf_train::pipeline::{paper_def, STANDARD_TEACHER_WIDTH};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

const ROWS: usize = 1024;

fn teacher_step(c: &mut Criterion) {
    let student = paper_def(diffbsdf::Domain::Sphere);
    let def = ModelDef {
        velocity: NetShape {
            width: STANDARD_TEACHER_WIDTH,
            ..student.velocity
        },
        ..student
    };
    let mut rng = Pcg64::seed_from_u64(7);
    let net = Mlp::new(&def, Net::Velocity, &mut rng);
    let inputs: Vec<f32> = (0..ROWS * net.inputs())
        .map(|_| rng.gen_range(-1.0f32..1.0))
        .collect();
    let mut group = c.benchmark_group("train");
    group.throughput(Throughput::Elements(ROWS as u64));
    group.bench_function("teacher 4x96 loss and gradient, 1024 rows", |b| {
        b.iter(|| {
            loss_and_grad(&net, &inputs, |_, v, d| {
                d[0] = v[0];
                d[1] = v[1];
                f64::from(v[0] * v[0] + v[1] * v[1])
            })
        })
    });
    group.finish();
}

criterion_group!(benches, teacher_step);
criterion_main!(benches);
