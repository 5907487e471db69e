//! Mirrors `src/base/`: the Gaussian quantile and log-density (`gaussian.rs`), the
//! wrapped Cauchy sample and log-density (`wrapped_cauchy.rs`) and the base distribution
//! `p0(x0 | wi)` of each domain (`mod.rs`).

use super::Emitter;
use crate::dialect::{Math, T};
use diffbsdf::spec::{
    ERFINV_BRANCH_W, ERFINV_CENTRAL, ERFINV_CENTRAL_SHIFT, ERFINV_TAIL, ERFINV_TAIL_SHIFT,
    GAUSSIAN_TAIL_MIN, LN_4PI, LN_INV_SQRT_2PI,
};

impl Emitter<'_> {
    pub(super) fn poly(&mut self, coeffs: &[f32]) {
        self.code.line(format!("p = {};", self.f(coeffs[0])));
        for c in &coeffs[1..] {
            self.code.line(format!("p = {} + p * w;", self.f(*c)));
        }
    }

    pub(super) fn quantile(&mut self) {
        self.code
            .line("// The standard normal quantile Phi^-1(u) = sqrt(2) erfinv(2u - 1), by Giles'");
        self.code
            .line("// single-precision erfinv on the tail probability q = min(u, 1 - u).");
        self.fn_open(T::F, "quantile", false, &[(T::F, "u")]);
        self.decl(T::F, "q", "u");
        let half = self.f(0.5);
        let one = self.f(1.0);
        self.code.open(format!("if (u >= {half}) {{"));
        self.code.line(format!("q = {one} - u;"));
        self.code.close("}");
        let tail = self.f(GAUSSIAN_TAIL_MIN);
        self.code
            .line(format!("q = {};", self.d.clamp("q", &tail, &half)));
        let two = self.f(2.0);
        self.decl(T::F, "x", &format!("{one} - {two} * q"));
        let ln = self.math(Math::Log, &format!("{} * q * ({one} - q)", self.f(4.0)));
        self.decl(T::F, "w", &format!("-{ln}"));
        self.decl(T::F, "p", &self.f(0.0));
        self.code
            .open(format!("if (w < {}) {{", self.f(ERFINV_BRANCH_W)));
        self.code
            .line(format!("w = w - {};", self.f(ERFINV_CENTRAL_SHIFT)));
        self.poly(&ERFINV_CENTRAL);
        self.code.reopen("} else {");
        let sq = self.math(Math::Sqrt, "w");
        self.code
            .line(format!("w = {sq} - {};", self.f(ERFINV_TAIL_SHIFT)));
        self.poly(&ERFINV_TAIL);
        self.code.close("}");
        let s2 = self.f(core::f32::consts::SQRT_2);
        self.decl(T::F, "z", &format!("{s2} * p * x"));
        self.code.open(format!("if (u < {half}) {{"));
        self.code.line("return -z;");
        self.code.close("}");
        self.code.line("return z;");
        self.end_fn();
    }

    pub(super) fn wc_sample(&mut self) {
        self.code
            .line("// Wrapped Cauchy offset for u: 2 atan2(-tanh(gamma/2) cos(pi u), sin(pi u)).");
        self.fn_open(
            T::F,
            "wrapped_cauchy_sample",
            false,
            &[(T::F, "u"), (T::F, "gamma")],
        );
        self.decl(T::F, "a", &format!("{} * u", self.f(core::f32::consts::PI)));
        let th = self.math(Math::Tanh, &format!("{} * gamma", self.f(0.5)));
        let y = format!("-{th} * {}", self.math(Math::Cos, "a"));
        let x = self.math(Math::Sin, "a");
        self.code.line(format!(
            "return {} * {};",
            self.f(2.0),
            self.d.atan2(&y, &x)
        ));
        self.end_fn();
    }

    pub(super) fn wc_ln_pdf(&mut self) {
        self.code.line(
            "// ln of the wrapped Cauchy density at offset d, in its cancellation-free form.",
        );
        self.fn_open(
            T::F,
            "wrapped_cauchy_ln_pdf",
            false,
            &[(T::F, "d"), (T::F, "gamma")],
        );
        let half = self.f(0.5);
        let sh = self.math(Math::Sinh, &format!("{half} * gamma"));
        self.decl(T::F, "sh", &sh);
        let sd = self.math(Math::Sin, &format!("{half} * d"));
        self.decl(T::F, "sd", &sd);
        let a = self.math(Math::Log, &self.math(Math::Sinh, "gamma"));
        let b = self.math(Math::Log, "sh * sh + sd * sd");
        self.code
            .line(format!("return {a} - {} - {b};", self.f(LN_4PI)));
        self.end_fn();
    }

    pub(super) fn base_sample(&mut self) {
        let cond_t = self.st("Cond");
        let vec_t = self.st("Vec2");
        if self.warped() {
            self.code.line(
                "// y0 for u: the standard normal's quantiles, warped (the flow runs in warped standard coordinates).",
            );
        } else if self.standardized() {
            self.code.line(
                "// z0 for u: the standard normal's quantiles (the flow runs in standard coordinates).",
            );
        } else {
            self.code
                .line("// x0 for u: the deterministic map of the base distribution.");
        }
        // In standard coordinates z0 does not depend on wi (no `cond`), unless `u` is
        // drawn through the latent table first.
        let ps = if self.standardized() && !self.table() {
            vec![(T::F, "u0"), (T::F, "u1")]
        } else {
            vec![(cond_t, "cond"), (T::F, "u0"), (T::F, "u1")]
        };
        self.fn_open(vec_t.clone(), "base_sample", self.table(), &ps);
        let r = self.d.decl(&vec_t, "r", None);
        self.code.line(r);
        let (u0, u1) = if self.table() {
            // u through the latent table (docs/math.md, (76)).
            let tu = self.call("table_warp", true, &["cond", "u0", "u1"]);
            self.decl(vec_t.clone(), "tu", &tu);
            ("tu.x", "tu.y")
        } else {
            ("u0", "u1")
        };
        let q0 = self.call("quantile", false, &[u0]);
        if self.sphere() {
            let e1 = self.math(Math::Exp, "cond.p1");
            self.code.line(format!("r.x = cond.p0 + {e1} * {q0};"));
            let g = self.math(Math::Exp, "cond.p3");
            let wc = self.call("wrapped_cauchy_sample", false, &["u1", &g]);
            self.code.line(format!("r.y = cond.p2 + {wc};"));
        } else if self.standardized() {
            // docs/math.md, (59); (63) in warped coordinates.
            let q1 = self.call("quantile", false, &[u1]);
            if self.warped() {
                let (w0, w1) = (
                    self.call("warp_compress", false, &[&q0]),
                    self.call("warp_compress", false, &[&q1]),
                );
                self.code.line(format!("r.x = {w0};"));
                self.code.line(format!("r.y = {w1};"));
            } else {
                self.code.line(format!("r.x = {q0};"));
                self.code.line(format!("r.y = {q1};"));
            }
        } else {
            let q1 = self.call("quantile", false, &["u1"]);
            let e2 = self.math(Math::Exp, "cond.p2");
            let e3 = self.math(Math::Exp, "cond.p3");
            self.code.line(format!("r.x = cond.p0 + {e2} * {q0};"));
            self.code.line(format!("r.y = cond.p1 + {e3} * {q1};"));
        }
        self.code.line("return r;");
        self.end_fn();
    }

    /// The arguments of a `base_sample` call.
    pub(super) fn base_sample_call(&self) -> String {
        if self.table() {
            self.call("base_sample", true, &["cond", "u0", "u1"])
        } else if self.standardized() {
            self.call("base_sample", false, &["u0", "u1"])
        } else {
            self.call("base_sample", false, &["cond", "u0", "u1"])
        }
    }

    /// Turns the flow's end point `(a, b)` into the chart point `mu + sigma z` in standard
    /// coordinates (docs/math.md, (61)); nothing otherwise.
    pub(super) fn chart_point(&mut self) {
        if !self.standardized() {
            return;
        }
        self.code
            .line("// The end point in chart coordinates: x = mu + sigma z (docs/math.md, (61)).");
        let e2 = self.math(Math::Exp, "cond.p2");
        let e3 = self.math(Math::Exp, "cond.p3");
        let (za, zb) = if self.warped() {
            // z of the warped end point (docs/math.md, (64)).
            (
                self.call("warp_expand", false, &["a"]),
                self.call("warp_expand", false, &["b"]),
            )
        } else {
            ("a".to_string(), "b".to_string())
        };
        self.code.line(format!("a = cond.p0 + {e2} * {za};"));
        self.code.line(format!("b = cond.p1 + {e3} * {zb};"));
    }

    /// The flow's end point for the chart point `(ya, yb)`: `(x - mu) / sigma` in standard
    /// coordinates (docs/math.md, (62)), the point itself otherwise.
    pub(super) fn flow_point(&mut self) -> (&'static str, &'static str) {
        if !self.standardized() {
            return ("ya", "yb");
        }
        let e2 = self.math(Math::Exp, "-cond.p2");
        let e3 = self.math(Math::Exp, "-cond.p3");
        let (za, zb) = (
            format!("(ya - cond.p0) * {e2}"),
            format!("(yb - cond.p1) * {e3}"),
        );
        if self.warped() {
            // The warped end point (docs/math.md, (63)).
            self.decl(T::F, "za", &self.call("warp_compress", false, &[&za]));
            self.decl(T::F, "zb", &self.call("warp_compress", false, &[&zb]));
        } else {
            self.decl(T::F, "za", &za);
            self.decl(T::F, "zb", &zb);
        }
        ("za", "zb")
    }

    pub(super) fn base_ln_pdf(&mut self) {
        let cond_t = self.st("Cond");
        self.code.line("// ln p0(x0) in flow coordinates.");
        let ps = [(cond_t, "cond"), (T::F, "x0"), (T::F, "x1")];
        self.fn_open(T::F, "base_ln_pdf", self.table(), &ps);
        let c = self.f(LN_INV_SQRT_2PI);
        let mh = self.f(-0.5);
        if self.sphere() {
            let e = self.math(Math::Exp, "-cond.p1");
            self.decl(T::F, "z", &format!("(x0 - cond.p0) * {e}"));
            let g = self.math(Math::Exp, "cond.p3");
            let wc = self.call("wrapped_cauchy_ln_pdf", false, &["x1 - cond.p2", &g]);
            self.code
                .line(format!("return {mh} * z * z + {c} - cond.p1 + {wc};"));
        } else {
            if self.warped() {
                // z0 of the warped start point (docs/math.md, (64)).
                self.decl(T::F, "z0", &self.call("warp_expand", false, &["x0"]));
                self.decl(T::F, "z1", &self.call("warp_expand", false, &["x1"]));
            } else if self.standardized() {
                // The start point is z0 already (docs/math.md, (60)).
                self.decl(T::F, "z0", "x0");
                self.decl(T::F, "z1", "x1");
            } else {
                let e0 = self.math(Math::Exp, "-cond.p2");
                let e1 = self.math(Math::Exp, "-cond.p3");
                self.decl(T::F, "z0", &format!("(x0 - cond.p0) * {e0}"));
                self.decl(T::F, "z1", &format!("(x1 - cond.p1) * {e1}"));
            }
            // Plus ln |dz/dy| at the start point in warped coordinates (docs/math.md, (66)).
            let warp = if self.warped() {
                format!(" + {}", self.warp_ln_expansion_sum("x0", "x1"))
            } else {
                String::new()
            };
            // Plus ln of the latent table's density at Phi(z0) (docs/math.md, (77)).
            let table = if self.table() {
                let (p0, p1) = (
                    self.call("normal_cdf", false, &["z0"]),
                    self.call("normal_cdf", false, &["z1"]),
                );
                format!(
                    " + {}",
                    self.call("table_ln_density", true, &["cond", &p0, &p1])
                )
            } else {
                String::new()
            };
            self.code.line(format!(
                "return ({mh} * z0 * z0 + {c}) + ({mh} * z1 * z1 + {c}) - cond.p2 - cond.p3{warp}{table};"
            ));
        }
        self.end_fn();
    }
}
