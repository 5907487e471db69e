//! WGSL output: functions to paste into (or concatenate with) a WGSL module. f16 output
//! starts with `enable f16;` (the device needs the `shader-f16` feature).

pub(crate) mod keywords;

use crate::code::{Code, Namer};
use crate::desc::ModelDesc;
use crate::dialect::{Dialect, Math, T};
use crate::emit::Emitter;
use crate::{float_repr, header_lines, prefix_for, Float, Options, Weights};

struct Wgsl {
    fused: bool,
    half: bool,
    prefix: String,
    buffer: bool,
}

impl Dialect for Wgsl {
    fn half(&self) -> bool {
        self.half
    }
    fn ty(&self, t: &T) -> String {
        match t {
            T::F => "f32".into(),
            T::N if self.half => "f16".into(),
            T::N => "f32".into(),
            T::U => "u32".into(),
            T::B => "bool".into(),
            T::Arr(e, n) => format!("array<{}, {n}>", self.ty(e)),
            T::Struct(s) => s.clone(),
        }
    }
    fn lit(&self, v: f32, t: &T) -> String {
        match t {
            T::N if self.half => format!("{}h", float_repr(half::f16::from_f32(v).to_f32())),
            _ => format!("{}f", float_repr(v)),
        }
    }
    fn bool_lit(&self, b: bool) -> &'static str {
        if b {
            "true"
        } else {
            "false"
        }
    }
    fn decl(&self, t: &T, name: &str, init: Option<&str>) -> String {
        match init {
            Some(i) => format!("var {name}: {} = {i};", self.ty(t)),
            None => format!("var {name}: {};", self.ty(t)),
        }
    }
    fn param(&self, t: &T, name: &str) -> String {
        format!("{name}: {}", self.ty(t))
    }
    fn for_open(&self, var: &str, bound: &str) -> String {
        format!("for (var {var} = 0u; {var} < {bound}; {var}++) {{")
    }
    fn fn_open(&self, ret: &T, name: &str, params: &[String]) -> String {
        format!("fn {name}({}) -> {} {{", params.join(", "), self.ty(ret))
    }
    fn struct_decl(&self, name: &str, fields: &[(T, &str)]) -> Vec<String> {
        let mut v = vec![format!("struct {name} {{")];
        for (t, f) in fields {
            v.push(format!("    {},", self.param(t, f)));
        }
        v.push("}".into());
        v
    }
    fn math(&self, f: Math) -> &'static str {
        match f {
            Math::Exp => "exp",
            Math::Log => "log",
            Math::Sqrt => "sqrt",
            Math::Sin => "sin",
            Math::Cos => "cos",
            Math::Tanh => "tanh",
            Math::Sinh => "sinh",
            Math::Floor => "floor",
            Math::Abs => "abs",
            Math::Max => "max",
        }
    }
    fn fused(&self) -> bool {
        self.fused
    }
    fn fma_name(&self) -> &'static str {
        "fma"
    }
    fn atan2(&self, y: &str, x: &str) -> String {
        format!("atan2({y}, {x})")
    }
    fn clamp(&self, x: &str, lo: &str, hi: &str) -> String {
        format!("clamp({x}, {lo}, {hi})")
    }
    fn cast(&self, t: &T, e: &str) -> String {
        format!("{}({e})", self.ty(t))
    }
    fn finite(&self, x: &str) -> String {
        format!("((bitcast<u32>({x}) & 0x7f800000u) != 0x7f800000u)")
    }
    fn weights_param(&self) -> Option<String> {
        self.buffer.then(|| "base: u32".to_string())
    }
    fn weights_arg(&self) -> Option<&'static str> {
        self.buffer.then_some("base")
    }
    fn weight(&self, idx: &str) -> String {
        let p = &self.prefix;
        if self.buffer {
            let e = format!("{p}_params[base + {idx}]");
            if self.half {
                format!("f16({e})")
            } else {
                e
            }
        } else {
            format!("{}_PARAMS[{idx}]", p.to_uppercase())
        }
    }
    fn prefix(&self) -> &str {
        &self.prefix
    }
}

