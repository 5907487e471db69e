//! Mirrors `src/input.rs` (unit directions, `u` in `[0, 1]^2`) and the shared start of
//! every entry point in `src/sampler.rs` (steps, incident frame, conditioning).

use super::Emitter;
use crate::dialect::{Math, T};
use diffbsdf::spec::{self, UNIT_TOLERANCE};

impl Emitter<'_> {
    pub(super) fn unit(&mut self) {
        let ut = self.st("Unit");
        self.code.line(format!(
            "// w normalised if finite and | |w|^2 - 1 | <= {}, else ok = false.",
            UNIT_TOLERANCE
        ));
        self.fn_open(
            ut.clone(),
            "unit",
            false,
            &[(T::F, "x"), (T::F, "y"), (T::F, "z")],
        );
        let r = self.d.decl(&ut, "r", None);
        self.code.line(r);
        self.decl(T::F, "l2", "x * x + y * y + z * z");
        let fin = self.d.finite("l2");
        let abs = self.math(Math::Abs, &format!("l2 - {}", self.f(1.0)));
        let tol = self.f(UNIT_TOLERANCE);
        self.code.line(format!("r.ok = {fin} && {abs} <= {tol};"));
        let s = format!("{} / {}", self.f(1.0), self.math(Math::Sqrt, "l2"));
        self.decl(T::F, "s", &s);
        self.code.line("r.x = x * s;");
        self.code.line("r.y = y * s;");
        self.code.line("r.z = z * s;");
        self.code.line("return r;");
        self.end_fn();
    }

    /// Shared prologue of the entry points: checks `wi` (and `u`), steps, conditions.
    pub(super) fn prologue(&mut self, with_u: bool, fail: &str) {
        let ut = self.st("Unit");
        let inc = self.call("unit", false, &["wx", "wy", "wz"]);
        self.decl(ut, "wi", &inc);
        let mut ok = "wi.ok".to_string();
        // The model's declared incident range (always the upper hemisphere on the disk).
        if !self.m.def.accepts_incident_z(-1.0) {
            ok.push_str(&format!(" && wi.z >= {}", self.f(0.0)));
        }
        if with_u {
            let (z, o) = (self.f(0.0), self.f(1.0));
            for u in ["u0", "u1"] {
                ok.push_str(&format!(
                    " && {} && {u} >= {z} && {u} <= {o}",
                    self.d.finite(u)
                ));
            }
        }
        self.code.open(format!("if (!({ok})) {{"));
        self.code.line(fail);
        self.code.close("}");
        // steps = DEFAULT_STEPS: the model's default; above MAX_STEPS: no sample.
        self.decl(T::U, "n", "steps");
        let default = self.u(spec::DEFAULT_STEPS as usize);
        self.code.open(format!("if (n == {default}) {{"));
        self.code
            .line(format!("n = {}u;", self.m.def.default_steps));
        self.code.close("}");
        let max = self.u(spec::MAX_STEPS as usize);
        self.code.open(format!("if (n > {max}) {{"));
        self.code.line(fail);
        self.code.close("}");
        self.decl(
            T::F,
            "h",
            &format!("{} / {}", self.f(1.0), self.d.cast(&T::F, "n")),
        );
        let enc = if self.has_frame() {
            self.incident_frame();
            let (lx, ly) = self.to_local_xy("wi.x", "wi.y");
            self.call("encode", false, &[&lx, &ly, "wi.z"])
        } else {
            self.call("encode", false, &["wi.x", "wi.y", "wi.z"])
        };
        let cond = self.call("condition", true, &[&enc]);
        self.decl(self.st("Cond"), "cond", &cond);
        if self.half_vector() {
            // wi in the incident frame: the half-vector chart reflects it.
            self.local_incident();
        }
    }

    /// `lwx, lwy, lwz`: `wi` in the incident frame (the world's for an anisotropic model
    /// without a fold).
    fn local_incident(&mut self) {
        if self.has_frame() {
            let (lx, ly) = self.to_local_xy("wi.x", "wi.y");
            self.decl(T::F, "lwx", &lx);
            self.decl(T::F, "lwy", &ly);
        } else {
            self.decl(T::F, "lwx", "wi.x");
            self.decl(T::F, "lwy", "wi.y");
        }
        self.decl(T::F, "lwz", "wi.z");
    }
}
