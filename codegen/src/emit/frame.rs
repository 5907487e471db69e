//! Mirrors `src/frame.rs`: the incident frame of an isotropic model and the turn back of
//! a sample into the world.

use super::Emitter;
use crate::dialect::{Math, T};
use diffbsdf::spec::NORMAL_INCIDENCE_RHO;

impl Emitter<'_> {
    /// Isotropic models: the frame of `wi`, `(c, s) = wi.xy / |wi.xy|` (the identity at
    /// normal incidence), as the kernel's `IncidentFrame::aligning` computes it.
    pub(super) fn frame(&mut self) {
        let ft = self.st("Frame");
        self.code.line(
            "// Isotropic model: the rotation about the normal that turns wi into the xz-plane",
        );
        self.code.line(
            "// (phi_i = 0); samples are turned back by it. The identity at normal incidence.",
        );
        self.fn_open(ft.clone(), "frame", false, &[(T::F, "x"), (T::F, "y")]);
        let f = self.d.decl(&ft, "f", None);
        self.code.line(f);
        self.code.line(format!("f.c = {};", self.f(1.0)));
        self.code.line(format!("f.s = {};", self.f(0.0)));
        self.decl(T::F, "rho", &self.math(Math::Sqrt, "x * x + y * y"));
        self.code
            .open(format!("if (rho > {}) {{", self.f(NORMAL_INCIDENCE_RHO)));
        self.decl(T::F, "inv", &format!("{} / rho", self.f(1.0)));
        self.code.line("f.c = x * inv;");
        self.code.line("f.s = y * inv;");
        self.code.close("}");
        self.code.line("return f;");
        self.end_fn();
    }

    /// Isotropic models: `fr`, the frame of `wi` (the encoding takes `wi` turned into it).
    pub(super) fn incident_frame(&mut self) {
        let fr = self.call("frame", false, &["wi.x", "wi.y"]);
        self.decl(self.st("Frame"), "fr", &fr);
    }

    /// The validated direction `wo` (a `Unit`) in the incident frame: its `x`, `y` as
    /// locals `lox`, `loy` for an isotropic model (`wo.x`, `wo.y` otherwise); `z` is
    /// unchanged by the frame.
    pub(super) fn direction_in_frame(&mut self) -> (&'static str, &'static str) {
        if !self.m.def.isotropic {
            return ("wo.x", "wo.y");
        }
        self.decl(T::F, "lox", "fr.c * wo.x + fr.s * wo.y");
        self.decl(T::F, "loy", "fr.c * wo.y - fr.s * wo.x");
        ("lox", "loy")
    }

    /// Isotropic models: `r.xy` turned back from the incident frame into the world.
    pub(super) fn turn_back(&mut self, r: &str) {
        if !self.m.def.isotropic {
            return;
        }
        self.decl(T::F, "rx", &format!("fr.c * {r}.x - fr.s * {r}.y"));
        self.code
            .line(format!("{r}.y = fr.s * {r}.x + fr.c * {r}.y;"));
        self.code.line(format!("{r}.x = rx;"));
    }
}
