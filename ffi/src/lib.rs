//! C ABI over the kernel (see issue "Use it from C, GLSL and WGSL").
