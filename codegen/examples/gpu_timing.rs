//! Times the generated WGSL on a GPU: `count` directions (`direction`), `count` samples
//! with their PDF (`sample`) and `count` PDFs of given directions (`pdf`) per dispatch, for
//! the shipped rough-copper disk (3x32, N = 4) and sphere (4x32, N = 8) models with f32 and
//! f16 arithmetic, the weights read from a storage buffer (`buffer`, as a renderer with
//! many materials binds them) and baked into the shader as constants (`baked`).
//!
//! ```text
//! cargo run --release -p diffbsdf-codegen --example gpu_timing -- \
//!     [--adapter NAME] [--count 1048576] [--repeats 20] [--models disk,sphere] \
//!     [--floats f32,f16] [--weights buffer,baked] [--checks on,off,...] [--workgroup 64]
//! ```
//!
//! The adapter is the first discrete or integrated GPU (or the first whose name contains
//! `NAME`); with none, the software one, whose figures say nothing about a GPU (and whose
//! shader compiler takes minutes on the sphere shaders: use `--models disk` there). Each
//! entry point runs once untimed, then `repeats` dispatches each timed on the GPU (the
//! compute pass between two timestamp queries, where the adapter has them) and on the host
//! (submission to completion); the table gives the best and the median of each, and the
//! rate from the GPU median. `--checks on,off,no-bounds,no-loop-bound` also times each
//! shader without the run-time checks wgpu adds to WGSL (index clamping, loop bounding),
//! or without one of them. Buffers are uploaded once and the pipelines compiled before
//! timing. Not a test: nothing depends on a GPU. `scripts/gpu.sh` runs the conformance
//! tests on the GPU's driver and then this, in one command.

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
    weights: Vec<String>,
    checks: Vec<String>,
    workgroup: usize,
}

