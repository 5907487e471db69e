//! Standalone C99 header: every function `static inline`, no dependency beyond
//! `<math.h>`, valid C++ as well. f32 only.

pub(crate) mod keywords;

use crate::code::{Code, Namer};
use crate::desc::ModelDesc;
use crate::dialect::{Dialect, Math, T};
use crate::emit::Emitter;
use crate::{float_repr, header_lines, prefix_for, Options, Weights};
use diffbsdf::spec;

struct C {
    fused: bool,
    prefix: String,
    buffer: bool,
}

impl Dialect for C {
    fn half(&self) -> bool {
        false
    }
    fn ty(&self, t: &T) -> String {
        match t {
            T::F | T::N => "float".into(),
            T::U => "unsigned".into(),
            T::B => "int".into(),
            T::Arr(e, _) => self.ty(e),
            T::Struct(s) => s.clone(),
        }
    }
    fn lit(&self, v: f32, _t: &T) -> String {
        format!("{}f", float_repr(v))
    }
    fn bool_lit(&self, b: bool) -> &'static str {
        if b {
            "1"
        } else {
            "0"
        }
    }
    fn decl(&self, t: &T, name: &str, init: Option<&str>) -> String {
        match (t, init) {
            (T::Arr(e, n), _) => format!("{} {name}[{n}];", self.ty(e)),
            (_, Some(i)) => format!("{} {name} = {i};", self.ty(t)),
            (_, None) => format!("{} {name};", self.ty(t)),
        }
    }
    fn param(&self, t: &T, name: &str) -> String {
        match t {
            T::Arr(e, n) => format!("{} {name}[{n}]", self.ty(e)),
            _ => format!("{} {name}", self.ty(t)),
        }
    }
    fn for_open(&self, var: &str, bound: &str) -> String {
        format!("for (unsigned {var} = 0u; {var} < {bound}; {var}++) {{")
    }
    fn fn_open(&self, ret: &T, name: &str, params: &[String]) -> String {
        let ps = if params.is_empty() {
            "void".to_string()
        } else {
            params.join(", ")
        };
        format!("static inline {} {name}({ps}) {{", self.ty(ret))
    }
    fn struct_decl(&self, name: &str, fields: &[(T, &str)]) -> Vec<String> {
        let mut v = vec![format!("typedef struct {name} {{")];
        for (t, f) in fields {
            v.push(format!("    {};", self.param(t, f)));
        }
        v.push(format!("}} {name};"));
        v
    }
    fn math(&self, f: Math) -> &'static str {
        match f {
            Math::Exp => "expf",
            Math::Log => "logf",
            Math::Sqrt => "sqrtf",
            Math::Sin => "sinf",
            Math::Cos => "cosf",
            Math::Tanh => "tanhf",
            Math::Sinh => "sinhf",
            Math::Floor => "floorf",
            Math::Abs => "fabsf",
            Math::Max => "fmaxf",
        }
    }
    fn fused(&self) -> bool {
        self.fused
    }
    fn fma_name(&self) -> &'static str {
        "fmaf"
    }
    fn atan2(&self, y: &str, x: &str) -> String {
        format!("atan2f({y}, {x})")
    }
    fn clamp(&self, x: &str, lo: &str, hi: &str) -> String {
        format!("fminf(fmaxf({x}, {lo}), {hi})")
    }
    fn cast(&self, t: &T, e: &str) -> String {
        format!("({})({e})", self.ty(t))
    }
    fn finite(&self, x: &str) -> String {
        format!("(fabsf({x}) <= 3.40282347e+38f)")
    }
    fn weights_param(&self) -> Option<String> {
        self.buffer.then(|| "const float *params".to_string())
    }
    fn weights_arg(&self) -> Option<&'static str> {
        self.buffer.then_some("params")
    }
    fn weight(&self, idx: &str) -> String {
        if self.buffer {
            format!("params[{idx}]")
        } else {
            format!("{}_PARAMS[{idx}]", self.prefix.to_uppercase())
        }
    }
    fn prefix(&self) -> &str {
        &self.prefix
    }
}

