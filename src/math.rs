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

/// `a * b + c`, the multiply-add of every dense layer and of `exp_poly`'s polynomial.
///
/// Default build: rounded twice, bit for bit `a * b + c` (what the generated GLSL, WGSL and C
/// compute too). With the `fma` feature: rounded once, by the CPU's fused multiply-add.
/// Either way `sample` and `pdf` of one build run the same arithmetic, so they agree.
#[inline(always)]
pub fn mul_add(a: f32, b: f32, c: f32) -> f32 {
    #[cfg(feature = "fma")]
    {
        fused::mul_add(a, b, c)
    }
    #[cfg(not(feature = "fma"))]
    {
        a * b + c
    }
}

#[cfg(feature = "fma")]
mod fused {
    #[cfg(not(all(target_arch = "x86_64", target_feature = "fma")))]
    compile_error!(
        "the `fma` feature needs an x86-64 target with FMA: build with \
         `-C target-feature=+fma` (or a `-C target-cpu` that has it), or without the feature"
    );

    /// `a * b + c` rounded once (`vfmadd`); the compiler vectorises it across a layer.
    #[cfg(all(target_arch = "x86_64", target_feature = "fma"))]
    #[inline(always)]
    #[allow(unsafe_code)]
    pub(super) fn mul_add(a: f32, b: f32, c: f32) -> f32 {
        use core::arch::x86_64::{_mm_cvtss_f32, _mm_fmadd_ss, _mm_set_ss};
        // SAFETY: compiled only for targets with FMA (the `cfg` above); the intrinsics
        // only move values between registers and compute.
        unsafe { _mm_cvtss_f32(_mm_fmadd_ss(_mm_set_ss(a), _mm_set_ss(b), _mm_set_ss(c))) }
    }
}

/// `sqrt(x)`, correctly rounded. On x86-64 the CPU's square-root instruction (SSE is part
/// of the baseline), inlined and encoded for whatever vector extension the calling code is
/// compiled with; elsewhere libm's portable routine, correctly rounded too: the same bits.
#[inline(always)]
#[allow(unsafe_code)]
pub(crate) fn sqrt(x: f32) -> f32 {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_mm_cvtss_f32, _mm_set_ss, _mm_sqrt_ss};
        // SAFETY: SSE is part of every x86-64 target; the intrinsics only move values
        // between registers and compute.
        unsafe { _mm_cvtss_f32(_mm_sqrt_ss(_mm_set_ss(x))) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        libm::sqrtf(x)
    }
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

/// `(sin x, cos x)` with one argument reduction: the same bits as [`sin`] and libm's
/// `cosf` (its `sincosf` shares their reduction and kernels; tested below), in one call
/// instead of two.
#[inline(always)]
pub(crate) fn sin_cos(x: f32) -> (f32, f32) {
    libm::sincosf(x)
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
    let p = mul_add(p, r, 1.0 / 120.0);
    let p = mul_add(p, r, 1.0 / 24.0);
    let p = mul_add(p, r, 1.0 / 6.0);
    let p = mul_add(p, r, 0.5);
    let p = mul_add(p, r, 1.0);
    let p = mul_add(p, r, 1.0);
    // 2^n without a float-to-int cast (which is saturating and does not vectorise): the
    // low mantissa bits of 2^23 + (n + 127) hold the biased exponent n + 127, and the shift
    // moves them into the exponent field (the bits of 2^23 fall off the top).
    let biased = n + (127.0 + 8_388_608.0);
    let scale = f32::from_bits(biased.to_bits() << 23);
    p * scale
}

#[cfg(test)]
mod tests {
    extern crate std;

    /// `sin_cos` gives the bits of `sin` and libm's `cosf`, so code that calls it computes
    /// what the two calls computed: special values, the branch boundaries of the argument
    /// reduction and random floats of every exponent.
    #[test]
    fn sin_cos_matches_sin_and_cos() {
        let special = [
            0.0f32,
            -0.0,
            1e-45,
            f32::MIN_POSITIVE,
            core::f32::consts::FRAC_PI_4,
            core::f32::consts::PI,
            -core::f32::consts::PI,
            1e30,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let random = (0..2_000_000).map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            f32::from_bits((state >> 32) as u32)
        });
        let grid = (-40_000..=40_000).map(|i| i as f32 * 1e-4 * core::f32::consts::PI);
        let same = |a: f32, b: f32| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        for x in special.into_iter().chain(random).chain(grid) {
            let (s, c) = super::sin_cos(x);
            assert!(
                same(s, super::sin(x)),
                "sin({x:e}): {s:e} vs {:e}",
                super::sin(x)
            );
            assert!(
                same(c, libm::cosf(x)),
                "cos({x:e}): {c:e} vs {:e}",
                libm::cosf(x)
            );
        }
    }

    /// `sqrt` is correctly rounded: the same bits as libm's portable routine (what other
    /// targets use) and as `std`'s square root, on the special values and on random floats
    /// of every exponent.
    #[test]
    fn sqrt_matches_the_hardware_square_root() {
        let special = [0.0f32, -0.0, 1.0, -1.0, f32::MIN_POSITIVE, 1e-45, f32::MAX];
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let random = (0..1_000_000).map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            f32::from_bits((state >> 32) as u32 & 0x7fff_ffff)
        });
        for x in special.into_iter().chain(random) {
            let ours = super::sqrt(x);
            for (what, other) in [("std", x.sqrt()), ("libm", libm::sqrtf(x))] {
                assert!(
                    ours.to_bits() == other.to_bits() || (ours.is_nan() && other.is_nan()),
                    "sqrt({x:e}) = {ours:e}, {what} gives {other:e}"
                );
            }
        }
    }
}
