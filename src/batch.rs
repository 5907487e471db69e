//! Batch forms over slices, for throughput and for the C API. Invalid samples are written
//! as `wo = 0` (and `pdf = 0`); nothing is skipped, so `out[i]` always belongs to input `i`.

use crate::model::Model;
use crate::sampler::Sample;
use core::fmt;
use glam::{Vec2, Vec3};

/// Why a batch call did nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BatchError {
    /// The input and output slices differ in length.
    LengthMismatch,
}

impl fmt::Display for BatchError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BatchError::LengthMismatch => write!(f, "batch slices differ in length"),
        }
    }
}

fn same_len(a: usize, b: usize, c: usize) -> Result<(), BatchError> {
    if a == b && b == c {
        Ok(())
    } else {
        Err(BatchError::LengthMismatch)
    }
}

impl<
        const BE: usize,
        const BW: usize,
        const BM: usize,
        const VE: usize,
        const VW: usize,
        const VM: usize,
    > Model<BE, BW, BM, VE, VW, VM>
{
    /// `out[i] = sample_direction_steps(wi[i], u[i], steps)`, `Vec3::ZERO` if invalid.
    pub fn sample_direction_batch(
        &self,
        wi: &[Vec3],
        u: &[Vec2],
        steps: u32,
        out: &mut [Vec3],
    ) -> Result<(), BatchError> {
        same_len(wi.len(), u.len(), out.len())?;
        for ((o, &w), &r) in out.iter_mut().zip(wi).zip(u) {
            *o = self
                .sample_direction_steps(w, r, steps)
                .unwrap_or(Vec3::ZERO);
        }
        Ok(())
    }

    /// `out[i] = sample_steps(wi[i], u[i], steps)`, [`Sample::INVALID`] if invalid.
    pub fn sample_batch(
        &self,
        wi: &[Vec3],
        u: &[Vec2],
        steps: u32,
        out: &mut [Sample],
    ) -> Result<(), BatchError> {
        same_len(wi.len(), u.len(), out.len())?;
        for ((o, &w), &r) in out.iter_mut().zip(wi).zip(u) {
            *o = self.sample_steps(w, r, steps).unwrap_or(Sample::INVALID);
        }
        Ok(())
    }

    /// `out[i] = pdf_steps(wi[i], wo[i], steps)`.
    pub fn pdf_batch(
        &self,
        wi: &[Vec3],
        wo: &[Vec3],
        steps: u32,
        out: &mut [f32],
    ) -> Result<(), BatchError> {
        same_len(wi.len(), wo.len(), out.len())?;
        for ((o, &a), &b) in out.iter_mut().zip(wi).zip(wo) {
            *o = self.pdf_steps(a, b, steps);
        }
        Ok(())
    }
}
