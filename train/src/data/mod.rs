//! Training pairs `(wi, wo)` whose conditional law of `wo` given `wi` is the normalised
//! target (see [`diffbsdf_materials::target`]): per unit solid angle `p(wo | wi) =
//! Y(f(wi, wo)) |cos theta_o| / Z(wi)`; on the disk domain `wo` is restricted to the upper
//! hemisphere. Two generators, both seeded and deterministic:
//!
//! - [`exact`]: importance resampling of the material's own sampler (needs `sample`/`pdf`);
//! - [`mcmc`]: an affine-invariant ensemble sampler (Goodman & Weare 2010) over the 4D
//!   joint `(wi, wo)` in bands of `theta_i` (needs only `eval`).

pub mod exact;
pub mod mcmc;
pub mod pair;

pub use exact::{exact_pairs, exact_pairs_for_wi, exact_pairs_uniform_angle, ExactConfig};
pub use mcmc::{mcmc_pairs, McmcConfig};
pub use pair::{Band, DomainTarget, Generated, Pair};
