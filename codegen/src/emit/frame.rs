//! Mirrors `src/frame.rs`: the incident frame of an isotropic model (a rotation) or of a
//! folded one (sign changes), and the turn back of a sample into the world.

use super::Emitter;
use crate::dialect::{Math, T};
use diffbsdf::spec::NORMAL_INCIDENCE_RHO;
use diffbsdf::IncidentFold;

impl Emitter<'_> {
    /// Whether the nets see `wi` in a frame of their own: isotropic or folded models.
    pub(super) fn has_frame(&self) -> bool {
        self.m.def.isotropic || self.m.def.fold != IncidentFold::None
    }

    /// The comment above the `Frame` struct.
    pub(super) fn frame_comment(&self) -> &'static str {
        if self.m.def.isotropic {
            "// A rotation about the normal: cos and sin of its angle."
        } else {
            "// A fold of the incident azimuth: the signs of x (c) and of y (s)."
        }
    }

    /// The frame of `wi` (`fr`'s constructor): for an isotropic model `(c, s) = wi.xy /
    /// |wi.xy|` (the identity at normal incidence), as the kernel's
    /// `IncidentFrame::aligning` computes it; for a folded one the signs of
    /// `IncidentFrame::folding`.
    pub(super) fn frame(&mut self) {
        if !self.m.def.isotropic {
            self.fold_frame();
            return;
        }
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

    /// Folded models: the signs that fold `wi` into the part of the turn the nets learned
    /// (docs/math.md, (83)), `-1` where a coordinate is `>= 0`.
    fn fold_frame(&mut self) {
        let ft = self.st("Frame");
        let quarter = self.m.def.fold == IncidentFold::Quarter;
        self.code.line(if quarter {
            "// Folded model: the signs that mirror wi.x and wi.y to be negative (a material"
        } else {
            "// Folded model: a half turn about the normal where wi.y >= 0 (a material"
        });
        self.code.line(if quarter {
            "// unchanged by either mirror); samples are unfolded by the same signs."
        } else {
            "// unchanged by it); samples are unfolded by the same signs."
        });
        // A half turn reads `y` alone.
        let params: &[(T, &str)] = if quarter {
            &[(T::F, "x"), (T::F, "y")]
        } else {
            &[(T::F, "y")]
        };
        self.fn_open(ft.clone(), "frame", false, params);
        let f = self.d.decl(&ft, "f", None);
        self.code.line(f);
        let (one, minus_one, zero) = (self.f(1.0), self.f(-1.0), self.f(0.0));
        self.code.line(format!("f.c = {one};"));
        self.code.line(format!("f.s = {one};"));
        self.code.open(format!("if (y >= {zero}) {{"));
        self.code.line(format!("f.s = {minus_one};"));
        if !quarter {
            self.code.line(format!("f.c = {minus_one};"));
        }
        self.code.close("}");
        if quarter {
            self.code.open(format!("if (x >= {zero}) {{"));
            self.code.line(format!("f.c = {minus_one};"));
            self.code.close("}");
        }
        self.code.line("return f;");
        self.end_fn();
    }

    /// `(x, y)` of a world vector in the frame `fr`.
    pub(super) fn to_local_xy(&self, x: &str, y: &str) -> (String, String) {
        if self.m.def.isotropic {
            (
                format!("fr.c * {x} + fr.s * {y}"),
                format!("fr.c * {y} - fr.s * {x}"),
            )
        } else {
            (format!("fr.c * {x}"), format!("fr.s * {y}"))
        }
    }

    /// `fr`, the frame of `wi` (the encoding takes `wi` in it).
    pub(super) fn incident_frame(&mut self) {
        let args: &[&str] = if self.m.def.fold == IncidentFold::HalfTurn {
            &["wi.y"]
        } else {
            &["wi.x", "wi.y"]
        };
        let fr = self.call("frame", false, args);
        self.decl(self.st("Frame"), "fr", &fr);
    }

    /// The validated direction `wo` (a `Unit`) in the incident frame: its `x`, `y` as
    /// locals `lox`, `loy` for a model with a frame (`wo.x`, `wo.y` otherwise); `z` is
    /// unchanged by the frame.
    pub(super) fn direction_in_frame(&mut self) -> (&'static str, &'static str) {
        if !self.has_frame() {
            return ("wo.x", "wo.y");
        }
        let (lx, ly) = self.to_local_xy("wo.x", "wo.y");
        self.decl(T::F, "lox", &lx);
        self.decl(T::F, "loy", &ly);
        ("lox", "loy")
    }

    /// Models with a frame: `r.xy` turned back (or unfolded) from the incident frame into
    /// the world.
    pub(super) fn turn_back(&mut self, r: &str) {
        if !self.has_frame() {
            return;
        }
        if !self.m.def.isotropic {
            self.code.line(format!("{r}.x = fr.c * {r}.x;"));
            self.code.line(format!("{r}.y = fr.s * {r}.y;"));
            return;
        }
        self.decl(T::F, "rx", &format!("fr.c * {r}.x - fr.s * {r}.y"));
        self.code
            .line(format!("{r}.y = fr.s * {r}.x + fr.c * {r}.y;"));
        self.code.line(format!("{r}.x = rx;"));
    }
}
