//! The sampling API. Each entry point computes only what it returns:
//!
//! | call | work |
//! |---|---|
//! | [`Model::sample_direction`] | base net, `N` velocity evaluations |
//! | [`Model::sample`] | + forward Jacobians and `N` determinants |
//! | [`Model::pdf`] | `N` Newton inversions (2 to 3 Jacobian evaluations each) |
//!
//! The `_steps` variants take the number of Euler steps per call; the plain ones use the
//! model's default. Densities are per unit solid angle. Invalid input, or a sample that
//! leaves the domain, gives `None` (or a PDF of 0): the lost mass is never renormalised.

use crate::def::IncidentFold;
use crate::flow::Conditioned;
use crate::frame::IncidentFrame;
use crate::input::{uniform_pair, unit_direction};
use crate::math::exp;
use crate::model::Model;
use crate::spec;
use glam::{Vec2, Vec3};

/// A direction's flow before it runs ([`Model::direction_start`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct DirectionStart<const VW: usize> {
    /// The rotation into the nets' frame.
    pub frame: IncidentFrame,
    /// `wi` in that frame.
    pub wi: Vec3,
    /// What `wi` fixes for the call.
    pub c: Conditioned<VW>,
    /// The flow's start point.
    pub x0: [f32; 2],
}

/// A sampled direction and the density it was sampled with (per unit solid angle).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Sample {
    /// The sampled direction (unit, local shading frame).
    pub wo: Vec3,
    /// Its density per unit solid angle.
    pub pdf: f32,
}

impl Sample {
    /// What batch calls write for an invalid sample: `wo = 0`, `pdf = 0`.
    pub const INVALID: Sample = Sample {
        wo: Vec3::ZERO,
        pdf: 0.0,
    };

    /// Whether this is a real sample (`pdf > 0`).
    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.pdf > 0.0
    }
}

