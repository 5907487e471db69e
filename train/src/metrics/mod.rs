//! Sampling-quality metrics with the definitions of `docs/math.md` ("Metrics"):
//! per `wi` on a fixed grid, `w = f |cos theta_o| / pdf` (0 for invalid samples); relative
//! variance, firefly ratio, KL on a quadrature grid, forward/inverse PDF consistency and
//! step determinants, side by side with the material's own sampler and cosine sampling.

pub mod consistency;
pub mod cost;
pub mod evaluate;
pub mod exactness;
pub mod grid;
pub mod kl;
pub mod off_grid;
pub mod sampler;
pub mod stats;
pub mod table;

pub use evaluate::{evaluate, EvalConfig, Report};
