//! Errors of the RGL `.bsdf` reader.

use std::fmt;

/// Why a `.bsdf` file was rejected. The reader never panics on malformed input; every
/// failure is one of these.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RglError {
    /// The file could not be read from disk.
    Io(std::io::ErrorKind),
    /// The first 12 bytes are not `"tensor_file\0"`.
    BadMagic,
    /// The format version is not 1.0.
    UnsupportedVersion {
        /// Major version found.
        major: u8,
        /// Minor version found.
        minor: u8,
    },
    /// The header or a field's data ends past the end of the file.
    Truncated,
    /// A field has a dtype code outside 1..=11.
    BadDtype(u8),
    /// A size or offset computation overflowed.
    Overflow,
    /// A field name is not valid UTF-8.
    BadName,
    /// A field the reader needs is missing.
    MissingField(&'static str),
    /// A field has the wrong element type.
    WrongDtype(&'static str),
    /// A field has the wrong number of dimensions or inconsistent extents.
    BadShape(&'static str),
    /// A field contains NaN or infinite values.
    NonFinite(&'static str),
    /// A table that must be sampled has no positive mass in some slice.
    NotNormalizable(&'static str),
    /// Incidence angles are not increasing, or out of range; or the incident azimuths of
    /// an anisotropic file span neither the whole turn nor a half or a quarter of it.
    BadAngles(&'static str),
    /// The `wavelengths` of a spectral file are not increasing, or miss visible light.
    BadWavelengths,
}

impl fmt::Display for RglError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RglError::Io(k) => write!(f, "cannot read file: {k}"),
            RglError::BadMagic => write!(f, "not a tensor_file (bad magic)"),
            RglError::UnsupportedVersion { major, minor } => {
                write!(f, "unsupported tensor_file version {major}.{minor}")
            }
            RglError::Truncated => write!(f, "file is truncated"),
            RglError::BadDtype(d) => write!(f, "invalid dtype code {d}"),
            RglError::Overflow => write!(f, "size or offset overflows"),
            RglError::BadName => write!(f, "field name is not UTF-8"),
            RglError::MissingField(n) => write!(f, "missing field `{n}`"),
            RglError::WrongDtype(n) => write!(f, "field `{n}` has the wrong dtype"),
            RglError::BadShape(n) => write!(f, "field `{n}` has the wrong shape"),
            RglError::NonFinite(n) => write!(f, "field `{n}` contains NaN or infinity"),
            RglError::NotNormalizable(n) => write!(f, "table `{n}` has a slice with no mass"),
            RglError::BadAngles(n) => write!(f, "field `{n}` is not increasing within range"),
            RglError::BadWavelengths => write!(
                f,
                "field `wavelengths` is not increasing or misses the visible range"
            ),
        }
    }
}

impl std::error::Error for RglError {}
