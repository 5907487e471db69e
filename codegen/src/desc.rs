//! The one model description every writer reads: the definition and the parameters of a
//! blob, with the offset of every layer in the flat parameter block.
//!
//! The parameter block is the blob's parameter order decoded to f32 (see
//! `docs/blob-format.md`): each layer stores its weight matrix row by row (output-major)
//! and then its biases. The velocity net's first layer has the inputs
//! `[state features, t, wi encoding]`. The buffer layout of the generated code is exactly
//! this block, so `docs/codegen.md` can point at one table.

use crate::Error;
use diffbsdf::internals::blob::Blob;
use diffbsdf::spec::BASE_OUTPUTS;
use diffbsdf::ModelDef;

/// A fully connected layer inside the parameter block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layer {
    /// Offset of `W[0][0]`; `W[o][i]` is at `w + o * inputs + i`.
    pub w: usize,
    /// Offset of `b[0]`.
    pub b: usize,
    pub inputs: usize,
    pub outputs: usize,
}

/// A model as the writers see it.
#[derive(Clone, Debug)]
pub struct ModelDesc {
    pub def: ModelDef,
    /// The CRC-32 stored at the end of the blob.
    pub crc32: u32,
    /// Every parameter in blob order, decoded to f32.
    pub params: Vec<f32>,
    /// Base net layers, the last one the readout (4 outputs).
    pub base: Vec<Layer>,
    /// Velocity net layers, the first over `[features, t, encoding]`, the last the
    /// readout (2 outputs).
    pub velocity: Vec<Layer>,
}

impl ModelDesc {
    /// Parses and validates a blob.
    pub fn from_blob(bytes: &[u8]) -> Result<Self, Error> {
        let blob = Blob::parse(bytes).map_err(Error::Blob)?;
        let def = blob.def;
        let params: Vec<f32> = blob.weights().collect();
        let tail = bytes.len().saturating_sub(4);
        let crc = bytes.get(tail..).unwrap_or(&[0; 4]);
        let crc32 = u32::from_le_bytes([crc[0], crc[1], crc[2], crc[3]]);
        let mut at = 0;
        let base = layers(
            &mut at,
            def.base.encoding_len(),
            def.base.width as usize,
            def.base.hidden_layers as usize,
            BASE_OUTPUTS,
        );
        let velocity = layers(
            &mut at,
            def.velocity_inputs(),
            def.velocity.width as usize,
            def.velocity.hidden_layers as usize,
            2,
        );
        if at != params.len() {
            return Err(Error::Internal("layer offsets do not cover the parameters"));
        }
        Ok(ModelDesc {
            def,
            crc32,
            params,
            base,
            velocity,
        })
    }

    /// Flow-state features the velocity net sees (2 on the disk, 3 on the sphere).
    pub fn features(&self) -> usize {
        self.def.domain.feature_count()
    }

    /// Length of the velocity net's `wi` encoding (the base net uses a prefix).
    pub fn encoding_len(&self) -> usize {
        self.def.velocity.encoding_len()
    }
}

fn layers(
    at: &mut usize,
    inputs: usize,
    width: usize,
    hidden: usize,
    outputs: usize,
) -> Vec<Layer> {
    let mut out = Vec::with_capacity(hidden + 1);
    let mut fan_in = inputs;
    for k in 0..=hidden {
        let n = if k == hidden { outputs } else { width };
        let w = *at;
        let b = w + n * fan_in;
        *at = b + n;
        out.push(Layer {
            w,
            b,
            inputs: fan_in,
            outputs: n,
        });
        fan_in = n;
    }
    out
}