fn args() -> Args {
    let mut a = Args {
        adapter: None,
        count: 1 << 20,
        repeats: 20,
        models: vec!["disk".into(), "sphere".into()],
        floats: vec!["f32".into(), "f16".into()],
        weights: vec!["buffer".into(), "baked".into()],
        checks: vec!["on".into()],
        workgroup: 64,
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
            "--weights" => a.weights = list(&value),
            "--checks" => a.checks = list(&value),
            "--workgroup" => a.workgroup = value.parse().expect("--workgroup: a number"),
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

/// The shader module of `source` with wgpu's run-time checks as `checks` says: `on` (all,
/// wgpu's default), `off` (none), `no-bounds` (no index clamping) or `no-loop-bound` (no
/// loop bounding).
fn module(gpu: &Gpu, source: &str, checks: &str) -> wgpu::ShaderModule {
    let desc = wgpu::ShaderModuleDescriptor {
        label: None,
        source: wgpu::ShaderSource::Wgsl(source.into()),
    };
    let mut runtime = wgpu::ShaderRuntimeChecks::checked();
    match checks {
        "on" => return gpu.device.create_shader_module(desc),
        "off" => runtime = wgpu::ShaderRuntimeChecks::unchecked(),
        "no-bounds" => runtime.bounds_checks = false,
        "no-loop-bound" => runtime.force_loop_bounding = false,
        other => panic!("--checks: on, off, no-bounds or no-loop-bound, not {other}"),
    }
    // SAFETY: the generated code indexes its arrays and the buffers only within their
    // lengths and its loops are bounded (both checked by the conformance tests), which is
    // what dropping the checks asks of the caller.
    unsafe { gpu.device.create_shader_module_trusted(desc, runtime) }
}

/// `f()` with wgpu's validation and out-of-memory errors caught: they end the run, named.
fn caught<T>(gpu: &Gpu, what: &str, f: impl FnOnce() -> T) -> T {
    let memory = gpu.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let out = f();
    let errors = [validation, memory].map(|scope| pollster::block_on(scope.pop()));
    if let Some(e) = errors.into_iter().flatten().next() {
        panic!("{what}: {e}");
    }
    out
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

/// One entry point's times over `repeats` dispatches: submission to completion on the host,
/// and (where the adapter has timestamp queries) the compute pass alone on the GPU.
struct Times {
    host: Vec<Duration>,
    gpu: Vec<Duration>,
}

/// The median of `d` (upper middle; zero when empty).
fn median(d: &[Duration]) -> Duration {
    let mut v = d.to_vec();
    v.sort();
    v.get(v.len() / 2).copied().unwrap_or_default()
}

/// The pass's GPU time from its two resolved timestamps (`period` ns per tick).
fn read_timestamps(gpu: &Gpu, readback: &wgpu::Buffer, period: f32) -> Duration {
    readback.map_async(wgpu::MapMode::Read, .., |r| r.expect("map timestamps"));
    gpu.device
        .poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        })
        .expect("poll");
    let ticks: Vec<u64> = {
        let view = readback.get_mapped_range(..).expect("mapped timestamps");
        view.chunks_exact(8)
            .map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect()
    };
    readback.unmap();
    let ns = ticks[1].saturating_sub(ticks[0]) as f64 * f64::from(period);
    Duration::from_nanos(ns as u64)
}

/// `repeats` dispatches of `pipeline` over `inputs` (weights `params`), each timed on its
/// own, after one dispatch that is not timed.
fn time(
    gpu: &Gpu,
    pipeline: &wgpu::ComputePipeline,
    params: &[f32],
    inputs: &[[f32; 4]],
    repeats: usize,
    workgroup: usize,
) -> Times {
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
    let stamps = d.features().contains(wgpu::Features::TIMESTAMP_QUERY);
    let queries = stamps.then(|| {
        let set = d.create_query_set(&wgpu::QuerySetDescriptor {
            label: None,
            ty: wgpu::QueryType::Timestamp,
            count: 2,
        });
        let buffer = |usage| {
            d.create_buffer(&wgpu::BufferDescriptor {
                label: None,
                size: 16,
                usage,
                mapped_at_creation: false,
            })
        };
        let resolve = buffer(wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC);
        let readback = buffer(wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST);
        (set, resolve, readback)
    });
    let period = gpu.queue.get_timestamp_period();
    let items = inputs.len() / 2;
    let mut times = Times {
        host: Vec::new(),
        gpu: Vec::new(),
    };
    for round in 0..=repeats.max(1) {
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let timestamp_writes =
                queries
                    .as_ref()
                    .map(|(set, _, _)| wgpu::ComputePassTimestampWrites {
                        query_set: set,
                        beginning_of_pass_write_index: Some(0),
                        end_of_pass_write_index: Some(1),
                    });
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: None,
                timestamp_writes,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(items.div_ceil(workgroup) as u32, 1, 1);
        }
        if let Some((set, resolve, readback)) = &queries {
            enc.resolve_query_set(set, 0..2, resolve, 0);
            enc.copy_buffer_to_buffer(resolve, 0, readback, 0, 16);
        }
        let start = Instant::now();
        gpu.queue.submit([enc.finish()]);
        d.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        })
        .expect("poll");
        let host = start.elapsed();
        let on_gpu = queries
            .as_ref()
            .map(|(_, _, readback)| read_timestamps(gpu, readback, period));
        // The first round warms caches and clocks; it is not counted.
        if round > 0 {
            times.host.push(host);
            times.gpu.extend(on_gpu);
        }
    }
    times
}

