//! Writes a blob into a caller's buffer (no allocation, so it works in `no_std` too).

use super::{
    body_len, crc32, BlobError, CHECKSUM_LEN, FLAG_BLENDED_SLICES, FLAG_CODED_TABLE,
    FLAG_HALF_TURN, FLAG_ISOTROPIC, FLAG_LATENT_TABLE, FLAG_QUARTER, FLAG_STANDARDIZED,
    FLAG_STANDARD_WARP, FLAG_UPPER_HEMISPHERE, FLAG_WARPED_TABLE, HEADER_LEN, MAGIC, VERSION,
};
use crate::base::table::{encode, TableGrid};
use crate::def::{IncidentFold, IncidentRange};
use crate::def::{ModelDef, NetShape, Precision, NAME_CAPACITY};

/// Bytes of the blob for `def`: the header, the nets' weights at `def.precision`, the
/// latent table's nodes (one byte each on [`TableGrid::Codes`]) and the checksum.
pub fn blob_len(def: &ModelDef) -> usize {
    let body = body_len(def.param_count(), def.precision, def.latent_table).unwrap_or(0);
    HEADER_LEN + body + CHECKSUM_LEN
}

/// Writes `def` and `params` (blob order, see `docs/blob-format.md`) into `out`, rounding
/// to f16 when `def.precision` says so and a coded latent table's nodes to their nearest
/// code. Returns the number of bytes written.
///
/// Fails if `params` does not hold exactly `def.param_count()` finite values, or `out` is
/// too small.
pub fn write_blob(def: &ModelDef, params: &[f32], out: &mut [u8]) -> Result<usize, BlobError> {
    let count = def.param_count();
    if params.len() != count {
        return Err(BlobError::ParamCountMismatch {
            declared: params.len() as u32,
            from_shape: count,
        });
    }
    if let Some(index) = params.iter().position(|w| !w.is_finite()) {
        return Err(BlobError::NonFiniteWeight { index });
    }
    write_blob_with(def, out, |emit| params.iter().for_each(|&w| emit(w)))
}

/// Writes `def` and the parameters that `visit` passes to its argument, in blob order,
/// straight into `out`. Returns the number of bytes written; fails on a parameter count
/// other than `def.param_count()`, a non-finite value (also after rounding to f16) or a
/// short `out` (whose contents are then unspecified).
pub(crate) fn write_blob_with(
    def: &ModelDef,
    out: &mut [u8],
    visit: impl FnOnce(&mut dyn FnMut(f32)),
) -> Result<usize, BlobError> {
    let count = def.param_count();
    let len = blob_len(def);
    let got = out.len();
    let out = out
        .get_mut(..len)
        .ok_or(BlobError::BufferTooSmall { needed: len, got })?;
    let (header, rest) = out.split_at_mut(HEADER_LEN);
    write_header(def, header);
    let body = rest
        .get_mut(..len - HEADER_LEN - CHECKSUM_LEN)
        .ok_or(BlobError::BufferTooSmall { needed: len, got })?;
    let precision = def.precision;
    let first_table = count - def.table_len();
    let coded = def.latent_table.is_some_and(TableGrid::is_coded);
    let mut index = 0usize;
    let mut error = None;
    visit(&mut |w: f32| {
        if error.is_some() {
            return;
        }
        let at = index;
        index += 1;
        error = if at >= count {
            Some(BlobError::ParamCountMismatch {
                declared: index as u32,
                from_shape: count,
            })
        } else if !w.is_finite() {
            Some(BlobError::NonFiniteWeight { index: at })
        } else if coded && at >= first_table {
            let code = encode(w).ok_or(BlobError::TableValueOutOfRange { index: at });
            let dst = body.get_mut(first_table * precision.bytes() + (at - first_table));
            code.and_then(|c| {
                dst.map(|d| *d = c).ok_or(BlobError::ParamCountMismatch {
                    declared: index as u32,
                    from_shape: count,
                })
            })
            .err()
        } else {
            let dst = body.get_mut(at * precision.bytes()..(at + 1) * precision.bytes());
            match (dst, precision) {
                (Some(dst), Precision::F32) => {
                    dst.copy_from_slice(&w.to_le_bytes());
                    None
                }
                (Some(dst), Precision::F16) => {
                    let h = half::f16::from_f32(w);
                    dst.copy_from_slice(&h.to_bits().to_le_bytes());
                    (!h.is_finite()).then_some(BlobError::NonFiniteWeight { index: at })
                }
                (None, _) => Some(BlobError::ParamCountMismatch {
                    declared: index as u32,
                    from_shape: count,
                }),
            }
        };
    });
    if let Some(e) = error {
        return Err(e);
    }
    if index != count {
        return Err(BlobError::ParamCountMismatch {
            declared: index as u32,
            from_shape: count,
        });
    }
    let crc = crc32(&out[..len - CHECKSUM_LEN]);
    out[len - CHECKSUM_LEN..].copy_from_slice(&crc.to_le_bytes());
    Ok(len)
}

fn write_header(def: &ModelDef, h: &mut [u8]) {
    h.fill(0);
    h[0..8].copy_from_slice(&MAGIC);
    h[8..10].copy_from_slice(&VERSION.to_le_bytes());
    h[10] = def.domain.code();
    h[11] = def.precision.code();
    h[12] = def.activation.code();
    write_shape(&mut h[13..17], def.base);
    write_shape(&mut h[17..21], def.velocity);
    h[21] = def.name.as_bytes().len() as u8;
    h[22..24].copy_from_slice(&def.default_steps.to_le_bytes());
    h[24..28].copy_from_slice(&(def.param_count() as u32).to_le_bytes());
    let mut flags = if def.isotropic { FLAG_ISOTROPIC } else { 0 };
    flags |= match def.fold {
        IncidentFold::None => 0,
        IncidentFold::HalfTurn => FLAG_HALF_TURN,
        IncidentFold::Quarter => FLAG_QUARTER,
    };
    // Implied on the disk: disk blobs keep the bytes they had before the flag existed.
    if def.domain.is_spherical() && def.incident == IncidentRange::UpperHemisphere {
        flags |= FLAG_UPPER_HEMISPHERE;
    }
    if def.standardized {
        flags |= FLAG_STANDARDIZED;
    }
    if def.standard_warp {
        flags |= FLAG_STANDARD_WARP;
    }
    if let Some(grid) = def.latent_table {
        flags |= FLAG_LATENT_TABLE;
        if grid.is_coded() {
            flags |= FLAG_CODED_TABLE;
        }
        if grid.is_warped() {
            flags |= FLAG_WARPED_TABLE;
        }
        if grid.is_blended() {
            flags |= FLAG_BLENDED_SLICES;
        }
    }
    h[28..32].copy_from_slice(&flags.to_le_bytes());
    h[32..32 + def.name.as_bytes().len()].copy_from_slice(def.name.as_bytes());
    debug_assert!(def.name.as_bytes().len() <= NAME_CAPACITY);
}

fn write_shape(dst: &mut [u8], shape: NetShape) {
    dst[0] = shape.freqs;
    dst[1..3].copy_from_slice(&shape.width.to_le_bytes());
    dst[3] = shape.hidden_layers;
}
