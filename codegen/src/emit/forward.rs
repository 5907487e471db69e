//! Mirrors `src/flow/forward.rs` (Euler steps without and with Jacobians, `step_det` of
//! `src/flow/mod.rs`) and `src/sampler.rs` (the invalid result, `sample_direction` and
//! `sample`).

use super::Emitter;
use crate::dialect::{Math, T};

impl Emitter<'_> {
    pub(super) fn none(&mut self) {
        let rt = self.st("Result");
        self.code.line("// The invalid result: wo = 0, pdf = 0.");
        self.fn_open(rt.clone(), "none", false, &[]);
        let r = self.d.decl(&rt, "r", None);
        self.code.line(r);
        let z = self.f(0.0);
        for f in ["x", "y", "z", "pdf"] {
            self.code.line(format!("r.{f} = {z};"));
        }
        self.code.line("return r;");
        self.end_fn();
    }

    /// `det(I + h dv/dx)` of the Jacobian `j`, as the kernel's `step_det` computes it.
    pub(super) fn det_expr(&self) -> String {
        let one = self.f(1.0);
        format!("({one} + h * j.j00) * ({one} + h * j.j11) - (h * j.j01) * (h * j.j10)")
    }

    pub(super) fn det_line(&mut self) {
        let det = self.det_expr();
        self.decl(T::F, "det", &det);
    }

    pub(super) fn direction_impl(&mut self) {
        let rt = self.st("Result");
        let none = format!("return {};", self.call("none", false, &[]));
        self.code
            .line("// x_N by N Euler steps, no Jacobians; pdf = 1 marks a valid direction.");
        let ps = [
            (T::F, "wx"),
            (T::F, "wy"),
            (T::F, "wz"),
            (T::F, "u0"),
            (T::F, "u1"),
            (T::U, "steps"),
        ];
        self.fn_open(rt.clone(), "direction_impl", true, &ps);
        self.prologue(true, &none);
        let bs = self.base_sample_call();
        self.decl(self.st("Vec2"), "x0", &bs);
        self.start_point("x0.x", "x0.y");
        self.for_open("k", "n");
        let t = format!("{} * h", self.d.cast(&T::F, "k"));
        self.decl(T::F, "t", &t);
        let v = self.call("velocity", true, &["cond", "t", "a", "b"]);
        self.decl(self.st("Vec2"), "v", &v);
        for l in self.advance("a", "h * v.x", "b", "h * v.y") {
            self.code.line(l);
        }
        self.code.close("}");
        self.chart_point();
        let td = self.call("to_direction", false, &self.point_args("a", "b"));
        if self.m.def.isotropic {
            self.decl(rt, "r", &td);
            self.turn_back("r");
            self.code.line("return r;");
        } else {
            self.code.line(format!("return {td};"));
        }
        self.end_fn();
    }

    pub(super) fn sample_impl(&mut self) {
        let rt = self.st("Result");
        let none = format!("return {};", self.call("none", false, &[]));
        self.code.line(
            "// x_N and sum_k ln det(I + h dv/dx(x_k)); pdf = p0(x0) / prod det * (pdf_w / pdf_x).",
        );
        let ps = [
            (T::F, "wx"),
            (T::F, "wy"),
            (T::F, "wz"),
            (T::F, "u0"),
            (T::F, "u1"),
            (T::U, "steps"),
        ];
        self.fn_open(rt.clone(), "sample_impl", true, &ps);
        self.prologue(true, &none);
        let bs = self.base_sample_call();
        self.decl(self.st("Vec2"), "x0", &bs);
        self.start_point("x0.x", "x0.y");
        self.decl(T::F, "ln_det", &self.f(0.0));
        self.for_open("k", "n");
        let t = format!("{} * h", self.d.cast(&T::F, "k"));
        self.decl(T::F, "t", &t);
        let j = self.call("velocity_jacobian", true, &["cond", "t", "a", "b"]);
        self.decl(self.st("Jac"), "j", &j);
        self.det_line();
        let zero = self.f(0.0);
        self.code.open(format!(
            "if (!({} && det > {zero})) {{",
            self.d.finite("det")
        ));
        self.code.line(&none);
        self.code.close("}");
        self.code.line(format!(
            "ln_det = ln_det + {};",
            self.math(Math::Log, "det")
        ));
        for l in self.advance("a", "h * j.v0", "b", "h * j.v1") {
            self.code.line(l);
        }
        self.code.close("}");
        if self.warped() {
            self.code.line(
                "// ln |dz/dy| of the warp at the end point joins the steps' sum (docs/math.md, (66)).",
            );
            let end = self.warp_ln_expansion_sum("a", "b");
            self.code.line(format!("ln_det = ln_det + {end};"));
        }
        self.chart_point();
        let td = self.call("to_direction", false, &self.point_args("a", "b"));
        self.decl(rt, "r", &td);
        self.code.open(format!("if (!(r.pdf > {zero})) {{"));
        self.code.line(&none);
        self.code.close("}");
        let lp = self.call("base_ln_pdf", false, &["cond", "x0.x", "x0.y"]);
        if self.half_vector() {
            self.half_vector_sum("r.x", "r.y", "r.z");
        }
        let lm = self.ln_measure("r.z", "a");
        self.decl(T::F, "ln_pdf", &format!("{lp} - ln_det + {lm}"));
        self.code
            .line(format!("r.pdf = {};", self.math(Math::Exp, "ln_pdf")));
        self.turn_back("r");
        let fin: Vec<String> = ["r.x", "r.y", "r.z", "r.pdf"]
            .iter()
            .map(|v| self.d.finite(v))
            .collect();
        self.code
            .open(format!("if (!({} && r.pdf > {zero})) {{", fin.join(" && ")));
        self.code.line(&none);
        self.code.close("}");
        self.code.line("return r;");
        self.end_fn();
    }
}
