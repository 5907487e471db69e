//! Mirrors `src/flow/inverse.rs`: the residual of one Euler step, Newton's method with its
//! line search, the four starts of `invert_step`, and the PDF of a given direction.

use super::Emitter;
use crate::dialect::{Math, T};
use diffbsdf::spec::{
    DET_REUSE_TOL, DET_SECANT_TOL, LINE_SEARCH_HALVINGS, NEWTON_MAX_ITERS, NEWTON_TOL,
    NEWTON_TOL_F16,
};

impl Emitter<'_> {
    /// Newton's tolerance: the kernel's, or the f16 one.
    fn newton_tol(&self) -> f32 {
        if self.d.half() {
            NEWTON_TOL_F16
        } else {
            NEWTON_TOL
        }
    }

    fn step_params() -> [(T, &'static str); 4] {
        [(T::F, "t"), (T::F, "h"), (T::F, "ya"), (T::F, "yb")]
    }

    /// The kernel's `residual`: `x + h v(x) - y` (phi difference wrapped), `dv/dx` and
    /// `det(I + h dv/dx)` at `x = (a, b)`.
    pub(super) fn residual(&mut self) {
        self.code
            .line("// x + h v(x) - y (phi wrapped), v, dv/dx and det(I + h dv/dx) at x = (a, b).");
        let cond = self.st("Cond");
        let mut ps = vec![(cond, "cond")];
        ps.extend(Self::step_params());
        ps.extend([(T::F, "a"), (T::F, "b")]);
        self.fn_open(self.st("Residual"), "residual", true, &ps);
        let j = self.call("velocity_jacobian", true, &["cond", "t", "a", "b"]);
        self.decl(self.st("Jac"), "j", &j);
        let decl = self.d.decl(&self.st("Residual"), "r", None);
        self.code.line(decl);
        self.code.line("r.r0 = (a + h * j.v0) - ya;");
        if self.sphere() {
            let adv = self.call("wrap", false, &["b + h * j.v1"]);
            let dif = self.call("wrap", false, &[&format!("{adv} - yb")]);
            self.code.line(format!("r.r1 = {dif};"));
        } else {
            self.code.line("r.r1 = (b + h * j.v1) - yb;");
        }
        for c in ["v0", "v1", "j00", "j01", "j10", "j11"] {
            self.code.line(format!("r.{c} = j.{c};"));
        }
        self.code.line(format!("r.det = {};", self.det_expr()));
        self.code.line("return r;");
        self.end_fn();
    }

    /// `(a', b') = (a - l d0, b - l d1)` (phi wrapped), as one statement.
    fn step_to(&mut self, a: &str, b: &str, l: &str) {
        self.code.line(format!("{a} = a - {l}d0;"));
        if self.sphere() {
            let w = self.call("wrap", false, &[&format!("b - {l}d1")]);
            self.code.line(format!("{b} = {w};"));
        } else {
            self.code.line(format!("{b} = b - {l}d1;"));
        }
    }

    /// The kernel's `newton`: Newton steps where `I + h dv/dx` is orientation preserving,
    /// fixed-point steps where it is not, each with a backtracking line search.
    ///
    /// Written as one loop around a single `residual` call: the start point, each
    /// line-search trial and the converged point's determinant are the same call site, as
    /// a state (`mode`) says which one is due. Shader compilers inline every call, so the
    /// kernel's three call sites would be three copies of the Jacobian; the arithmetic and
    /// the order of evaluations are the kernel's.
    pub(super) fn newton(&mut self) {
        self.code.line(
            "// Solves x + h v(x) = y from x = (xa, xb): Newton steps where det(I + h dv/dx) > 0,",
        );
        self.code.line(
            "// fixed-point steps where not; each step backtracks from the same point (full,",
        );
        self.code.line(format!(
            "// half, ..., at most {LINE_SEARCH_HALVINGS} halvings) to the first that shrinks the residual."
        ));
        self.code.line(
            "// One residual call site: mode 0 evaluates the start, 1 a line-search trial, 2 the",
        );
        self.code.line("// converged point.");
        let cond = self.st("Cond");
        let root = self.st("Root");
        let mut ps = vec![(cond, "cond")];
        ps.extend(Self::step_params());
        ps.extend([(T::F, "xa"), (T::F, "xb")]);
        self.fn_open(root.clone(), "newton", true, &ps);
        let zero = self.f(0.0);
        let one = self.f(1.0);
        let tol = self.f(self.newton_tol());
        let decl = self.d.decl(&root, "x", None);
        self.code.line(decl);
        for c in ["a", "b", "det", "va", "vb"] {
            self.code.line(format!("x.{c} = {zero};"));
        }
        self.decl(T::F, "a", "xa");
        self.decl(T::F, "b", "xb");
        // The point the next residual is taken at.
        self.decl(T::F, "pa", "xa");
        self.decl(T::F, "pb", "xb");
        for v in ["d0", "d1", "size", "scale", "norm"] {
            self.decl(T::F, v, &zero);
        }
        // The determinant at (a, b) while a step from it is searched, then at the iterate
        // before (a, b) and the length of the step taken from it (0: (a, b) is the start).
        for v in ["cdet", "pdet", "pstep"] {
            self.decl(T::F, v, &zero);
        }
        self.decl(T::F, "lambda", &one);
        self.decl(T::U, "mode", &self.u(0));
        self.decl(T::U, "it", &self.u(0));
        self.decl(T::U, "ls", &self.u(0));
        let abs = |s: &Self, x: &str| s.math(Math::Abs, x);
        let mx = self.d.math(Math::Max);
        let iters = NEWTON_MAX_ITERS as usize;
        let evaluations = 2 + iters * (LINE_SEARCH_HALVINGS as usize + 1);
        self.for_open("k", &self.u(evaluations));
        let res = self.call(
            "residual",
            true,
            &["cond", "t", "h", "ya", "yb", "pa", "pb"],
        );
        self.decl(self.st("Residual"), "at", &res);
        // mode 2: the converged point's determinant and velocity.
        self.code.open(format!("if (mode == {}) {{", self.u(2)));
        self.code.open(format!("if (at.det > {zero}) {{"));
        self.code.line("x.det = at.det;");
        self.code.line("x.va = at.v0;");
        self.code.line("x.vb = at.v1;");
        self.code.close("}");
        self.code.line("return x;");
        self.code.close("}");
        // mode 1: a line-search trial; halve again, or take the step.
        self.code.open(format!("if (mode == {}) {{", self.u(1)));
        let next = format!("{mx}({}, {})", abs(self, "at.r0"), abs(self, "at.r1"));
        let last = self.u(LINE_SEARCH_HALVINGS as usize);
        self.code
            .open(format!("if (!({next} < norm || ls == {last})) {{"));
        self.code
            .line(format!("lambda = lambda * {};", self.f(0.5)));
        self.code.line(format!("ls = ls + {};", self.u(1)));
        self.step_to("pa", "pb", "lambda * ");
        self.code.line("continue;");
        self.code.close("}");
        self.code.line("pdet = cdet;");
        self.code.line("pstep = lambda * size;");
        self.code.line("a = pa;");
        self.code.line("b = pb;");
        self.code.open(format!(
            "if (lambda * size <= {tol} * scale && at.det > {zero}) {{"
        ));
        self.code
            .line("// The step just taken was below the noise: converged here.");
        self.code.line("x.a = a;");
        self.code.line("x.b = b;");
        self.code.line("x.det = at.det;");
        self.code.line("x.va = at.v0;");
        self.code.line("x.vb = at.v1;");
        self.code.line("return x;");
        self.code.close("}");
        self.code.line(format!("it = it + {};", self.u(1)));
        self.code.open(format!("if (it == {}) {{", self.u(iters)));
        self.code.line("return x;");
        self.code.close("}");
        self.code.close("}");
        // A Newton iteration from (a, b), whose residual is `at`.
        self.code.line("d0 = at.r0;");
        self.code.line("d1 = at.r1;");
        self.code.open(format!("if (at.det > {zero}) {{"));
        self.code.line("// d = (I + h J)^-1 r by the 2x2 adjugate.");
        self.code.line(format!(
            "d0 = (({one} + h * at.j11) * at.r0 - (h * at.j01) * at.r1) / at.det;"
        ));
        self.code.line(format!(
            "d1 = (({one} + h * at.j00) * at.r1 - (h * at.j10) * at.r0) / at.det;"
        ));
        self.code.close("}");
        self.code.line(format!(
            "size = {mx}({}, {});",
            abs(self, "d0"),
            abs(self, "d1")
        ));
        self.code
            .open(format!("if (!{}) {{", self.d.finite("size")));
        self.code.line("return x;");
        self.code.close("}");
        self.code.line(format!(
            "scale = {one} + {mx}({}, {});",
            abs(self, "a"),
            abs(self, "b")
        ));
        self.code.open(format!("if (size <= {tol} * scale) {{"));
        self.code.line(
            "// Converged: the update is below the f32 noise of x + h v(x); det is taken at the",
        );
        self.code.line(
            "// returned point, where the forward pass takes it (at x itself where the update",
        );
        self.code.line(
            "// is about one rounding of x, or where det changes by less than the secant bound",
        );
        self.code.line("// over it).");
        self.step_to("x.a", "x.b", "");
        let reuse = self.f(DET_REUSE_TOL);
        let secant = self.f(DET_SECANT_TOL);
        let change = format!("({} / at.det) * (size / pstep)", abs(self, "at.det - pdet"));
        self.code.line(
            "// det's change over the update, extrapolated from its change over the step before.",
        );
        let flat =
            format!("at.det > {zero} && pdet > {zero} && pstep > {zero} && {change} <= {secant}");
        self.decl(T::B, "det_flat", &flat);
        self.code
            .open(format!("if (size > {reuse} * scale && !det_flat) {{"));
        self.code.line("pa = x.a;");
        self.code.line("pb = x.b;");
        self.code.line(format!("mode = {};", self.u(2)));
        self.code.line("continue;");
        self.code.close("}");
        self.code.open(format!("if (at.det > {zero}) {{"));
        self.code.line("x.det = at.det;");
        self.code.line("x.va = at.v0;");
        self.code.line("x.vb = at.v1;");
        self.code.close("}");
        self.code.line("return x;");
        self.code.close("}");
        self.code.line(format!(
            "norm = {mx}({}, {});",
            abs(self, "at.r0"),
            abs(self, "at.r1")
        ));
        self.code.line("cdet = at.det;");
        self.code.line(format!("lambda = {one};"));
        self.code.line(format!("ls = {};", self.u(0)));
        self.step_to("pa", "pb", "");
        self.code.line(format!("mode = {};", self.u(1)));
        self.code.close("}");
        self.code.line("return x;");
        self.end_fn();
    }

    /// The kernel's `invert_step`: Newton from `y - h v_next` (the velocity where the
    /// trajectory is at the next time), then (rarely needed) from `y - h v(y)`, from one
    /// fixed-point iterate further and from `y - h v(y) / 2`. One loop over the starts
    /// around a single `newton` and a single `velocity` call (see [`Self::newton`]).
    pub(super) fn invert_step(&mut self) {
        self.code.line(
            "// The x with x + h v(x) = y: Newton from y - h (va, vb), the velocity at the next",
        );
        self.code.line(
            "// time; else from y - h v(y), one fixed-point iterate further, y - h v(y) / 2.",
        );
        let cond = self.st("Cond");
        let root = self.st("Root");
        let mut ps = vec![(cond, "cond")];
        ps.extend(Self::step_params());
        ps.extend([(T::F, "va"), (T::F, "vb")]);
        self.fn_open(root.clone(), "invert_step", true, &ps);
        let zero = self.f(0.0);
        let wrap = |s: &Self, x: String| -> String {
            if s.sphere() {
                s.call("wrap", false, &[&x])
            } else {
                x
            }
        };
        self.decl(T::F, "sa", "ya - h * va");
        self.decl(T::F, "sb", &wrap(self, "yb - h * vb".to_owned()));
        // Where the next velocity is taken: y, then the second start.
        self.decl(T::F, "qa", "ya");
        self.decl(T::F, "qb", "yb");
        self.decl(T::F, "vya", &zero);
        self.decl(T::F, "vyb", &zero);
        let decl = self.d.decl(&root, "x", None);
        self.code.line(decl);
        self.for_open("s", &self.u(4));
        self.code
            .open(format!("if (s == {} || s == {}) {{", self.u(1), self.u(2)));
        let v = self.call("velocity", true, &["cond", "t", "qa", "qb"]);
        self.decl(self.st("Vec2"), "v", &v);
        self.code.open(format!("if (s == {}) {{", self.u(1)));
        self.code.line("vya = v.x;");
        self.code.line("vyb = v.y;");
        self.code.close("}");
        self.code.line("sa = ya - h * v.x;");
        let sb = wrap(self, "yb - h * v.y".to_owned());
        self.code.line(format!("sb = {sb};"));
        self.code.line("qa = sa;");
        self.code.line("qb = sb;");
        self.code.close("}");
        self.code.open(format!("if (s == {}) {{", self.u(3)));
        let half = self.f(0.5);
        self.code.line(format!("sa = ya - {half} * h * vya;"));
        let sb = wrap(self, format!("yb - {half} * h * vyb"));
        self.code.line(format!("sb = {sb};"));
        self.code.close("}");
        let n = self.call("newton", true, &["cond", "t", "h", "ya", "yb", "sa", "sb"]);
        self.code.line(format!("x = {n};"));
        self.code.open(format!("if (x.det > {zero}) {{"));
        self.code.line("return x;");
        self.code.close("}");
        self.code.close("}");
        self.code.line("return x;");
        self.end_fn();
    }

    pub(super) fn pdf_impl(&mut self) {
        let zero = self.f(0.0);
        let fail = format!("return {zero};");
        self.code.line(
            "// The PDF of direction (ox, oy, oz): each Euler step inverted exactly by Newton's",
        );
        self.code.line(
            "// method on x + h v(x) = y, starting from y - h v at the next time (the end: t = 1).",
        );
        let ps = [
            (T::F, "wx"),
            (T::F, "wy"),
            (T::F, "wz"),
            (T::F, "ox"),
            (T::F, "oy"),
            (T::F, "oz"),
            (T::U, "steps"),
        ];
        self.fn_open(T::F, "pdf_impl", true, &ps);
        let ut = self.st("Unit");
        let wo = self.call("unit", false, &["ox", "oy", "oz"]);
        self.decl(ut, "wo", &wo);
        self.code.open("if (!wo.ok) {");
        self.code.line(&fail);
        self.code.close("}");
        self.prologue(false, &fail);
        let (ox, oy) = self.direction_in_frame();
        self.point_of_direction(ox, oy, &fail);
        let (fa, fb) = self.flow_point();
        self.start_point(fa, fb);
        self.decl(T::F, "ln_det", &zero);
        let t_end = format!("{} * h", self.d.cast(&T::F, "n"));
        let v_end = self.call("velocity", true, &["cond", &t_end, "a", "b"]);
        self.decl(self.st("Vec2"), "vn", &v_end);
        self.decl(T::F, "va", "vn.x");
        self.decl(T::F, "vb", "vn.y");
        self.for_open("kk", "n");
        self.decl(T::U, "k", "n - 1u - kk");
        let t = format!("{} * h", self.d.cast(&T::F, "k"));
        self.decl(T::F, "t", &t);
        let root = self.call(
            "invert_step",
            true,
            &["cond", "t", "h", "a", "b", "va", "vb"],
        );
        self.decl(self.st("Root"), "x", &root);
        self.code.open(format!("if (!(x.det > {zero})) {{"));
        self.code.line(&fail);
        self.code.close("}");
        self.code.line("a = x.a;");
        self.code.line("b = x.b;");
        self.code.line("va = x.va;");
        self.code.line("vb = x.vb;");
        self.code.line(format!(
            "ln_det = ln_det + {};",
            self.math(Math::Log, "x.det")
        ));
        self.code.close("}");
        if self.warped() {
            self.code.line(
                "// ln |dz/dy| of the warp at the end point joins the steps' sum (docs/math.md, (66)).",
            );
            let end = self.warp_ln_expansion_sum(fa, fb);
            self.code.line(format!("ln_det = ln_det + {end};"));
        }
        let lp = self.call("base_ln_pdf", self.table(), &["cond", "a", "b"]);
        let lm = self.ln_measure("wo.z", "ya");
        self.decl(
            T::F,
            "pdf",
            &self.math(Math::Exp, &format!("{lp} - ln_det + {lm}")),
        );
        self.code.open(format!("if (!{}) {{", self.d.finite("pdf")));
        self.code.line(&fail);
        self.code.close("}");
        self.code.line("return pdf;");
        self.end_fn();
    }
}
