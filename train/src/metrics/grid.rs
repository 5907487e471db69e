//! The fixed grid of incident directions every model is measured on.

use diffbsdf_materials::{from_spherical, DVec3};
use serde::Serialize;

/// Polar angles of `wi` above the surface, in degrees (incl. grazing).
pub const THETA_UPPER: [f64; 7] = [0.0, 20.0, 40.0, 60.0, 75.0, 85.0, 89.0];
/// Polar angles below the surface, for transmissive materials on the sphere.
pub const THETA_LOWER: [f64; 4] = [100.0, 120.0, 150.0, 175.0];
/// Azimuths in degrees (anisotropic materials differ along them).
pub const PHI: [f64; 3] = [0.0, 45.0, 90.0];

/// One incident direction of the grid.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct GridPoint {
    /// Polar angle in degrees.
    pub theta_deg: f64,
    /// Azimuth in degrees.
    pub phi_deg: f64,
    /// The direction.
    #[serde(skip)]
    pub wi: DVec3,
}

/// The grid: upper hemisphere, plus the lower one when `both_sides`.
pub fn wi_grid(both_sides: bool) -> Vec<GridPoint> {
    let lower: &[f64] = if both_sides { &THETA_LOWER } else { &[] };
    let mut out = Vec::new();
    for &theta in THETA_UPPER.iter().chain(lower) {
        let phis: &[f64] = if theta == 0.0 { &PHI[..1] } else { &PHI };
        for &phi in phis {
            out.push(GridPoint {
                theta_deg: theta,
                phi_deg: phi,
                wi: from_spherical(theta.to_radians(), phi.to_radians()),
            });
        }
    }
    out
}
