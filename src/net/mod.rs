//! The two MLPs and their pieces: dense layers, SiLU, the `wi` encoding.

pub mod activation;
pub mod base_net;
pub mod dense;
pub mod encoding;
pub mod velocity_net;

pub use base_net::BaseNet;
pub use dense::{Dense, Readout};
pub use velocity_net::{Jacobian, VelocityNet};
