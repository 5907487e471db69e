//! The trained student as the kernel sees it: base-net parameters followed by
//! velocity-net parameters (blob order), loaded into the kernel's compiled model and
//! written as f32 or f16 blobs.

use super::error::TrainError;
use super::mlp::Mlp;
use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::internals::blob::blob_len;
use diffbsdf::internals::Diagnostics;
use diffbsdf::{Domain, Model3x32, Model4x32, ModelDef, ModelName, Precision, Sample};

/// A kernel model of one of the two shipped shapes.
#[derive(Clone, Debug)]
pub enum LearnedModel {
    /// The paper's disk shape (velocity 3x32).
    Disk(Box<Model3x32>),
    /// The paper's sphere shape (velocity 4x32).
    Sphere(Box<Model4x32>),
}

impl LearnedModel {
    /// The kernel definition of a student for `domain`.
    pub fn definition(domain: Domain, name: &str, steps: u16) -> Result<ModelDef, TrainError> {
        let mut def = match domain {
            Domain::Disk => ModelDef::paper_disk(),
            Domain::Sphere => ModelDef::paper_sphere(),
        };
        def.name = ModelName::new(name).ok_or(TrainError::NameTooLong)?;
        def.default_steps = steps.max(1);
        Ok(def)
    }

    /// The model from trained base and velocity nets.
    pub fn from_nets(def: ModelDef, base: &Mlp, velocity: &Mlp) -> Result<Self, TrainError> {
        let mut params = base.params().to_vec();
        params.extend_from_slice(velocity.params());
        Self::from_params(def, &params)
    }

    /// The model from parameters in blob order.
    pub fn from_params(def: ModelDef, params: &[f32]) -> Result<Self, TrainError> {
        Ok(match def.domain {
            Domain::Disk => LearnedModel::Disk(Box::new(Model3x32::from_params(def, params)?)),
            Domain::Sphere => LearnedModel::Sphere(Box::new(Model4x32::from_params(def, params)?)),
        })
    }

    /// Loads a blob of either shape.
    pub fn from_blob(bytes: &[u8]) -> Result<Self, TrainError> {
        match Model3x32::from_blob(bytes) {
            Ok(m) => Ok(LearnedModel::Disk(Box::new(m))),
            Err(diffbsdf::BlobError::ShapeMismatch) => {
                Ok(LearnedModel::Sphere(Box::new(Model4x32::from_blob(bytes)?)))
            }
            Err(e) => Err(e.into()),
        }
    }

    /// The same model with another default number of Euler steps.
    pub fn with_steps(mut self, steps: u16) -> Self {
        let name = self.def().name;
        match &mut self {
            LearnedModel::Disk(m) => m.set_metadata(name, steps),
            LearnedModel::Sphere(m) => m.set_metadata(name, steps),
        }
        self
    }

    /// The definition.
    pub fn def(&self) -> &ModelDef {
        match self {
            LearnedModel::Disk(m) => m.def(),
            LearnedModel::Sphere(m) => m.def(),
        }
    }

    /// The blob in `precision`.
    pub fn blob(&self, precision: Precision) -> Result<Vec<u8>, TrainError> {
        let mut def = *self.def();
        def.precision = precision;
        let mut out = vec![0u8; blob_len(&def)];
        let n = match self {
            LearnedModel::Disk(m) => m.write_blob(precision, &mut out)?,
            LearnedModel::Sphere(m) => m.write_blob(precision, &mut out)?,
        };
        out.truncate(n);
        Ok(out)
    }

    /// A direction and its PDF (default steps).
    pub fn sample(&self, wi: Vec3, u: Vec2) -> Option<Sample> {
        match self {
            LearnedModel::Disk(m) => m.sample(wi, u),
            LearnedModel::Sphere(m) => m.sample(wi, u),
        }
    }

    /// A direction without its PDF (default steps).
    pub fn sample_direction(&self, wi: Vec3, u: Vec2) -> Option<Vec3> {
        match self {
            LearnedModel::Disk(m) => m.sample_direction(wi, u),
            LearnedModel::Sphere(m) => m.sample_direction(wi, u),
        }
    }

    /// The PDF of `wo` by the exact inverse (default steps).
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        match self {
            LearnedModel::Disk(m) => m.pdf(wi, wo),
            LearnedModel::Sphere(m) => m.pdf(wi, wo),
        }
    }

    /// Smallest step determinant `det(I + h dv/dx)` along the trajectory from `u`.
    pub fn min_det(&self, wi: Vec3, u: Vec2) -> Option<f32> {
        let mut pts = [[0.0f32; 2]; 65];
        let steps = (self.def().default_steps as u32).min(64);
        match self {
            LearnedModel::Disk(m) => m.trajectory(wi, u, steps, &mut pts),
            LearnedModel::Sphere(m) => m.trajectory(wi, u, steps, &mut pts),
        }
    }

    /// `v` and `dv/dx` at a flow point (the kernel's evaluation).
    pub fn velocity_at(&self, wi: Vec3, x: [f32; 2], t: f32) -> Option<[f32; 2]> {
        match self {
            LearnedModel::Disk(m) => m.velocity_at(wi, x, t).map(|(v, _)| v),
            LearnedModel::Sphere(m) => m.velocity_at(wi, x, t).map(|(v, _)| v),
        }
    }
}
