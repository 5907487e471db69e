//! Runs generated shaders as compute shaders on lavapipe (Mesa's software Vulkan driver)
//! through wgpu: WGSL through wgpu's own front end, GLSL as glslang's SPIR-V through
//! naga's SPIR-V front end (wgpu then writes the SPIR-V lavapipe compiles, as for WGSL).
//! Handed to lavapipe as is (passthrough), glslang's SPIR-V of f16 and of `sample` /
//! `pdf` shaders takes lavapipe minutes to tens of minutes to compile at the first
//! dispatch on two cores (more than 5 minutes for an f16 sphere direction shader, with or
//! without `precise` and after `spirv-opt -O`); translated, seconds.
#![allow(dead_code)]

use std::borrow::Cow;

pub const LAVAPIPE_HINT: &str = "apt-get install -y mesa-vulkan-drivers libvulkan1";

pub struct Gpu {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub name: String,
    layout: wgpu::PipelineLayout,
    bgl: wgpu::BindGroupLayout,
    /// The same buffers all read-write, for shaders from naga's SPIR-V front end (it reads
    /// glslang's `readonly` blocks as read-write; wgpu wants the access to match exactly).
    layout_rw: wgpu::PipelineLayout,
}

/// Names the Vulkan adapter the conformance tests run on instead of lavapipe (a part of its
/// name, e.g. `NVIDIA`): the same tests, bounds and vectors on a hardware driver.
pub const ADAPTER_VAR: &str = "DIFFBSDF_GPU_ADAPTER";

/// The lavapipe device with f16 (or the adapter [`ADAPTER_VAR`] names); fails (never
/// skips) when there is none, saying what to install.
pub fn lavapipe() -> Gpu {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    let instance = wgpu::Instance::new(desc);
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
    let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
    let wanted = std::env::var(ADAPTER_VAR).unwrap_or_else(|_| "llvmpipe".into());
    let adapter = adapters
        .into_iter()
        .find(|a| a.get_info().name.contains(&wanted))
        .unwrap_or_else(|| {
            panic!(
                "no Vulkan adapter named *{wanted}* (found {names:?}): for lavapipe install the driver and loader with `{LAVAPIPE_HINT}`"
            )
        });
    let name = adapter.get_info().name;
    let needed = wgpu::Features::SHADER_F16;
    assert!(
        adapter.features().contains(needed),
        "{name} lacks {:?}: a newer `{LAVAPIPE_HINT}` is needed",
        needed - adapter.features()
    );
    Gpu::on(&adapter, needed)
}

impl Gpu {
    /// A device on `adapter` with `features`, and the three-buffer layout of the test
    /// kernels (0 parameters, 1 inputs, 2 outputs).
    pub fn on(adapter: &wgpu::Adapter, features: wgpu::Features) -> Gpu {
        let name = adapter.get_info().name;
        let needed = features;
        let desc = wgpu::DeviceDescriptor {
            label: Some("diffbsdf conformance"),
            required_features: needed,
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        };
        let (device, queue) =
            pollster::block_on(adapter.request_device(&desc)).expect("lavapipe device");
        let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout_of = |read_only: bool| {
            let bgl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: None,
                entries: &[
                    storage(0, read_only),
                    storage(1, read_only),
                    storage(2, false),
                ],
            });
            let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(&bgl)],
                immediate_size: 0,
            });
            (bgl, layout)
        };
        let (bgl, layout) = layout_of(true);
        let (_, layout_rw) = layout_of(false);
        Gpu {
            device,
            queue,
            name,
            layout,
            bgl,
            layout_rw,
        }
    }

    pub fn wgsl(&self, source: &str) -> wgpu::ShaderModule {
        self.device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: None,
                source: wgpu::ShaderSource::Wgsl(Cow::Owned(source.to_string())),
            })
    }

    /// SPIR-V (glslang's, validated by spirv-val) through naga's SPIR-V front end.
    pub fn spirv(&self, words: &[u32]) -> wgpu::ShaderModule {
        self.device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: None,
                source: wgpu::ShaderSource::SpirV(Cow::Borrowed(words)),
            })
    }

    /// The compute pipeline of `module`'s `main` (a WGSL module: parameters and inputs
    /// read-only): the driver compiles the shader here, once, however many times it then
    /// runs.
    pub fn pipeline(&self, module: &wgpu::ShaderModule) -> wgpu::ComputePipeline {
        self.pipeline_in(module, &self.layout)
    }

    /// [`Gpu::pipeline`] for a module from [`Gpu::spirv`] (every buffer read-write).
    pub fn spirv_pipeline(&self, module: &wgpu::ShaderModule) -> wgpu::ComputePipeline {
        self.pipeline_in(module, &self.layout_rw)
    }

    fn pipeline_in(
        &self,
        module: &wgpu::ShaderModule,
        layout: &wgpu::PipelineLayout,
    ) -> wgpu::ComputePipeline {
        self.device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: None,
                layout: Some(layout),
                module,
                entry_point: Some("main"),
                compilation_options: Default::default(),
                cache: None,
            })
    }

    /// The layout of the three buffers (0 parameters, 1 inputs, 2 outputs).
    pub fn bind_group_layout(&self) -> &wgpu::BindGroupLayout {
        &self.bgl
    }

    /// Runs `pipeline` over `inputs` (two vec4 per item), returns two vec4 per item.
    pub fn run(
        &self,
        pipeline: &wgpu::ComputePipeline,
        params: &[f32],
        inputs: &[[f32; 4]],
    ) -> Vec<[f32; 4]> {
        use wgpu::util::DeviceExt;
        let d = &self.device;
        let bytes = |v: &[f32]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
        let params = if params.is_empty() {
            &[0.0f32][..]
        } else {
            params
        };
        let flat: Vec<f32> = inputs.iter().flatten().copied().collect();
        let pbuf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: &bytes(params),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let ibuf = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: None,
            contents: &bytes(&flat),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let size = (flat.len() * 4) as u64;
        let obuf = d.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let rbuf = d.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: pbuf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: ibuf.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: obuf.as_entire_binding(),
                },
            ],
        });
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: None,
                timestamp_writes: None,
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            let items = inputs.len() / 2;
            pass.dispatch_workgroups(items.div_ceil(64) as u32, 1, 1);
        }
        enc.copy_buffer_to_buffer(&obuf, 0, &rbuf, 0, size);
        self.queue.submit([enc.finish()]);
        rbuf.map_async(wgpu::MapMode::Read, .., |r| r.expect("map"));
        d.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: None,
        })
        .expect("poll");
        let view = rbuf.get_mapped_range(..).expect("mapped range");
        let out: Vec<f32> = view
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        out.chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect()
    }
}
