//! What can be wrong with a weight blob.

use core::fmt;

/// Why a blob was rejected. Loading never panics: every malformed input maps to one of
/// these, and the model being loaded into is left unchanged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlobError {
    /// The first 8 bytes are not `DIFFBSDF`.
    BadMagic,
    /// The format version is not one this kernel reads.
    UnsupportedVersion(u16),
    /// The blob ends before the header, weights and checksum it declares.
    Truncated {
        /// Bytes the header declares.
        needed: usize,
        /// Bytes given.
        got: usize,
    },
    /// Bytes follow the checksum.
    TrailingBytes {
        /// Bytes the header declares.
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// The CRC-32 over the blob does not match the stored one.
    ChecksumMismatch {
        /// The CRC-32 at the end of the blob.
        stored: u32,
        /// The CRC-32 of the bytes before it.
        computed: u32,
    },
    /// The domain byte is not a known domain.
    UnknownDomain(u8),
    /// The precision byte is not a known weight precision.
    UnknownPrecision(u8),
    /// The activation byte is not a known activation.
    UnknownActivation(u8),
    /// A header field is out of range (zero width, zero layers, name too long or not
    /// UTF-8, unknown flag bits set, base encoding longer than the velocity encoding...).
    BadHeader(&'static str),
    /// The declared parameter count does not match the declared shape.
    ParamCountMismatch {
        /// The count in the header (or given).
        declared: u32,
        /// The count the shape implies.
        from_shape: usize,
    },
    /// A weight is NaN or infinite.
    NonFiniteWeight {
        /// Position of the weight in blob order.
        index: usize,
    },
    /// A node of the latent table is not one its grid may hold: a value not in `(0,
    /// spec::LATENT_TABLE_VALUE_MAX]`, or on the coded grid code 0 or a value whose
    /// nearest code is outside 1..=255 (`docs/math.md`, (79)).
    TableValueOutOfRange {
        /// Position of the value in blob order.
        index: usize,
    },
    /// The blob is valid but its shape is not the one this model type was compiled for.
    ShapeMismatch,
    /// The output buffer is too small for the blob being written.
    BufferTooSmall {
        /// Bytes needed.
        needed: usize,
        /// Bytes given.
        got: usize,
    },
}

impl fmt::Display for BlobError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            BlobError::BadMagic => write!(f, "not a diffbsdf blob (bad magic)"),
            BlobError::UnsupportedVersion(v) => write!(f, "unsupported blob version {v}"),
            BlobError::Truncated { needed, got } => {
                write!(f, "blob truncated: needs {needed} bytes, got {got}")
            }
            BlobError::TrailingBytes { expected, got } => {
                write!(
                    f,
                    "blob has trailing bytes: expected {expected} bytes, got {got}"
                )
            }
            BlobError::ChecksumMismatch { stored, computed } => write!(
                f,
                "blob checksum mismatch: stored {stored:08x}, computed {computed:08x}"
            ),
            BlobError::UnknownDomain(c) => write!(f, "unknown domain code {c}"),
            BlobError::UnknownPrecision(c) => write!(f, "unknown precision code {c}"),
            BlobError::UnknownActivation(c) => write!(f, "unknown activation code {c}"),
            BlobError::BadHeader(why) => write!(f, "bad blob header: {why}"),
            BlobError::ParamCountMismatch {
                declared,
                from_shape,
            } => write!(
                f,
                "blob declares {declared} parameters but its shape has {from_shape}"
            ),
            BlobError::NonFiniteWeight { index } => write!(f, "weight {index} is not finite"),
            BlobError::TableValueOutOfRange { index } => write!(
                f,
                "latent table node {index} is out of range: a value not in (0, {}], or a code \
                 outside 1..=255",
                crate::spec::LATENT_TABLE_VALUE_MAX
            ),
            BlobError::ShapeMismatch => {
                write!(f, "blob shape differs from the compiled model shape")
            }
            BlobError::BufferTooSmall { needed, got } => {
                write!(
                    f,
                    "output buffer too small: needs {needed} bytes, got {got}"
                )
            }
        }
    }
}
