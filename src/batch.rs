//! Batch forms over slices, for throughput and for the C API. Invalid samples are written
//! as `wo = 0` (and `pdf = 0`); nothing is skipped, so `out[i]` always belongs to input `i`.

use crate::model::Model;
use crate::sampler::Sample;
use crate::spec;

/// Samples per flow pass of a batch call.
const LANES: usize = spec::BATCH_LANES;
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
    /// `out[i] = sample_direction_steps(wi[i], u[i], steps)`, `Vec3::ZERO` if invalid, bit
    /// for bit. With fused multiply-adds (the `fma` feature) it runs
    /// [`spec::BATCH_LANES`] samples through the flow together (`docs/performance.md`,
    /// "Samples in lanes"); without them a sample at a time, which is as fast there.
    pub fn sample_direction_batch(
        &self,
        wi: &[Vec3],
        u: &[Vec2],
        steps: u32,
        out: &mut [Vec3],
    ) -> Result<(), BatchError> {
        if spec::FUSED_MULTIPLY_ADD {
            return self.sample_direction_lanes(wi, u, steps, out);
        }
        same_len(wi.len(), u.len(), out.len())?;
        self.directions_one_at_a_time(wi, u, steps, out);
        Ok(())
    }

    /// `out[i] = sample_direction_steps(wi[i], u[i], steps)`, `Vec3::ZERO` if invalid.
    #[inline(always)]
    fn directions_one_at_a_time(&self, wi: &[Vec3], u: &[Vec2], steps: u32, out: &mut [Vec3]) {
        for ((o, &w), &r) in out.iter_mut().zip(wi).zip(u) {
            *o = self
                .sample_direction_steps(w, r, steps)
                .unwrap_or(Vec3::ZERO);
        }
    }

    /// [`Model::sample_direction_batch`] with [`spec::BATCH_LANES`] samples per flow pass,
    /// whatever the build.
    pub(crate) fn sample_direction_lanes(
        &self,
        wi: &[Vec3],
        u: &[Vec2],
        steps: u32,
        out: &mut [Vec3],
    ) -> Result<(), BatchError> {
        same_len(wi.len(), u.len(), out.len())?;
        let Some(steps) = self.resolve_steps(steps) else {
            out.fill(Vec3::ZERO);
            return Ok(());
        };
        let chunks = wi
            .chunks(LANES)
            .zip(u.chunks(LANES))
            .zip(out.chunks_mut(LANES));
        for ((w, r), o) in chunks {
            match (<&[Vec3; LANES]>::try_from(w), <&[Vec2; LANES]>::try_from(r)) {
                (Ok(w), Ok(r)) => self.directions_in_lanes(w, r, steps, o),
                _ => self.directions_one_at_a_time(w, r, steps, o),
            }
        }
        Ok(())
    }

    /// [`spec::BATCH_LANES`] directions through one flow pass ([`Model::flow_lanes`]); a
    /// lane with invalid input runs another lane's start and writes `Vec3::ZERO`.
    #[inline(always)]
    fn directions_in_lanes(
        &self,
        wi: &[Vec3; LANES],
        u: &[Vec2; LANES],
        steps: u32,
        out: &mut [Vec3],
    ) {
        let starts: [_; LANES] = core::array::from_fn(|s| self.direction_start(wi[s], u[s]));
        let Some(fill) = starts.iter().flatten().next().copied() else {
            out.fill(Vec3::ZERO);
            return;
        };
        let c = starts.map(|s| s.unwrap_or(fill).c);
        let x0 = starts.map(|s| s.unwrap_or(fill).x0);
        let x = self.flow_lanes(&c, x0, steps);
        for ((o, start), xs) in out.iter_mut().zip(&starts).zip(x) {
            *o = start
                .as_ref()
                .and_then(|s| self.direction_end(s, xs))
                .unwrap_or(Vec3::ZERO);
        }
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
