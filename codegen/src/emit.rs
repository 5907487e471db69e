//! The sampling algorithm, written once over a [`Dialect`]: the `wi` encoding, the two
//! MLPs (with forward-mode Jacobians), the base distributions, the Euler flow, its exact
//! Newton inverse and the input checks, mirroring the kernel step for step (same
//! operation order, same constants) so that every language agrees with it to rounding.

use crate::desc::{Layer, ModelDesc};
use crate::dialect::{Dialect, Math, T};
use crate::{code::Code, EntryPoints};
use diffbsdf::Domain;

/// Coefficients of Giles' single-precision erfinv, central branch (`w < 5`), highest
/// degree first, exactly as in the kernel's `base::gaussian::quantile`.
const ERFINV_CENTRAL: [f32; 9] = [
    2.810_226_4e-8,
    3.432_739_4e-7,
    -3.523_387_7e-6,
    -4.391_506_5e-6,
    2.185_808_7e-4,
    -1.253_725e-3,
    -4.177_681_6e-3,
    0.246_640_73,
    1.501_409_4,
];
/// The tail branch (`w >= 5`, in `sqrt(w) - 3`).
const ERFINV_TAIL: [f32; 9] = [
    -2.002_142_6e-4,
    1.009_505_6e-4,
    1.349_343_2e-3,
    -3.673_428_4e-3,
    5.739_507_7e-3,
    -7.622_461_3e-3,
    9.438_870_5e-3,
    1.001_674,
    2.832_976_8,
];
/// `ln(1 / sqrt(2 pi))`.
const LN_INV_SQRT_2PI: f32 = -0.918_938_5;
/// `ln(4 pi)`.
const LN_4PI: f32 = 2.531_024_3;
/// Newton tolerance of the f16 inverse: the f16 velocity is a step function of `x` at
/// about 1e-3 of its size, so the kernel's 1e-6 cannot be reached (docs/codegen.md).
const NEWTON_TOL_F16: f32 = 2e-3;

/// Writes the helper functions and the `*_impl` functions the entry points need.
pub struct Emitter<'a> {
    d: &'a dyn Dialect,
    m: &'a ModelDesc,
    e: EntryPoints,
    pub code: Code,
}

impl<'a> Emitter<'a> {
    pub fn new(d: &'a dyn Dialect, m: &'a ModelDesc, e: EntryPoints) -> Self {
        Emitter {
            d,
            m,
            e,
            code: Code::new(),
        }
    }

    fn p(&self, name: &str) -> String {
        format!("{}_{name}", self.d.prefix())
    }
    fn st(&self, name: &str) -> T {
        T::Struct(self.p(name))
    }
    fn f(&self, v: f32) -> String {
        self.d.lit(v, &T::F)
    }
    fn nl(&self, v: f32) -> String {
        self.d.lit(v, &T::N)
    }
    fn u(&self, v: usize) -> String {
        format!("{v}u")
    }
    fn math(&self, f: Math, x: &str) -> String {
        format!("{}({x})", self.d.math(f))
    }
    /// `e` (an f32 expression) as the network type.
    fn to_n(&self, e: &str) -> String {
        if self.d.half() {
            self.d.cast(&T::N, e)
        } else {
            e.to_string()
        }
    }
    /// `e` (a network-type expression) as f32.
    fn to_f(&self, e: &str) -> String {
        if self.d.half() {
            self.d.cast(&T::F, e)
        } else {
            e.to_string()
        }
    }
    fn decl(&mut self, t: T, name: &str, init: &str) {
        let s = self.d.decl(&t, name, Some(init));
        self.code.line(s);
    }
    fn arr(&mut self, t: T, n: usize, name: &str) {
        let s = self.d.decl(&T::Arr(Box::new(t), n), name, None);
        self.code.line(s);
    }
    fn for_open(&mut self, var: &str, bound: &str) {
        let s = self.d.for_open(var, bound);
        self.code.open(s);
    }
    /// A call to a generated function; `weights` adds the parameter-buffer argument.
    fn call(&self, name: &str, weights: bool, args: &[&str]) -> String {
        let mut all: Vec<&str> = Vec::new();
        if weights {
            if let Some(w) = self.d.weights_arg() {
                all.push(w);
            }
        }
        all.extend_from_slice(args);
        format!("{}({})", self.p(name), all.join(", "))
    }
    fn fn_open(&mut self, ret: T, name: &str, weights: bool, params: &[(T, &str)]) {
        let mut ps: Vec<String> = Vec::new();
        if weights {
            if let Some(w) = self.d.weights_param() {
                ps.push(w);
            }
        }
        ps.extend(params.iter().map(|(t, n)| self.d.param(t, n)));
        let s = self.d.fn_open(&ret, &self.p(name), &ps);
        self.code.open(s);
    }
    fn end_fn(&mut self) {
        self.code.close("}");
        self.code.blank();
    }
    fn w(&self, idx: String) -> String {
        self.d.weight(&idx)
    }

