//! Read-only views of the intermediate quantities, for tests, conformance suites and
//! tools: the velocity and its Jacobian at a point, the base distribution, a whole
//! trajectory and the inverse of the flow. None of this is on the sampling hot path.
//!
//! Flow points `x` are in the frame the nets work in: for an isotropic model, the frame
//! turned about the normal so that `wi` has `phi = 0` ([`crate::frame::IncidentFrame`]);
//! for a model with [`crate::ModelDef::standardized`], in the base's standard coordinates
//! (docs/math.md, §6.3).

use crate::any_model::{with_model, AnyModel};
use crate::base::BaseDist;
use crate::flow::{step_det, step_time};
use crate::input::{uniform_pair, unit_direction};
use crate::math::{ln, sqrt};
use crate::model::Model;
use crate::net::Jacobian;
use crate::spec;
use glam::{Vec2, Vec3};

/// Intermediate quantities of a model's evaluation (import the trait to call them).
pub trait Diagnostics {
    /// `v(x, t, wi)` and the hand-derived `dv/dx` at a flow point `x`.
    fn velocity_at(&self, wi: Vec3, x: [f32; 2], t: f32) -> Option<([f32; 2], Jacobian)>;

    /// `v(x, t, wi)` alone (the direction-only path).
    fn velocity_only_at(&self, wi: Vec3, x: [f32; 2], t: f32) -> Option<[f32; 2]>;

    /// The base distribution `p0(. | wi)`.
    fn base_distribution(&self, wi: Vec3) -> Option<BaseDist>;

    /// Writes `x_0 .. x_steps` into `points` (which must hold `steps + 1` points) and
    /// returns the smallest step determinant `det(I + h dv/dx)` along the way.
    fn trajectory(&self, wi: Vec3, u: Vec2, steps: u32, points: &mut [[f32; 2]]) -> Option<f32>;

    /// The flow point `x0` that `steps` Euler steps carry to `x`, by the exact inverse.
    fn invert_flow(&self, wi: Vec3, x: [f32; 2], steps: u32) -> Option<[f32; 2]>;

    /// How much one f32 rounding can move the PDF of a sample (relative): the larger of
    /// the density's change over one machine epsilon of `wo` and the base density's change
    /// over one rounding of the start point `x0`, by finite differences (default steps).
    /// `pdf` is `pdf(wi, wo)`. See `spec::PDF_ROUNDING_SPAN`.
    fn pdf_rounding(&self, wi: Vec3, wo: Vec3, pdf: f32, x0: [f32; 2]) -> f32;

    /// Whether `pdf(wi, wo)` (`back`) agrees with the PDF `sampled` with `wo` from start
    /// point `x0` as the kernel promises: never 0, and within `spec::PDF_CONSISTENCY_TOL`
    /// relative or, where rounding allows more, `spec::PDF_ROUNDING_SPAN` times
    /// [`Diagnostics::pdf_rounding`].
    fn pdf_consistent(&self, wi: Vec3, wo: Vec3, sampled: f32, back: f32, x0: [f32; 2]) -> bool {
        if !(back > 0.0) {
            return false;
        }
        let rel = (back - sampled).abs() / sampled;
        rel <= spec::PDF_CONSISTENCY_TOL
            || rel <= spec::PDF_ROUNDING_SPAN * self.pdf_rounding(wi, wo, back, x0)
    }
}

