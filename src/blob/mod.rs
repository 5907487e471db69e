//! The compact weight blob: a versioned little-endian binary that carries a model's
//! definition, its weights (f32 or f16) and a CRC-32. The byte layout is documented in
//! `docs/blob-format.md`; the constants below are that table.
//!
//! Reading validates everything before anything is used and never panics or allocates.

mod crc32;
mod cursor;
mod error;
mod writer;

pub use crc32::crc32;
pub use error::BlobError;
pub(crate) use writer::write_blob_with;
pub use writer::{blob_len, write_blob};

use crate::base::table::{code_value, LatentTable, TableGrid};
use crate::def::{
    Activation, Domain, IncidentFold, IncidentRange, ModelDef, ModelName, NetShape, Precision,
    NAME_CAPACITY,
};
use cursor::Cursor;

/// The first 8 bytes of every blob.
pub const MAGIC: [u8; 8] = *b"DIFFBSDF";
/// The format version this kernel reads and writes.
pub const VERSION: u16 = 1;
/// Bytes before the first weight.
pub const HEADER_LEN: usize = 64;
/// Bytes of the trailing checksum.
pub const CHECKSUM_LEN: usize = 4;

/// A validated blob: its definition and a view of its weights.
#[derive(Clone, Copy, Debug)]
pub struct Blob<'a> {
    /// The model definition from the header.
    pub def: ModelDef,
    weights: &'a [u8],
}

impl<'a> Blob<'a> {
    /// Validates `bytes` completely: magic, version, lengths, checksum, header fields and
    /// that every weight is finite.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, BlobError> {
        let mut cur = Cursor::new(bytes);
        let truncated = BlobError::Truncated {
            needed: HEADER_LEN + CHECKSUM_LEN,
            got: bytes.len(),
        };
        if cur.take(8).ok_or(truncated)? != MAGIC {
            return Err(BlobError::BadMagic);
        }
        let version = cur.u16().ok_or(truncated)?;
        if version != VERSION {
            return Err(BlobError::UnsupportedVersion(version));
        }
        let raw = RawHeader::read(&mut cur).ok_or(truncated)?;
        let precision = Precision::from_code(raw.precision)
            .ok_or(BlobError::UnknownPrecision(raw.precision))?;
        let grid = raw.table_grid()?;
        let total = body_len(raw.param_count as usize, precision, grid)
            .and_then(|body| body.checked_add(HEADER_LEN + CHECKSUM_LEN))
            .ok_or(BlobError::BadHeader(
                "parameter count overflows or is below the latent table's",
            ))?;
        if bytes.len() < total {
            return Err(BlobError::Truncated {
                needed: total,
                got: bytes.len(),
            });
        }
        if bytes.len() > total {
            return Err(BlobError::TrailingBytes {
                expected: total,
                got: bytes.len(),
            });
        }
        let (body, tail) = bytes.split_at(total - CHECKSUM_LEN);
        let stored = u32::from_le_bytes([tail[0], tail[1], tail[2], tail[3]]);
        let computed = crc32(body);
        if stored != computed {
            return Err(BlobError::ChecksumMismatch { stored, computed });
        }
        let def = raw.into_def(precision)?;
        let weights = &body[HEADER_LEN..];
        let blob = Blob { def, weights };
        blob.check_values()?;
        Ok(blob)
    }

    /// The stored parameters in blob order, decoded to f32: the nets' weights, then the
    /// latent table's nodes (a code's value at the blob's precision, [`code_value`]).
    pub fn weights(&self) -> impl Iterator<Item = f32> + 'a {
        let precision = self.def.precision;
        let grid = self.def.latent_table;
        let table_len = self.def.table_len();
        let split = (self.def.param_count() - table_len) * precision.bytes();
        let (nets, table) = self.weights.split_at(split.min(self.weights.len()));
        let node_bytes = grid.map_or(1, |g| g.node_bytes(precision));
        let nets = nets
            .chunks_exact(precision.bytes())
            .map(move |c| decode(c, precision));
        let table = table.chunks_exact(node_bytes).map(move |c| match grid {
            Some(g) if g.is_coded() => code_value(c[0], precision),
            _ => decode(c, precision),
        });
        nets.chain(table)
    }

    fn check_values(&self) -> Result<(), BlobError> {
        let first_table = self.def.param_count() - self.def.table_len();
        if self.def.latent_table.is_some_and(TableGrid::is_coded) {
            // Code 0 stands for no value (docs/blob-format.md).
            let codes = self.weights.get(first_table * self.def.precision.bytes()..);
            if let Some(at) = codes.and_then(|c| c.iter().position(|&c| c == 0)) {
                return Err(BlobError::TableValueOutOfRange {
                    index: first_table + at,
                });
            }
        }
        check_params(self.weights(), first_table, self.def.latent_table)
    }
}

