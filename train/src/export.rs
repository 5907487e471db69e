//! The trained student as the kernel sees it: base-net parameters followed by
//! velocity-net parameters (blob order), loaded into the kernel's [`AnyModel`] and written
//! as f32 or f16 blobs.

use crate::error::TrainError;
use crate::mlp::Mlp;
use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::internals::blob::blob_len;
use diffbsdf::internals::Diagnostics;
use diffbsdf::{AnyModel, ModelDef, Precision};

/// The kernel model of `def` from trained base and velocity nets.
pub fn model_from_nets(def: ModelDef, base: &Mlp, velocity: &Mlp) -> Result<AnyModel, TrainError> {
    let mut params = base.params().to_vec();
    params.extend_from_slice(velocity.params());
    Ok(AnyModel::from_params(def, &params)?)
}

/// Conveniences of the tools over the kernel's model.
pub trait ModelExt: Sized {
    /// The blob in `precision`, as a vector.
    fn blob(&self, precision: Precision) -> Result<Vec<u8>, TrainError>;

    /// The same model with another default number of Euler steps.
    fn with_steps(self, steps: u16) -> Self;

    /// Smallest step determinant `det(I + h dv/dx)` along the trajectory from `u`
    /// (default steps, at most 64).
    fn min_det(&self, wi: Vec3, u: Vec2) -> Option<f32>;
}

impl ModelExt for AnyModel {
    fn blob(&self, precision: Precision) -> Result<Vec<u8>, TrainError> {
        let mut def = *self.def();
        def.precision = precision;
        let mut out = vec![0u8; blob_len(&def)];
        let n = self.write_blob(precision, &mut out)?;
        out.truncate(n);
        Ok(out)
    }

    fn with_steps(mut self, steps: u16) -> Self {
        let name = self.def().name;
        self.set_metadata(name, steps);
        self
    }

    fn min_det(&self, wi: Vec3, u: Vec2) -> Option<f32> {
        let steps = self.def().default_steps as u32;
        let mut pts = vec![[0.0f32; 2]; steps as usize + 1];
        self.trajectory(wi, u, steps, &mut pts)
    }
}
