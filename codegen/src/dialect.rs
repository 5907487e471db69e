//! What a target language supplies to the shared emitter: type names, literals,
//! declarations, loops, function headers, struct declarations and builtin names. Each
//! language module (`glsl`, `wgsl`, `c`) implements this and writes its own public entry
//! points; the algorithm itself is written once, in `emit/`, so the three outputs
//! cannot drift apart. What differs between languages (types, literals, casts, builtins,
//! half-precision support) is answered here, never by a test on the language in `emit/`.

/// A type in generated code.
#[derive(Clone, Debug, PartialEq)]
pub enum T {
    /// f32 always: directions, flow state, densities.
    F,
    /// The network type: f32, or f16 in half-precision output.
    N,
    /// Unsigned 32-bit integer.
    U,
    /// Boolean (an `int` in C).
    B,
    /// Fixed-size array.
    Arr(Box<T>, usize),
    /// A struct of the generated code (full name).
    Struct(String),
}

/// Builtins the emitter calls.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Math {
    Exp,
    Log,
    Sqrt,
    Sin,
    Cos,
    Tanh,
    Sinh,
    Floor,
    Abs,
    Max,
}

/// The per-language syntax the shared emitter needs.
pub trait Dialect {
    /// Whether the network type is f16.
    fn half(&self) -> bool;
    /// Scalar or struct type name (arrays are spelled by `decl` and `param`).
    fn ty(&self, t: &T) -> String;
    /// A float literal of type `t` (`F` or `N`) that round-trips `v`.
    fn lit(&self, v: f32, t: &T) -> String;
    /// `true` / `false`.
    fn bool_lit(&self, b: bool) -> &'static str;
    /// A mutable local: `float x = init;` / `var x: f32 = init;`. Arrays take no init.
    fn decl(&self, t: &T, name: &str, init: Option<&str>) -> String;
    /// A function parameter.
    fn param(&self, t: &T, name: &str) -> String;
    /// `for (uint i = 0u; i < bound; i++) {`.
    fn for_open(&self, var: &str, bound: &str) -> String;
    /// A function header up to and including `{`.
    fn fn_open(&self, ret: &T, name: &str, params: &[String]) -> String;
    /// A struct declaration, as lines.
    fn struct_decl(&self, name: &str, fields: &[(T, &str)]) -> Vec<String>;
    /// Builtin name for `t` (`expf` in C, `exp` elsewhere).
    fn math(&self, f: Math) -> &'static str;
    /// Whether the networks' multiply-adds are fused ([`crate::Options::fused`]).
    fn fused(&self) -> bool;
    /// The fused multiply-add builtin (`fmaf` in C, `fma` elsewhere).
    fn fma_name(&self) -> &'static str;
    /// A network multiply-add `c + a * b`: `fma(a, b, c)` when fused (rounded once, as
    /// the kernel's `math::mul_add` with its `fma` feature), else the sum of the rounded
    /// product (as the default kernel).
    fn mad(&self, a: &str, b: &str, c: &str) -> String {
        if self.fused() {
            format!("{}({a}, {b}, {c})", self.fma_name())
        } else {
            format!("{c} + {a} * {b}")
        }
    }
    /// `atan2(y, x)` call.
    fn atan2(&self, y: &str, x: &str) -> String;
    /// `clamp(x, lo, hi)` call.
    fn clamp(&self, x: &str, lo: &str, hi: &str) -> String;
    /// Conversion to `t`.
    fn cast(&self, t: &T, e: &str) -> String;
    /// `e` (an f32 expression) as the network type: a cast in f16 output, else `e`.
    fn to_net(&self, e: &str) -> String {
        if self.half() {
            self.cast(&T::N, e)
        } else {
            e.to_string()
        }
    }
    /// `e` (a network-type expression) as f32: a cast in f16 output, else `e`.
    fn to_f32(&self, e: &str) -> String {
        if self.half() {
            self.cast(&T::F, e)
        } else {
            e.to_string()
        }
    }
    /// An expression that is true when the f32 `x` is neither infinite nor NaN, robust to
    /// compilers that assume no NaN in comparisons.
    fn finite(&self, x: &str) -> String;
    /// The declaration of the parameter-buffer argument threaded through every function
    /// in buffer mode (`uint base`, `base: u32`, `const float *params`), or `None`.
    fn weights_param(&self) -> Option<String>;
    /// The argument passed along for it (`base` / `params`).
    fn weights_arg(&self) -> Option<&'static str>;
    /// Parameter number `idx` (an integer expression), as an `N` expression.
    fn weight(&self, idx: &str) -> String;
    /// The constant name prefix and function name prefix.
    fn prefix(&self) -> &str;
}
