//! Mirrors `src/base/table.rs` and `gaussian::cdf`: the latent table's bilinear density,
//! the map that draws `u` through it, and the normal CDF that reads a start point back
//! into the table's square (docs/math.md, §6.5, (73)-(77)), in the kernel's operation
//! order.

use super::Emitter;
use crate::dialect::{Math, T};
use diffbsdf::spec::{ERFC_POLY, LATENT_TABLE_SLICE_BLEND};
use diffbsdf::TableGrid;

impl Emitter<'_> {
    /// Whether the model draws `u` through a latent table.
    pub(super) fn table(&self) -> bool {
        self.m.def.latent_table.is_some()
    }

    /// Whether the table's axes are warped (docs/math.md, (81)).
    pub(super) fn table_axes(&self) -> bool {
        self.m.def.latent_table.is_some_and(TableGrid::is_warped)
    }

    /// The table's grid (the coded one where the model has none: nothing is emitted then).
    fn table_grid(&self) -> TableGrid {
        self.m.def.latent_table.unwrap_or(TableGrid::Codes)
    }

    /// Cells per side of the table's grid.
    fn table_cells(&self) -> usize {
        self.table_grid().cells()
    }

    /// Nodes per side of the table's grid.
    pub(super) fn table_nodes(&self) -> usize {
        self.table_grid().nodes()
    }

    /// Incidence slices of the table.
    fn table_slice_count(&self) -> usize {
        self.table_grid().slices()
    }

    /// Nodes per slice.
    fn table_slice_len(&self) -> usize {
        self.table_grid().slice_len()
    }

    /// The table's first node value in the parameter block (after the nets' weights).
    fn table_offset(&self) -> usize {
        self.m.def.param_count() - self.m.def.table_len()
    }

    /// The slices of `wi.z = enc.e[2]` into `r.tk`, `r.tt` (docs/math.md, (75), (82));
    /// inside `condition`.
    pub(super) fn table_slices(&mut self) {
        let slices = self.table_slice_count();
        let (zero, one) = (self.f(0.0), self.f(1.0));
        let z = self.d.clamp("enc.e[2]", &zero, &one);
        let root = self.math(Math::Sqrt, &z);
        let last = self.f((slices - 1) as f32);
        if self.table_grid().is_blended() {
            self.code.line(
                "// The latent table's two slices for wi.z on the blended layout, s = x (b + (1 - b) x) (S - 1), x = sqrt(1 - sqrt(wi.z)), and the second's weight (docs/math.md, (75), (82)).",
            );
            let x = self.math(Math::Sqrt, &format!("{one} - {root}"));
            self.decl(T::F, "tx", &x);
            let b = self.f(LATENT_TABLE_SLICE_BLEND);
            let c = self.f(1.0 - LATENT_TABLE_SLICE_BLEND);
            self.decl(T::F, "ts", &format!("tx * ({b} + {c} * tx) * {last}"));
        } else {
            self.code
                .line("// The latent table's two slices for wi.z and the second's weight (docs/math.md, (75)).");
            self.decl(T::F, "ts", &format!("({one} - {root}) * {last}"));
        }
        self.code
            .line(format!("r.tk = {};", self.d.cast(&T::U, "ts")));
        let last = self.u(slices - 2);
        self.code.open(format!("if (r.tk > {last}) {{"));
        self.code.line(format!("r.tk = {last};"));
        self.code.close("}");
        self.code
            .line(format!("r.tt = ts - {};", self.d.cast(&T::F, "r.tk")));
    }

    /// `Phi(z) = erfc(-z / sqrt 2) / 2` (docs/math.md, (73)).
    pub(super) fn normal_cdf(&mut self) {
        self.code.line(
            "// The standard normal CDF Phi(z) = erfc(-z / sqrt 2) / 2, erfc by its Chebyshev fit (docs/math.md, (73)).",
        );
        self.fn_open(T::F, "normal_cdf", false, &[(T::F, "z")]);
        let x = format!(
            "{} * {}",
            self.math(Math::Abs, "z"),
            self.f(core::f32::consts::FRAC_1_SQRT_2)
        );
        self.decl(T::F, "x", &x);
        let one = self.f(1.0);
        self.decl(T::F, "w", &format!("{one} / ({one} + {} * x)", self.f(0.5)));
        self.decl(T::F, "p", &self.f(0.0));
        self.poly(&ERFC_POLY);
        let e = self.math(Math::Exp, "p - x * x");
        self.decl(T::F, "tail", &format!("{} * w * {e}", self.f(0.5)));
        self.code.open(format!("if (z > {}) {{", self.f(0.0)));
        self.code.line(format!("return {one} - tail;"));
        self.code.close("}");
        self.code.line("return tail;");
        self.end_fn();
    }

    /// The mixed node value `(1 - t) v_k[i][j] + t v_(k+1)[i][j]` (75).
    pub(super) fn table_node(&mut self) {
        self.code
            .line("// A node of the latent table, mixed between the wi's two slices (docs/math.md, (75)).");
        let ps = [(self.st("Cond"), "cond"), (T::U, "i"), (T::U, "j")];
        self.fn_open(T::F, "table_node", true, &ps);
        let (slice_len, nodes) = (self.table_slice_len(), self.table_nodes());
        let at = format!(
            "{}u + cond.tk * {slice_len}u + i * {nodes}u + j",
            self.table_offset(),
        );
        self.decl(T::U, "at", &at);
        let lo = self.d.to_f32(&self.w("at".into()));
        let hi = self.d.to_f32(&self.w(format!("at + {slice_len}u")));
        let one = self.f(1.0);
        self.code
            .line(format!("return ({one} - cond.tt) * {lo} + cond.tt * {hi};"));
        self.end_fn();
    }

    /// The fraction of a linear cell from `lo` to `hi` that holds the area `r` (76).
    pub(super) fn table_fraction(&mut self) {
        self.code.line(
            "// The fraction a of a cell, density lo to hi, holding area r: 2r / (lo + sqrt(lo^2 + 2 (hi - lo) r)) (docs/math.md, (76)).",
        );
        let ps = [(T::F, "lo"), (T::F, "hi"), (T::F, "r")];
        self.fn_open(T::F, "table_fraction", false, &ps);
        let mx = self.d.math(Math::Max);
        let (zero, one, two) = (self.f(0.0), self.f(1.0), self.f(2.0));
        self.decl(
            T::F,
            "disc",
            &format!("{mx}(lo * lo + {two} * (hi - lo) * r, {zero})"),
        );
        let root = self.math(Math::Sqrt, "disc");
        let a = format!("{two} * r / (lo + {root})");
        self.code
            .line(format!("return {};", self.d.clamp(&a, &zero, &one)));
        self.end_fn();
    }

    /// The function returning the mixed slice's column integrals `m[i] = (1 - t) M_k[i] + t
    /// M_(k+1)[i]`, `M_k[i] = sum_j w_j v_k[i][j]` (trapezoid weights, `j` ascending: the
    /// kernel's `LatentTable::prepare`), and their total `tot = sum_i w_i m[i]` (74), (75):
    /// one function for the map and the density.
    pub(super) fn table_columns(&mut self) {
        self.code.line(
            "// The mixed slice's column integrals and their total (docs/math.md, (74), (75)).",
        );
        let cols_t = self.st("Cols");
        self.fn_open(
            cols_t.clone(),
            "table_columns",
            true,
            &[(self.st("Cond"), "cond")],
        );
        let r = self.d.decl(&cols_t, "r", None);
        self.code.line(r);
        let arr = "r.m";
        let (slice_len, nodes) = (self.table_slice_len(), self.table_nodes());
        self.for_open("ci", &self.u(nodes));
        let (zero, one) = (self.f(0.0), self.f(1.0));
        self.decl(T::F, "sa", &zero);
        self.decl(T::F, "sb", &zero);
        self.for_open("cj", &self.u(nodes));
        self.trapezoid("cj");
        let at = format!(
            "{}u + cond.tk * {slice_len}u + ci * {nodes}u + cj",
            self.table_offset()
        );
        self.decl(T::U, "at", &at);
        let va = self.d.to_f32(&self.w("at".into()));
        let vb = self.d.to_f32(&self.w(format!("at + {slice_len}u")));
        self.code.line(format!("sa = sa + tw * {va};"));
        self.code.line(format!("sb = sb + tw * {vb};"));
        self.code.close("}");
        self.code.line(format!(
            "{arr}[ci] = ({one} - cond.tt) * sa + cond.tt * sb;"
        ));
        self.code.close("}");
        self.table_total(arr, "tm");
        self.code.line("r.tot = tm;");
        self.code.line("return r;");
        self.end_fn();
    }

    /// `cm`: the column integrals of the wi's mixed slice, by `table_columns`.
    fn table_columns_call(&mut self) {
        let call = self.call("table_columns", true, &["cond"]);
        self.decl(self.st("Cols"), "cm", &call);
    }

    /// `tot = sum_i w_i arr[i]`.
    fn table_total(&mut self, arr: &str, tot: &str) {
        self.decl(T::F, tot, &self.f(0.0));
        self.for_open("ti", &self.u(self.table_nodes()));
        self.trapezoid("ti");
        self.code.line(format!("{tot} = {tot} + tw * {arr}[ti];"));
        self.code.close("}");
    }

    /// `tw`: the trapezoid weight of node `i` (0.5 at the ends, 1 inside).
    fn trapezoid(&mut self, i: &str) {
        self.decl(T::F, "tw", &self.f(1.0));
        self.code.open(format!(
            "if ({i} == 0u || {i} == {}) {{",
            self.u(self.table_cells())
        ));
        self.code.line(format!("tw = {};", self.f(0.5)));
        self.code.close("}");
    }

    /// `out`: the point of `[0, 1]` where the CDF of the piecewise-linear density `arr`
    /// (total `tot`) reaches `u` (76).
    fn table_invert(&mut self, arr: &str, tot: &str, u: &str, out: &str) {
        self.decl(T::F, "rem", &format!("{u} * {tot}"));
        self.decl(T::U, "cell", &self.u(0));
        self.for_open("n", &self.u(self.table_cells() - 1));
        let half = self.f(0.5);
        self.decl(
            T::F,
            "area",
            &format!("{half} * ({arr}[cell] + {arr}[cell + 1u])"),
        );
        self.code.open("if (rem <= area) {");
        self.code.line("break;");
        self.code.close("}");
        self.code.line("rem = rem - area;");
        self.code.line("cell = cell + 1u;");
        self.code.close("}");
        let frac = self.call(
            "table_fraction",
            false,
            &[&format!("{arr}[cell]"), &format!("{arr}[cell + 1u]"), "rem"],
        );
        let pos = format!(
            "({} + {frac}) / {}",
            self.d.cast(&T::F, "cell"),
            self.f(self.table_cells() as f32)
        );
        let (zero, one) = (self.f(0.0), self.f(1.0));
        self.decl(T::F, out, &self.d.clamp(&pos, &zero, &one));
    }

    /// `(ci, ca)`: the cell of `x` in `[0, C]` and the position in it.
    fn table_cell(&mut self, x: &str, i: &str, a: &str) {
        let mx = self.d.math(Math::Max);
        let cx = self.d.cast(&T::U, &format!("{mx}({x}, {})", self.f(0.0)));
        self.decl(T::U, i, &cx);
        let last = self.u(self.table_cells() - 1);
        self.code.open(format!("if ({i} > {last}) {{"));
        self.code.line(format!("{i} = {last};"));
        self.code.close("}");
        self.decl(T::F, a, &format!("{x} - {}", self.d.cast(&T::F, i)));
    }

    /// The point of `[0, 1]^2` the table draws for `u` (76).
    pub(super) fn table_warp(&mut self) {
        self.code.line(
            "// u drawn through the latent table: u0 by the marginal CDF, u1 by the conditional one (docs/math.md, (76)).",
        );
        let ps = [(self.st("Cond"), "cond"), (T::F, "u0"), (T::F, "u1")];
        let vec_t = self.st("Vec2");
        self.fn_open(vec_t.clone(), "table_warp", true, &ps);
        self.table_columns_call();
        self.table_invert("cm.m", "cm.tot", "u0", "x0");
        let c = self.f(self.table_cells() as f32);
        self.table_cell(&format!("x0 * {c}"), "i", "a");
        let nodes = self.table_nodes();
        self.arr(T::F, nodes, "cq");
        let one = self.f(1.0);
        self.for_open("qj", &self.u(nodes));
        let lo = self.call("table_node", true, &["cond", "i", "qj"]);
        let hi = self.call("table_node", true, &["cond", "i + 1u", "qj"]);
        self.code
            .line(format!("cq[qj] = ({one} - a) * {lo} + a * {hi};"));
        self.code.close("}");
        self.table_total("cq", "tq");
        self.code.open("{");
        self.table_invert("cq", "tq", "u1", "x1");
        let r = self.d.decl(&vec_t, "r", None);
        self.code.line(r);
        if self.table_axes() {
            self.code
                .line("// Then through the axis warps (docs/math.md, (81)).");
            for (a, (x, field)) in [("x0", "x"), ("x1", "y")].into_iter().enumerate() {
                let g = self.call("table_axis", true, &[&self.u(a)]);
                self.decl(self.st("Cols"), &format!("g{a}"), &g);
                let w = self.call("table_axis_forward", false, &[&format!("g{a}"), x]);
                self.code.line(format!("r.{field} = {w};"));
            }
        } else {
            self.code.line("r.x = x0;");
            self.code.line("r.y = x1;");
        }
        self.code.line("return r;");
        self.code.close("}");
        self.end_fn();
    }

    /// `ln` of the table's density at `(x0, x1)` (74).
    pub(super) fn table_ln_density(&mut self) {
        self.code.line(
            "// ln of the latent table's density: the mixed nodes' bilinear interpolation times C^2 over their total (docs/math.md, (74)).",
        );
        let ps = [(self.st("Cond"), "cond"), (T::F, "x0"), (T::F, "x1")];
        self.fn_open(T::F, "table_ln_density", true, &ps);
        // With axis warps, the table's point is w^-1 of x and their slopes divide (81).
        let (p0, p1) = if self.table_axes() {
            for a in 0..2 {
                let g = self.call("table_axis", true, &[&self.u(a)]);
                self.decl(self.st("Cols"), &format!("g{a}"), &g);
                let (ga, xa, ya) = (format!("g{a}"), format!("x{a}"), format!("y{a}"));
                let back = self.call("table_axis_inverse", false, &[&ga, &xa]);
                self.decl(T::F, &ya, &back);
                let slope = self.call("table_axis_slope", false, &[&ga, &ya]);
                self.decl(T::F, &format!("s{a}"), &slope);
            }
            ("y0", "y1")
        } else {
            ("x0", "x1")
        };
        self.table_columns_call();
        let cells = self.table_cells();
        let c = self.f(cells as f32);
        self.table_cell(&format!("{p0} * {c}"), "i", "a");
        self.table_cell(&format!("{p1} * {c}"), "j", "b");
        let one = self.f(1.0);
        let n = |e: &Self, i: &str, j: &str| e.call("table_node", true, &["cond", i, j]);
        let lo = format!(
            "({one} - b) * {} + b * {}",
            n(self, "i", "j"),
            n(self, "i", "j + 1u")
        );
        let hi = format!(
            "({one} - b) * {} + b * {}",
            n(self, "i + 1u", "j"),
            n(self, "i + 1u", "j + 1u")
        );
        self.decl(T::F, "lo", &lo);
        self.decl(T::F, "hi", &hi);
        self.decl(T::F, "bil", &format!("({one} - a) * lo + a * hi"));
        let density = format!("bil * {} / cm.tot", self.f((cells * cells) as f32));
        let ln = if self.table_axes() {
            self.math(Math::Log, &format!("{density} / (s0 * s1)"))
        } else {
            self.math(Math::Log, &density)
        };
        self.code.line(format!("return {ln};"));
        self.end_fn();
    }

    /// The nodes of axis warp `a` (0 or 1) and their total, in the column integrals'
    /// struct (docs/math.md, (81)); the kernel's `LatentTable::prepare` sums them in the
    /// same order.
    pub(super) fn table_axis(&mut self) {
        self.code
            .line("// An axis warp's nodes g_a and their total (docs/math.md, (81)).");
        let cols_t = self.st("Cols");
        self.fn_open(cols_t.clone(), "table_axis", true, &[(T::U, "ax")]);
        let r = self.d.decl(&cols_t, "r", None);
        self.code.line(r);
        let nodes = self.table_nodes();
        let first = self.table_offset() + self.table_slice_count() * self.table_slice_len();
        self.for_open("gi", &self.u(nodes));
        let g = self
            .d
            .to_f32(&self.w(format!("{first}u + ax * {nodes}u + gi")));
        self.code.line(format!("r.m[gi] = {g};"));
        self.code.close("}");
        self.table_total("r.m", "gt");
        self.code.line("r.tot = gt;");
        self.code.line("return r;");
        self.end_fn();
    }

    /// `w_a(x)`: the area of `g_a` below `x` over its total (81), for the axis `g` that
    /// `table_axis` returns (read once per axis in each caller).
    pub(super) fn table_axis_forward(&mut self) {
        self.code.line(
            "// w_a(x): the area of g_a from 0 to x over its total, whole cells then a g_i + a^2 (g_(i+1) - g_i) / 2 (docs/math.md, (81)).",
        );
        let ps = [(self.st("Cols"), "g"), (T::F, "x")];
        self.fn_open(T::F, "table_axis_forward", false, &ps);
        let c = self.f(self.table_cells() as f32);
        self.table_cell(&format!("x * {c}"), "i", "a");
        let (zero, one, half) = (self.f(0.0), self.f(1.0), self.f(0.5));
        self.decl(T::F, "before", &zero);
        self.for_open("k", "i");
        self.code.line(format!(
            "before = before + {half} * (g.m[k] + g.m[k + 1u]);"
        ));
        self.code.close("}");
        self.decl(
            T::F,
            "within",
            &format!("a * (g.m[i] + {half} * (g.m[i + 1u] - g.m[i]) * a)"),
        );
        let y = self.d.clamp("(before + within) / g.tot", &zero, &one);
        self.code.line(format!("return {y};"));
        self.end_fn();
    }

    /// `w_a^-1(y)`: the table's inversion of a piecewise-linear CDF (76), (81).
    pub(super) fn table_axis_inverse(&mut self) {
        self.code
            .line("// w_a^-1(y), as the table inverts its CDFs (docs/math.md, (76), (81)).");
        let ps = [(self.st("Cols"), "g"), (T::F, "y")];
        self.fn_open(T::F, "table_axis_inverse", false, &ps);
        self.table_invert("g.m", "g.tot", "y", "x");
        self.code.line("return x;");
        self.end_fn();
    }

    /// `w_a'(x) = g_a(x) C / total` (81).
    pub(super) fn table_axis_slope(&mut self) {
        self.code
            .line("// w_a'(x) = g_a(x) C / total (docs/math.md, (81)).");
        let ps = [(self.st("Cols"), "g"), (T::F, "x")];
        self.fn_open(T::F, "table_axis_slope", false, &ps);
        let c = self.f(self.table_cells() as f32);
        self.table_cell(&format!("x * {c}"), "i", "a");
        let one = self.f(1.0);
        self.code.line(format!(
            "return (({one} - a) * g.m[i] + a * g.m[i + 1u]) * {c} / g.tot;"
        ));
        self.end_fn();
    }
}
