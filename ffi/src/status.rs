//! Status codes: one per failure the C caller can see, one per [`BlobError`] variant.

use diffbsdf::BlobError;

/// What a call did. `0` is success, `1` a valid call whose sample is invalid (zero
/// contribution), negative values are errors. Values are stable: they are in the header.
#[repr(i32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(non_camel_case_types)]
pub enum diffbsdf_status {
    /// Success.
    DIFFBSDF_OK = diffbsdf::spec::STATUS_OK,
    /// The inputs were not valid (non-unit `wi`, `u` outside [0, 1], ...) or the sample
    /// left the domain; the outputs are zero.
    DIFFBSDF_NO_SAMPLE = diffbsdf::spec::STATUS_NO_SAMPLE,
    /// A required pointer was null.
    DIFFBSDF_ERR_NULL = -1,
    /// A pointer was not aligned for its type.
    DIFFBSDF_ERR_MISALIGNED = -2,
    /// A length or count is too small or too large.
    DIFFBSDF_ERR_LENGTH = -3,
    /// A Rust panic was caught at the boundary (a bug: please report it).
    DIFFBSDF_ERR_PANIC = -4,
    /// Blob: the first 8 bytes are not `DIFFBSDF`.
    DIFFBSDF_ERR_BAD_MAGIC = -10,
    /// Blob: format version not supported.
    DIFFBSDF_ERR_UNSUPPORTED_VERSION = -11,
    /// Blob: shorter than its header says.
    DIFFBSDF_ERR_TRUNCATED = -12,
    /// Blob: bytes after the checksum.
    DIFFBSDF_ERR_TRAILING_BYTES = -13,
    /// Blob: CRC-32 mismatch.
    DIFFBSDF_ERR_CHECKSUM = -14,
    /// Blob: unknown domain code.
    DIFFBSDF_ERR_UNKNOWN_DOMAIN = -15,
    /// Blob: unknown weight precision code.
    DIFFBSDF_ERR_UNKNOWN_PRECISION = -16,
    /// Blob: unknown activation code.
    DIFFBSDF_ERR_UNKNOWN_ACTIVATION = -17,
    /// Blob: a header field is out of range.
    DIFFBSDF_ERR_BAD_HEADER = -18,
    /// Blob: parameter count does not match the shape.
    DIFFBSDF_ERR_PARAM_COUNT = -19,
    /// Blob: a weight is NaN or infinite.
    DIFFBSDF_ERR_NON_FINITE_WEIGHT = -20,
    /// Blob: valid, but of an architecture this library is not compiled for.
    DIFFBSDF_ERR_SHAPE_MISMATCH = -21,
    /// An output buffer is too small.
    DIFFBSDF_ERR_BUFFER_TOO_SMALL = -22,
    /// Blob: a latent-table value is not positive, too large, or a coded node is 0.
    DIFFBSDF_ERR_TABLE_VALUE = -23,
}

use diffbsdf_status as S;

impl From<BlobError> for diffbsdf_status {
    fn from(e: BlobError) -> Self {
        // Exhaustive on purpose: a new kernel error must get its own code.
        match e {
            BlobError::BadMagic => S::DIFFBSDF_ERR_BAD_MAGIC,
            BlobError::UnsupportedVersion(_) => S::DIFFBSDF_ERR_UNSUPPORTED_VERSION,
            BlobError::Truncated { .. } => S::DIFFBSDF_ERR_TRUNCATED,
            BlobError::TrailingBytes { .. } => S::DIFFBSDF_ERR_TRAILING_BYTES,
            BlobError::ChecksumMismatch { .. } => S::DIFFBSDF_ERR_CHECKSUM,
            BlobError::UnknownDomain(_) => S::DIFFBSDF_ERR_UNKNOWN_DOMAIN,
            BlobError::UnknownPrecision(_) => S::DIFFBSDF_ERR_UNKNOWN_PRECISION,
            BlobError::UnknownActivation(_) => S::DIFFBSDF_ERR_UNKNOWN_ACTIVATION,
            BlobError::BadHeader(_) => S::DIFFBSDF_ERR_BAD_HEADER,
            BlobError::ParamCountMismatch { .. } => S::DIFFBSDF_ERR_PARAM_COUNT,
            BlobError::NonFiniteWeight { .. } => S::DIFFBSDF_ERR_NON_FINITE_WEIGHT,
            BlobError::ShapeMismatch => S::DIFFBSDF_ERR_SHAPE_MISMATCH,
            BlobError::BufferTooSmall { .. } => S::DIFFBSDF_ERR_BUFFER_TOO_SMALL,
            BlobError::TableValueOutOfRange { .. } => S::DIFFBSDF_ERR_TABLE_VALUE,
        }
    }
}