impl<
        const BE: usize,
        const BW: usize,
        const BM: usize,
        const VE: usize,
        const VW: usize,
        const VM: usize,
    > Model<BE, BW, BM, VE, VW, VM>
{
    /// The model's default number of Euler steps.
    #[must_use]
    pub fn default_steps(&self) -> u32 {
        self.def.default_steps as u32
    }

    /// The step count a call runs: `steps`, or the model's default for
    /// [`spec::DEFAULT_STEPS`] (0); `None` above [`spec::MAX_STEPS`].
    #[inline]
    #[must_use]
    pub fn resolve_steps(&self, steps: u32) -> Option<u32> {
        match steps {
            spec::DEFAULT_STEPS => Some(self.default_steps()),
            n if n <= spec::MAX_STEPS => Some(n),
            _ => None,
        }
    }

    /// A direction for `wi` and `u in [0,1]^2`, without its PDF.
    #[inline]
    #[must_use]
    pub fn sample_direction(&self, wi: Vec3, u: Vec2) -> Option<Vec3> {
        self.sample_direction_steps(wi, u, self.default_steps())
    }

    /// A direction and its PDF.
    #[inline]
    #[must_use]
    pub fn sample(&self, wi: Vec3, u: Vec2) -> Option<Sample> {
        self.sample_steps(wi, u, self.default_steps())
    }

    /// The PDF (per unit solid angle) with which `sample` produces `wo` for `wi`.
    #[inline]
    #[must_use]
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        self.pdf_steps(wi, wo, self.default_steps())
    }

    /// [`Model::sample_direction`] with `steps` Euler steps (0: the model's default; at
    /// most [`spec::MAX_STEPS`], `None` above).
    #[inline(always)]
    #[must_use]
    pub fn sample_direction_steps(&self, wi: Vec3, u: Vec2, steps: u32) -> Option<Vec3> {
        let steps = self.resolve_steps(steps)?;
        let start = self.direction_start(wi, u)?;
        let x = self.flow(&start.c, start.x0, steps);
        self.direction_end(&start, x)
    }

    /// What a direction's flow starts from: `wi` checked and in the nets' frame, its
    /// conditioning and the start point for `u`; `None` for invalid input.
    #[inline(always)]
    pub(crate) fn direction_start(&self, wi: Vec3, u: Vec2) -> Option<DirectionStart<VW>> {
        let (wi, u) = (self.incident(wi)?, uniform_pair(u)?);
        let (frame, wi) = self.incident_frame(wi);
        let c = self.condition(wi);
        let x0 = self.flow_start(&c, u);
        Some(DirectionStart { frame, wi, c, x0 })
    }

    /// The world direction of the flow's end point `x`; `None` outside the domain.
    #[inline(always)]
    pub(crate) fn direction_end(&self, start: &DirectionStart<VW>, x: [f32; 2]) -> Option<Vec3> {
        let wo = self
            .def
            .domain
            .to_direction(self.chart_point(&start.c, x), start.wi)?;
        Some(start.frame.to_world(wo)).filter(|wo| wo.is_finite())
    }

    /// [`Model::sample`] with `steps` Euler steps (0: the model's default; at most
    /// [`spec::MAX_STEPS`], `None` above).
    #[inline(always)]
    #[must_use]
    pub fn sample_steps(&self, wi: Vec3, u: Vec2, steps: u32) -> Option<Sample> {
        let (wi, u) = (self.incident(wi)?, uniform_pair(u)?);
        let steps = self.resolve_steps(steps)?;
        let (frame, wi) = self.incident_frame(wi);
        let c = self.condition(wi);
        let pass = self.flow_with_ln_det(&c, self.flow_start(&c, u), steps)?;
        let wo = self
            .def
            .domain
            .to_direction(self.chart_point(&c, pass.end), wi)?;
        let wo = frame.to_world(wo);
        // The density at the returned `wo` as `pdf` reads it: its flow point `end`, the start
        // point reaching it (docs/math.md, (71), (72)), the measure at `wo` itself.
        let (back, y) = self.read_back(frame, wo, wi)?;
        let end = self.flow_point(&c, y);
        let (x0, ln_det) = self.returned_start(&c, &pass, end, steps)?;
        // The warp's end term joins the steps' sum (docs/math.md, (66)).
        let ln_det = ln_det + self.end_ln_expansion(end);
        // pdf_w = p0(x0) / prod det * (pdf_w / pdf_x)   (docs/math.md, (38))
        let ln_pdf = self.start_ln_pdf(&c, x0) - ln_det + self.def.domain.ln_measure(y, back, wi);
        let pdf = exp(ln_pdf);
        (wo.is_finite() && pdf.is_finite() && pdf > 0.0).then_some(Sample { wo, pdf })
    }

    /// [`Model::pdf`] with `steps` Euler steps (0: the model's default; at most
    /// [`spec::MAX_STEPS`]); 0 for invalid input.
    #[inline(always)]
    #[must_use]
    pub fn pdf_steps(&self, wi: Vec3, wo: Vec3, steps: u32) -> f32 {
        self.pdf_inner(wi, wo, steps).unwrap_or(0.0)
    }

    #[inline(always)]
    fn pdf_inner(&self, wi: Vec3, wo: Vec3, steps: u32) -> Option<f32> {
        let wi = self.incident(wi)?;
        let steps = self.resolve_steps(steps)?;
        let domain = self.def.domain;
        let (frame, wi) = self.incident_frame(wi);
        let (wo, y) = self.read_back(frame, wo, wi)?;
        let c = self.condition(wi);
        let end = self.flow_point(&c, y);
        let (x0, ln_det) = self.flow_inverse(&c, end, steps)?;
        let ln_det = ln_det + self.end_ln_expansion(end);
        let ln_pdf = self.start_ln_pdf(&c, x0) - ln_det + domain.ln_measure(y, wo, wi);
        let pdf = exp(ln_pdf);
        pdf.is_finite().then_some(pdf)
    }

    /// A world direction as `pdf` reads it: normalised ([`unit_direction`]), in the
    /// incident frame, and its chart point; `None` where it is not a unit direction or the
    /// domain has no density there. `sample` reads its own result back the same way.
    #[inline(always)]
    fn read_back(&self, frame: IncidentFrame, wo: Vec3, wi: Vec3) -> Option<(Vec3, [f32; 2])> {
        let wo = frame.to_local(unit_direction(wo)?);
        Some((wo, self.def.domain.point_of(wo, wi)?))
    }

    /// `wi` normalised, or `None` if invalid or outside the model's declared incident
    /// range ([`crate::IncidentRange`]).
    #[inline]
    fn incident(&self, wi: Vec3) -> Option<Vec3> {
        let wi = unit_direction(wi)?;
        self.def.accepts_incident_z(wi.z).then_some(wi)
    }

    /// The frame the nets work in, and `wi` in it: for an isotropic model the rotation that
    /// puts `wi` at `phi = 0`, for a folded one the signs that fold `wi` into its part of
    /// the turn, otherwise the identity.
    #[inline(always)]
    pub(crate) fn incident_frame(&self, wi: Vec3) -> (IncidentFrame, Vec3) {
        let frame = if self.def.isotropic {
            IncidentFrame::aligning(wi)
        } else if self.def.fold != IncidentFold::None {
            IncidentFrame::folding(wi, self.def.fold)
        } else {
            return (IncidentFrame::IDENTITY, wi);
        };
        (frame, frame.to_local(wi))
    }
}
