//! One runtime shape dispatch: a loaded model of any shape the kernel is compiled for,
//! chosen from the blob's definition. `Copy`, no allocation; the FFI, the trainer and the
//! tools all use this one type.

use crate::batch::BatchError;
use crate::blob::BlobError;
use crate::def::{ModelDef, ModelName, Precision};
use crate::model::{Model3x32, Model4x32};
use crate::sampler::Sample;
use glam::{Vec2, Vec3};

/// A model of one of the compiled shapes: velocity net 3x32 (the paper's disk
/// architecture) or 4x32 (its sphere architecture), on either domain.
// The variants differ by one velocity layer (4 KiB); boxing them would need an allocator
// and defeat loading into caller memory.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AnyModel {
    /// Base 1x16, velocity 3x32.
    Velocity3x32(Model3x32),
    /// Base 1x16, velocity 4x32.
    Velocity4x32(Model4x32),
}

/// Evaluates `$body` with `$m` bound to the concrete model.
macro_rules! with_model {
    ($any:expr, $m:ident => $body:expr) => {
        match $any {
            AnyModel::Velocity3x32($m) => $body,
            AnyModel::Velocity4x32($m) => $body,
        }
    };
}
pub(crate) use with_model;

impl AnyModel {
    /// The velocity-net depths the kernel compiles (hidden layers of width 32), shallowest
    /// first: what a trainer may give a student.
    pub const VELOCITY_HIDDEN_LAYERS: [u8; 2] = [
        Model3x32::VELOCITY_HIDDEN_LAYERS,
        Model4x32::VELOCITY_HIDDEN_LAYERS,
    ];

    /// Whether some compiled shape accepts a model of definition `def`.
    #[must_use]
    pub const fn accepts(def: &ModelDef) -> bool {
        Model3x32::accepts(def) || Model4x32::accepts(def)
    }

    /// Loads and validates a blob of any compiled shape.
    pub fn from_blob(bytes: &[u8]) -> Result<Self, BlobError> {
        match Model3x32::from_blob(bytes) {
            Ok(m) => Ok(AnyModel::Velocity3x32(m)),
            Err(BlobError::ShapeMismatch) => Model4x32::from_blob(bytes).map(Self::Velocity4x32),
            Err(e) => Err(e),
        }
    }

    /// A model of definition `def` from its parameters in blob order.
    pub fn from_params(def: ModelDef, params: &[f32]) -> Result<Self, BlobError> {
        if Model3x32::accepts(&def) {
            Model3x32::from_params(def, params).map(Self::Velocity3x32)
        } else {
            Model4x32::from_params(def, params).map(Self::Velocity4x32)
        }
    }

    /// The definition.
    #[must_use]
    pub fn def(&self) -> &ModelDef {
        with_model!(self, m => m.def())
    }

    /// The model's default number of Euler steps.
    #[must_use]
    pub fn default_steps(&self) -> u32 {
        with_model!(self, m => m.default_steps())
    }

    /// See [`crate::Model::resolve_steps`].
    #[must_use]
    pub fn resolve_steps(&self, steps: u32) -> Option<u32> {
        with_model!(self, m => m.resolve_steps(steps))
    }

    /// Changes the stored name and default step count (metadata only).
    pub fn set_metadata(&mut self, name: ModelName, default_steps: u16) {
        with_model!(self, m => m.set_metadata(name, default_steps))
    }

    /// Copies every parameter, in blob order, into `out`; returns how many were written.
    pub fn params(&self, out: &mut [f32]) -> Result<usize, BlobError> {
        with_model!(self, m => m.params(out))
    }

    /// Writes the model as a blob of the given precision into `out`; returns its length.
    pub fn write_blob(&self, precision: Precision, out: &mut [u8]) -> Result<usize, BlobError> {
        with_model!(self, m => m.write_blob(precision, out))
    }

    /// See [`crate::Model::sample_direction`].
    #[must_use]
    pub fn sample_direction(&self, wi: Vec3, u: Vec2) -> Option<Vec3> {
        with_model!(self, m => m.sample_direction(wi, u))
    }

    /// See [`crate::Model::sample`].
    #[must_use]
    pub fn sample(&self, wi: Vec3, u: Vec2) -> Option<Sample> {
        with_model!(self, m => m.sample(wi, u))
    }

    /// See [`crate::Model::pdf`].
    #[must_use]
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        with_model!(self, m => m.pdf(wi, wo))
    }

    /// See [`crate::Model::sample_direction_steps`].
    #[inline(always)]
    #[must_use]
    pub fn sample_direction_steps(&self, wi: Vec3, u: Vec2, steps: u32) -> Option<Vec3> {
        with_model!(self, m => m.sample_direction_steps(wi, u, steps))
    }

    /// See [`crate::Model::sample_steps`].
    #[inline(always)]
    #[must_use]
    pub fn sample_steps(&self, wi: Vec3, u: Vec2, steps: u32) -> Option<Sample> {
        with_model!(self, m => m.sample_steps(wi, u, steps))
    }

    /// See [`crate::Model::pdf_steps`].
    #[inline(always)]
    #[must_use]
    pub fn pdf_steps(&self, wi: Vec3, wo: Vec3, steps: u32) -> f32 {
        with_model!(self, m => m.pdf_steps(wi, wo, steps))
    }

    /// See [`crate::Model::sample_direction_batch`].
    pub fn sample_direction_batch(
        &self,
        wi: &[Vec3],
        u: &[Vec2],
        steps: u32,
        out: &mut [Vec3],
    ) -> Result<(), BatchError> {
        with_model!(self, m => m.sample_direction_batch(wi, u, steps, out))
    }

    /// See [`crate::Model::sample_batch`].
    pub fn sample_batch(
        &self,
        wi: &[Vec3],
        u: &[Vec2],
        steps: u32,
        out: &mut [Sample],
    ) -> Result<(), BatchError> {
        with_model!(self, m => m.sample_batch(wi, u, steps, out))
    }

    /// See [`crate::Model::pdf_batch`].
    pub fn pdf_batch(
        &self,
        wi: &[Vec3],
        wo: &[Vec3],
        steps: u32,
        out: &mut [f32],
    ) -> Result<(), BatchError> {
        with_model!(self, m => m.pdf_batch(wi, wo, steps, out))
    }
}

impl From<Model3x32> for AnyModel {
    fn from(m: Model3x32) -> Self {
        AnyModel::Velocity3x32(m)
    }
}

impl From<Model4x32> for AnyModel {
    fn from(m: Model4x32) -> Self {
        AnyModel::Velocity4x32(m)
    }
}