impl diffbsdf_status {
    /// A static, NUL-terminated description.
    pub const fn message(self) -> &'static [u8] {
        match self {
            S::DIFFBSDF_OK => b"ok\0",
            S::DIFFBSDF_NO_SAMPLE => b"no sample: invalid input or the sample left the domain\0",
            S::DIFFBSDF_ERR_NULL => b"a required pointer is null\0",
            S::DIFFBSDF_ERR_MISALIGNED => b"a pointer is not aligned for its type\0",
            S::DIFFBSDF_ERR_LENGTH => b"a length or count is out of range\0",
            S::DIFFBSDF_ERR_PANIC => b"internal error (panic caught at the C boundary)\0",
            S::DIFFBSDF_ERR_BAD_MAGIC => b"not a diffbsdf blob (bad magic)\0",
            S::DIFFBSDF_ERR_UNSUPPORTED_VERSION => b"unsupported blob version\0",
            S::DIFFBSDF_ERR_TRUNCATED => b"blob truncated\0",
            S::DIFFBSDF_ERR_TRAILING_BYTES => b"blob has trailing bytes\0",
            S::DIFFBSDF_ERR_CHECKSUM => b"blob checksum mismatch\0",
            S::DIFFBSDF_ERR_UNKNOWN_DOMAIN => b"unknown domain code in blob\0",
            S::DIFFBSDF_ERR_UNKNOWN_PRECISION => b"unknown precision code in blob\0",
            S::DIFFBSDF_ERR_UNKNOWN_ACTIVATION => b"unknown activation code in blob\0",
            S::DIFFBSDF_ERR_BAD_HEADER => b"bad blob header\0",
            S::DIFFBSDF_ERR_PARAM_COUNT => b"blob parameter count does not match its shape\0",
            S::DIFFBSDF_ERR_NON_FINITE_WEIGHT => b"blob has a non-finite weight\0",
            S::DIFFBSDF_ERR_SHAPE_MISMATCH => {
                b"blob architecture is not one this library is compiled for\0"
            }
            S::DIFFBSDF_ERR_BUFFER_TOO_SMALL => b"output buffer too small\0",
            S::DIFFBSDF_ERR_TABLE_VALUE => b"a latent-table value in the blob is out of range\0",
        }
    }

    /// Every status, for tests and for `diffbsdf_status_message` of unknown values.
    pub const ALL: [diffbsdf_status; 20] = [
        S::DIFFBSDF_OK,
        S::DIFFBSDF_NO_SAMPLE,
        S::DIFFBSDF_ERR_NULL,
        S::DIFFBSDF_ERR_MISALIGNED,
        S::DIFFBSDF_ERR_LENGTH,
        S::DIFFBSDF_ERR_PANIC,
        S::DIFFBSDF_ERR_BAD_MAGIC,
        S::DIFFBSDF_ERR_UNSUPPORTED_VERSION,
        S::DIFFBSDF_ERR_TRUNCATED,
        S::DIFFBSDF_ERR_TRAILING_BYTES,
        S::DIFFBSDF_ERR_CHECKSUM,
        S::DIFFBSDF_ERR_UNKNOWN_DOMAIN,
        S::DIFFBSDF_ERR_UNKNOWN_PRECISION,
        S::DIFFBSDF_ERR_UNKNOWN_ACTIVATION,
        S::DIFFBSDF_ERR_BAD_HEADER,
        S::DIFFBSDF_ERR_PARAM_COUNT,
        S::DIFFBSDF_ERR_NON_FINITE_WEIGHT,
        S::DIFFBSDF_ERR_SHAPE_MISMATCH,
        S::DIFFBSDF_ERR_BUFFER_TOO_SMALL,
        S::DIFFBSDF_ERR_TABLE_VALUE,
    ];
}
