//! Batch calls over slices for Rust callers (the Python package): the C ABI's row loop
//! (`parallel::each`), so the same run-time choice of the kernel's AVX2 copy, and
//! the same bits as the kernel's own batch calls (`AnyModel::sample_batch` etc.), which
//! they otherwise equal: same arguments, same results, same errors.

use crate::parallel::{each, Rows};
use crate::status::diffbsdf_status as S;
use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::{AnyModel, BatchError, Sample};

/// `out[i] = sample_direction_steps(wi[i], u[i], steps)`, `Vec3::ZERO` if invalid.
pub fn sample_direction_batch(
    model: &AnyModel,
    wi: &[Vec3],
    u: &[Vec2],
    steps: u32,
    out: &mut [Vec3],
) -> Result<(), BatchError> {
    same_len(wi.len(), u.len(), out.len())?;
    let rows = DirectionSlices {
        model,
        steps,
        wi,
        u,
        out: out.as_mut_ptr(),
    };
    complete(each(0..out.len(), &rows))
}

/// `out[i] = sample_steps(wi[i], u[i], steps)`, [`Sample::INVALID`] if invalid.
pub fn sample_batch(
    model: &AnyModel,
    wi: &[Vec3],
    u: &[Vec2],
    steps: u32,
    out: &mut [Sample],
) -> Result<(), BatchError> {
    same_len(wi.len(), u.len(), out.len())?;
    let rows = SampleSlices {
        model,
        steps,
        wi,
        u,
        out: out.as_mut_ptr(),
    };
    complete(each(0..out.len(), &rows))
}

/// `out[i] = pdf_steps(wi[i], wo[i], steps)`.
pub fn pdf_batch(
    model: &AnyModel,
    wi: &[Vec3],
    wo: &[Vec3],
    steps: u32,
    out: &mut [f32],
) -> Result<(), BatchError> {
    same_len(wi.len(), wo.len(), out.len())?;
    let rows = PdfSlices {
        model,
        steps,
        wi,
        wo,
        out: out.as_mut_ptr(),
    };
    complete(each(0..out.len(), &rows))
}

fn same_len(a: usize, b: usize, c: usize) -> Result<(), BatchError> {
    if a == b && b == c {
        Ok(())
    } else {
        Err(BatchError::LengthMismatch)
    }
}

/// The rows below never fail: every row writes its output, valid or not.
fn complete(done: Result<(), S>) -> Result<(), BatchError> {
    debug_assert!(done.is_ok());
    Ok(())
}

/// The rows of [`sample_direction_batch`]. `out` is the call's exclusive borrow of an
/// output slice as long as `wi` and `u`, held for the whole call.
struct DirectionSlices<'a> {
    model: &'a AnyModel,
    steps: u32,
    wi: &'a [Vec3],
    u: &'a [Vec2],
    out: *mut Vec3,
}

// SAFETY: `out` comes from a `&mut` slice that the call holds; the rows of one call run on
// the calling thread only (`each`), one write per row.
unsafe impl Sync for DirectionSlices<'_> {}

impl Rows for DirectionSlices<'_> {
    #[inline(always)]
    fn row(&self, i: usize) -> Result<(), S> {
        let (Some(&wi), Some(&u)) = (self.wi.get(i), self.u.get(i)) else {
            return Err(S::DIFFBSDF_ERR_LENGTH);
        };
        let d = self.model.sample_direction_steps(wi, u, self.steps);
        // SAFETY: `i < wi.len() == out.len()` (checked by the caller and just above).
        unsafe { self.out.add(i).write(d.unwrap_or(Vec3::ZERO)) };
        Ok(())
    }
}

/// The rows of [`sample_batch`] (see [`DirectionSlices`]).
struct SampleSlices<'a> {
    model: &'a AnyModel,
    steps: u32,
    wi: &'a [Vec3],
    u: &'a [Vec2],
    out: *mut Sample,
}

// SAFETY: as for `DirectionSlices`.
unsafe impl Sync for SampleSlices<'_> {}

impl Rows for SampleSlices<'_> {
    #[inline(always)]
    fn row(&self, i: usize) -> Result<(), S> {
        let (Some(&wi), Some(&u)) = (self.wi.get(i), self.u.get(i)) else {
            return Err(S::DIFFBSDF_ERR_LENGTH);
        };
        let s = self.model.sample_steps(wi, u, self.steps);
        // SAFETY: `i < wi.len() == out.len()` (checked by the caller and just above).
        unsafe { self.out.add(i).write(s.unwrap_or(Sample::INVALID)) };
        Ok(())
    }
}

/// The rows of [`pdf_batch`] (see [`DirectionSlices`]).
struct PdfSlices<'a> {
    model: &'a AnyModel,
    steps: u32,
    wi: &'a [Vec3],
    wo: &'a [Vec3],
    out: *mut f32,
}

// SAFETY: as for `DirectionSlices`.
unsafe impl Sync for PdfSlices<'_> {}

impl Rows for PdfSlices<'_> {
    #[inline(always)]
    fn row(&self, i: usize) -> Result<(), S> {
        let (Some(&wi), Some(&wo)) = (self.wi.get(i), self.wo.get(i)) else {
            return Err(S::DIFFBSDF_ERR_LENGTH);
        };
        let p = self.model.pdf_steps(wi, wo, self.steps);
        // SAFETY: `i < wi.len() == out.len()` (checked by the caller and just above).
        unsafe { self.out.add(i).write(p) };
        Ok(())
    }
}
