//! How training reports progress: stages with a known amount of work, and the loss.

/// A progress sink. Implementations must be cheap; `advance` may be called from several
/// threads.
pub trait Progress: Sync {
    /// A new stage begins with `total` units of work.
    fn stage(&self, name: &'static str, total: u64);
    /// `n` units done; the latest loss if there is one.
    fn advance(&self, n: u64, loss: Option<f64>);
    /// All stages done.
    fn finish(&self) {}
}

/// Reports nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {
    fn stage(&self, _: &'static str, _: u64) {}
    fn advance(&self, _: u64, _: Option<f64>) {}
}
