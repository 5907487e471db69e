//! Mirrors `src/flow/forward.rs` (Euler steps without and with Jacobians, `step_det` of
//! `src/flow/mod.rs`) and `src/sampler.rs` (the invalid result, `sample_direction` and
//! `sample`).

use super::Emitter;
use crate::dialect::{Math, T};
use diffbsdf::spec::RETURNED_START_TOL;

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
        if self.has_frame() {
            self.decl(rt, "r", &td);
            self.turn_back("r");
            self.code.line("return r;");
        } else {
            self.code.line(format!("return {td};"));
        }
        self.end_fn();
    }

    /// The kernel's tail of `sample` up to the density (`src/sampler.rs`): from the pass's
    /// end point `(ea, eb)`, the direction returned (turned into the world), that direction
    /// validated and read back as `pdf` reads it (in the incident frame), its chart point
    /// and its flow point `end` (docs/math.md, (71)). `ok = false` where any of these fails.
    pub(super) fn returned(&mut self) {
        let qt = self.st("Returned");
        self.code.line(
            "// The direction returned for the flow's end point (ea, eb), and that direction as",
        );
        self.code.line(
            "// pdf() reads it: in the incident frame (lx, ly, lz), its chart point (ya, yb) and",
        );
        self.code
            .line("// its flow point (fa, fb). ok = false where any of these fails.");
        // `cond` (the base's parameters) only where the chart point is in standard coordinates.
        let mut ps = Vec::new();
        if self.standardized() {
            ps.push((self.st("Cond"), "cond"));
        }
        ps.extend([(T::F, "ea"), (T::F, "eb")]);
        if self.half_vector() {
            ps.extend([(T::F, "lwx"), (T::F, "lwy"), (T::F, "lwz")]);
        }
        if self.has_frame() {
            ps.push((self.st("Frame"), "fr"));
        }
        self.fn_open(qt.clone(), "returned", false, &ps);
        let q = self.d.decl(&qt, "q", None);
        self.code.line(q);
        let zero = self.f(0.0);
        for f in RETURNED_FIELDS {
            self.code.line(format!("q.{f} = {zero};"));
        }
        self.code
            .line(format!("q.ok = {};", self.d.bool_lit(false)));
        let fail = "return q;";
        self.decl(T::F, "a", "ea");
        self.decl(T::F, "b", "eb");
        self.chart_point();
        let td = self.call("to_direction", false, &self.point_args("a", "b"));
        self.decl(self.st("Result"), "r", &td);
        self.code.open(format!("if (!(r.pdf > {zero})) {{"));
        self.code.line(fail);
        self.code.close("}");
        self.turn_back("r");
        self.code.line("q.x = r.x;");
        self.code.line("q.y = r.y;");
        self.code.line("q.z = r.z;");
        let wo = self.call("unit", false, &["r.x", "r.y", "r.z"]);
        self.decl(self.st("Unit"), "wo", &wo);
        self.code.open("if (!wo.ok) {");
        self.code.line(fail);
        self.code.close("}");
        let (ox, oy) = self.direction_in_frame();
        self.point_of_direction(ox, oy, fail);
        let (fa, fb) = self.flow_point();
        self.code.line(format!("q.lx = {ox};"));
        self.code.line(format!("q.ly = {oy};"));
        self.code.line("q.lz = wo.z;");
        self.code.line("q.ya = ya;");
        self.code.line("q.yb = yb;");
        self.code.line(format!("q.fa = {fa};"));
        self.code.line(format!("q.fb = {fb};"));
        self.code.line(format!("q.ok = {};", self.d.bool_lit(true)));
        self.code.line("return q;");
        self.end_fn();
    }

    pub(super) fn sample_impl(&mut self) {
        let rt = self.st("Result");
        let none = format!("return {};", self.call("none", false, &[]));
        self.code.line(
            "// x_N and sum_k ln det(I + h dv/dx(x_k)); pdf = p0(x0) / prod det * (pdf_w / pdf_x),",
        );
        self.code.line(
            "// at the flow point pdf() reads for the direction returned: the start point moved by",
        );
        self.code.line(format!(
            "// M^-1 (end - x_N), M = prod (I + h J_k), and where it moves by more than {} (1 + |x0|),",
            RETURNED_START_TOL
        ));
        self.code
            .line("// a second pass from it for the determinants (docs/math.md, (71), (72)).");
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
        let (zero, one) = (self.f(0.0), self.f(1.0));
        // The pass's start point, moved once between the passes.
        self.decl(T::F, "sa", "a");
        self.decl(T::F, "sb", "b");
        self.decl(T::F, "ln_det", &zero);
        for (m, v) in [("m00", &one), ("m01", &zero), ("m10", &zero), ("m11", &one)] {
            self.decl(T::F, m, v);
        }
        let q = self.d.decl(&self.st("Returned"), "q", None);
        self.code.line(q);
        self.for_open("pass_no", &self.u(2));
        self.code.line("a = sa;");
        self.code.line("b = sb;");
        self.code.line(format!("ln_det = {zero};"));
        for (m, v) in [("m00", &one), ("m01", &zero), ("m10", &zero), ("m11", &one)] {
            self.code.line(format!("{m} = {v};"));
        }
        self.for_open("k", "n");
        let t = format!("{} * h", self.d.cast(&T::F, "k"));
        self.decl(T::F, "t", &t);
        let j = self.call("velocity_jacobian", true, &["cond", "t", "a", "b"]);
        self.decl(self.st("Jac"), "j", &j);
        self.det_line();
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
        self.code.line("// M = (I + h J) M.");
        self.decl(T::F, "a00", &format!("{one} + h * j.j00"));
        self.decl(T::F, "a01", "h * j.j01");
        self.decl(T::F, "a10", "h * j.j10");
        self.decl(T::F, "a11", &format!("{one} + h * j.j11"));
        self.decl(T::F, "n00", "a00 * m00 + a01 * m10");
        self.decl(T::F, "n01", "a00 * m01 + a01 * m11");
        self.code.line("m10 = a10 * m00 + a11 * m10;");
        self.code.line("m11 = a10 * m01 + a11 * m11;");
        self.code.line("m00 = n00;");
        self.code.line("m01 = n01;");
        for l in self.advance("a", "h * j.v0", "b", "h * j.v1") {
            self.code.line(l);
        }
        self.code.close("}");
        self.code.open(format!("if (pass_no == {}) {{", self.u(1)));
        self.code.line("break;");
        self.code.close("}");
        let mut qa = if self.standardized() {
            vec!["cond", "a", "b"]
        } else {
            vec!["a", "b"]
        };
        if self.half_vector() {
            qa.extend(["lwx", "lwy", "lwz"]);
        }
        if self.has_frame() {
            qa.push("fr");
        }
        let ret = self.call("returned", false, &qa);
        self.code.line(format!("q = {ret};"));
        self.code.open("if (!q.ok) {");
        self.code.line(&none);
        self.code.close("}");
        self.code
            .line("// dx0 = M^-1 (end - x_N) by the 2x2 adjugate (docs/math.md, (71)).");
        self.decl(T::F, "d0", "q.fa - a");
        if self.sphere() {
            let w = self.call("wrap", false, &["q.fb - b"]);
            self.decl(T::F, "d1", &w);
        } else {
            self.decl(T::F, "d1", "q.fb - b");
        }
        self.decl(T::F, "mdet", "m00 * m11 - m01 * m10");
        self.decl(T::F, "dx0", "(m11 * d0 - m01 * d1) / mdet");
        self.decl(T::F, "dx1", "(m00 * d1 - m10 * d0) / mdet");
        self.code.open(format!(
            "if (!({} && {})) {{",
            self.d.finite("dx0"),
            self.d.finite("dx1")
        ));
        self.code.line("break;");
        self.code.close("}");
        let abs = |s: &Self, x: &str| s.math(Math::Abs, x);
        let mx = self.d.math(Math::Max);
        self.decl(
            T::F,
            "size",
            &format!("{mx}({}, {})", abs(self, "dx0"), abs(self, "dx1")),
        );
        self.decl(
            T::F,
            "scale",
            &format!("{one} + {mx}({}, {})", abs(self, "sa"), abs(self, "sb")),
        );
        for l in self.advance("sa", "dx0", "sb", "dx1") {
            self.code.line(l);
        }
        let tol = self.f(RETURNED_START_TOL);
        self.code.open(format!("if (size <= {tol} * scale) {{"));
        self.code.line("break;");
        self.code.close("}");
        self.code.close("}");
        if self.warped() {
            self.code.line(
                "// ln |dz/dy| of the warp at the end point joins the steps' sum (docs/math.md, (66)).",
            );
            let end = self.warp_ln_expansion_sum("q.fa", "q.fb");
            self.code.line(format!("ln_det = ln_det + {end};"));
        }
        let lp = self.call("base_ln_pdf", self.table(), &["cond", "sa", "sb"]);
        if self.half_vector() {
            self.half_vector_sum("q.lx", "q.ly", "q.lz");
        }
        let lm = self.ln_measure("q.lz", "q.ya");
        self.decl(T::F, "ln_pdf", &format!("{lp} - ln_det + {lm}"));
        let r = self.d.decl(&rt, "r", None);
        self.code.line(r);
        self.code.line("r.x = q.x;");
        self.code.line("r.y = q.y;");
        self.code.line("r.z = q.z;");
        self.code
            .line(format!("r.pdf = {};", self.math(Math::Exp, "ln_pdf")));
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

/// The float fields of the generated `Returned` struct (besides `ok`).
pub(super) const RETURNED_FIELDS: [&str; 10] =
    ["x", "y", "z", "lx", "ly", "lz", "ya", "yb", "fa", "fb"];
