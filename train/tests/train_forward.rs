//! The trainer's forward pass is the kernel's: a student's velocity and base outputs,
//! computed by the training MLP on training features, equal what the kernel computes from
//! the exported parameters.

use diffbsdf::glam::Vec3;
use diffbsdf::internals::base::BaseDist;
use diffbsdf::internals::Diagnostics;
use diffbsdf::{AnyModel, Domain, Net};
use diffbsdf_train::features::{encoding, push_velocity_row};
use diffbsdf_train::mlp::Mlp;
use diffbsdf_train::{model_from_nets, paper_def, ModelExt};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

fn check(domain: Domain, layers: u8) {
    let mut rng = Pcg64::seed_from_u64(11);
    let def = paper_def(domain);
    assert_eq!(def.velocity.hidden_layers, layers);
    let base = Mlp::new(&def, Net::Base, &mut rng);
    let vel = Mlp::new(&def, Net::Velocity, &mut rng);
    let model = model_from_nets(def, &base, &vel).unwrap();
    // Round trip through the f32 blob as well.
    let model = AnyModel::from_blob(&model.blob(diffbsdf::Precision::F32).unwrap()).unwrap();
    let mut worst = 0.0f32;
    for _ in 0..200 {
        let (th, ph) = (rng.gen_range(0.0..1.5f32), rng.gen_range(-3.1..3.1f32));
        let wi = [th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()];
        let x = [rng.gen_range(-1.0..1.0f32), rng.gen_range(-3.0..3.0f32)];
        let t = rng.gen::<f32>();
        let mut row = Vec::new();
        push_velocity_row(&def, x, t, &encoding(wi, def.velocity.freqs), &mut row);
        let mut v = [0.0f32; 2];
        vel.forward(&row, &mut v);
        let (k, _) = model.velocity_at(Vec3::from(wi), x, t).unwrap();
        for c in 0..2 {
            worst = worst.max((v[c] - k[c]).abs() / (1.0 + k[c].abs()));
        }
        let mut o = [0.0f32; 4];
        base.forward(&encoding(wi, def.base.freqs), &mut o);
        let mine = BaseDist::from_net(domain, o);
        let kernel = model.base_distribution(Vec3::from(wi)).unwrap();
        let (a, b) = (mine.sample([0.3, 0.8]), kernel.sample([0.3, 0.8]));
        worst = worst.max((a[0] - b[0]).abs().max((a[1] - b[1]).abs()));
    }
    assert!(
        worst < 2e-5,
        "{domain:?}: training forward differs from the kernel by {worst}"
    );
}

#[test]
fn disk_student_forward_equals_kernel() {
    check(Domain::Disk, 3);
}

#[test]
fn sphere_student_forward_equals_kernel() {
    check(Domain::Sphere, 4);
}
