//! Vulkan GLSL 450 output: functions to `#include` in a shader. f16 output needs
//! `GL_EXT_shader_explicit_arithmetic_types_float16` (the file enables it; include it
//! before other declarations of the shader).

pub(crate) mod keywords;

use crate::code::{Code, Namer};
use crate::desc::ModelDesc;
use crate::dialect::{Dialect, Math, T};
use crate::emit::Emitter;
use crate::{float_repr, header_lines, prefix_for, Float, Options, Weights};

struct Glsl {
    fused: bool,
    half: bool,
    prefix: String,
    buffer: bool,
}

impl Dialect for Glsl {
    fn half(&self) -> bool {
        self.half
    }
    fn ty(&self, t: &T) -> String {
        match t {
            T::F => "float".into(),
            T::N if self.half => "float16_t".into(),
            T::N => "float".into(),
            T::U => "uint".into(),
            T::B => "bool".into(),
            T::Arr(e, _) => self.ty(e),
            T::Struct(s) => s.clone(),
        }
    }
    fn lit(&self, v: f32, t: &T) -> String {
        if self.half && *t == T::N {
            format!("{}hf", float_repr(half::f16::from_f32(v).to_f32()))
        } else {
            float_repr(v)
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
        // `precise`: a driver may not fuse or reorder the arithmetic that computes a float
        // variable, so every GPU evaluates the kernel's unfused operation order (the same
        // order the kernel, the C ABI and the generated C use).
        let q = if precise(t) { "precise " } else { "" };
        match (t, init) {
            (T::Arr(e, n), _) => format!("{q}{} {name}[{n}];", self.ty(e)),
            (_, Some(i)) => format!("{q}{} {name} = {i};", self.ty(t)),
            (_, None) => format!("{q}{} {name};", self.ty(t)),
        }
    }
    fn param(&self, t: &T, name: &str) -> String {
        match t {
            T::Arr(e, n) => format!("{} {name}[{n}]", self.ty(e)),
            _ => format!("{} {name}", self.ty(t)),
        }
    }
    fn for_open(&self, var: &str, bound: &str) -> String {
        format!("for (uint {var} = 0u; {var} < {bound}; {var}++) {{")
    }
    fn fn_open(&self, ret: &T, name: &str, params: &[String]) -> String {
        format!("{} {name}({}) {{", self.ty(ret), params.join(", "))
    }
    fn struct_decl(&self, name: &str, fields: &[(T, &str)]) -> Vec<String> {
        let mut v = vec![format!("struct {name} {{")];
        for (t, f) in fields {
            v.push(format!("    {};", self.param(t, f)));
        }
        v.push("};".into());
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
        format!("atan({y}, {x})")
    }
    fn clamp(&self, x: &str, lo: &str, hi: &str) -> String {
        format!("clamp({x}, {lo}, {hi})")
    }
    fn cast(&self, t: &T, e: &str) -> String {
        format!("{}({e})", self.ty(t))
    }
    fn finite(&self, x: &str) -> String {
        format!("((floatBitsToUint({x}) & 0x7f800000u) != 0x7f800000u)")
    }
    fn weights_param(&self) -> Option<String> {
        self.buffer.then(|| "uint base".to_string())
    }
    fn weights_arg(&self) -> Option<&'static str> {
        self.buffer.then_some("base")
    }
    fn weight(&self, idx: &str) -> String {
        let p = &self.prefix;
        if self.buffer {
            let e = format!("{p}_params[base + {idx}]");
            if self.half {
                format!("float16_t({e})")
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
    let d = Glsl {
        half,
        prefix: prefix.clone(),
        buffer: matches!(options.weights, Weights::Buffer { .. }),
        fused: options.fused,
    };
    let mut c = Code::new();
    for l in header_lines(model, options, &prefix) {
        c.line(format!("// {l}"));
    }
    let guard = format!("{}_GLSL", prefix.to_uppercase());
    c.line(format!("#ifndef {guard}"));
    c.line(format!("#define {guard}"));
    if half {
        c.line("#extension GL_EXT_shader_explicit_arithmetic_types_float16 : require");
    }
    c.blank();
    c.line(format!(
        "const uint {}_PARAM_COUNT = {}u;",
        prefix.to_uppercase(),
        model.params.len()
    ));
    c.line(format!(
        "const uint {}_DEFAULT_STEPS = {}u;",
        prefix.to_uppercase(),
        model.def.default_steps
    ));
    match options.weights {
        Weights::Buffer { set, binding } => {
            c.line(
                "// Parameters of every material, blob order, f32; a material starts at `base`.",
            );
            c.line(format!(
                "layout(std430, set = {set}, binding = {binding}) readonly buffer {prefix}_Params {{"
            ));
            c.line(format!("    float {prefix}_params[];"));
            c.line("};");
        }
        Weights::Baked => {
            let ty = d.ty(&T::N);
            let n = model.params.len();
            c.line(format!(
                "const {ty} {}_PARAMS[{n}] = {ty}[{n}](",
                prefix.to_uppercase()
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
        ("uint base, ", "base, ")
    } else {
        ("", "")
    };
    let ep = options.entry_points;
    if ep.direction {
        c.line("// A direction for wi (unit) and u in [0, 1]^2, without its PDF; vec3(0) when invalid.");
        c.open(format!(
            "vec3 {prefix}_sample_direction({wp}vec3 wi, vec2 u, uint steps) {{"
        ));
        c.line(format!(
            "{prefix}_Result r = {prefix}_direction_impl({wa}wi.x, wi.y, wi.z, u.x, u.y, steps);"
        ));
        c.line("return vec3(r.x, r.y, r.z);");
        c.close("}");
        c.blank();
    }
    if ep.sample {
        c.line("// A direction and its PDF: vec4(wo, pdf); vec4(0) when invalid.");
        c.open(format!(
            "vec4 {prefix}_sample({wp}vec3 wi, vec2 u, uint steps) {{"
        ));
        c.line(format!(
            "{prefix}_Result r = {prefix}_sample_impl({wa}wi.x, wi.y, wi.z, u.x, u.y, steps);"
        ));
        c.line("return vec4(r.x, r.y, r.z, r.pdf);");
        c.close("}");
        c.blank();
    }
    if ep.pdf {
        c.line("// The PDF with which sample() produces wo for wi; 0 when invalid.");
        c.open(format!(
            "float {prefix}_pdf({wp}vec3 wi, vec3 wo, uint steps) {{"
        ));
        c.line(format!(
            "return {prefix}_pdf_impl({wa}wi.x, wi.y, wi.z, wo.x, wo.y, wo.z, steps);"
        ));
        c.close("}");
        c.blank();
    }
    c.line(format!("#endif // {guard}"));
    out.push_str(&c.finish());
    out
}

/// Whether a variable of type `t` holds floats (directly, in an array or in a struct).
fn precise(t: &T) -> bool {
    match t {
        T::F | T::N | T::Struct(_) => true,
        T::Arr(e, _) => precise(e),
        T::U | T::B => false,
    }
}
