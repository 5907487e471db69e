//! The target density in the flow's own coordinates, up to a constant per `wi`, and its
//! gradient: what the flow's end point should be distributed as (docs/math.md, (68)).
//!
//! A flow end point `y` maps to a direction as the kernel maps it (expansion of the warp,
//! standard coordinates to the chart, chart to `wo`), so
//! `ln q(y) = ln(Y(f) |cos theta_o|)(wo) + E(y) - ln(pdf_w / pdf_x)(x, wo)`, where `E` is
//! the warp's `ln |dz/dy|` (65) and the last term the chart's measure; the base's
//! `sum ln sigma` is the same for every `y` of one `wi` and left out.

use crate::data::DomainTarget;
use diffbsdf::glam::Vec3;
use diffbsdf::internals::base::{warp, BaseDist};
use diffbsdf::ModelDef;
use diffbsdf_materials::{DVec3, Material};

/// One incidence as the flow sees it.
pub(super) struct Incidence<'a> {
    /// The model.
    pub def: &'a ModelDef,
    /// The material.
    pub material: &'a dyn Material,
    /// `wi` in the model's frame.
    pub wi: Vec3,
    /// Its base distribution.
    pub base: BaseDist,
}

/// Central-difference step in standard coordinates (a spike spans units there).
const STEP_STANDARD: f32 = 1e-3;
/// Central-difference step in chart coordinates (a spike spans hundredths there).
const STEP_CHART: f32 = 1e-4;

impl Incidence<'_> {
    /// The flow's start point for `u` and its `ln p0` in the flow's coordinates (up to the
    /// same constant per `wi` as [`Incidence::ln_target`]).
    pub(super) fn start(&self, u: [f32; 2]) -> ([f32; 2], f64) {
        let y0 = if self.def.standardized {
            BaseDist::standard_start(u, self.def.standard_warp)
        } else {
            self.base.sample(u)
        };
        (y0, self.ln_start(y0))
    }

    /// `ln p0` of a start point in the flow's coordinates (as [`Incidence::start`]).
    pub(super) fn ln_start(&self, y0: [f32; 2]) -> f64 {
        f64::from(match (self.def.standardized, self.def.standard_warp) {
            (false, _) => self.base.ln_pdf(y0),
            (true, true) => self.base.standard_ln_pdf(warp::expand2(y0)) + warp::ln_expansion2(y0),
            (true, false) => self.base.standard_ln_pdf(y0),
        })
    }

    /// `grad ln p0` at a start point, by central differences.
    pub(super) fn ln_start_gradient(&self, y0: [f32; 2]) -> [f32; 2] {
        let step = self.step();
        let mut gradient = [0.0f32; 2];
        for (j, g) in gradient.iter_mut().enumerate() {
            let (mut plus, mut minus) = (y0, y0);
            plus[j] += step;
            minus[j] -= step;
            let taken = f64::from(plus[j]) - f64::from(minus[j]);
            *g = ((self.ln_start(plus) - self.ln_start(minus)) / taken) as f32;
        }
        gradient
    }

    /// The flow's end point of the direction `wo` (the kernel's `pdf` maps it the same
    /// way); `None` outside the chart.
    pub(super) fn end_point(&self, wo: Vec3) -> Option<[f32; 2]> {
        let x = self.def.domain.point_of(wo, self.wi)?;
        Some(match (self.def.standardized, self.def.standard_warp) {
            (false, _) => x,
            (true, true) => warp::compress2(self.base.to_standard(x)),
            (true, false) => self.base.to_standard(x),
        })
    }

    /// Central-difference step of the flow's coordinates.
    fn step(&self) -> f32 {
        if self.def.standardized {
            STEP_STANDARD
        } else {
            STEP_CHART
        }
    }

    /// `ln q(y)`; `None` where `y` leaves the domain or the target is 0 there.
    pub(super) fn ln_target(&self, y: [f32; 2]) -> Option<f64> {
        let (z, expansion) = match (self.def.standardized, self.def.standard_warp) {
            (true, true) => (warp::expand2(y), warp::ln_expansion2(y)),
            _ => (y, 0.0),
        };
        let x = if self.def.standardized {
            self.base.from_standard(z)
        } else {
            z
        };
        let domain = self.def.domain;
        let wo = domain.to_direction(x, self.wi)?;
        let as64 = |w: Vec3| DVec3::new(f64::from(w.x), f64::from(w.y), f64::from(w.z));
        let target = domain.target(self.material, as64(self.wi), as64(wo));
        (target > 0.0).then(|| {
            target.ln() + f64::from(expansion) - f64::from(domain.ln_measure(x, wo, self.wi))
        })
    }

    /// `grad ln q(y)` by central differences (the sample's `ln q(y)` itself is known);
    /// `None` where any of the four points is outside the target's support.
    pub(super) fn ln_target_gradient(&self, y: [f32; 2]) -> Option<[f32; 2]> {
        let step = self.step();
        let mut gradient = [0.0f32; 2];
        for (j, g) in gradient.iter_mut().enumerate() {
            let (mut plus, mut minus) = (y, y);
            plus[j] += step;
            minus[j] -= step;
            // The step actually taken, after rounding.
            let taken = f64::from(plus[j]) - f64::from(minus[j]);
            *g = ((self.ln_target(plus)? - self.ln_target(minus)?) / taken) as f32;
        }
        Some(gradient)
    }
}
