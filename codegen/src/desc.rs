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
use diffbsdf::{ModelDef, Net};

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
    /// Base net layers, the last one the readout (`BASE_OUTPUTS` outputs).
    pub base: Vec<Layer>,
    /// Velocity net layers, the first over `[features, t, encoding]`, the last the
    /// readout (`VELOCITY_OUTPUTS` outputs).
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
        let base = layers(&def, Net::Base, &mut at);
        let velocity = layers(&def, Net::Velocity, &mut at);
        if at + def.table_len() != def.param_count() || params.len() != def.param_count() {
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

/// The layers of `net` as `def` describes them, placed in the parameter block from `*at`
/// on (`W` row by row, then `b`); `*at` ends past the last one.
fn layers(def: &ModelDef, net: Net, at: &mut usize) -> Vec<Layer> {
    (0..def.layer_count(net))
        .filter_map(|index| def.layer(net, index))
        .map(|l| {
            let w = *at;
            let b = w + l.outputs * l.inputs;
            *at += l.param_count();
            Layer {
                w,
                b,
                inputs: l.inputs,
                outputs: l.outputs,
            }
        })
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use diffbsdf::internals::blob::{blob_len, write_blob};

    /// A valid blob for `def` with small, deterministic weights (and latent-table values
    /// in [0.25, 0.75]).
    pub(crate) fn blob(def: &ModelDef) -> Vec<u8> {
        let first_table = def.param_count() - def.table_len();
        let params: Vec<f32> = (0..def.param_count())
            .map(|i| {
                let w = 0.25 * (i as f32 * 0.618).sin();
                if i >= first_table {
                    0.5 + w
                } else {
                    w
                }
            })
            .collect();
        let mut out = vec![0; blob_len(def)];
        write_blob(def, &params, &mut out).expect("write blob");
        out
    }

    /// Each layer sits right after the previous one and spans `ModelDef::layer`'s
    /// parameter count, `W` first; the two nets together cover the whole blob.
    #[test]
    fn offsets_follow_the_kernel_layers() {
        for mut def in [ModelDef::paper_disk(), ModelDef::paper_sphere()] {
            for isotropic in [false, true] {
                def.isotropic = isotropic;
                let m = ModelDesc::from_blob(&blob(&def)).expect("desc");
                let mut at = 0;
                for (net, layers) in [(Net::Base, &m.base), (Net::Velocity, &m.velocity)] {
                    assert_eq!(layers.len(), def.layer_count(net));
                    for (index, l) in layers.iter().enumerate() {
                        let k = def.layer(net, index).expect("layer");
                        assert_eq!((l.inputs, l.outputs), (k.inputs, k.outputs));
                        assert_eq!(l.w, at);
                        assert_eq!(l.b, at + k.inputs * k.outputs);
                        at += k.param_count();
                    }
                    assert_eq!(layers[0].inputs, def.net_inputs(net));
                    assert_eq!(layers[layers.len() - 1].outputs, def.net_outputs(net));
                }
                assert_eq!(at, def.param_count());
                assert_eq!(m.params.len(), def.param_count());
            }
        }
    }
}
