//! Why training or export failed.

use std::fmt;

/// Training and export errors.
#[derive(Debug)]
pub enum TrainError {
    /// The kernel rejected the parameters or the blob.
    Blob(diffbsdf::BlobError),
    /// The model name does not fit the blob's 32 bytes.
    NameTooLong,
    /// The data generator produced no usable pairs.
    NoData,
    /// The training set's domain or encoding does not fit the configuration.
    Mismatch,
    /// The loss became NaN or infinite.
    Diverged {
        /// Which stage.
        stage: &'static str,
    },
}

impl fmt::Display for TrainError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TrainError::Blob(e) => write!(f, "kernel rejected the model: {e}"),
            TrainError::NameTooLong => write!(f, "model name longer than 32 bytes"),
            TrainError::NoData => write!(
                f,
                "no training pairs (is the material black in this domain?)"
            ),
            TrainError::Mismatch => write!(
                f,
                "training set does not match the model definition (domain or frequencies)"
            ),
            TrainError::Diverged { stage } => write!(f, "training diverged in the {stage} stage"),
        }
    }
}

impl std::error::Error for TrainError {}

impl From<diffbsdf::BlobError> for TrainError {
    fn from(e: diffbsdf::BlobError) -> Self {
        TrainError::Blob(e)
    }
}
