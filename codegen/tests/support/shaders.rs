//! Compute-shader wrappers around generated GLSL and WGSL (prefix `dbsdf`), and the
//! compilers and validators they go through.
#![allow(dead_code)]

use super::vectors::run_tool;
use diffbsdf_codegen::EntryPoints;
use std::path::Path;
use std::process::Command;

/// The right-hand sides of the three outputs: an entry point's call, or zeros.
fn calls(e: EntryPoints, base: &str, v4: &str) -> (String, String, String) {
    let zero = format!("{v4}(0.0)");
    let dir = if e.direction {
        format!("{v4}(dbsdf_sample_direction({base}a.xyz, b.xy, steps), 0.0)")
    } else {
        zero.clone()
    };
    let smp = if e.sample {
        format!("dbsdf_sample({base}a.xyz, b.xy, steps)")
    } else {
        zero.clone()
    };
    let pdf = if e.pdf {
        format!("{v4}(dbsdf_pdf({base}a.xyz, b.xyz, steps), 0.0, 0.0, 0.0)")
    } else {
        zero
    };
    (dir, smp, pdf)
}
fn calls_glsl(e: EntryPoints, base: &str) -> (String, String, String) {
    calls(e, base, "vec4")
}
fn calls_wgsl(e: EntryPoints, base: &str) -> (String, String, String) {
    calls(e, base, "vec4<f32>")
}

pub const GLSLANG_HINT: &str = "apt-get install -y glslang-tools";
pub const SPIRV_HINT: &str = "apt-get install -y spirv-tools";

/// Bindings of the test kernels: 0 parameters (buffer mode), 1 inputs, 2 outputs. Each
/// item is two vec4 in and two vec4 out:
/// in  `(wi, mode) (u or wo, steps)` with mode and steps as raw u32 bits;
/// out mode 0: `(sample_direction, 0) (sample)`; mode 1: `(pdf, 0, 0, 0) (0)`.
pub fn glsl_compute(generated: &str, e: EntryPoints, buffer: bool, param_count: usize) -> String {
    let base = if buffer {
        format!("{param_count}u, ")
    } else {
        String::new()
    };
    let (dir, smp, pdf) = calls_glsl(e, &base);
    format!(
        "#version 450\n{generated}\n\
layout(local_size_x = 64) in;\n\
layout(std430, set = 0, binding = 1) readonly buffer Inputs {{ vec4 inp[]; }};\n\
layout(std430, set = 0, binding = 2) buffer Outputs {{ vec4 outp[]; }};\n\
void main() {{\n\
    uint i = gl_GlobalInvocationID.x;\n\
    if (i >= uint(inp.length()) / 2u) {{ return; }}\n\
    vec4 a = inp[2u * i];\n\
    vec4 b = inp[2u * i + 1u];\n\
    uint steps = floatBitsToUint(b.w);\n\
    if (floatBitsToUint(a.w) == 0u) {{\n\
        outp[2u * i] = {dir};\n\
        outp[2u * i + 1u] = {smp};\n\
    }} else {{\n\
        outp[2u * i] = {pdf};\n\
        outp[2u * i + 1u] = vec4(0.0);\n\
    }}\n\
}}\n"
    )
}

/// The WGSL counterpart of [`glsl_compute`].
pub fn wgsl_compute(generated: &str, e: EntryPoints, buffer: bool, param_count: usize) -> String {
    let base = if buffer {
        format!("{param_count}u, ")
    } else {
        String::new()
    };
    let (dir, smp, pdf) = calls_wgsl(e, &base);
    format!(
        "{generated}\n\
@group(0) @binding(1) var<storage, read> inp: array<vec4<f32>>;\n\
@group(0) @binding(2) var<storage, read_write> outp: array<vec4<f32>>;\n\
@compute @workgroup_size(64)\n\
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {{\n\
    let i = gid.x;\n\
    if (i >= arrayLength(&inp) / 2u) {{ return; }}\n\
    let a = inp[2u * i];\n\
    let b = inp[2u * i + 1u];\n\
    let steps = bitcast<u32>(b.w);\n\
    if (bitcast<u32>(a.w) == 0u) {{\n\
        outp[2u * i] = {dir};\n\
        outp[2u * i + 1u] = {smp};\n\
    }} else {{\n\
        outp[2u * i] = {pdf};\n\
        outp[2u * i + 1u] = vec4<f32>(0.0);\n\
    }}\n\
}}\n"
    )
}

/// Compiles a compute shader with `glslangValidator -V` and validates it with
/// `spirv-val`; returns the SPIR-V words.
pub fn glslang(dir: &Path, name: &str, source: &str) -> Vec<u32> {
    let src = dir.join(format!("{name}.comp"));
    let spv = dir.join(format!("{name}.spv"));
    std::fs::write(&src, source).expect("write shader");
    let mut cmd = Command::new("glslangValidator");
    cmd.arg("-V")
        .arg("--target-env")
        .arg("vulkan1.1")
        .arg(&src)
        .arg("-o")
        .arg(&spv);
    run_tool(&mut cmd, GLSLANG_HINT);
    let mut cmd = Command::new("spirv-val");
    cmd.arg("--target-env").arg("vulkan1.1").arg(&spv);
    run_tool(&mut cmd, SPIRV_HINT);
    let bytes = std::fs::read(&spv).expect("read spv");
    bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// Parses and validates WGSL with naga (all capabilities, f16 included).
pub fn naga_validate(name: &str, source: &str) {
    let module = match naga::front::wgsl::parse_str(source) {
        Ok(m) => m,
        Err(e) => panic!("{name}: WGSL does not parse:\n{}", e.emit_to_string(source)),
    };
    let mut v = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    );
    if let Err(e) = v.validate(&module) {
        panic!(
            "{name}: WGSL does not validate:\n{}",
            e.emit_to_string(source)
        );
    }
}