    fn sphere(&self) -> bool {
        self.m.def.domain == Domain::Sphere
    }
    fn needs_velocity(&self) -> bool {
        self.e.direction || self.e.pdf
    }
    fn needs_jacobian(&self) -> bool {
        self.e.sample || self.e.pdf
    }
    fn needs_base_sample(&self) -> bool {
        self.e.direction || self.e.sample
    }
    fn needs_ln_pdf(&self) -> bool {
        self.e.sample || self.e.pdf
    }

    /// Every helper and `*_impl` function, in dependency order.
    pub fn write(&mut self) {
        self.structs();
        self.sigmoid();
        self.encode();
        self.condition();
        if self.sphere() {
            self.wrap();
        }
        if self.needs_velocity() {
            self.velocity();
        }
        if self.needs_jacobian() {
            self.velocity_jacobian();
        }
        if self.needs_base_sample() {
            self.quantile();
        }
        if self.sphere() && self.needs_base_sample() {
            self.wc_sample();
        }
        if self.sphere() && self.needs_ln_pdf() {
            self.wc_ln_pdf();
        }
        if self.needs_base_sample() {
            self.base_sample();
        }
        if self.needs_ln_pdf() {
            self.base_ln_pdf();
        }
        self.none();
        self.incident();
        if self.m.def.isotropic {
            self.frame_fn();
        }
        if self.needs_base_sample() {
            self.write_to_direction();
        }
        if self.e.direction {
            self.direction_impl();
        }
        if self.e.sample {
            self.sample_impl();
        }
        if self.e.pdf {
            self.residual();
            self.newton();
            self.invert_step();
            self.pdf_impl();
        }
    }

    fn structs(&mut self) {
        let ve = self.m.encoding_len();
        let vw = self.m.def.velocity.width as usize;
        let mut lines = Vec::new();
        lines.push("// The NeRF encoding of wi (f32).".to_string());
        lines.extend(
            self.d
                .struct_decl(&self.p("Enc"), &[(T::Arr(Box::new(T::F), ve), "e")]),
        );
        lines.push(
            "// What one wi fixes for a whole call: the velocity net's first-layer wi part (plus"
                .into(),
        );
        lines.push("// bias) and the base distribution's parameters (log-scales clamped).".into());
        let cond = [
            (T::Arr(Box::new(T::N), vw), "c"),
            (T::F, "p0"),
            (T::F, "p1"),
            (T::F, "p2"),
            (T::F, "p3"),
        ];
        lines.extend(self.d.struct_decl(&self.p("Cond"), &cond));
        lines.push("// A flow point or a velocity.".into());
        lines.extend(
            self.d
                .struct_decl(&self.p("Vec2"), &[(T::F, "x"), (T::F, "y")]),
        );
        if self.needs_jacobian() {
            lines.push("// A velocity and its Jacobian j_rc = dv_r / dx_c.".into());
            let f = [
                (T::F, "v0"),
                (T::F, "v1"),
                (T::F, "j00"),
                (T::F, "j01"),
                (T::F, "j10"),
                (T::F, "j11"),
            ];
            lines.extend(self.d.struct_decl(&self.p("Jac"), &f));
        }
        if self.e.pdf {
            lines.push(
                "// A Newton residual x + h v(x) - y, dv/dx and det(I + h dv/dx) at x.".into(),
            );
            let f = [
                (T::F, "r0"),
                (T::F, "r1"),
                (T::F, "j00"),
                (T::F, "j01"),
                (T::F, "j10"),
                (T::F, "j11"),
                (T::F, "det"),
            ];
            lines.extend(self.d.struct_decl(&self.p("Residual"), &f));
            lines.push(
                "// The point x one Euler step came from, and det(I + h dv/dx(x)); det = 0: none."
                    .into(),
            );
            let f = [(T::F, "a"), (T::F, "b"), (T::F, "det")];
            lines.extend(self.d.struct_decl(&self.p("Root"), &f));
        }
        if self.m.def.isotropic {
            lines.push("// A rotation about the normal: cos and sin of its angle.".into());
            lines.extend(
                self.d
                    .struct_decl(&self.p("Frame"), &[(T::F, "c"), (T::F, "s")]),
            );
        }
        lines.push("// A direction and its PDF; all zero when invalid.".into());
        let r = [(T::F, "x"), (T::F, "y"), (T::F, "z"), (T::F, "pdf")];
        lines.extend(self.d.struct_decl(&self.p("Result"), &r));
        lines.push("// Validated input: a unit direction, or ok = false.".into());
        let i = [(T::F, "x"), (T::F, "y"), (T::F, "z"), (T::B, "ok")];
        lines.extend(self.d.struct_decl(&self.p("Unit"), &i));
        for l in lines {
            self.code.line(l);
        }
        self.code.blank();
    }