pub(crate) fn write(model: &ModelDesc, options: &Options) -> String {
    let namer = Namer::new(keywords::RESERVED);
    let prefix = prefix_for(model, options, &namer);
    let half = options.float == Float::F16;
    let d = Wgsl {
        half,
        prefix: prefix.clone(),
        buffer: matches!(options.weights, Weights::Buffer { .. }),
        fused: options.fused,
    };
    let mut c = Code::new();
    if half {
        c.line("enable f16;");
        c.blank();
    }
    for l in header_lines(model, options, &prefix) {
        c.line(format!("// {l}"));
    }
    c.blank();
    let up = prefix.to_uppercase();
    c.line(format!(
        "const {up}_PARAM_COUNT: u32 = {}u;",
        model.params.len()
    ));
    c.line(format!(
        "const {up}_DEFAULT_STEPS: u32 = {}u;",
        model.def.default_steps
    ));
    match options.weights {
        Weights::Buffer { set, binding } => {
            c.line(
                "// Parameters of every material, blob order, f32; a material starts at `base`.",
            );
            c.line(format!(
                "@group({set}) @binding({binding}) var<storage, read> {prefix}_params: array<f32>;"
            ));
        }
        Weights::Baked => {
            let ty = d.ty(&T::N);
            let n = model.params.len();
            // A private copy: constant arrays indexed at run time are spilled per access by
            // some compilers; a module-scope variable is initialised once per invocation.
            c.line(format!(
                "var<private> {up}_PARAMS: array<{ty}, {n}> = array<{ty}, {n}>("
            ));
            let items: Vec<String> = model.params.iter().map(|w| d.lit(*w, &T::N)).collect();
            c.list(&items);
            c.line(");");
        }
    }
    c.blank();
    let mut e = Emitter::new(&d, model, options.entry_points);
    e.write();
    let mut out = c.finish();
    out.push_str(&e.code.finish());
    let mut c = Code::new();
    let (wp, wa) = if d.buffer {
        ("base: u32, ", "base, ")
    } else {
        ("", "")
    };
    let ep = options.entry_points;
    if ep.direction {
        c.line("// A direction for wi (unit) and u in [0, 1]^2, without its PDF; vec3(0) when invalid.");
        c.open(format!(
            "fn {prefix}_sample_direction({wp}wi: vec3<f32>, u: vec2<f32>, steps: u32) -> vec3<f32> {{"
        ));
        c.line(format!(
            "let r = {prefix}_direction_impl({wa}wi.x, wi.y, wi.z, u.x, u.y, steps);"
        ));
        c.line("return vec3<f32>(r.x, r.y, r.z);");
        c.close("}");
        c.blank();
    }
    if ep.sample {
        c.line("// A direction and its PDF: vec4(wo, pdf); vec4(0) when invalid.");
        c.open(format!(
            "fn {prefix}_sample({wp}wi: vec3<f32>, u: vec2<f32>, steps: u32) -> vec4<f32> {{"
        ));
        c.line(format!(
            "let r = {prefix}_sample_impl({wa}wi.x, wi.y, wi.z, u.x, u.y, steps);"
        ));
        c.line("return vec4<f32>(r.x, r.y, r.z, r.pdf);");
        c.close("}");
        c.blank();
    }
    if ep.pdf {
        c.line("// The PDF with which sample() produces wo for wi; 0 when invalid.");
        c.open(format!(
            "fn {prefix}_pdf({wp}wi: vec3<f32>, wo: vec3<f32>, steps: u32) -> f32 {{"
        ));
        c.line(format!(
            "return {prefix}_pdf_impl({wa}wi.x, wi.y, wi.z, wo.x, wo.y, wo.z, steps);"
        ));
        c.close("}");
        c.blank();
    }
    out.push_str(&c.finish());
    while out.ends_with("\n\n") {
        out.pop();
    }
    out
}