impl<
        const BE: usize,
        const BW: usize,
        const BM: usize,
        const VE: usize,
        const VW: usize,
        const VM: usize,
    > Diagnostics for Model<BE, BW, BM, VE, VW, VM>
{
    fn velocity_at(&self, wi: Vec3, x: [f32; 2], t: f32) -> Option<([f32; 2], Jacobian)> {
        let c = self.condition(self.incident_frame(unit_direction(wi)?).1);
        let step = self.velocity.at_time(&c.cond, t);
        let (feat, dfeat) = self.def.domain.features_with_derivative(x);
        Some(self.velocity.velocity_jacobian(&step, feat, dfeat))
    }

    fn velocity_only_at(&self, wi: Vec3, x: [f32; 2], t: f32) -> Option<[f32; 2]> {
        let c = self.condition(self.incident_frame(unit_direction(wi)?).1);
        let step = self.velocity.at_time(&c.cond, t);
        Some(self.velocity.velocity(&step, self.def.domain.features(x)))
    }

    fn base_distribution(&self, wi: Vec3) -> Option<BaseDist> {
        Some(
            self.condition(self.incident_frame(unit_direction(wi)?).1)
                .base,
        )
    }

    fn trajectory(&self, wi: Vec3, u: Vec2, steps: u32, points: &mut [[f32; 2]]) -> Option<f32> {
        let c = self.condition(self.incident_frame(unit_direction(wi)?).1);
        let points = points.get_mut(..steps as usize + 1)?;
        let domain = self.def.domain;
        let h = 1.0 / steps as f32;
        let mut x = domain.advance(self.flow_start(&c, uniform_pair(u)?), [0.0, 0.0]);
        let mut min_det = f32::INFINITY;
        for (k, slot) in points.iter_mut().enumerate() {
            *slot = x;
            if k as u32 == steps {
                break;
            }
            let step = self.velocity.at_time(&c.cond, step_time(k as u32, h));
            let (feat, dfeat) = domain.features_with_derivative(x);
            let (v, j) = self.velocity.velocity_jacobian(&step, feat, dfeat);
            min_det = min_det.min(step_det(h, &j));
            x = domain.advance(x, [h * v[0], h * v[1]]);
        }
        Some(min_det)
    }

    fn invert_flow(&self, wi: Vec3, x: [f32; 2], steps: u32) -> Option<[f32; 2]> {
        let c = self.condition(self.incident_frame(unit_direction(wi)?).1);
        self.flow_inverse(&c, x, steps).map(|(x0, _)| x0)
    }

    fn pdf_rounding(&self, wi: Vec3, wo: Vec3, pdf: f32, x0: [f32; 2]) -> f32 {
        const DW: f32 = 1e-4;
        const DX: f32 = 1e-5;
        let ln_pdf = ln(pdf);
        let mut slope = 0.0f32;
        for (dx, dy) in [(DW, 0.0), (-DW, 0.0), (0.0, DW), (0.0, -DW)] {
            let moved = wo + Vec3::new(dx, dy, 0.0);
            let p = self.pdf(wi, moved * (1.0 / sqrt(moved.length_squared())));
            if p > 0.0 {
                slope = slope.max((ln(p) - ln_pdf).abs() / DW);
            }
        }
        let mut base_slope = 0.0f32;
        if let Some(wi) = unit_direction(wi) {
            let c = self.condition(self.incident_frame(wi).1);
            let at = self.start_ln_pdf(&c, x0);
            for (dx, dy) in [(DX, 0.0), (-DX, 0.0), (0.0, DX), (0.0, -DX)] {
                let moved = self.start_ln_pdf(&c, [x0[0] + dx, x0[1] + dy]);
                base_slope = base_slope.max((moved - at).abs() / DX);
            }
        }
        let x0_size = 1.0 + x0[0].abs().max(x0[1].abs());
        (slope * f32::EPSILON).max(base_slope * x0_size * f32::EPSILON)
    }
}

impl Diagnostics for AnyModel {
    fn velocity_at(&self, wi: Vec3, x: [f32; 2], t: f32) -> Option<([f32; 2], Jacobian)> {
        with_model!(self, m => m.velocity_at(wi, x, t))
    }

    fn velocity_only_at(&self, wi: Vec3, x: [f32; 2], t: f32) -> Option<[f32; 2]> {
        with_model!(self, m => m.velocity_only_at(wi, x, t))
    }

    fn base_distribution(&self, wi: Vec3) -> Option<BaseDist> {
        with_model!(self, m => m.base_distribution(wi))
    }

    fn trajectory(&self, wi: Vec3, u: Vec2, steps: u32, points: &mut [[f32; 2]]) -> Option<f32> {
        with_model!(self, m => m.trajectory(wi, u, steps, points))
    }

    fn invert_flow(&self, wi: Vec3, x: [f32; 2], steps: u32) -> Option<[f32; 2]> {
        with_model!(self, m => m.invert_flow(wi, x, steps))
    }

    fn pdf_rounding(&self, wi: Vec3, wo: Vec3, pdf: f32, x0: [f32; 2]) -> f32 {
        with_model!(self, m => m.pdf_rounding(wi, wo, pdf, x0))
    }
}
