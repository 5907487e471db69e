//! Time per sample of the learned model (with and without PDF, and the PDF of a given
//! direction) next to the material's own sampler, measured in the same run on one thread.
//! Ratios are what to read; bare times depend on the machine and its load.

use super::sampler::to_glam;
use diffbsdf::glam::Vec2;
use diffbsdf::AnyModel;
use diffbsdf_materials::{DVec3, Material};
use serde::{Deserialize, Serialize};
use std::hint::black_box;
use std::time::Instant;

/// Nanoseconds per call.
#[derive(Clone, Copy, Debug, Serialize, Deserialize)]
pub struct Cost {
    /// Learned: direction only.
    pub learned_direction_ns: f64,
    /// Learned: direction and PDF.
    pub learned_sample_ns: f64,
    /// Learned: PDF of a given direction (exact inverse).
    pub learned_pdf_ns: f64,
    /// The material's own sampler (direction, PDF and weight).
    pub material_sample_ns: f64,
    /// `learned_sample_ns / material_sample_ns`.
    pub ratio_sample: f64,
}

/// Times `n` calls of each at a fixed `wi`.
pub fn measure(model: &AnyModel, material: &dyn Material, wi: DVec3, n: usize) -> Cost {
    let g = to_glam(wi);
    let us: Vec<Vec2> = (0..n)
        .map(|k| {
            let a = (k as f32 + 0.5) / n as f32;
            Vec2::new(a, (a * 7919.0).fract())
        })
        .collect();
    let time = |f: &mut dyn FnMut(Vec2)| {
        let t = Instant::now();
        for &u in &us {
            f(u);
        }
        t.elapsed().as_secs_f64() * 1e9 / n.max(1) as f64
    };
    let dir = time(&mut |u| {
        black_box(model.sample_direction(g, u));
    });
    let sample = time(&mut |u| {
        black_box(model.sample(g, u));
    });
    let wos: Vec<_> = us
        .iter()
        .filter_map(|&u| model.sample(g, u))
        .map(|s| s.wo)
        .collect();
    let t = Instant::now();
    for &wo in &wos {
        black_box(model.pdf(g, wo));
    }
    let pdf = t.elapsed().as_secs_f64() * 1e9 / wos.len().max(1) as f64;
    let mat = time(&mut |u| {
        black_box(material.sample(wi, [u.x as f64, u.y as f64, 0.5]));
    });
    Cost {
        learned_direction_ns: dir,
        learned_sample_ns: sample,
        learned_pdf_ns: pdf,
        material_sample_ns: mat,
        ratio_sample: sample / mat.max(1e-9),
    }
}
