//! The `tensor_file` container (Dupuy & Jakob 2018): a header followed by named,
//! typed, n-dimensional fields at absolute offsets.

use super::cursor::Cursor;
use super::RglError;

/// Element type of a field (dtype codes 1..=11).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dtype {
    /// 1
    U8,
    /// 2
    I8,
    /// 3
    U16,
    /// 4
    I16,
    /// 5
    U32,
    /// 6
    I32,
    /// 7
    U64,
    /// 8
    I64,
    /// 9
    F16,
    /// 10
    F32,
    /// 11
    F64,
}

impl Dtype {
    /// Decodes a dtype code.
    pub fn from_code(c: u8) -> Result<Dtype, RglError> {
        Ok(match c {
            1 => Dtype::U8,
            2 => Dtype::I8,
            3 => Dtype::U16,
            4 => Dtype::I16,
            5 => Dtype::U32,
            6 => Dtype::I32,
            7 => Dtype::U64,
            8 => Dtype::I64,
            9 => Dtype::F16,
            10 => Dtype::F32,
            11 => Dtype::F64,
            _ => return Err(RglError::BadDtype(c)),
        })
    }

    /// Bytes per element.
    pub fn size(self) -> usize {
        match self {
            Dtype::U8 | Dtype::I8 => 1,
            Dtype::U16 | Dtype::I16 | Dtype::F16 => 2,
            Dtype::U32 | Dtype::I32 | Dtype::F32 => 4,
            Dtype::U64 | Dtype::I64 | Dtype::F64 => 8,
        }
    }
}

/// One field of the file: its name, type, shape and bytes.
#[derive(Debug, Clone)]
pub struct Field<'a> {
    /// Field name.
    pub name: String,
    /// Element type.
    pub dtype: Dtype,
    /// Extent per dimension.
    pub shape: Vec<usize>,
    /// The raw little-endian element bytes (already bounds-checked).
    pub bytes: &'a [u8],
}

impl Field<'_> {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// True when the field has no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The elements of an `f32` field widened to `f64`, all finite.
    pub fn f32_values(&self, name: &'static str) -> Result<Vec<f64>, RglError> {
        if self.dtype != Dtype::F32 {
            return Err(RglError::WrongDtype(name));
        }
        let v: Vec<f64> = self
            .bytes
            .chunks_exact(4)
            .map(|c| f64::from(f32::from_le_bytes([c[0], c[1], c[2], c[3]])))
            .collect();
        if v.iter().any(|x| !x.is_finite()) {
            return Err(RglError::NonFinite(name));
        }
        Ok(v)
    }
}

/// A parsed `tensor_file`: the fields in file order.
#[derive(Debug, Clone)]
pub struct TensorFile<'a> {
    /// All fields.
    pub fields: Vec<Field<'a>>,
}

/// Magic bytes at the start of every file.
pub const MAGIC: &[u8; 12] = b"tensor_file\0";

impl<'a> TensorFile<'a> {
    /// Parses the header and bounds-checks every field against `data`.
    pub fn parse(data: &'a [u8]) -> Result<Self, RglError> {
        let mut c = Cursor::new(data);
        if c.bytes(12).map_err(|_| RglError::BadMagic)? != MAGIC {
            return Err(RglError::BadMagic);
        }
        let (major, minor) = (c.u8()?, c.u8()?);
        if (major, minor) != (1, 0) {
            return Err(RglError::UnsupportedVersion { major, minor });
        }
        let count = c.u32()?;
        let mut fields = Vec::new();
        for _ in 0..count {
            let name_len = usize::from(c.u16()?);
            let name = std::str::from_utf8(c.bytes(name_len)?)
                .map_err(|_| RglError::BadName)?
                .to_string();
            let ndim = usize::from(c.u16()?);
            let dtype = Dtype::from_code(c.u8()?)?;
            let offset = usize::try_from(c.u64()?).map_err(|_| RglError::Overflow)?;
            let mut shape = Vec::with_capacity(ndim.min(16));
            let mut count: usize = 1;
            for _ in 0..ndim {
                let n = usize::try_from(c.u64()?).map_err(|_| RglError::Overflow)?;
                count = count.checked_mul(n).ok_or(RglError::Overflow)?;
                shape.push(n);
            }
            let size = count.checked_mul(dtype.size()).ok_or(RglError::Overflow)?;
            let end = offset.checked_add(size).ok_or(RglError::Overflow)?;
            let bytes = data.get(offset..end).ok_or(RglError::Truncated)?;
            fields.push(Field {
                name,
                dtype,
                shape,
                bytes,
            });
        }
        Ok(Self { fields })
    }

    /// The field called `name`.
    pub fn field(&self, name: &'static str) -> Result<&Field<'a>, RglError> {
        self.fields
            .iter()
            .find(|f| f.name == name)
            .ok_or(RglError::MissingField(name))
    }
}