/// One stored weight of `precision` (`c` holds its bytes).
fn decode(c: &[u8], precision: Precision) -> f32 {
    match precision {
        Precision::F32 => f32::from_le_bytes([c[0], c[1], c[2], c[3]]),
        Precision::F16 => half::f16::from_bits(u16::from_le_bytes([c[0], c[1]])).to_f32(),
    }
}

/// Bytes of the parameters of a blob with `param_count` parameters (latent-table nodes
/// included) of `precision` and a table on `grid`; `None` on overflow or a count below the
/// table's.
pub(crate) fn body_len(
    param_count: usize,
    precision: Precision,
    grid: Option<TableGrid>,
) -> Option<usize> {
    let table = grid.map_or(0, TableGrid::node_count);
    let nets = param_count
        .checked_sub(table)?
        .checked_mul(precision.bytes())?;
    let node_bytes = grid.map_or(0, |g| g.node_bytes(precision));
    nets.checked_add(table * node_bytes)
}

/// Every parameter finite, every latent-table node (from index `first_table` on) one a
/// table on `grid` may hold ([`LatentTable::accepts`]).
pub(crate) fn check_params(
    params: impl Iterator<Item = f32>,
    first_table: usize,
    grid: Option<TableGrid>,
) -> Result<(), BlobError> {
    for (index, w) in params.enumerate() {
        if !w.is_finite() {
            return Err(BlobError::NonFiniteWeight { index });
        }
        let in_table = grid.filter(|_| index >= first_table);
        if in_table.is_some_and(|g| !LatentTable::accepts(g, w)) {
            return Err(BlobError::TableValueOutOfRange { index });
        }
    }
    Ok(())
}

/// The header fields after magic and version, as stored (offsets in `docs/blob-format.md`).
struct RawHeader {
    domain: u8,
    precision: u8,
    activation: u8,
    base: NetShape,
    velocity: NetShape,
    name_len: u8,
    default_steps: u16,
    param_count: u32,
    flags: u32,
    name: [u8; NAME_CAPACITY],
}

impl RawHeader {
    fn read(cur: &mut Cursor<'_>) -> Option<Self> {
        let domain = cur.u8()?;
        let precision = cur.u8()?;
        let activation = cur.u8()?;
        let base = read_shape(cur)?;
        let velocity = read_shape(cur)?;
        let name_len = cur.u8()?;
        let default_steps = cur.u16()?;
        let param_count = cur.u32()?;
        let flags = cur.u32()?;
        let mut name = [0; NAME_CAPACITY];
        name.copy_from_slice(cur.take(NAME_CAPACITY)?);
        Some(RawHeader {
            domain,
            precision,
            activation,
            base,
            velocity,
            name_len,
            default_steps,
            param_count,
            flags,
            name,
        })
    }

