//! Reference materials for diffbsdf: analytic BSDFs and RGL measured tables, each with
//! its own importance sampler and PDF, and the one-string spec parser
//! ([`parse_spec`]). `MATERIALS.md` lists the models and their parameters.
//!
//! # Conventions (every material follows them)
//! - Local shading frame, z = surface normal. Directions are unit [`DVec3`]s pointing away
//!   from the surface.
//! - `wi` is the fixed direction (the one a path arrives along: the camera side in a path
//!   tracer), `wo` the sampled direction.
//! - [`Material::eval`] returns the BSDF value `f(wi, wo)` **without** the cosine, in the
//!   radiance-transport convention of Mitsuba and pbrt (for a dielectric the transmitted
//!   part carries the `1/eta'^2` factor, where `eta'` is the relative index of the side of
//!   `wo` over that of `wi`). [`Material::eval_cos`] returns `f(wi, wo) |cos theta_o|`.
//! - [`Material::pdf`] is a density per unit solid angle of `wo`. It is the density of the
//!   *valid* samples only: mass that the sampler loses (e.g. a microfacet reflection that
//!   lands below the horizon) is not renormalised, so `pdf` integrates to the sampled-mass
//!   fraction.
//! - One-sided BRDFs (everything but the dielectric and the principled BSDF with specular
//!   transmission) are zero unless `wi.z > 0` and `wo.z > 0`.

#![forbid(unsafe_code)]
// `!(x > 0.0)` is deliberate throughout: it is true for NaN, which must be rejected too.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod conductor;
pub mod dielectric;
pub mod disk_view;
pub mod fresnel;
pub mod halfway;
pub mod lambertian;
pub mod microfacet;
pub mod plastic;
pub mod principled;
pub mod radial;
pub mod rgb;
pub mod rgl;
pub mod spec;
pub mod special;
pub mod spherical;
pub mod symmetry;
pub mod target;
pub mod warp;
pub mod zoom;

pub use diffbsdf::glam::DVec3;
pub use rgb::{luminance, Rgb};
pub use spec::{parse_spec, SpecError};
pub use spherical::{from_spherical, reflect, Spherical};
pub use symmetry::IncidentFold;
pub use target::{disk_target, sphere_target};

/// One sample drawn by a material's own sampler.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialSample {
    /// The sampled direction (unit, away from the surface).
    pub wo: DVec3,
    /// Density of `wo` per unit solid angle; equals `pdf(wi, wo)` up to rounding.
    pub pdf: f64,
    /// Throughput weight `f(wi, wo) |cos theta_o| / pdf` per channel.
    pub weight: Rgb,
}

/// A reference BSDF with its own importance sampler. Object safe, `Send + Sync`.
pub trait Material: Send + Sync + std::fmt::Debug {
    /// Short name of the model, e.g. `"conductor"`.
    fn name(&self) -> &'static str;

    /// The one-string spec that [`parse_spec`] turns back into this material.
    fn spec(&self) -> String;

    /// The BSDF value `f(wi, wo)` (no cosine factor), per RGB channel.
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb;

    /// `f(wi, wo) |cos theta_o|` (what Mitsuba's `eval` returns).
    fn eval_cos(&self, wi: DVec3, wo: DVec3) -> Rgb {
        self.eval(wi, wo) * wo.z.abs()
    }

    /// Luminance of `f(wi, wo)`.
    fn eval_luminance(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.eval(wi, wo).luminance()
    }

    /// Draws `wo` from the material's own sampler. `u[0], u[1]` drive the direction, `u[2]`
    /// picks a lobe. `None` is an invalid sample (zero contribution, mass lost).
    fn sample(&self, wi: DVec3, u: [f64; 3]) -> Option<MaterialSample>;

    /// Density of the sampler per unit solid angle at `wo`.
    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64;

    /// True when the BSDF transmits light (has a non-zero part with `wi.z * wo.z < 0`).
    fn is_transmissive(&self) -> bool;

    /// True when the BSDF is unchanged by rotations about the normal:
    /// `f(R wi, R wo) = f(wi, wo)` for every rotation `R` about `z`.
    fn is_isotropic(&self) -> bool;

    /// A symmetry of an anisotropic BSDF in the incident azimuth that a model may use to
    /// learn part of the turn only: `f` is unchanged when `wi` and `wo` are folded
    /// together by [`symmetry::fold_signs`]. `None` unless the material says so.
    fn azimuth_fold(&self) -> IncidentFold {
        IncidentFold::None
    }

    /// Refractive index of the medium on the side of `w` relative to the outside (1 above
    /// the surface); used by the generalized reciprocity `f(wi,wo)/eta(wi)^2 =
    /// f(wo,wi)/eta(wo)^2` (Veach 1997, eq. 5.14). 1 for non-transmissive materials.
    fn index_of_side(&self, w: DVec3) -> f64 {
        let _ = w;
        1.0
    }
}

/// The luminance of an RGB triple given as an array; see [`rgb::luminance`].
pub fn rgb_luminance(rgb: Rgb) -> f64 {
    rgb.luminance()
}
