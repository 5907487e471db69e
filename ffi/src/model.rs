//! The model behind the opaque C handle: either compiled architecture.

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::{BlobError, Model3x32, Model4x32, ModelDef, Sample};

/// A loaded model of one of the compiled shapes (velocity net 3x32 or 4x32).
// The variants differ by the fourth velocity layer (4 KiB); boxing them would defeat
// `diffbsdf_model_init`, which places the model in caller memory without allocating.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug)]
pub enum AnyModel {
    /// Velocity net 3x32 (the paper's disk architecture; either domain).
    Three(Model3x32),
    /// Velocity net 4x32 (the paper's sphere architecture; either domain).
    Four(Model4x32),
}

/// Calls `$body` with `$m` bound to the concrete model.
macro_rules! with_model {
    ($any:expr, $m:ident => $body:expr) => {
        match $any {
            AnyModel::Three($m) => $body,
            AnyModel::Four($m) => $body,
        }
    };
}

impl AnyModel {
    /// Loads a blob into whichever compiled shape accepts it.
    pub fn from_blob(bytes: &[u8]) -> Result<Self, BlobError> {
        match Model3x32::from_blob(bytes) {
            Ok(m) => Ok(AnyModel::Three(m)),
            Err(BlobError::ShapeMismatch) => Model4x32::from_blob(bytes).map(AnyModel::Four),
            Err(e) => Err(e),
        }
    }

    pub fn def(&self) -> &ModelDef {
        with_model!(self, m => m.def())
    }

    /// `steps`, or the model's default when 0.
    pub fn steps(&self, steps: u32) -> u32 {
        if steps == 0 {
            self.def().default_steps as u32
        } else {
            steps
        }
    }

    pub fn sample_direction(&self, wi: Vec3, u: Vec2, steps: u32) -> Option<Vec3> {
        let steps = self.steps(steps);
        with_model!(self, m => m.sample_direction_steps(wi, u, steps))
    }

    pub fn sample(&self, wi: Vec3, u: Vec2, steps: u32) -> Option<Sample> {
        let steps = self.steps(steps);
        with_model!(self, m => m.sample_steps(wi, u, steps))
    }

    pub fn pdf(&self, wi: Vec3, wo: Vec3, steps: u32) -> f32 {
        let steps = self.steps(steps);
        with_model!(self, m => m.pdf_steps(wi, wo, steps))
    }
}