    /// The latent table's grid from flag bits 4, 5, 6 and 7 (bit 5 without bit 4, bit 6
    /// without bit 5, or bit 7 without bit 6, is an error).
    fn table_grid(&self) -> Result<Option<TableGrid>, BlobError> {
        let blended = self.flags & FLAG_BLENDED_SLICES != 0;
        match (
            self.flags & FLAG_LATENT_TABLE != 0,
            self.flags & FLAG_CODED_TABLE != 0,
            self.flags & FLAG_WARPED_TABLE != 0,
        ) {
            (false, true, _) => Err(BlobError::BadHeader(
                "a coded latent table without a latent table",
            )),
            (_, false, true) => Err(BlobError::BadHeader(
                "warped axes without a coded latent table",
            )),
            (_, _, false) if blended => {
                Err(BlobError::BadHeader("blended slices without warped axes"))
            }
            (false, false, false) => Ok(None),
            (true, false, false) => Ok(Some(TableGrid::Values)),
            (true, true, false) => Ok(Some(TableGrid::Codes)),
            (true, true, true) if blended => Ok(Some(TableGrid::BlendedSlices)),
            (true, true, true) => Ok(Some(TableGrid::WarpedCodes)),
        }
    }

    /// The incident fold from flag bits 8 and 9 (both, or either with the isotropic bit 0,
    /// is an error).
    fn fold(&self) -> Result<IncidentFold, BlobError> {
        let isotropic = self.flags & FLAG_ISOTROPIC != 0;
        match (
            self.flags & FLAG_HALF_TURN != 0,
            self.flags & FLAG_QUARTER != 0,
        ) {
            (false, false) => Ok(IncidentFold::None),
            (true, true) => Err(BlobError::BadHeader("two incident folds")),
            _ if isotropic => Err(BlobError::BadHeader(
                "an incident fold on an isotropic model",
            )),
            (true, false) => Ok(IncidentFold::HalfTurn),
            (false, true) => Ok(IncidentFold::Quarter),
        }
    }

    fn into_def(self, precision: Precision) -> Result<ModelDef, BlobError> {
        let domain = Domain::from_code(self.domain).ok_or(BlobError::UnknownDomain(self.domain))?;
        let activation = Activation::from_code(self.activation)
            .ok_or(BlobError::UnknownActivation(self.activation))?;
        let known = FLAG_ISOTROPIC
            | FLAG_HALF_TURN
            | FLAG_QUARTER
            | FLAG_UPPER_HEMISPHERE
            | FLAG_STANDARDIZED
            | FLAG_STANDARD_WARP
            | FLAG_LATENT_TABLE
            | FLAG_CODED_TABLE
            | FLAG_BLENDED_SLICES
            | FLAG_WARPED_TABLE;
        if self.flags & !known != 0 {
            return Err(BlobError::BadHeader("unknown flag bits are set"));
        }
        let standardized = self.flags & FLAG_STANDARDIZED != 0;
        if standardized && domain.is_spherical() {
            return Err(BlobError::BadHeader(
                "standard coordinates on a spherical domain",
            ));
        }
        let standard_warp = self.flags & FLAG_STANDARD_WARP != 0;
        if standard_warp && !standardized {
            return Err(BlobError::BadHeader(
                "warped standard coordinates without standard coordinates",
            ));
        }
        let latent_table = self.table_grid()?;
        let fold = self.fold()?;
        if latent_table.is_some() && !standardized {
            return Err(BlobError::BadHeader(
                "a latent table without standard coordinates",
            ));
        }
        check_shape(self.base, "base net")?;
        check_shape(self.velocity, "velocity net")?;
        if self.base.freqs > self.velocity.freqs {
            return Err(BlobError::BadHeader(
                "base net has more frequencies than the velocity net",
            ));
        }
        if self.default_steps == 0 {
            return Err(BlobError::BadHeader("default steps is zero"));
        }
        if u32::from(self.default_steps) > crate::spec::MAX_STEPS {
            return Err(BlobError::BadHeader("default steps above spec::MAX_STEPS"));
        }
        let name_bytes = self
            .name
            .get(..self.name_len as usize)
            .ok_or(BlobError::BadHeader("name longer than 32 bytes"))?;
        let name =
            ModelName::from_bytes(name_bytes).ok_or(BlobError::BadHeader("name is not UTF-8"))?;
        let def = ModelDef {
            domain,
            precision,
            activation,
            base: self.base,
            velocity: self.velocity,
            default_steps: self.default_steps,
            isotropic: self.flags & FLAG_ISOTROPIC != 0,
            fold,
            incident: if self.flags & FLAG_UPPER_HEMISPHERE != 0 || !domain.is_spherical() {
                IncidentRange::UpperHemisphere
            } else {
                IncidentRange::WholeSphere
            },
            standardized,
            standard_warp,
            latent_table,
            name,
        };
        let from_shape = def.param_count();
        if from_shape != self.param_count as usize {
            return Err(BlobError::ParamCountMismatch {
                declared: self.param_count,
                from_shape,
            });
        }
        Ok(def)
    }
}

