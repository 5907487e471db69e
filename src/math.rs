//! The math backend, chosen in one place: every transcendental the kernel uses goes
//! through these wrappers (libm, so the crate builds with no `std`).
//!
//! `exp_poly` is the one function the kernel does not take from libm: it is evaluated
//! 32 times per layer per Euler step, so it is written as plain arithmetic that the
//! compiler vectorises across a layer. The trainer uses the same function, so it evaluates the same
//! activation; the generated GLSL, WGSL and C instead call their language's built-in `exp`
//! on the same clamped argument (`spec::EXP_ARG_MIN..=EXP_ARG_MAX`, or
//! `±spec::EXP_ARG_LIMIT_F16` in f16 shaders), which agrees with `exp_poly` to within its
//! 2e-7 relative truncation error.

#[inline(always)]
pub(crate) fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

#[inline(always)]
pub(crate) fn ln(x: f32) -> f32 {
    libm::logf(x)
}

#[inline(always)]
pub(crate) fn exp(x: f32) -> f32 {
    libm::expf(x)
}

#[inline(always)]
pub(crate) fn sin(x: f32) -> f32 {
    libm::sinf(x)
}

#[inline(always)]
pub(crate) fn cos(x: f32) -> f32 {
    libm::cosf(x)
}

#[inline(always)]
pub(crate) fn atan2(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

#[inline(always)]
pub(crate) fn tanh(x: f32) -> f32 {
    libm::tanhf(x)
}

#[inline(always)]
pub(crate) fn sinh(x: f32) -> f32 {
    libm::sinhf(x)
}

#[inline(always)]
pub(crate) fn floor(x: f32) -> f32 {
    libm::floorf(x)
}

/// `exp(x)` for `x` in [-87, 88] (inputs outside are clamped; NaN is never passed here).
///
/// `exp(x) = 2^n * exp(r)` with `n = round(x / ln 2)`, `|r| <= ln(2)/2`, and `exp(r)` by its
/// degree-6 Taylor polynomial (truncation error < 2e-7 relative). Written branch-free so a
/// loop over a layer vectorises.
#[inline(always)]
pub fn exp_poly(x: f32) -> f32 {
    use crate::spec::{EXP_ARG_MAX, EXP_ARG_MIN, LN2_HI, LN2_LO, ROUND_MAGIC};
    const LOG2E: f32 = core::f32::consts::LOG2_E;
    let x = x.clamp(EXP_ARG_MIN, EXP_ARG_MAX);
    let n = (x * LOG2E + ROUND_MAGIC) - ROUND_MAGIC;
    let r = (x - n * LN2_HI) - n * LN2_LO;
    // Horner form of 1 + r + r^2/2 + r^3/6 + r^4/24 + r^5/120 + r^6/720.
    let p = 1.0 / 720.0;
    let p = p * r + 1.0 / 120.0;
    let p = p * r + 1.0 / 24.0;
    let p = p * r + 1.0 / 6.0;
    let p = p * r + 0.5;
    let p = p * r + 1.0;
    let p = p * r + 1.0;
    // 2^n without a float-to-int cast (which is saturating and does not vectorise): the
    // low mantissa bits of 2^23 + (n + 127) hold the biased exponent n + 127, and the shift
    // moves them into the exponent field (the bits of 2^23 fall off the top).
    let biased = n + (127.0 + 8_388_608.0);
    let scale = f32::from_bits(biased.to_bits() << 23);
    p * scale
}
