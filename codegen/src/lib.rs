//! Code generator (see issue "Use it from C, GLSL and WGSL").