/// Header flag (bytes 28..32, u32): the model is isotropic.
pub(crate) const FLAG_ISOTROPIC: u32 = 1;
/// Header flag: an anisotropic model folds `wi` by a half turn ([`IncidentFold::HalfTurn`];
/// not with [`FLAG_ISOTROPIC`] or [`FLAG_QUARTER`]).
pub(crate) const FLAG_HALF_TURN: u32 = 256;
/// Header flag: an anisotropic model folds `wi` into a quarter of the turn
/// ([`IncidentFold::Quarter`]; not with [`FLAG_ISOTROPIC`] or [`FLAG_HALF_TURN`]).
pub(crate) const FLAG_QUARTER: u32 = 512;

/// Header flag: the flow runs in the base distribution's standard coordinates
/// ([`ModelDef::standardized`]; disk and half-vector chart only).
pub(crate) const FLAG_STANDARDIZED: u32 = 4;
/// Header flag: the flow runs in the compressed standard coordinates
/// ([`ModelDef::standard_warp`]; only with [`FLAG_STANDARDIZED`]).
pub(crate) const FLAG_STANDARD_WARP: u32 = 8;
/// Header flag: the blob stores a latent table after the nets' weights
/// ([`ModelDef::latent_table`]; only with [`FLAG_STANDARDIZED`]).
pub(crate) const FLAG_LATENT_TABLE: u32 = 16;
/// Header flag: the latent table has [`crate::spec::LATENT_TABLE_CELLS`] cells per side and
/// stores each node as an 8-bit code ([`TableGrid::Codes`]; only with
/// [`FLAG_LATENT_TABLE`]).
pub(crate) const FLAG_CODED_TABLE: u32 = 32;
/// Header flag: the coded latent table's axes are warped, their nodes stored after the
/// slices' ([`TableGrid::WarpedCodes`], docs/math.md, (81); only with
/// [`FLAG_CODED_TABLE`]).
pub(crate) const FLAG_WARPED_TABLE: u32 = 64;
/// Header flag: the warped coded table has [`crate::spec::LATENT_TABLE_BLENDED_SLICES`]
/// incidence slices on the blended layout ([`TableGrid::BlendedSlices`], docs/math.md, (82);
/// only with [`FLAG_WARPED_TABLE`]).
pub(crate) const FLAG_BLENDED_SLICES: u32 = 128;
/// Header flag: the model is defined for `wi` above the surface only
/// ([`IncidentRange::UpperHemisphere`]); implied on the disk, written there too.
pub(crate) const FLAG_UPPER_HEMISPHERE: u32 = 2;

use crate::spec::{MAX_FREQS, MAX_LAYERS, MAX_WIDTH};

fn read_shape(cur: &mut Cursor<'_>) -> Option<NetShape> {
    let freqs = cur.u8()?;
    let width = cur.u16()?;
    let hidden_layers = cur.u8()?;
    Some(NetShape {
        freqs,
        width,
        hidden_layers,
    })
}

fn check_shape(shape: NetShape, _which: &'static str) -> Result<(), BlobError> {
    if shape.width == 0 || shape.width > MAX_WIDTH {
        return Err(BlobError::BadHeader("net width is 0 or above 1024"));
    }
    if shape.hidden_layers == 0 || shape.hidden_layers > MAX_LAYERS {
        return Err(BlobError::BadHeader("hidden layer count is 0 or above 16"));
    }
    if shape.freqs > MAX_FREQS {
        return Err(BlobError::BadHeader("more than 16 encoding frequencies"));
    }
    Ok(())
}