    fn sigmoid(&mut self) {
        // The kernel's exp_poly clamps its argument to [-87, 88]; f16 clamps where e^x
        // still fits (e^11 < 65504), which moves sigmoid by < 2e-5.
        let (lo, hi) = if self.d.half() {
            (-11.0, 11.0)
        } else {
            (-87.0, 88.0)
        };
        self.code
            .line("// sigmoid(z) = 1 / (1 + e^-z); silu(z) = z sigmoid(z).");
        self.fn_open(T::N, "sigmoid", false, &[(T::N, "z")]);
        let e = self.math(Math::Exp, &self.d.clamp("-z", &self.nl(lo), &self.nl(hi)));
        let one = self.nl(1.0);
        self.code.line(format!("return {one} / ({one} + {e});"));
        self.end_fn();
    }

    fn encode(&mut self) {
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
        let pi = self.f(core::f32::consts::PI);
        for a in 0..3 {
            let s = self.math(Math::Sin, &format!("{pi} * w{a}"));
            self.decl(T::F, &format!("s{a}"), &s);
            let c = self.math(Math::Cos, &format!("{pi} * w{a}"));
            self.decl(T::F, &format!("c{a}"), &c);
        }
        for a in 0..3 {
            self.code.line(format!("r.e[{a}] = w{a};"));
        }
        if freqs > 0 {
            self.for_open("k", &self.u(freqs));
            self.decl(T::U, "at", "3u + 6u * k");
            for a in 0..3 {
                self.code.line(format!("r.e[at + {a}u] = s{a};"));
                self.code.line(format!("r.e[at + {}u] = c{a};", a + 3));
            }
            let (two, one) = (self.f(2.0), self.f(1.0));
            for a in 0..3 {
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
    fn hidden(&mut self, l: Layer, input: &str, in_is_f: bool, out: &str) {
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
            self.to_n(&format!("{input}[i]"))
        } else {
            format!("{input}[i]")
        };
        self.code.line(format!("z = z + {w} * {x};"));
        self.code.close("}");
        let sg = self.call("sigmoid", false, &["z"]);
        self.code.line(format!("{out}[o] = z * {sg};"));
        self.code.close("}");
    }

    fn condition(&mut self) {
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
            "// readout {} -> 4: weights at {}, biases at {}",
            ro.inputs, ro.w, ro.b
        ));
        self.arr(T::F, 4, "outv");
        self.for_open("o", "4u");
        let b = self.w(format!("{}u + o", ro.b));
        self.decl(T::N, "z", &b);
        self.for_open("i", &self.u(ro.inputs));
        let w = self.w(format!("{}u + o * {}u + i", ro.w, ro.inputs));
        self.code.line(format!("z = z + {w} * {input}[i];"));
        self.code.close("}");
        self.code.line(format!("outv[o] = {};", self.to_f("z")));
        self.code.close("}");
        let (lo, hi) = (
            self.f(diffbsdf::spec::LN_SCALE_MIN),
            self.f(diffbsdf::spec::LN_SCALE_MAX),
        );
        let scales: &[usize] = if self.sphere() { &[1, 3] } else { &[2, 3] };
        for k in 0..4 {
            let v = format!("outv[{k}]");
            let v = if scales.contains(&k) {
                self.d.clamp(&v, &lo, &hi)
            } else {
                v
            };
            self.code.line(format!("r.p{k} = {v};"));
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
        let x = self.to_n("enc.e[i]");
        self.code.line(format!("z = z + {w} * {x};"));
        self.code.close("}");
        self.code.line("r.c[o] = z;");
        self.code.close("}");
        self.code.line("return r;");
        self.end_fn();
    }

    fn wrap(&mut self) {
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
    fn features(&mut self) {
        let fa = self.to_n("a");
        self.decl(T::N, "f0", &fa);
        if self.sphere() {
            let s = self.to_n(&self.math(Math::Sin, "b"));
            let c = self.to_n(&self.math(Math::Cos, "b"));
            self.decl(T::N, "f1", &s);
            self.decl(T::N, "f2", &c);
        } else {
            let fb = self.to_n("b");
            self.decl(T::N, "f1", &fb);
        }
        let tn = self.to_n("t");
        self.decl(T::N, "tn", &tn);
    }

    /// First-layer pre-activation `z` for output `o`: `c + w_t t + sum_f w_f f`.
    fn first_z(&mut self) {
        let v0 = self.m.velocity[0];
        let feats = self.m.features();
        let row = format!("{}u + o * {}u", v0.w, v0.inputs);
        let wt = self.w(format!("{row} + {feats}u"));
        self.decl(T::N, "z", &format!("cond.c[o] + {wt} * tn"));
        for f in 0..feats {
            let wf = self.w(format!("{row} + {f}u"));
            self.code.line(format!("z = z + {wf} * f{f};"));
        }
    }

    fn velocity(&mut self) {
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
            "// readout {} -> 2: weights at {}, biases at {}",
            ro.inputs, ro.w, ro.b
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
        self.code.line(format!("v0 = v0 + {w0} * {input}[i];"));
        self.code.line(format!("v1 = v1 + {w1} * {input}[i];"));
        self.code.close("}");
        let r = self.d.decl(&vec_t, "r", None);
        self.code.line(r);
        self.code.line(format!("r.x = {};", self.to_f("v0")));
        self.code.line(format!("r.y = {};", self.to_f("v1")));
        self.code.line("return r;");
        self.end_fn();
    }

    fn velocity_jacobian(&mut self) {
        let m = self.m;
        let v0 = m.velocity[0];
        let feats = m.features();
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
        let wa = self.w(format!("{row} + 0u"));
        self.decl(T::N, "ta", &wa);
        if feats == 3 {
            // d feat / db = (0, cos b, -sin b)
            let w1 = self.w(format!("{row} + 1u"));
            let w2 = self.w(format!("{row} + 2u"));
            self.decl(T::N, "tb", &format!("{w1} * f2 + {w2} * (-f1)"));
        } else {
            let w1 = self.w(format!("{row} + 1u"));
            self.decl(T::N, "tb", &w1);
        }
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
            self.code.line(format!("z = z + w * h{k_in}[i];"));
            self.code.line(format!("ta = ta + w * da{k_in}[i];"));
            self.code.line(format!("tb = tb + w * db{k_in}[i];"));
            self.code.close("}");
            self.slope_store(&k_out.to_string(), "ta", "tb");
            self.code.close("}");
            k_in = k_out;
        }
        let ro = m.velocity[n - 1];
        self.code.line(format!(
            "// readout {} -> 2: weights at {}, biases at {}",
            ro.inputs, ro.w, ro.b
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
        self.code.line(format!("v0 = v0 + w0 * h{k}[i];"));
        self.code.line(format!("v1 = v1 + w1 * h{k}[i];"));
        self.code.line(format!("j00 = j00 + w0 * da{k}[i];"));
        self.code.line(format!("j01 = j01 + w0 * db{k}[i];"));
        self.code.line(format!("j10 = j10 + w1 * da{k}[i];"));
        self.code.line(format!("j11 = j11 + w1 * db{k}[i];"));
        self.code.close("}");
        let r = self.d.decl(&jac_t, "r", None);
        self.code.line(r);
        for f in ["v0", "v1", "j00", "j01", "j10", "j11"] {
            self.code.line(format!("r.{f} = {};", self.to_f(f)));
        }
        self.code.line("return r;");
        self.end_fn();
    }

    /// `h[o] = silu(z)`, tangents scaled by `silu'(z)`.
    fn slope_store(&mut self, k: &str, ta: &str, tb: &str) {
        let sg = self.call("sigmoid", false, &["z"]);
        self.decl(T::N, "s", &sg);
        let one = self.nl(1.0);
        self.decl(T::N, "g", &format!("s * ({one} + z * ({one} - s))"));
        self.code.line(format!("h{k}[o] = z * s;"));
        self.code.line(format!("da{k}[o] = {ta} * g;"));
        self.code.line(format!("db{k}[o] = {tb} * g;"));
    }

    fn poly(&mut self, coeffs: &[f32]) {
        self.code.line(format!("p = {};", self.f(coeffs[0])));
        for c in &coeffs[1..] {
            self.code.line(format!("p = {} + p * w;", self.f(*c)));
        }
    }

    fn quantile(&mut self) {
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
        let tail = self.f(diffbsdf::spec::GAUSSIAN_TAIL_MIN);
        self.code
            .line(format!("q = {};", self.d.clamp("q", &tail, &half)));
        let two = self.f(2.0);
        self.decl(T::F, "x", &format!("{one} - {two} * q"));
        let ln = self.math(Math::Log, &format!("{} * q * ({one} - q)", self.f(4.0)));
        self.decl(T::F, "w", &format!("-{ln}"));
        self.decl(T::F, "p", &self.f(0.0));
        self.code.open(format!("if (w < {}) {{", self.f(5.0)));
        self.code.line(format!("w = w - {};", self.f(2.5)));
        self.poly(&ERFINV_CENTRAL);
        self.code.reopen("} else {");
        let sq = self.math(Math::Sqrt, "w");
        self.code.line(format!("w = {sq} - {};", self.f(3.0)));
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

    fn wc_sample(&mut self) {
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

    fn wc_ln_pdf(&mut self) {
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

    fn base_sample(&mut self) {
        let cond_t = self.st("Cond");
        let vec_t = self.st("Vec2");
        self.code
            .line("// x0 for u: the deterministic map of the base distribution.");
        let ps = [(cond_t, "cond"), (T::F, "u0"), (T::F, "u1")];
        self.fn_open(vec_t.clone(), "base_sample", false, &ps);
        let r = self.d.decl(&vec_t, "r", None);
        self.code.line(r);
        let q0 = self.call("quantile", false, &["u0"]);
        if self.sphere() {
            let e1 = self.math(Math::Exp, "cond.p1");
            self.code.line(format!("r.x = cond.p0 + {e1} * {q0};"));
            let g = self.math(Math::Exp, "cond.p3");
            let wc = self.call("wrapped_cauchy_sample", false, &["u1", &g]);
            self.code.line(format!("r.y = cond.p2 + {wc};"));
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

    fn base_ln_pdf(&mut self) {
        let cond_t = self.st("Cond");
        self.code.line("// ln p0(x0) in flow coordinates.");
        let ps = [(cond_t, "cond"), (T::F, "x0"), (T::F, "x1")];
        self.fn_open(T::F, "base_ln_pdf", false, &ps);
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
            let e0 = self.math(Math::Exp, "-cond.p2");
            let e1 = self.math(Math::Exp, "-cond.p3");
            self.decl(T::F, "z0", &format!("(x0 - cond.p0) * {e0}"));
            self.decl(T::F, "z1", &format!("(x1 - cond.p1) * {e1}"));
            self.code.line(format!(
                "return ({mh} * z0 * z0 + {c}) + ({mh} * z1 * z1 + {c}) - cond.p2 - cond.p3;"
            ));
        }
        self.end_fn();
    }

    fn none(&mut self) {
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

    fn incident(&mut self) {
        let ut = self.st("Unit");
        self.code.line(format!(
            "// w normalised if finite and | |w|^2 - 1 | <= {}, else ok = false.",
            diffbsdf::spec::UNIT_TOLERANCE
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
        let tol = self.f(diffbsdf::spec::UNIT_TOLERANCE);
        self.code.line(format!("r.ok = {fin} && {abs} <= {tol};"));
        let s = format!("{} / {}", self.f(1.0), self.math(Math::Sqrt, "l2"));
        self.decl(T::F, "s", &s);
        self.code.line("r.x = x * s;");
        self.code.line("r.y = y * s;");
        self.code.line("r.z = z * s;");
        self.code.line("return r;");
        self.end_fn();
    }

    fn write_to_direction(&mut self) {
        let rt = self.st("Result");
        self.code.line(
            "// The direction of flow point (a, b) with pdf = 1, or none() outside the domain.",
        );
        self.fn_open(
            rt.clone(),
            "to_direction",
            false,
            &[(T::F, "a"), (T::F, "b")],
        );
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
            self.code
                .line(format!("r.x = st * {};", self.math(Math::Cos, "b")));
            self.code
                .line(format!("r.y = st * {};", self.math(Math::Sin, "b")));
            self.code
                .line(format!("r.z = {};", self.math(Math::Cos, "a")));
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
            self.code.line("r.x = a;");
            self.code.line("r.y = b;");
            self.code.line("r.z = z;");
        }
        self.code.line(format!("r.pdf = {one};"));
        self.code.line("return r;");
        self.end_fn();
    }

    /// Shared prologue of the entry points: checks `wi` (and `u`), steps, conditions.
    fn prologue(&mut self, with_u: bool, fail: &str) {
        let ut = self.st("Unit");
        let inc = self.call("unit", false, &["wx", "wy", "wz"]);
        self.decl(ut, "wi", &inc);
        let mut ok = "wi.ok".to_string();
        if self.m.def.domain == Domain::Disk {
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
        self.decl(T::U, "n", "steps");
        self.code.open("if (n == 0u) {");
        self.code
            .line(format!("n = {}u;", self.m.def.default_steps));
        self.code.close("}");
        self.decl(
            T::F,
            "h",
            &format!("{} / {}", self.f(1.0), self.d.cast(&T::F, "n")),
        );
        let enc = if self.m.def.isotropic {
            self.incident_frame();
            self.call(
                "encode",
                false,
                &[
                    "fr.c * wi.x + fr.s * wi.y",
                    "fr.c * wi.y - fr.s * wi.x",
                    "wi.z",
                ],
            )
        } else {
            self.call("encode", false, &["wi.x", "wi.y", "wi.z"])
        };
        let cond = self.call("condition", true, &[&enc]);
        self.decl(self.st("Cond"), "cond", &cond);
    }

    /// Isotropic models: the frame of `wi`, `(c, s) = wi.xy / |wi.xy|` (the identity at
    /// normal incidence), as the kernel's `IncidentFrame::aligning` computes it.
    fn frame_fn(&mut self) {
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
        self.code.open(format!(
            "if (rho > {}) {{",
            self.f(diffbsdf::spec::NORMAL_INCIDENCE_RHO)
        ));
        self.decl(T::F, "inv", &format!("{} / rho", self.f(1.0)));
        self.code.line("f.c = x * inv;");
        self.code.line("f.s = y * inv;");
        self.code.close("}");
        self.code.line("return f;");
        self.end_fn();
    }

    /// Isotropic models: `fr`, the frame of `wi` (the encoding takes `wi` turned into it).
    fn incident_frame(&mut self) {
        let fr = self.call("frame", false, &["wi.x", "wi.y"]);
        self.decl(self.st("Frame"), "fr", &fr);
    }

    /// Isotropic models: `r.xy` turned back from the incident frame into the world.
    fn turn_back(&mut self, r: &str) {
        if !self.m.def.isotropic {
            return;
        }
        self.decl(T::F, "rx", &format!("fr.c * {r}.x - fr.s * {r}.y"));
        self.code
            .line(format!("{r}.y = fr.s * {r}.x + fr.c * {r}.y;"));
        self.code.line(format!("{r}.x = rx;"));
    }

    /// `var = var + h * dv` with phi wrapped on the sphere.
    fn advance(&self, a: &str, da: &str, b: &str, db: &str) -> Vec<String> {
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

    fn start_point(&mut self, a: &str, b: &str) {
        self.decl(T::F, "a", a);
        if self.sphere() {
            let w = self.call("wrap", false, &[b]);
            self.decl(T::F, "b", &w);
        } else {
            self.decl(T::F, "b", b);
        }
    }

    fn direction_impl(&mut self) {
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
        let bs = self.call("base_sample", false, &["cond", "u0", "u1"]);
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
        let td = self.call("to_direction", false, &["a", "b"]);
        if self.m.def.isotropic {
            self.decl(rt, "r", &td);
            self.turn_back("r");
            self.code.line("return r;");
        } else {
            self.code.line(format!("return {td};"));
        }
        self.end_fn();
    }

    /// `det(I + h dv/dx)` of the Jacobian `j`, as the kernel's `step_det` computes it.
    fn det_expr(&self) -> String {
        let one = self.f(1.0);
        format!("({one} + h * j.j00) * ({one} + h * j.j11) - (h * j.j01) * (h * j.j10)")
    }

    fn det_line(&mut self) {
        let det = self.det_expr();
        self.decl(T::F, "det", &det);
    }

    fn ln_measure(&self, wo_z: &str, theta: &str) -> String {
        if self.sphere() {
            format!("-{}", self.math(Math::Log, &self.math(Math::Sin, theta)))
        } else {
            self.math(Math::Log, wo_z)
        }
    }

    fn sample_impl(&mut self) {
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
        let bs = self.call("base_sample", false, &["cond", "u0", "u1"]);
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
        let td = self.call("to_direction", false, &["a", "b"]);
        self.decl(rt, "r", &td);
        self.code.open(format!("if (!(r.pdf > {zero})) {{"));
        self.code.line(&none);
        self.code.close("}");
        let lp = self.call("base_ln_pdf", false, &["cond", "x0.x", "x0.y"]);
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

    /// Newton's tolerance: the kernel's, or the f16 one.
    fn newton_tol(&self) -> f32 {
        if self.d.half() {
            NEWTON_TOL_F16
        } else {
            diffbsdf::spec::NEWTON_TOL
        }
    }

    fn step_params() -> [(T, &'static str); 4] {
        [(T::F, "t"), (T::F, "h"), (T::F, "ya"), (T::F, "yb")]
    }

    /// The kernel's `residual`: `x + h v(x) - y` (phi difference wrapped), `dv/dx` and
    /// `det(I + h dv/dx)` at `x = (a, b)`.
    fn residual(&mut self) {
        self.code
            .line("// x + h v(x) - y (phi wrapped), dv/dx and det(I + h dv/dx) at x = (a, b).");
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
        for c in ["j00", "j01", "j10", "j11"] {
            self.code.line(format!("r.{c} = j.{c};"));
        }
        self.code.line(format!("r.det = {};", self.det_expr()));
        self.code.line("return r;");
        self.end_fn();
    }

    /// The kernel's `newton`: Newton steps where `I + h dv/dx` is orientation preserving,
    /// fixed-point steps where it is not, each with a backtracking line search.
    fn newton(&mut self) {
        self.code.line(
            "// Solves x + h v(x) = y from x = (xa, xb): Newton steps where det(I + h dv/dx) > 0,",
        );
        self.code.line(
            "// fixed-point steps where not, each halved (at most 8 times) until the residual shrinks.",
        );
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
        self.code.line(format!("x.a = {zero};"));
        self.code.line(format!("x.b = {zero};"));
        self.code.line(format!("x.det = {zero};"));
        self.decl(T::F, "a", "xa");
        self.decl(T::F, "b", "xb");
        let res = self.call("residual", true, &["cond", "t", "h", "ya", "yb", "a", "b"]);
        self.decl(self.st("Residual"), "at", &res);
        let abs = |s: &Self, x: &str| s.math(Math::Abs, x);
        let mx = self.d.math(Math::Max);
        self.for_open("it", &self.u(diffbsdf::spec::NEWTON_MAX_ITERS as usize));
        self.decl(T::F, "d0", "at.r0");
        self.decl(T::F, "d1", "at.r1");
        self.code.open(format!("if (at.det > {zero}) {{"));
        self.code.line("// d = (I + h J)^-1 r by the 2x2 adjugate.");
        self.code.line(format!(
            "d0 = (({one} + h * at.j11) * at.r0 - (h * at.j01) * at.r1) / at.det;"
        ));
        self.code.line(format!(
            "d1 = (({one} + h * at.j00) * at.r1 - (h * at.j10) * at.r0) / at.det;"
        ));
        self.code.close("}");
        let size = format!("{mx}({}, {})", abs(self, "d0"), abs(self, "d1"));
        self.decl(T::F, "size", &size);
        self.code
            .open(format!("if (!{}) {{", self.d.finite("size")));
        self.code.line("return x;");
        self.code.close("}");
        let scale = format!("{one} + {mx}({}, {})", abs(self, "a"), abs(self, "b"));
        self.decl(T::F, "scale", &scale);
        self.code.open(format!("if (size <= {tol} * scale) {{"));
        self.code.line(
            "// Converged: the update is below the f32 noise of x + h v(x); det is taken at the",
        );
        self.code
            .line("// returned point, where the forward pass takes it.");
        self.code.line("x.a = a - d0;");
        if self.sphere() {
            let w = self.call("wrap", false, &["b - d1"]);
            self.code.line(format!("x.b = {w};"));
        } else {
            self.code.line("x.b = b - d1;");
        }
        let fin = self.call(
            "residual",
            true,
            &["cond", "t", "h", "ya", "yb", "x.a", "x.b"],
        );
        self.decl(self.st("Residual"), "fin", &fin);
        self.code.open(format!("if (fin.det > {zero}) {{"));
        self.code.line("x.det = fin.det;");
        self.code.close("}");
        self.code.line("return x;");
        self.code.close("}");
        let norm = format!("{mx}({}, {})", abs(self, "at.r0"), abs(self, "at.r1"));
        self.decl(T::F, "norm", &norm);
        self.decl(T::F, "lambda", &one);
        self.for_open("ls", "8u");
        self.decl(T::F, "ta", "a - lambda * d0");
        if self.sphere() {
            let w = self.call("wrap", false, &["b - lambda * d1"]);
            self.decl(T::F, "tb", &w);
        } else {
            self.decl(T::F, "tb", "b - lambda * d1");
        }
        let res = self.call(
            "residual",
            true,
            &["cond", "t", "h", "ya", "yb", "ta", "tb"],
        );
        self.code.line(format!("at = {res};"));
        self.code.line("a = ta;");
        self.code.line("b = tb;");
        let next = format!("{mx}({}, {})", abs(self, "at.r0"), abs(self, "at.r1"));
        self.code.open(format!("if ({next} < norm) {{"));
        self.code.line("break;");
        self.code.close("}");
        self.code
            .line(format!("lambda = lambda * {};", self.f(0.5)));
        self.code.close("}");
        self.code.open(format!(
            "if (lambda * size <= {tol} * scale && at.det > {zero}) {{"
        ));
        self.code
            .line("// The step just taken was below the noise: converged here.");
        self.code.line("x.a = a;");
        self.code.line("x.b = b;");
        self.code.line("x.det = at.det;");
        self.code.line("return x;");
        self.code.close("}");
        self.code.close("}");
        self.code.line("return x;");
        self.end_fn();
    }

    /// The kernel's `invert_step`: Newton from `y - h v(y)`, then (rarely needed) from one
    /// fixed-point iterate further and from `y - h v(y) / 2`.
    fn invert_step(&mut self) {
        self.code.line(
            "// The x with x + h v(x) = y: Newton from y - h v(y), else from one fixed-point",
        );
        self.code
            .line("// iterate further, else from y - h v(y) / 2 (breaks rare Newton cycles).");
        let cond = self.st("Cond");
        let root = self.st("Root");
        let mut ps = vec![(cond, "cond")];
        ps.extend(Self::step_params());
        self.fn_open(root.clone(), "invert_step", true, &ps);
        let zero = self.f(0.0);
        let v = self.call("velocity", true, &["cond", "t", "ya", "yb"]);
        self.decl(self.st("Vec2"), "v", &v);
        let start = |s: &Self, scale: &str, vv: &str| -> (String, String) {
            let a = format!("ya - {scale}h * {vv}.x");
            let b = if s.sphere() {
                s.call("wrap", false, &[&format!("yb - {scale}h * {vv}.y")])
            } else {
                format!("yb - {scale}h * {vv}.y")
            };
            (a, b)
        };
        let (a0, b0) = start(self, "", "v");
        self.decl(T::F, "a0", &a0);
        self.decl(T::F, "b0", &b0);
        let n0 = self.call("newton", true, &["cond", "t", "h", "ya", "yb", "a0", "b0"]);
        self.decl(root.clone(), "x", &n0);
        self.code.open(format!("if (x.det > {zero}) {{"));
        self.code.line("return x;");
        self.code.close("}");
        let v1 = self.call("velocity", true, &["cond", "t", "a0", "b0"]);
        self.decl(self.st("Vec2"), "v1", &v1);
        let (a1, b1) = start(self, "", "v1");
        self.decl(T::F, "a1", &a1);
        self.decl(T::F, "b1", &b1);
        let n1 = self.call("newton", true, &["cond", "t", "h", "ya", "yb", "a1", "b1"]);
        self.code.line(format!("x = {n1};"));
        self.code.open(format!("if (x.det > {zero}) {{"));
        self.code.line("return x;");
        self.code.close("}");
        let half = format!("{} * ", self.f(0.5));
        let (a2, b2) = start(self, &half, "v");
        self.decl(T::F, "a2", &a2);
        self.decl(T::F, "b2", &b2);
        let n2 = self.call("newton", true, &["cond", "t", "h", "ya", "yb", "a2", "b2"]);
        self.code.line(format!("return {n2};"));
        self.end_fn();
    }

    fn pdf_impl(&mut self) {
        let zero = self.f(0.0);
        let fail = format!("return {zero};");
        self.code.line(
            "// The PDF of direction (ox, oy, oz): each Euler step inverted exactly by Newton's",
        );
        self.code
            .line("// method on x + h v(x) = y, starting from y - h v(y).");
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
        let (ox, oy) = if self.m.def.isotropic {
            self.decl(T::F, "lox", "fr.c * wo.x + fr.s * wo.y");
            self.decl(T::F, "loy", "fr.c * wo.y - fr.s * wo.x");
            ("lox", "loy")
        } else {
            ("wo.x", "wo.y")
        };
        if self.sphere() {
            let rho = self.math(Math::Sqrt, &format!("{ox} * {ox} + {oy} * {oy}"));
            self.decl(T::F, "rho", &rho);
            self.code.open(format!("if (!(rho > {zero})) {{"));
            self.code.line(&fail);
            self.code.close("}");
            self.decl(T::F, "ya", &self.d.atan2("rho", "wo.z"));
            self.decl(T::F, "yb", &self.d.atan2(oy, ox));
        } else {
            self.code.open(format!("if (!(wo.z > {zero})) {{"));
            self.code.line(&fail);
            self.code.close("}");
            self.decl(T::F, "ya", ox);
            self.decl(T::F, "yb", oy);
        }
        self.start_point("ya", "yb");
        self.decl(T::F, "ln_det", &zero);
        self.for_open("kk", "n");
        self.decl(T::U, "k", "n - 1u - kk");
        let t = format!("{} * h", self.d.cast(&T::F, "k"));
        self.decl(T::F, "t", &t);
        let root = self.call("invert_step", true, &["cond", "t", "h", "a", "b"]);
        self.decl(self.st("Root"), "x", &root);
        self.code.open(format!("if (!(x.det > {zero})) {{"));
        self.code.line(&fail);
        self.code.close("}");
        self.code.line("a = x.a;");
        self.code.line("b = x.b;");
        self.code.line(format!(
            "ln_det = ln_det + {};",
            self.math(Math::Log, "x.det")
        ));
        self.code.close("}");
        let lp = self.call("base_ln_pdf", false, &["cond", "a", "b"]);
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
