//! Mirrors the kernel (`src/`) as a whole: the sampling algorithm, written once over a
//! [`Dialect`], one file per kernel concept, each opposite the kernel file it mirrors (same
//! operation order, same constants read from `diffbsdf::spec`), so that every language
//! agrees with the kernel to rounding.
//!
//! | emitter      | kernel                                                   |
//! |--------------|----------------------------------------------------------|
//! | `net.rs`     | `src/net/`: SiLU, `wi` encoding, the two MLPs, `dv/dx`   |
//! | `base.rs`    | `src/base/`: Gaussian quantile, wrapped Cauchy, `p0`     |
//! | `warp.rs`    | `src/base/warp.rs`: the warp of the standard coordinates |
//! | `table.rs`   | `src/base/table.rs`, `gaussian::cdf`: the latent table   |
//! | `domain.rs`  | `src/domain/`: wrap, features, advance, directions       |
//! | `frame.rs`   | `src/frame.rs`: the incident frame (isotropic, folded)   |
//! | `input.rs`   | `src/input.rs`: input checks, the entry points' prologue |
//! | `forward.rs` | `src/flow/forward.rs`, `src/sampler.rs`: Euler steps     |
//! | `inverse.rs` | `src/flow/inverse.rs`: the Newton inverse, the PDF       |
//!
//! This file holds the [`Emitter`], its small helpers, the types of the generated code and
//! [`Emitter::write`], the plan of which pieces the requested entry points need (the
//! sampler's "pay for what you use"). `tests.rs` parses the constants back out of every
//! language's output and compares them with `diffbsdf::spec`.

mod base;
mod domain;
mod forward;
mod frame;
mod input;
mod inverse;
mod net;
mod table;
#[cfg(test)]
mod tests;
mod warp;

use crate::desc::ModelDesc;
use crate::dialect::{Dialect, Math, T};
use crate::{code::Code, EntryPoints};
use diffbsdf::spec::BASE_OUTPUTS;
use diffbsdf::Domain;

/// Writes the helper functions and the `*_impl` functions the entry points need.
pub struct Emitter<'a> {
    d: &'a dyn Dialect,
    m: &'a ModelDesc,
    e: EntryPoints,
    pub code: Code,
}

impl<'a> Emitter<'a> {
    pub fn new(d: &'a dyn Dialect, m: &'a ModelDesc, e: EntryPoints) -> Self {
        Emitter {
            d,
            m,
            e,
            code: Code::new(),
        }
    }

    fn p(&self, name: &str) -> String {
        format!("{}_{name}", self.d.prefix())
    }
    fn st(&self, name: &str) -> T {
        T::Struct(self.p(name))
    }
    fn f(&self, v: f32) -> String {
        self.d.lit(v, &T::F)
    }
    fn nl(&self, v: f32) -> String {
        self.d.lit(v, &T::N)
    }
    fn u(&self, v: usize) -> String {
        format!("{v}u")
    }
    fn math(&self, f: Math, x: &str) -> String {
        format!("{}({x})", self.d.math(f))
    }
    fn decl(&mut self, t: T, name: &str, init: &str) {
        let s = self.d.decl(&t, name, Some(init));
        self.code.line(s);
    }
    fn arr(&mut self, t: T, n: usize, name: &str) {
        let s = self.d.decl(&T::Arr(Box::new(t), n), name, None);
        self.code.line(s);
    }
    fn for_open(&mut self, var: &str, bound: &str) {
        let s = self.d.for_open(var, bound);
        self.code.open(s);
    }
    /// A call to a generated function; `weights` adds the parameter-buffer argument.
    fn call(&self, name: &str, weights: bool, args: &[&str]) -> String {
        let mut all: Vec<&str> = Vec::new();
        if weights {
            if let Some(w) = self.d.weights_arg() {
                all.push(w);
            }
        }
        all.extend_from_slice(args);
        format!("{}({})", self.p(name), all.join(", "))
    }
    fn fn_open(&mut self, ret: T, name: &str, weights: bool, params: &[(T, &str)]) {
        let mut ps: Vec<String> = Vec::new();
        if weights {
            if let Some(w) = self.d.weights_param() {
                ps.push(w);
            }
        }
        ps.extend(params.iter().map(|(t, n)| self.d.param(t, n)));
        let s = self.d.fn_open(&ret, &self.p(name), &ps);
        self.code.open(s);
    }
    fn end_fn(&mut self) {
        self.code.close("}");
        self.code.blank();
    }
    fn w(&self, idx: String) -> String {
        self.d.weight(&idx)
    }

