//! Times the generated WGSL on a GPU: `count` samples with their PDF (`sample`) and
//! `count` PDFs of given directions (`pdf`) per dispatch, for the shipped rough-copper disk
//! (3x32, N = 4) and sphere (4x32, N = 8) models with f32 and f16 arithmetic, the weights
//! read from a storage buffer (`--weights buffer`, as a renderer with many materials binds
//! them) or baked into the shader as constants (`--weights baked`).
//!
//! ```text
//! cargo run --release -p diffbsdf-codegen --example gpu_timing -- \
//!     [--adapter NAME] [--count 1048576] [--repeats 10] [--models disk,sphere] \
//!     [--floats f32,f16] [--weights buffer|baked]
//! ```
//!
//! The adapter is the first discrete or integrated GPU (or the first whose name contains
//! `NAME`); with none, the software one, whose figures say nothing about a GPU (and whose
//! shader compiler takes minutes on the sphere shaders: use `--models disk` there). Each
//! figure is the fastest of `repeats` dispatches, timed from submission to completion on
//! the host (buffers uploaded once; the pipelines are compiled before timing). Not a test:
//! nothing depends on a GPU.

#[path = "../tests/support/mod.rs"]
#[allow(dead_code, unused_imports)]
mod support;

use diffbsdf_codegen::{generate, EntryPoints, Float, Language, ModelDesc, Options, Weights};
use std::time::{Duration, Instant};
use support::gpu::Gpu;
use support::shaders::wgsl_compute;
use wgpu::util::DeviceExt;

struct Args {
    adapter: Option<String>,
    count: usize,
    repeats: usize,
    models: Vec<String>,
    floats: Vec<String>,
    baked: bool,
}

fn args() -> Args {
    let mut a = Args {
        adapter: None,
        count: 1 << 20,
        repeats: 10,
        models: vec!["disk".into(), "sphere".into()],
        floats: vec!["f32".into(), "f16".into()],
        baked: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let value = it.next().unwrap_or_else(|| panic!("{flag} needs a value"));
        let list = |v: &str| v.split(',').map(str::to_owned).collect();
        match flag.as_str() {
            "--adapter" => a.adapter = Some(value),
            "--count" => a.count = value.parse().expect("--count: a number"),
            "--repeats" => a.repeats = value.parse().expect("--repeats: a number"),
            "--models" => a.models = list(&value),
            "--floats" => a.floats = list(&value),
            "--weights" => a.baked = value == "baked",
            _ => panic!("unknown option {flag}"),
        }
    }
    a
}

/// The adapter: by name, else the first hardware GPU, else the first there is.
fn adapter(name: Option<&str>) -> wgpu::Adapter {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::all();
    let instance = wgpu::Instance::new(desc);
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
    let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
    let hardware = |a: &wgpu::Adapter| {
        matches!(
            a.get_info().device_type,
            wgpu::DeviceType::DiscreteGpu | wgpu::DeviceType::IntegratedGpu
        )
    };
    let pick = match name {
        Some(n) => adapters.iter().position(|a| a.get_info().name.contains(n)),
        None => adapters
            .iter()
            .position(hardware)
            .or((!adapters.is_empty()).then_some(0)),
    };
    let index = pick.unwrap_or_else(|| panic!("no adapter {name:?} among {names:?}"));
    adapters
        .into_iter()
        .nth(index)
        .expect("index from the list")
}

/// `count` upper-hemisphere `wi` and uniform `u` as the test kernels' inputs (mode 0).
fn sample_inputs(count: usize) -> Vec<[f32; 4]> {
    let mut s = 7u64;
    let mut next = || {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let zero = f32::from_bits(0);
    let mut out = Vec::with_capacity(2 * count);
    for _ in 0..count {
        let z = 0.05 + 0.95 * next();
        let phi = std::f32::consts::TAU * next();
        let r = (1.0 - z * z).sqrt();
        out.push([r * phi.cos(), r * phi.sin(), z, zero]);
        out.push([next(), next(), 0.0, zero]);
    }
    out
}

/// The pdf inputs (mode 1): each `wi` with the direction its sample produced (or `wi`).
fn pdf_inputs(samples: &[[f32; 4]], outputs: &[[f32; 4]]) -> Vec<[f32; 4]> {
    let one = f32::from_bits(1);
    let mut out = Vec::with_capacity(samples.len());
    for (pair, result) in samples.chunks_exact(2).zip(outputs.chunks_exact(2)) {
        let wi = pair[0];
        let s = result[1];
        let wo = if s[3] > 0.0 {
            [s[0], s[1], s[2]]
        } else {
            [wi[0], wi[1], wi[2]]
        };
        out.push([wi[0], wi[1], wi[2], one]);
        out.push([wo[0], wo[1], wo[2], 0.0]);
    }
    out
}

/// The fastest of `repeats` dispatches of `pipeline` over `inputs` (weights `params`),
/// submission to completion.
fn time(
    gpu: &Gpu,
    pipeline: &wgpu::ComputePipeline,
    params: &[f32],
    inputs: &[[f32; 4]],
    repeats: usize,
) -> Duration {
    let d = &gpu.device;
    let bytes: Vec<u8> = inputs
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let storage = |contents: &[u8]| {
        d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents,
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let params: Vec<u8> = if params.is_empty() {
        vec![0; 4]
    } else {
        params.iter().flat_map(|x| x.to_le_bytes()).collect()
    };
    let params = storage(&params);
    let inp = storage(&bytes);
    let outp = storage(&vec![0u8; bytes.len()]);
    let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: gpu.bind_group_layout(),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: params.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: inp.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: outp.as_entire_binding(),
            },
        ],
    });
    let items = inputs.len() / 2;
    let mut best = Duration::MAX;
    for _ in 0..repeats.max(1) {
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(items.div_ceil(64) as u32, 1, 1);
        }
        let start = Instant::now();
        gpu.queue.submit([enc.finish()]);
        d.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        })
        .expect("poll");
        best = best.min(start.elapsed());
    }
    best
}

