//! What accuracy costs in time: the shipped models swept over Euler steps and weight
//! precision, timed next to the material's own sampler, written as a markdown table, an
//! accuracy-vs-time plot and PDF slice images (`diffbsdf tradeoff`, docs/tradeoff.md).

pub mod catalog;
pub mod markdown;
pub mod plot;
pub mod slice_labels;
pub mod slices;
pub mod sweep;

pub use catalog::{load_catalog, CatalogError, ShippedModel};
pub use sweep::{sweep, Point, SweepConfig, SweepError, SweepRecord};
