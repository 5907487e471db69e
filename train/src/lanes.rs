//! Eight floats that travel together through the trainer's register tiles ([`crate::tiles`]):
//! one portable form, and on x86-64 one AVX register written with its intrinsics.
//!
//! Both forms round every product and every sum apart (no fused multiply-add), so they give
//! the same bits. The AVX form exists because the compiler, left to vectorise the portable
//! form for a target with AVX-512, turned the weight-gradient tile into masked gathers and
//! scatters of its accumulators (measured on a Zen 4 CPU: the teacher's training 4.3x
//! slower than the same code built for baseline x86-64); written with intrinsics the tile
//! stays in registers whatever the target.

/// Floats per vector: one per partial sum of the kernel's dot product.
pub(crate) const LANES: usize = diffbsdf::spec::DOT_PARTIAL_SUMS;

/// [`LANES`] floats in one vector, with the few operations the tiles need.
pub(crate) trait Lanes: Copy {
    /// Every lane 0.
    fn zero() -> Self;
    /// The first [`LANES`] entries of `v`.
    fn load(v: &[f32]) -> Self;
    /// `x` in every lane.
    fn splat(x: f32) -> Self;
    /// `self + a b`, lane by lane, rounded twice.
    fn add_product(self, a: Self, b: Self) -> Self;
    /// `self + other`, lane by lane.
    fn add(self, other: Self) -> Self;
    /// Writes the lanes to the first [`LANES`] entries of `v`.
    fn store(self, v: &mut [f32]);
    /// The lanes as an array.
    fn to_array(self) -> [f32; LANES];
}

/// The portable form: an array the compiler may vectorise as it sees fit.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable([f32; LANES]);

impl Lanes for Portable {
    #[inline(always)]
    fn zero() -> Self {
        Portable([0.0; LANES])
    }

    #[inline(always)]
    fn load(v: &[f32]) -> Self {
        let mut out = [0.0; LANES];
        out.copy_from_slice(&v[..LANES]);
        Portable(out)
    }

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Portable([x; LANES])
    }

    #[inline(always)]
    fn add_product(self, a: Self, b: Self) -> Self {
        let mut out = self.0;
        for ((o, x), y) in out.iter_mut().zip(a.0).zip(b.0) {
            *o += x * y;
        }
        Portable(out)
    }

    #[inline(always)]
    fn add(self, other: Self) -> Self {
        let mut out = self.0;
        for (o, y) in out.iter_mut().zip(other.0) {
            *o += y;
        }
        Portable(out)
    }

    #[inline(always)]
    fn store(self, v: &mut [f32]) {
        v[..LANES].copy_from_slice(&self.0);
    }

    #[inline(always)]
    fn to_array(self) -> [f32; LANES] {
        self.0
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx::Avx;

/// The AVX form. Its values exist only inside the tiles' AVX2 copies, which run only where
/// the CPU has AVX2 ([`crate::tiles`]'s dispatch checks it first): that is what makes each
/// intrinsic call below sound.
#[cfg(target_arch = "x86_64")]
#[allow(unsafe_code)]
mod avx {
    use super::{Lanes, LANES};
    use std::arch::x86_64::{
        __m256, _mm256_add_ps, _mm256_loadu_ps, _mm256_mul_ps, _mm256_set1_ps, _mm256_setzero_ps,
        _mm256_storeu_ps,
    };

    /// One AVX register of [`LANES`] floats.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Avx(__m256);

    impl Lanes for Avx {
        #[inline(always)]
        fn zero() -> Self {
            // SAFETY: AVX is present wherever an `Avx` is made (module doc).
            Avx(unsafe { _mm256_setzero_ps() })
        }

        #[inline(always)]
        fn load(v: &[f32]) -> Self {
            let v = &v[..LANES];
            // SAFETY: AVX is present (module doc); `v` holds the 8 floats read.
            Avx(unsafe { _mm256_loadu_ps(v.as_ptr()) })
        }

        #[inline(always)]
        fn splat(x: f32) -> Self {
            // SAFETY: AVX is present (module doc).
            Avx(unsafe { _mm256_set1_ps(x) })
        }

        #[inline(always)]
        fn add_product(self, a: Self, b: Self) -> Self {
            // SAFETY: AVX is present (module doc).
            Avx(unsafe { _mm256_add_ps(self.0, _mm256_mul_ps(a.0, b.0)) })
        }

        #[inline(always)]
        fn add(self, other: Self) -> Self {
            // SAFETY: AVX is present (module doc).
            Avx(unsafe { _mm256_add_ps(self.0, other.0) })
        }

        #[inline(always)]
        fn store(self, v: &mut [f32]) {
            let v = &mut v[..LANES];
            // SAFETY: AVX is present (module doc); `v` has room for the 8 floats written.
            unsafe { _mm256_storeu_ps(v.as_mut_ptr(), self.0) }
        }

        #[inline(always)]
        fn to_array(self) -> [f32; LANES] {
            let mut out = [0.0; LANES];
            self.store(&mut out);
            out
        }
    }
}
