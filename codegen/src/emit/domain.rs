//! Mirrors `src/domain/`: `phi` wrapping (`sphere.rs`), the features the velocity net
//! sees, how a step advances a flow point, the map to a direction and the measure change
//! to solid angle (`mod.rs`, `disk.rs`, `sphere.rs`, `equatorial.rs`).

use super::Emitter;
use crate::dialect::{Math, T};
use diffbsdf::spec::HALF_VECTOR_IDENTITY_SPAN;

impl Emitter<'_> {
    pub(super) fn wrap(&mut self) {
        let tau = core::f32::consts::TAU;
        self.code.line("// phi wrapped into [-pi, pi).");
        self.fn_open(T::F, "wrap", false, &[(T::F, "phi")]);
        let fl = self.math(
            Math::Floor,
            &format!(
                "(phi + {}) * {}",
                self.f(core::f32::consts::PI),
                self.f(1.0 / tau)
            ),
        );
        self.code
            .line(format!("return phi - {} * {fl};", self.f(tau)));
        self.end_fn();
    }

    /// Features of the flow point `(a, b)` as network-type locals `f0..`.
    pub(super) fn features(&mut self) {
        let fa = self.d.to_net("a");
        self.decl(T::N, "f0", &fa);
        if self.sphere() {
            let s = self.d.to_net(&self.math(Math::Sin, "b"));
            let c = self.d.to_net(&self.math(Math::Cos, "b"));
            self.decl(T::N, "f1", &s);
            self.decl(T::N, "f2", &c);
        } else {
            let fb = self.d.to_net("b");
            self.decl(T::N, "f1", &fb);
        }
        let tn = self.d.to_net("t");
        self.decl(T::N, "tn", &tn);
    }

    /// The first layer's tangents `ta`, `tb` for output row `row`: its feature columns
    /// times `d feat / da` = (1, 0[, 0]) and `d feat / db` = (0, 1) on the disk,
    /// (0, cos b, -sin b) on the sphere (the kernel's `features_with_derivative`).
    pub(super) fn feature_tangents(&mut self, row: &str) {
        let wa = self.w(format!("{row} + 0u"));
        self.decl(T::N, "ta", &wa);
        let w1 = self.w(format!("{row} + 1u"));
        if self.sphere() {
            let w2 = self.w(format!("{row} + 2u"));
            // w1 f2 + w2 (-f1): the kernel's chain over the features, fused at its last step
            let mad = self.d.mad(&w2, "(-f1)", &format!("{w1} * f2"));
            self.decl(T::N, "tb", &mad);
        } else {
            self.decl(T::N, "tb", &w1);
        }
    }

    /// `var = var + h * dv` with phi wrapped on the sphere.
    pub(super) fn advance(&self, a: &str, da: &str, b: &str, db: &str) -> Vec<String> {
        let mut v = vec![format!("{a} = {a} + {da};")];
        if self.sphere() {
            v.push(format!(
                "{b} = {};",
                self.call("wrap", false, &[&format!("{b} + {db}")])
            ));
        } else {
            v.push(format!("{b} = {b} + {db};"));
        }
        v
    }

    pub(super) fn start_point(&mut self, a: &str, b: &str) {
        self.decl(T::F, "a", a);
        if self.sphere() {
            let w = self.call("wrap", false, &[b]);
            self.decl(T::F, "b", &w);
        } else {
            self.decl(T::F, "b", b);
        }
    }

    pub(super) fn point_to_direction(&mut self) {
        let rt = self.st("Result");
        self.code.line(
            "// The direction of flow point (a, b) with pdf = 1, or none() outside the domain.",
        );
        let mut params = vec![(T::F, "a"), (T::F, "b")];
        if self.half_vector() {
            params.extend([(T::F, "wx"), (T::F, "wy"), (T::F, "wz")]);
        }
        self.fn_open(rt.clone(), "to_direction", false, &params);
        let r = self.d.decl(&rt, "r", None);
        self.code.line(r);
        let zero = self.f(0.0);
        let one = self.f(1.0);
        let ret_none = format!("return {};", self.call("none", false, &[]));
        if self.sphere() {
            let pi = self.f(core::f32::consts::PI);
            self.decl(T::F, "st", &self.math(Math::Sin, "a"));
            self.code.open(format!(
                "if (!(st > {zero} && a > {zero} && a < {pi} && {})) {{",
                self.d.finite("b")
            ));
            self.code.line(&ret_none);
            self.code.close("}");
            // The equatorial chart is the sphere's about the y axis.
            let (second, third) = if self.equatorial() {
                ("z", "y")
            } else {
                ("y", "z")
            };
            self.code
                .line(format!("r.x = st * {};", self.math(Math::Cos, "b")));
            self.code
                .line(format!("r.{second} = st * {};", self.math(Math::Sin, "b")));
            self.code
                .line(format!("r.{third} = {};", self.math(Math::Cos, "a")));
        } else {
            self.decl(T::F, "r2", "a * a + b * b");
            self.code
                .open(format!("if (!({} && r2 < {one})) {{", self.d.finite("r2")));
            self.code.line(&ret_none);
            self.code.close("}");
            self.decl(T::F, "z", &self.math(Math::Sqrt, &format!("{one} - r2")));
            self.code.open(format!("if (!(z > {zero})) {{"));
            self.code.line(&ret_none);
            self.code.close("}");
            if self.half_vector() {
                // wo = 2 (wi.h) h - wi for the half vector h = (a, b, z).
                self.decl(T::F, "d", "wx * a + wy * b + wz * z");
                self.decl(T::F, "d2", &format!("{} * d", self.f(2.0)));
                self.code.line("r.x = a * d2 - wx;");
                self.code.line("r.y = b * d2 - wy;");
                self.code.line("r.z = z * d2 - wz;");
                self.code
                    .open(format!("if (!(d > {zero} && r.z > {zero})) {{"));
                self.code.line(&ret_none);
                self.code.close("}");
            } else {
                self.code.line("r.x = a;");
                self.code.line("r.y = b;");
                self.code.line("r.z = z;");
            }
        }
        self.code.line(format!("r.pdf = {one};"));
        self.code.line("return r;");
        self.end_fn();
    }

    /// `ln(pdf_w / pdf_x)` at flow point `a` with direction `wo` (in the incident frame):
    /// `-ln sin a` on the sphere, `ln wo.z` on the disk, `ln(s.z / (2 s.s))` with `s = wi +
    /// wo` on the half-vector chart (`src/domain/half_vector.rs`), whose `sx, sy, sz`
    /// [`Emitter::half_vector_sum`] has declared.
    pub(super) fn ln_measure(&self, wo_z: &str, a: &str) -> String {
        if self.sphere() {
            format!("-{}", self.math(Math::Log, &self.math(Math::Sin, a)))
        } else if self.half_vector() {
            self.math(
                Math::Log,
                &format!("sz / ({} * (sx * sx + sy * sy + sz * sz))", self.f(2.0)),
            )
        } else {
            self.math(Math::Log, wo_z)
        }
    }

    /// The half-vector chart: `sx, sy, sz = wi + wo` for `wo` in the incident frame
    /// (`lwx, lwy, lwz` is `wi` there).
    /// The tangent part is computed along `wi`'s azimuth and, where it cancels, from the
    /// unit-vector identity, as the kernel's `half_vector::sum` does (`docs/math.md`, (58)).
    pub(super) fn half_vector_sum(&mut self, ox: &str, oy: &str, oz: &str) {
        self.decl(T::F, "sx", &format!("lwx + {ox}"));
        self.decl(T::F, "sy", &format!("lwy + {oy}"));
        self.decl(T::F, "sz", &format!("lwz + {oz}"));
        let rho = self.math(Math::Sqrt, "lwx * lwx + lwy * lwy");
        self.decl(T::F, "rho", &rho);
        let zero = self.f(0.0);
        self.code.open(format!("if (rho > {zero}) {{"));
        self.decl(T::F, "hc", "lwx / rho");
        self.decl(T::F, "hs", "lwy / rho");
        self.decl(T::F, "ht", &format!("hc * {ox} + hs * {oy}"));
        self.decl(T::F, "hp", &format!("hc * {oy} - hs * {ox}"));
        self.decl(T::F, "st", "rho + ht");
        let span = self.f(HALF_VECTOR_IDENTITY_SPAN);
        self.code
            .open(format!("if (ht < {zero} && rho - ht > {span}) {{"));
        self.code.line(format!(
            "st = (hp * hp + ({oz} * {oz} - lwz * lwz)) / (rho - ht);"
        ));
        self.code.close("}");
        self.code.line("sx = hc * st - hs * hp;");
        self.code.line("sy = hs * st + hc * hp;");
        self.code.close("}");
    }

    /// Arguments of `to_direction`: the flow point, and `wi` in the incident frame on the
    /// half-vector chart.
    pub(super) fn point_args<'s>(&self, a: &'s str, b: &'s str) -> Vec<&'s str> {
        if self.half_vector() {
            vec![a, b, "lwx", "lwy", "lwz"]
        } else {
            vec![a, b]
        }
    }

    /// The chart point of the validated direction `wo` (its `x`, `y` in the incident frame
    /// given as `ox`, `oy`), as locals `ya`, `yb`; `fail` where the domain has no density
    /// there (the kernel's `Domain::point_of`).
    pub(super) fn point_of_direction(&mut self, ox: &str, oy: &str, fail: &str) {
        let zero = self.f(0.0);
        if self.sphere() {
            // The equatorial chart is the sphere's about the y axis.
            let (second, third) = if self.equatorial() {
                ("wo.z", oy)
            } else {
                (oy, "wo.z")
            };
            let rho = self.math(Math::Sqrt, &format!("{ox} * {ox} + {second} * {second}"));
            self.decl(T::F, "rho", &rho);
            self.code.open(format!("if (!(rho > {zero})) {{"));
            self.code.line(fail);
            self.code.close("}");
            self.decl(T::F, "ya", &self.d.atan2("rho", third));
            self.decl(T::F, "yb", &self.d.atan2(second, ox));
        } else if self.half_vector() {
            self.half_vector_point(ox, oy, fail);
        } else {
            self.code.open(format!("if (!(wo.z > {zero})) {{"));
            self.code.line(fail);
            self.code.close("}");
            self.decl(T::F, "ya", ox);
            self.decl(T::F, "yb", oy);
        }
    }

    /// The half-vector chart's flow point of `wo` (in the incident frame), as locals `ya`,
    /// `yb`: `h = (wi + wo) / |wi + wo|` (`src/domain/half_vector.rs`, `from_direction`).
    pub(super) fn half_vector_point(&mut self, ox: &str, oy: &str, fail: &str) {
        let zero = self.f(0.0);
        self.code.open(format!("if (!(wo.z > {zero})) {{"));
        self.code.line(fail);
        self.code.close("}");
        self.half_vector_sum(ox, oy, "wo.z");
        let len = self.math(Math::Sqrt, "sx * sx + sy * sy + sz * sz");
        self.decl(T::F, "slen", &len);
        self.code.open(format!("if (!(slen > {zero})) {{"));
        self.code.line(fail);
        self.code.close("}");
        self.decl(T::F, "sinv", &format!("{} / slen", self.f(1.0)));
        self.code.open(format!("if (!(sz * sinv > {zero})) {{"));
        self.code.line(fail);
        self.code.close("}");
        self.decl(T::F, "ya", "sx * sinv");
        self.decl(T::F, "yb", "sy * sinv");
    }
}