fn main() {
    let a = args();
    let adapter = adapter(a.adapter.as_deref());
    let info = adapter.get_info();
    let f16 = adapter.features().contains(wgpu::Features::SHADER_F16);
    let features = if f16 {
        wgpu::Features::SHADER_F16
    } else {
        wgpu::Features::empty()
    };
    let gpu = Gpu::on(&adapter, features);
    println!(
        "adapter: {} ({:?}, {:?}, driver {} {}); {} items per dispatch, best of {}",
        info.name,
        info.device_type,
        info.backend,
        info.driver,
        info.driver_info,
        a.count,
        a.repeats
    );
    if !matches!(
        info.device_type,
        wgpu::DeviceType::DiscreteGpu | wgpu::DeviceType::IntegratedGpu
    ) {
        println!("(not a hardware GPU: these figures say nothing about one)");
    }
    println!();
    println!("| model | arithmetic | entry point | ms per dispatch | M items/s |");
    println!("|---|---|---|---:|---:|");
    let models = [
        ("disk", "conductor-ggx-a0.3-cu-disk"),
        ("sphere", "conductor-ggx-a0.3-cu-sphere"),
    ];
    let samples = sample_inputs(a.count);
    for (label, file) in models
        .iter()
        .filter(|(l, _)| a.models.iter().any(|m| m == l))
    {
        let path = format!("{}/../models/{file}.dbsdf", env!("CARGO_MANIFEST_DIR"));
        let blob = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
        let params = if a.baked {
            Vec::new()
        } else {
            ModelDesc::from_blob(&blob).expect("blob").params
        };
        for float in [Float::F32, Float::F16] {
            let name = if float == Float::F32 { "f32" } else { "f16" };
            if !a.floats.iter().any(|f| f == name) {
                continue;
            }
            if float == Float::F16 && !f16 {
                println!("| {label} | f16 | (adapter has no shader f16) | | |");
                continue;
            }
            let pipeline = |e: EntryPoints| {
                let options = Options {
                    language: Language::Wgsl,
                    float,
                    entry_points: e,
                    weights: if a.baked {
                        Weights::Baked
                    } else {
                        Weights::Buffer { set: 0, binding: 0 }
                    },
                    prefix: Some("dbsdf".into()),
                };
                let code = generate(&blob, &options).expect("generate");
                // The material's offset in the buffer: 0 (it is the only one).
                let start = std::time::Instant::now();
                let p = gpu.pipeline(&gpu.wgsl(&wgsl_compute(&code, e, !a.baked, 0)));
                eprintln!(
                    "{label} {name} {e:?}: pipeline compiled in {:.1} s",
                    start.elapsed().as_secs_f64()
                );
                p
            };
            let sample = pipeline(EntryPoints {
                direction: false,
                sample: true,
                pdf: false,
            });
            let pdf = pipeline(EntryPoints {
                direction: false,
                sample: false,
                pdf: true,
            });
            let outputs = gpu.run(&sample, &params, &samples);
            let valid = outputs.chunks_exact(2).filter(|r| r[1][3] > 0.0).count();
            let pdf_in = pdf_inputs(&samples, &outputs);
            for (entry, p, inputs) in [
                ("sample (direction + PDF)", &sample, &samples),
                ("pdf", &pdf, &pdf_in),
            ] {
                let t = time(&gpu, p, &params, inputs, a.repeats);
                let ms = t.as_secs_f64() * 1e3;
                let rate = a.count as f64 / t.as_secs_f64() / 1e6;
                println!("| {label} | {name} | {entry} | {ms:.2} | {rate:.3} |");
            }
            eprintln!("{label} {name}: {valid} of {} samples valid", a.count);
        }
    }
}