fn main() {
    let a = args();
    let adapter = adapter(a.adapter.as_deref());
    let info = adapter.get_info();
    let f16 = adapter.features().contains(wgpu::Features::SHADER_F16);
    let wanted = wgpu::Features::SHADER_F16 | wgpu::Features::TIMESTAMP_QUERY;
    let gpu = Gpu::on(&adapter, adapter.features() & wanted);
    gpu.device.set_device_lost_callback(|reason, message| {
        eprintln!("device lost ({reason:?}): {message}");
    });
    let stamps = gpu
        .device
        .features()
        .contains(wgpu::Features::TIMESTAMP_QUERY);
    println!(
        "adapter: {} ({:?}, {:?}, driver {} {}); {} items per dispatch in workgroups of {}, {} timed dispatches each",
        info.name,
        info.device_type,
        info.backend,
        info.driver,
        info.driver_info,
        a.count,
        a.workgroup,
        a.repeats
    );
    if !matches!(
        info.device_type,
        wgpu::DeviceType::DiscreteGpu | wgpu::DeviceType::IntegratedGpu
    ) {
        println!("(not a hardware GPU: these figures say nothing about one)");
    }
    if stamps {
        println!(
            "GPU: the compute pass between its two timestamps; host: submission to completion"
        );
    } else {
        println!("(no timestamp queries on this adapter: host times only)");
    }
    println!();
    println!(
        "| model | weights | checks | arithmetic | entry point | GPU ms best / median | host ms best / median | M items/s |"
    );
    println!("|---|---|---|---|---|---:|---:|---:|");
    let models = [
        ("disk", "conductor-ggx-a0.3-cu-disk"),
        ("sphere", "conductor-ggx-a0.3-cu-sphere"),
    ];
    let samples = sample_inputs(a.count);
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    for (label, file) in models
        .iter()
        .filter(|(l, _)| a.models.iter().any(|m| m == l))
    {
        let path = format!("{}/../models/{file}.dbsdf", env!("CARGO_MANIFEST_DIR"));
        let blob = std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
        for (weights, checks) in a
            .weights
            .iter()
            .flat_map(|w| a.checks.iter().map(move |c| (w, c)))
        {
            let baked = weights == "baked";
            let params = if baked {
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
                    println!(
                        "| {label} | {weights} | {checks} | f16 | (adapter has no shader f16) | | | |"
                    );
                    continue;
                }
                let pipeline = |e: EntryPoints| {
                    let options = Options {
                        language: Language::Wgsl,
                        float,
                        entry_points: e,
                        weights: if baked {
                            Weights::Baked
                        } else {
                            Weights::Buffer { set: 0, binding: 0 }
                        },
                        prefix: Some("dbsdf".into()),
                        fused: false,
                    };
                    let code = generate(&blob, &options).expect("generate");
                    // The material's offset in the buffer: 0 (it is the only one).
                    let start = std::time::Instant::now();
                    let what = format!("{label} {weights} checks {checks} {name} {e:?}");
                    let source = wgsl_compute(&code, e, !baked, 0).replace(
                        "@workgroup_size(64)",
                        &format!("@workgroup_size({})", a.workgroup),
                    );
                    let p = caught(&gpu, &what, || gpu.pipeline(&module(&gpu, &source, checks)));
                    eprintln!(
                        "{what}: pipeline compiled in {:.1} s",
                        start.elapsed().as_secs_f64()
                    );
                    p
                };
                let [direction, sample, pdf] = EntryPoints::EACH_ALONE.map(pipeline);
                let outputs = caught(&gpu, "first sample run", || {
                    gpu.run(&sample, &params, &samples)
                });
                let valid = outputs.chunks_exact(2).filter(|r| r[1][3] > 0.0).count();
                let pdf_in = pdf_inputs(&samples, &outputs);
                for (entry, p, inputs) in [
                    ("direction", &direction, &samples),
                    ("sample (direction + PDF)", &sample, &samples),
                    ("pdf", &pdf, &pdf_in),
                ] {
                    let t = time(&gpu, p, &params, inputs, a.repeats, a.workgroup);
                    let (host_best, host_median) = (
                        t.host.iter().min().copied().unwrap_or_default(),
                        median(&t.host),
                    );
                    let gpu_ms = if stamps {
                        let best = t.gpu.iter().min().copied().unwrap_or_default();
                        format!("{:.3} / {:.3}", ms(best), ms(median(&t.gpu)))
                    } else {
                        "-".into()
                    };
                    let per = if stamps { median(&t.gpu) } else { host_median };
                    let rate = a.count as f64 / per.as_secs_f64() / 1e6;
                    println!(
                        "| {label} | {weights} | {checks} | {name} | {entry} | {gpu_ms} | {:.3} / {:.3} | {rate:.2} |",
                        ms(host_best),
                        ms(host_median)
                    );
                }
                eprintln!(
                    "{label} {weights} checks {checks} {name}: {valid} of {} samples valid",
                    a.count
                );
            }
        }
    }
}