    /// Spherical coordinates (the sphere or the equatorial chart).
    fn sphere(&self) -> bool {
        self.m.def.domain.is_spherical()
    }
    /// The equatorial chart: the sphere's about the y axis.
    fn equatorial(&self) -> bool {
        self.m.def.domain == Domain::Equatorial
    }
    /// The half-vector chart: the flow point is the half vector on the disk, and the
    /// direction its reflection of `wi` (in the incident frame: `lwx, lwy, lwz`).
    fn half_vector(&self) -> bool {
        self.m.def.domain == Domain::HalfVector
    }
    /// The flow runs in the base's standard coordinates `z = (x - mu) / sigma`
    /// (docs/math.md, section 6.3).
    fn standardized(&self) -> bool {
        self.m.def.standardized
    }
    /// The flow runs in the compressed standard coordinates `y = K asinh(z / K)`
    /// (docs/math.md, section 6.4).
    fn warped(&self) -> bool {
        self.m.def.standardized && self.m.def.standard_warp
    }
    fn needs_velocity(&self) -> bool {
        self.e.direction || self.e.pdf
    }
    fn needs_jacobian(&self) -> bool {
        self.e.sample || self.e.pdf
    }
    fn needs_base_sample(&self) -> bool {
        self.e.direction || self.e.sample
    }
    fn needs_ln_pdf(&self) -> bool {
        self.e.sample || self.e.pdf
    }

    /// Every helper and `*_impl` function the entry points need, in dependency order.
    /// Like the kernel's sampler, each entry point pays only for what it uses: no
    /// Jacobians without a PDF, no base sampling or to-direction map for the PDF alone,
    /// no Newton inverse without `pdf`.
    pub fn write(&mut self) {
        self.structs();
        // src/net: the activation, the encoding and what one wi fixes for a call.
        self.sigmoid();
        self.encode();
        self.condition();
        if self.sphere() {
            self.wrap();
        }
        // src/net/velocity_net.rs: v alone (direction, Newton's start), v with dv/dx
        // (every density).
        if self.needs_velocity() {
            self.velocity();
        }
        if self.needs_jacobian() {
            self.velocity_jacobian();
        }
        // src/base: the map from u to x0 and the log-density of x0.
        if self.needs_base_sample() {
            self.quantile();
        }
        if self.sphere() && self.needs_base_sample() {
            self.wc_sample();
        }
        if self.sphere() && self.needs_ln_pdf() {
            self.wc_ln_pdf();
        }
        // src/base/warp.rs: compress at the start (sample) and end (pdf); expand at the
        // end (sample) and start (every density); the log-Jacobian with every density.
        if self.warped() && (self.needs_base_sample() || self.e.pdf) {
            self.warp_compress();
        }
        if self.warped() {
            self.warp_expand();
        }
        if self.warped() && self.needs_ln_pdf() {
            self.warp_ln_expansion();
        }
        // src/base/table.rs: the latent table's nodes, its map (sample) and its density
        // (every density, at Phi of the standard start point).
        if self.table() {
            self.table_node();
            self.table_columns();
        }
        if self.table() && (self.needs_base_sample() || self.table_axes()) {
            self.table_fraction();
        }
        if self.table_axes() {
            self.table_axis();
        }
        if self.table_axes() && self.needs_base_sample() {
            self.table_axis_forward();
        }
        if self.table_axes() && self.needs_ln_pdf() {
            self.table_axis_inverse();
            self.table_axis_slope();
        }
        if self.table() && self.needs_base_sample() {
            self.table_warp();
        }
        if self.table() && self.needs_ln_pdf() {
            self.normal_cdf();
            self.table_ln_density();
        }
        if self.needs_base_sample() {
            self.base_sample();
        }
        if self.needs_ln_pdf() {
            self.base_ln_pdf();
        }
        // src/sampler.rs, src/input.rs, src/frame.rs, src/domain: results and inputs.
        self.none();
        self.unit();
        if self.has_frame() {
            self.frame();
        }
        if self.needs_base_sample() {
            self.point_to_direction();
        }
        // src/flow/forward.rs: the Euler steps.
        if self.e.direction {
            self.direction_impl();
        }
        if self.e.sample {
            self.returned();
            self.sample_impl();
        }
        // src/flow/inverse.rs: the exact inverse and the PDF of a given direction.
        if self.e.pdf {
            self.residual();
            self.newton();
            self.invert_step();
            self.pdf_impl();
        }
    }