pub(crate) fn write(model: &ModelDesc, options: &Options) -> String {
    let namer = Namer::new(keywords::RESERVED);
    let prefix = prefix_for(model, options, &namer);
    let d = C {
        prefix: prefix.clone(),
        buffer: matches!(options.weights, Weights::Buffer { .. }),
        fused: options.fused,
    };
    let up = prefix.to_uppercase();
    let mut c = Code::new();
    c.line("/*");
    for l in header_lines(model, options, &prefix) {
        c.line(format!(" * {l}"));
    }
    c.line(" *");
    c.line(" * Standalone C99 header (also valid C++): static inline functions, only <math.h>.");
    c.line(" * Compile without -ffast-math: the input checks rely on IEEE comparisons.");
    c.line(" */");
    c.line(format!("#ifndef {up}_H"));
    c.line(format!("#define {up}_H"));
    c.blank();
    c.line("#include <math.h>");
    c.blank();
    c.line(format!("#define {up}_PARAM_COUNT {}u", model.params.len()));
    c.line(format!(
        "#define {up}_DEFAULT_STEPS {}u",
        model.def.default_steps
    ));
    c.line("/* What sample() and sample_direction() return, as in the diffbsdf C ABI. */");
    c.line(format!("#define {up}_OK {}", spec::STATUS_OK));
    c.line(format!("#define {up}_NO_SAMPLE {}", spec::STATUS_NO_SAMPLE));
    c.blank();
    if !d.buffer {
        let n = model.params.len();
        c.line("/* Every parameter in blob order. */");
        c.line(format!("static const float {up}_PARAMS[{n}] = {{"));
        let items: Vec<String> = model.params.iter().map(|w| d.lit(*w, &T::F)).collect();
        c.list(&items);
        c.line("};");
        c.blank();
    }
    let mut e = Emitter::new(&d, model, options.entry_points);
    e.write();
    let mut out = c.finish();
    out.push_str(&e.code.finish().replace("// ", "/* ").replace_comment_ends());
    let mut c = Code::new();
    let (wp, wa) = if d.buffer {
        ("const float *params, ", "params, ")
    } else {
        ("", "")
    };
    let ep = options.entry_points;
    if ep.direction {
        c.line("/* A direction for wi (unit) and u in [0, 1]^2 into wo, without its PDF.");
        c.line(format!(
            " * Returns {up}_OK, or {up}_NO_SAMPLE with wo = 0 when invalid. */"
        ));
        c.open(format!(
            "static inline int {prefix}_sample_direction({wp}const float wi[3], const float u[2], unsigned steps, float wo[3]) {{"
        ));
        c.line(format!(
            "{prefix}_Result r = {prefix}_direction_impl({wa}wi[0], wi[1], wi[2], u[0], u[1], steps);"
        ));
        c.line("wo[0] = r.x;");
        c.line("wo[1] = r.y;");
        c.line("wo[2] = r.z;");
        c.line(format!("return r.pdf > 0.0f ? {up}_OK : {up}_NO_SAMPLE;"));
        c.close("}");
        c.blank();
    }
    if ep.sample {
        c.line(format!(
            "/* A direction and its PDF per unit solid angle. Returns {up}_OK, or {up}_NO_SAMPLE with zeros. */"
        ));
        c.open(format!(
            "static inline int {prefix}_sample({wp}const float wi[3], const float u[2], unsigned steps, float wo[3], float *pdf) {{"
        ));
        c.line(format!(
            "{prefix}_Result r = {prefix}_sample_impl({wa}wi[0], wi[1], wi[2], u[0], u[1], steps);"
        ));
        c.line("wo[0] = r.x;");
        c.line("wo[1] = r.y;");
        c.line("wo[2] = r.z;");
        c.line("*pdf = r.pdf;");
        c.line(format!("return r.pdf > 0.0f ? {up}_OK : {up}_NO_SAMPLE;"));
        c.close("}");
        c.blank();
    }
    if ep.pdf {
        c.line("/* The PDF with which sample() produces wo for wi; 0 when invalid. */");
        c.open(format!(
            "static inline float {prefix}_pdf({wp}const float wi[3], const float wo[3], unsigned steps) {{"
        ));
        c.line(format!(
            "return {prefix}_pdf_impl({wa}wi[0], wi[1], wi[2], wo[0], wo[1], wo[2], steps);"
        ));
        c.close("}");
        c.blank();
    }
    c.line(format!("#endif /* {up}_H */"));
    out.push_str(&c.finish());
    out
}

/// Turns the emitter's `//` line comments into C89-style `/* ... */`.
trait CommentEnds {
    fn replace_comment_ends(&self) -> String;
}

impl CommentEnds for String {
    fn replace_comment_ends(&self) -> String {
        let mut out = String::with_capacity(self.len() + 64);
        for line in self.lines() {
            out.push_str(line);
            if line.trim_start().starts_with("/* ") {
                out.push_str(" */");
            }
            out.push('\n');
        }
        out
    }
}
