//! Mirrors `src/base/warp.rs`: the compressive warp `y = K asinh(z / K)` of the standard
//! coordinates (docs/math.md, §6.4), written with `exp`, `log`, `sqrt` and `abs` in the
//! kernel's operation order, so every language evaluates the same expressions.

use super::Emitter;
use crate::dialect::{Math, T};
use diffbsdf::spec::STANDARD_WARP_K;

impl Emitter<'_> {
    /// `y = sign(z) K ln(a + sqrt(a^2 + 1))`, `a = |z| / K` (docs/math.md, (63)).
    pub(super) fn warp_compress(&mut self) {
        self.code
            .line("// y = K asinh(z / K), the warp of a standard coordinate (docs/math.md, (63)).");
        self.fn_open(T::F, "warp_compress", false, &[(T::F, "z")]);
        let k = self.f(STANDARD_WARP_K);
        self.decl(T::F, "a", &format!("{} / {k}", self.math(Math::Abs, "z")));
        let root = self.math(Math::Sqrt, &format!("a * a + {}", self.f(1.0)));
        let ln = self.math(Math::Log, &format!("a + {root}"));
        self.decl(T::F, "y", &format!("{k} * {ln}"));
        self.code.open(format!("if (z < {}) {{", self.f(0.0)));
        self.code.line("return -y;");
        self.code.close("}");
        self.code.line("return y;");
        self.end_fn();
    }

    /// `z = K (e^(y/K) - e^(-y/K)) / 2` (docs/math.md, (64)).
    pub(super) fn warp_expand(&mut self) {
        self.code.line(
            "// z = K sinh(y / K), the standard coordinate of a warped one (docs/math.md, (64)).",
        );
        self.fn_open(T::F, "warp_expand", false, &[(T::F, "y")]);
        let k = self.f(STANDARD_WARP_K);
        self.decl(T::F, "s", &format!("y / {k}"));
        let (ep, em) = (self.math(Math::Exp, "s"), self.math(Math::Exp, "-s"));
        self.code
            .line(format!("return {k} * ({} * ({ep} - {em}));", self.f(0.5)));
        self.end_fn();
    }

    /// `ln cosh(y / K) = a + ln(1/2 + e^(-2a)/2)`, `a = |y| / K` (docs/math.md, (65)).
    pub(super) fn warp_ln_expansion(&mut self) {
        self.code
            .line("// ln |dz/dy| = ln cosh(y / K), free of overflow (docs/math.md, (65)).");
        self.fn_open(T::F, "warp_ln_expansion", false, &[(T::F, "y")]);
        let k = self.f(STANDARD_WARP_K);
        self.decl(T::F, "a", &format!("{} / {k}", self.math(Math::Abs, "y")));
        let half = self.f(0.5);
        let e = self.math(Math::Exp, &format!("{} * a", self.f(-2.0)));
        let ln = self.math(Math::Log, &format!("{half} + {half} * {e}"));
        self.code.line(format!("return a + {ln};"));
        self.end_fn();
    }

    /// `(ln_expansion(a) + ln_expansion(b))`, the warp's term of a point's log-density.
    pub(super) fn warp_ln_expansion_sum(&self, a: &str, b: &str) -> String {
        format!(
            "({} + {})",
            self.call("warp_ln_expansion", false, &[a]),
            self.call("warp_ln_expansion", false, &[b])
        )
    }
}