    fn structs(&mut self) {
        let ve = self.m.encoding_len();
        let vw = self.m.velocity[0].outputs;
        let mut lines = Vec::new();
        lines.push("// The NeRF encoding of wi (f32).".to_string());
        lines.extend(
            self.d
                .struct_decl(&self.p("Enc"), &[(T::Arr(Box::new(T::F), ve), "e")]),
        );
        lines.push(
            "// What one wi fixes for a whole call: the velocity net's first-layer wi part (plus"
                .into(),
        );
        lines.push("// bias) and the base distribution's parameters (log-scales clamped).".into());
        let params: Vec<String> = (0..BASE_OUTPUTS).map(|k| format!("p{k}")).collect();
        let mut cond = vec![(T::Arr(Box::new(T::N), vw), "c")];
        cond.extend(params.iter().map(|p| (T::F, p.as_str())));
        if self.table() {
            // The latent table's first slice for wi and the next one's weight.
            cond.extend([(T::U, "tk"), (T::F, "tt")]);
        }
        lines.extend(self.d.struct_decl(&self.p("Cond"), &cond));
        lines.push("// A flow point or a velocity.".into());
        lines.extend(
            self.d
                .struct_decl(&self.p("Vec2"), &[(T::F, "x"), (T::F, "y")]),
        );
        if self.needs_jacobian() {
            lines.push("// A velocity and its Jacobian j_rc = dv_r / dx_c.".into());
            let f = [
                (T::F, "v0"),
                (T::F, "v1"),
                (T::F, "j00"),
                (T::F, "j01"),
                (T::F, "j10"),
                (T::F, "j11"),
            ];
            lines.extend(self.d.struct_decl(&self.p("Jac"), &f));
        }
        if self.e.pdf {
            lines.push(
                "// A Newton residual x + h v(x) - y, v, dv/dx and det(I + h dv/dx) at x.".into(),
            );
            let f = [
                (T::F, "r0"),
                (T::F, "r1"),
                (T::F, "v0"),
                (T::F, "v1"),
                (T::F, "j00"),
                (T::F, "j01"),
                (T::F, "j10"),
                (T::F, "j11"),
                (T::F, "det"),
            ];
            lines.extend(self.d.struct_decl(&self.p("Residual"), &f));
            lines.push(
                "// The point x one Euler step came from, det(I + h dv/dx(x)) (0: none) and v(x)."
                    .into(),
            );
            let f = [
                (T::F, "a"),
                (T::F, "b"),
                (T::F, "det"),
                (T::F, "va"),
                (T::F, "vb"),
            ];
            lines.extend(self.d.struct_decl(&self.p("Root"), &f));
        }
        if self.table() {
            lines.push(
                if self.table_axes() {
                    "// The latent table's column integrals of one wi's mixed slice, or an axis warp's nodes, and their total."
                } else {
                    "// The latent table's column integrals of one wi's mixed slice and their total."
                }
                .into(),
            );
            let f = [
                (T::Arr(Box::new(T::F), self.table_nodes()), "m"),
                (T::F, "tot"),
            ];
            lines.extend(self.d.struct_decl(&self.p("Cols"), &f));
        }
        if self.has_frame() {
            lines.push(self.frame_comment().into());
            lines.extend(
                self.d
                    .struct_decl(&self.p("Frame"), &[(T::F, "c"), (T::F, "s")]),
            );
        }
        if self.e.sample {
            lines.push(
                "// The direction a sample returns (x, y, z), read back as pdf() reads it: in the"
                    .into(),
            );
            lines.push(
                "// incident frame (lx, ly, lz), its chart point (ya, yb), its flow point (fa, fb)."
                    .into(),
            );
            let mut f: Vec<(T, &str)> = forward::RETURNED_FIELDS
                .iter()
                .map(|n| (T::F, *n))
                .collect();
            f.push((T::B, "ok"));
            lines.extend(self.d.struct_decl(&self.p("Returned"), &f));
        }
        lines.push("// A direction and its PDF; all zero when invalid.".into());
        let r = [(T::F, "x"), (T::F, "y"), (T::F, "z"), (T::F, "pdf")];
        lines.extend(self.d.struct_decl(&self.p("Result"), &r));
        lines.push("// Validated input: a unit direction, or ok = false.".into());
        let i = [(T::F, "x"), (T::F, "y"), (T::F, "z"), (T::B, "ok")];
        lines.extend(self.d.struct_decl(&self.p("Unit"), &i));
        for l in lines {
            self.code.line(l);
        }
        self.code.blank();
    }
}
