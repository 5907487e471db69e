//! A loaded model: its definition and its two nets, sized at compile time.

use crate::base::table::LatentTable;
use crate::blob::{write_blob_with, Blob, BlobError};
use crate::def::{encoding_len, ModelDef, Precision};
use crate::net::{BaseNet, VelocityNet};

/// A model whose sizes are fixed at compile time:
///
/// - `BE`, `BW`, `BM`: base net encoding length (`3 + 6 * freqs`), width, hidden layers - 1;
/// - `VE`, `VW`, `VM`: the same for the velocity net.
///
/// A blob of another shape is rejected with [`BlobError::ShapeMismatch`]. The aliases
/// [`Model3x32`] and [`Model4x32`] are the paper's disk and sphere architectures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Model<
    const BE: usize,
    const BW: usize,
    const BM: usize,
    const VE: usize,
    const VW: usize,
    const VM: usize,
> {
    pub(crate) def: ModelDef,
    pub(crate) base: BaseNet<BE, BW, BM>,
    pub(crate) velocity: VelocityNet<VE, VW, VM>,
    /// The latent table ([`ModelDef::latent_table`]); the uniform density without one.
    pub(crate) table: LatentTable,
}

/// Base 1x16 (3 frequencies), velocity 3x32 (5 frequencies): the paper's disk model.
pub type Model3x32 = Model<21, 16, 0, 33, 32, 2>;
/// Base 1x16 (3 frequencies), velocity 4x32 (5 frequencies): the paper's sphere model.
pub type Model4x32 = Model<21, 16, 0, 33, 32, 3>;

impl<
        const BE: usize,
        const BW: usize,
        const BM: usize,
        const VE: usize,
        const VW: usize,
        const VM: usize,
    > Model<BE, BW, BM, VE, VW, VM>
{
    /// Hidden layers of this type's velocity net (`ModelDef`'s `velocity.hidden_layers`).
    pub const VELOCITY_HIDDEN_LAYERS: u8 = (VM + 1) as u8;

    /// Whether a model of definition `def` has this type's compiled shape.
    #[must_use]
    pub const fn accepts(def: &ModelDef) -> bool {
        encoding_len(def.base.freqs) == BE
            && def.base.width as usize == BW
            && def.base.hidden_layers as usize == BM + 1
            && encoding_len(def.velocity.freqs) == VE
            && def.velocity.width as usize == VW
            && def.velocity.hidden_layers as usize == VM + 1
            && BE <= VE
            && !(def.standardized && def.domain.is_spherical())
            && (def.standardized || !def.standard_warp)
            && (def.standardized || def.latent_table.is_none())
    }

    /// Loads and validates a blob.
    pub fn from_blob(bytes: &[u8]) -> Result<Self, BlobError> {
        let blob = Blob::parse(bytes)?;
        let mut model = Self::zeroed(blob.def)?;
        let mut weights = blob.weights();
        model.load_params(|| weights.next().unwrap_or(0.0));
        Ok(model)
    }

    /// Loads a blob into `self` in place (no large stack copy). On error `self` is left
    /// exactly as it was.
    pub fn load_into(&mut self, bytes: &[u8]) -> Result<(), BlobError> {
        let blob = Blob::parse(bytes)?;
        if !Self::accepts(&blob.def) {
            return Err(BlobError::ShapeMismatch);
        }
        self.def = blob.def;
        // Columns a disk blob does not store (the third feature) are zero, as in
        // `from_blob`.
        self.base = BaseNet::ZERO;
        self.velocity = VelocityNet::ZERO;
        let mut weights = blob.weights();
        self.load_params(|| weights.next().unwrap_or(0.0));
        Ok(())
    }

    /// A model of definition `def` with every parameter zero.
    pub fn zeroed(def: ModelDef) -> Result<Self, BlobError> {
        if !Self::accepts(&def) {
            return Err(BlobError::ShapeMismatch);
        }
        Ok(Model {
            def,
            base: BaseNet::ZERO,
            velocity: VelocityNet::ZERO,
            table: LatentTable::UNIFORM,
        })
    }

    /// A model from its parameters in blob order (`def.param_count()` finite values).
    pub fn from_params(def: ModelDef, params: &[f32]) -> Result<Self, BlobError> {
        let mut model = Self::zeroed(def)?;
        model.set_params(params)?;
        Ok(model)
    }

    /// Replaces every parameter (blob order).
    pub fn set_params(&mut self, params: &[f32]) -> Result<(), BlobError> {
        let from_shape = self.def.param_count();
        if params.len() != from_shape {
            return Err(BlobError::ParamCountMismatch {
                declared: params.len() as u32,
                from_shape,
            });
        }
        let first_table = from_shape - self.def.table_len();
        crate::blob::check_params(params.iter().copied(), first_table, self.def.latent_table)?;
        let mut it = params.iter();
        self.load_params(|| it.next().copied().unwrap_or(0.0));
        Ok(())
    }

    /// Copies every parameter, in blob order, into `out`; returns how many were written.
    pub fn params(&self, out: &mut [f32]) -> Result<usize, BlobError> {
        let n = self.def.param_count();
        let got = out.len() * 4;
        let out = out
            .get_mut(..n)
            .ok_or(BlobError::BufferTooSmall { needed: n * 4, got })?;
        let mut it = out.iter_mut();
        self.visit_params(|p| {
            if let Some(o) = it.next() {
                *o = p;
            }
        });
        Ok(n)
    }

    /// Writes the model as a blob of the given precision into `out`; returns its length.
    /// The parameters go straight from the model into `out` (no staging copy, so this
    /// works on a small embedded stack); on error `out`'s contents are unspecified.
    pub fn write_blob(&self, precision: Precision, out: &mut [u8]) -> Result<usize, BlobError> {
        let mut def = self.def;
        def.precision = precision;
        write_blob_with(&def, out, |emit| self.visit_params(emit))
    }

    /// The definition.
    #[must_use]
    pub fn def(&self) -> &ModelDef {
        &self.def
    }

    /// Changes the stored name and default step count (metadata only).
    pub fn set_metadata(&mut self, name: crate::def::ModelName, default_steps: u16) {
        self.def.name = name;
        self.def.default_steps = default_steps.clamp(1, crate::spec::MAX_STEPS as u16);
    }

    /// Reads every parameter in blob order (the order of `load_params`); a coded table's
    /// nodes as their codes' values.
    fn visit_params(&self, mut f: impl FnMut(f32)) {
        let features = self.def.domain.feature_count();
        self.base.visit(&mut f);
        self.velocity.visit(features, &mut f);
        if self.def.latent_table.is_some() {
            self.table.visit(&mut f);
        }
    }

    /// Sets every parameter from `next`, in blob order (`docs/blob-format.md`): the nets'
    /// weights, then the latent table's nodes (the uniform table without one).
    fn load_params(&mut self, mut next: impl FnMut() -> f32) {
        let features = self.def.domain.feature_count();
        self.base.visit_mut(&mut |p: &mut f32| *p = next());
        self.velocity
            .visit_mut(features, &mut |p: &mut f32| *p = next());
        match self.def.latent_table {
            Some(grid) => self.table.load(grid, self.def.precision, &mut next),
            None => self.table = LatentTable::UNIFORM,
        }
    }
}
