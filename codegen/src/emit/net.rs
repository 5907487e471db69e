//! Mirrors `src/net/`: SiLU (`activation.rs`), the `wi` encoding (`encoding.rs`), the
//! dense layers (`dense.rs`), the base net (`base_net.rs`) and the velocity net with its
//! hand-derived Jacobian (`velocity_net.rs`), and the conditioning on `wi` that
//! `src/flow/mod.rs` does once per call.

use super::Emitter;
use crate::desc::Layer;
use crate::dialect::{Math, T};
use diffbsdf::spec::{
    ENCODING_PER_FREQ, ENCODING_RAW, EXP_ARG_LIMIT_F16, EXP_ARG_MAX, EXP_ARG_MIN, LN_SCALE_MAX,
    LN_SCALE_MIN, VELOCITY_OUTPUTS,
};

/// The readout is written out for `v = (v0, v1)` (the `Vec2` and `Jac` of the generated
/// code).
const _: () = assert!(VELOCITY_OUTPUTS == 2);

impl Emitter<'_> {
    pub(super) fn sigmoid(&mut self) {
        // The kernel's exp_poly clamps its argument to [EXP_ARG_MIN, EXP_ARG_MAX]; f16
        // clamps where e^x still fits (EXP_ARG_LIMIT_F16).
        let (lo, hi) = if self.d.half() {
            (-EXP_ARG_LIMIT_F16, EXP_ARG_LIMIT_F16)
        } else {
            (EXP_ARG_MIN, EXP_ARG_MAX)
        };
        self.code
            .line("// sigmoid(z) = 1 / (1 + e^-z); silu(z) = z sigmoid(z).");
        self.fn_open(T::N, "sigmoid", false, &[(T::N, "z")]);
        let e = self.math(Math::Exp, &self.d.clamp("-z", &self.nl(lo), &self.nl(hi)));
        let one = self.nl(1.0);
        self.code.line(format!("return {one} / ({one} + {e});"));
        self.end_fn();
    }

    pub(super) fn encode(&mut self) {
        let freqs = self.m.def.velocity.freqs as usize;
        self.code
            .line("// [wi, sin(pi wi), cos(pi wi), sin(2 pi wi), cos(2 pi wi), ...]: higher");
        self.code
            .line("// frequencies by the double-angle formulas, as the kernel and the trainer do.");
        let enc = self.st("Enc");
        self.fn_open(
            enc.clone(),
            "encode",
            false,
            &[(T::F, "w0"), (T::F, "w1"), (T::F, "w2")],
        );
        let r = self.d.decl(&enc, "r", None);
        self.code.line(r);
        // One sine and one cosine per axis and frequency.
        const AXES: usize = ENCODING_RAW;
        const _: () = assert!(ENCODING_PER_FREQ == 2 * AXES);
        let pi = self.f(core::f32::consts::PI);
        for a in 0..AXES {
            let s = self.math(Math::Sin, &format!("{pi} * w{a}"));
            self.decl(T::F, &format!("s{a}"), &s);
            let c = self.math(Math::Cos, &format!("{pi} * w{a}"));
            self.decl(T::F, &format!("c{a}"), &c);
        }
        for a in 0..AXES {
            self.code.line(format!("r.e[{a}] = w{a};"));
        }
        if freqs > 0 {
            self.for_open("k", &self.u(freqs));
            let at = format!(
                "{} + {} * k",
                self.u(ENCODING_RAW),
                self.u(ENCODING_PER_FREQ)
            );
            self.decl(T::U, "at", &at);
            for a in 0..AXES {
                self.code.line(format!("r.e[at + {a}u] = s{a};"));
                self.code.line(format!("r.e[at + {}u] = c{a};", a + AXES));
            }
            let (two, one) = (self.f(2.0), self.f(1.0));
            for a in 0..AXES {
                self.decl(T::F, &format!("t{a}"), &format!("s{a}"));
                self.code.line(format!("s{a} = {two} * t{a} * c{a};"));
                self.code
                    .line(format!("c{a} = {one} - {two} * t{a} * t{a};"));
            }
            self.code.close("}");
        }
        self.code.line("return r;");
        self.end_fn();
    }

    /// `out[o] = act(b[o] + sum_i W[o][i] in[i])` for a hidden layer.
    pub(super) fn hidden(&mut self, l: Layer, input: &str, in_is_f: bool, out: &str) {
        self.code.line(format!(
            "// {} -> {}: weights at {}, biases at {}",
            l.inputs, l.outputs, l.w, l.b
        ));
        self.arr(T::N, l.outputs, out);
        self.for_open("o", &self.u(l.outputs));
        let b = self.w(format!("{}u + o", l.b));
        self.decl(T::N, "z", &b);
        self.for_open("i", &self.u(l.inputs));
        let w = self.w(format!("{}u + o * {}u + i", l.w, l.inputs));
        let x = if in_is_f {
            self.d.to_net(&format!("{input}[i]"))
        } else {
            format!("{input}[i]")
        };
        let mad = self.d.mad(&w, &x, "z");
        self.code.line(format!("z = {mad};"));
        self.code.close("}");
        let sg = self.call("sigmoid", false, &["z"]);
        self.code.line(format!("{out}[o] = z * {sg};"));
        self.code.close("}");
    }

    pub(super) fn condition(&mut self) {
        let m = self.m;
        let enc_t = self.st("Enc");
        let cond_t = self.st("Cond");
        self.code.line(
            "// The base net (parameters of p0) and the velocity net's wi part: once per call.",
        );
        self.fn_open(cond_t.clone(), "condition", true, &[(enc_t, "enc")]);
        let r = self.d.decl(&cond_t, "r", None);
        self.code.line(r);
        let n = m.base.len();
        let mut input = "enc.e".to_string();
        for (k, l) in m.base[..n - 1].iter().enumerate() {
            let out = format!("h{k}");
            self.hidden(*l, &input, k == 0, &out);
            input = out;
        }
        let ro = m.base[n - 1];
        self.code.line(format!(
            "// readout {} -> {}: weights at {}, biases at {}",
            ro.inputs, ro.outputs, ro.w, ro.b
        ));
        self.arr(T::F, ro.outputs, "outv");
        self.for_open("o", &self.u(ro.outputs));
        let b = self.w(format!("{}u + o", ro.b));
        self.decl(T::N, "z", &b);
        self.for_open("i", &self.u(ro.inputs));
        let w = self.w(format!("{}u + o * {}u + i", ro.w, ro.inputs));
        let mad = self.d.mad(&w, &format!("{input}[i]"), "z");
        self.code.line(format!("z = {mad};"));
        self.code.close("}");
        self.code.line(format!("outv[o] = {};", self.d.to_f32("z")));
        self.code.close("}");
        // The log-scales among the outputs, clamped as the kernel's `BaseDist::from_net`
        // does: (mu_theta, ln sigma, mu_phi, ln gamma) on the sphere, (mu, ln sigma) on the
        // disk.
        let (lo, hi) = (self.f(LN_SCALE_MIN), self.f(LN_SCALE_MAX));
        let scales: &[usize] = if self.sphere() { &[1, 3] } else { &[2, 3] };
        for k in 0..ro.outputs {
            let v = format!("outv[{k}]");
            let v = if scales.contains(&k) {
                self.d.clamp(&v, &lo, &hi)
            } else {
                v
            };
            self.code.line(format!("r.p{k} = {v};"));
        }
        if self.table() {
            self.table_slices();
        }
        let v0 = m.velocity[0];
        let skip = m.features() + 1;
        self.code.line(format!(
            "// velocity layer 1, wi columns {}.. and bias: weights at {}, biases at {}",
            skip, v0.w, v0.b
        ));
        self.for_open("o", &self.u(v0.outputs));
        let b = self.w(format!("{}u + o", v0.b));
        self.decl(T::N, "z", &b);
        self.for_open("i", &self.u(m.encoding_len()));
        let w = self.w(format!("{}u + o * {}u + {}u + i", v0.w, v0.inputs, skip));
        let x = self.d.to_net("enc.e[i]");
        let mad = self.d.mad(&w, &x, "z");
        self.code.line(format!("z = {mad};"));
        self.code.close("}");
        self.code.line("r.c[o] = z;");
        self.code.close("}");
        self.code.line("return r;");
        self.end_fn();
    }

    /// First-layer pre-activation `z` for output `o`: `c + w_t t + sum_f w_f f`.
    pub(super) fn first_z(&mut self) {
        let v0 = self.m.velocity[0];
        let feats = self.m.features();
        let row = format!("{}u + o * {}u", v0.w, v0.inputs);
        let wt = self.w(format!("{row} + {feats}u"));
        let mad = self.d.mad(&wt, "tn", "cond.c[o]");
        self.decl(T::N, "z", &mad);
        for f in 0..feats {
            let wf = self.w(format!("{row} + {f}u"));
            let mad = self.d.mad(&wf, &format!("f{f}"), "z");
            self.code.line(format!("z = {mad};"));
        }
    }

    pub(super) fn velocity(&mut self) {
        let m = self.m;
        let v0 = m.velocity[0];
        let cond_t = self.st("Cond");
        let vec_t = self.st("Vec2");
        self.code
            .line("// v(x, t, wi) at the flow point (a, b), without its Jacobian.");
        let ps = [(cond_t, "cond"), (T::F, "t"), (T::F, "a"), (T::F, "b")];
        self.fn_open(vec_t.clone(), "velocity", true, &ps);
        self.features();
        self.arr(T::N, v0.outputs, "h0");
        self.for_open("o", &self.u(v0.outputs));
        self.first_z();
        let sg = self.call("sigmoid", false, &["z"]);
        self.code.line(format!("h0[o] = z * {sg};"));
        self.code.close("}");
        let n = m.velocity.len();
        let mut input = "h0".to_string();
        for (k, l) in m.velocity[1..n - 1].iter().enumerate() {
            let out = format!("h{}", k + 1);
            self.hidden(*l, &input, false, &out);
            input = out;
        }
        let ro = m.velocity[n - 1];
        self.code.line(format!(
            "// readout {} -> {}: weights at {}, biases at {}",
            ro.inputs, ro.outputs, ro.w, ro.b
        ));
        let (b0, b1) = (
            self.w(format!("{}u", ro.b)),
            self.w(format!("{}u", ro.b + 1)),
        );
        self.decl(T::N, "v0", &b0);
        self.decl(T::N, "v1", &b1);
        self.for_open("i", &self.u(ro.inputs));
        let w0 = self.w(format!("{}u + i", ro.w));
        let w1 = self.w(format!("{}u + i", ro.w + ro.inputs));
        let x = format!("{input}[i]");
        let (m0, m1) = (self.d.mad(&w0, &x, "v0"), self.d.mad(&w1, &x, "v1"));
        self.code.line(format!("v0 = {m0};"));
        self.code.line(format!("v1 = {m1};"));
        self.code.close("}");
        let r = self.d.decl(&vec_t, "r", None);
        self.code.line(r);
        self.code.line(format!("r.x = {};", self.d.to_f32("v0")));
        self.code.line(format!("r.y = {};", self.d.to_f32("v1")));
        self.code.line("return r;");
        self.end_fn();
    }

    pub(super) fn velocity_jacobian(&mut self) {
        let m = self.m;
        let v0 = m.velocity[0];
        let cond_t = self.st("Cond");
        let jac_t = self.st("Jac");
        self.code
            .line("// v and dv/dx by forward-mode differentiation: tangents da (along a) and db");
        self.code
            .line("// (along b) go through every layer, scaled by silu'(z) = s (1 + z (1 - s)).");
        let ps = [(cond_t, "cond"), (T::F, "t"), (T::F, "a"), (T::F, "b")];
        self.fn_open(jac_t.clone(), "velocity_jacobian", true, &ps);
        self.features();
        let w = v0.outputs;
        self.arr(T::N, w, "h0");
        self.arr(T::N, w, "da0");
        self.arr(T::N, w, "db0");
        self.for_open("o", &self.u(w));
        self.first_z();
        let row = format!("{}u + o * {}u", v0.w, v0.inputs);
        self.feature_tangents(&row);
        self.slope_store("0", "ta", "tb");
        self.code.close("}");
        let n = m.velocity.len();
        let mut k_in = 0;
        for (k, l) in m.velocity[1..n - 1].iter().enumerate() {
            let k_out = k + 1;
            self.code.line(format!(
                "// {} -> {}: weights at {}, biases at {}",
                l.inputs, l.outputs, l.w, l.b
            ));
            self.arr(T::N, l.outputs, &format!("h{k_out}"));
            self.arr(T::N, l.outputs, &format!("da{k_out}"));
            self.arr(T::N, l.outputs, &format!("db{k_out}"));
            self.for_open("o", &self.u(l.outputs));
            let b = self.w(format!("{}u + o", l.b));
            self.decl(T::N, "z", &b);
            let zero = self.nl(0.0);
            self.decl(T::N, "ta", &zero);
            self.decl(T::N, "tb", &zero);
            self.for_open("i", &self.u(l.inputs));
            let wi = self.w(format!("{}u + o * {}u + i", l.w, l.inputs));
            self.decl(T::N, "w", &wi);
            for (acc, input) in [("z", "h"), ("ta", "da"), ("tb", "db")] {
                let mad = self.d.mad("w", &format!("{input}{k_in}[i]"), acc);
                self.code.line(format!("{acc} = {mad};"));
            }
            self.code.close("}");
            self.slope_store(&k_out.to_string(), "ta", "tb");
            self.code.close("}");
            k_in = k_out;
        }
        let ro = m.velocity[n - 1];
        self.code.line(format!(
            "// readout {} -> {}: weights at {}, biases at {}",
            ro.inputs, ro.outputs, ro.w, ro.b
        ));
        let (b0, b1) = (
            self.w(format!("{}u", ro.b)),
            self.w(format!("{}u", ro.b + 1)),
        );
        self.decl(T::N, "v0", &b0);
        self.decl(T::N, "v1", &b1);
        let zero = self.nl(0.0);
        for j in ["j00", "j01", "j10", "j11"] {
            self.decl(T::N, j, &zero);
        }
        self.for_open("i", &self.u(ro.inputs));
        let w0 = self.w(format!("{}u + i", ro.w));
        let w1 = self.w(format!("{}u + i", ro.w + ro.inputs));
        self.decl(T::N, "w0", &w0);
        self.decl(T::N, "w1", &w1);
        let k = k_in;
        for (acc, w, input) in [
            ("v0", "w0", "h"),
            ("v1", "w1", "h"),
            ("j00", "w0", "da"),
            ("j01", "w0", "db"),
            ("j10", "w1", "da"),
            ("j11", "w1", "db"),
        ] {
            let mad = self.d.mad(w, &format!("{input}{k}[i]"), acc);
            self.code.line(format!("{acc} = {mad};"));
        }
        self.code.close("}");
        let r = self.d.decl(&jac_t, "r", None);
        self.code.line(r);
        for f in ["v0", "v1", "j00", "j01", "j10", "j11"] {
            self.code.line(format!("r.{f} = {};", self.d.to_f32(f)));
        }
        self.code.line("return r;");
        self.end_fn();
    }

    /// `h[o] = silu(z)`, tangents scaled by `silu'(z)`.
    pub(super) fn slope_store(&mut self, k: &str, ta: &str, tb: &str) {
        let sg = self.call("sigmoid", false, &["z"]);
        self.decl(T::N, "s", &sg);
        let one = self.nl(1.0);
        self.decl(T::N, "g", &format!("s * ({one} + z * ({one} - s))"));
        self.code.line(format!("h{k}[o] = z * s;"));
        self.code.line(format!("da{k}[o] = {ta} * g;"));
        self.code.line(format!("db{k}[o] = {tb} * g;"));
    }
}
