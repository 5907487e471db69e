//! The latent table (docs/math.md, §6.5; [`crate::ModelDef::latent_table`]): a density on
//! the unit square of `u` that the base distribution is drawn through, so that a model can
//! put more of its samples where its flow alone falls short of the target.
//!
//! Per incidence slice the table holds `(C + 1)^2` positive node values `v[i][j]` at
//! `u = (i / C, j / C)`, `C` the grid's cells per side ([`TableGrid::cells`]: 32 where the
//! blob stores 8-bit codes, 16 in blobs written before them); its density is their bilinear
//! interpolation over the integral of that surface (74). A `wi` between two slices mixes
//! their node values linearly (75), which keeps the density bilinear on the same grid.
//! Sampling inverts the marginal CDF of `u_0` and then the conditional CDF of `u_1`, each
//! piecewise quadratic, by a scan over the cells and one quadratic per coordinate (76):
//! a continuous, increasing map of `[0, 1]^2` onto itself whose density is (74) exactly.
//! Every formula is a sum, a product, a division or a square root, written as the generated
//! GLSL, WGSL and C write it.

use super::table_axes;
use crate::def::Precision;
use crate::math::{ln, sqrt};
use crate::spec::{
    LATENT_TABLE_BLENDED_SLICES, LATENT_TABLE_CELLS, LATENT_TABLE_CODE_FRACTIONS,
    LATENT_TABLE_CODE_ONE, LATENT_TABLE_CODE_STEPS, LATENT_TABLE_MAX_SLICES as MAX_SLICES,
    LATENT_TABLE_SLICES, LATENT_TABLE_SLICE_BLEND, LATENT_TABLE_VALUE_CELLS,
    LATENT_TABLE_VALUE_MAX,
};

/// How a blob stores a latent table's nodes, and so its grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TableGrid {
    /// [`LATENT_TABLE_VALUE_CELLS`] (16) cells per side, each node a value of the blob's
    /// precision (flag bit 4 alone: blobs written before the coded table).
    Values,
    /// [`LATENT_TABLE_CELLS`] (32) cells per side, each node an 8-bit code of its value
    /// ([`code_value`]; flag bits 4 and 5; the blobs written before the axis warps).
    Codes,
    /// The coded grid with its two axis warps (`crate::base::table_axes`, docs/math.md,
    /// (81)): after the slices' nodes, `2 (C + 1)` more codes, the nodes of `g_0` then
    /// `g_1` (flag bits 4, 5 and 6; the blobs written before the blended layout).
    WarpedCodes,
    /// The warped coded grid on [`LATENT_TABLE_BLENDED_SLICES`] (40) incidence slices on the
    /// blended layout (docs/math.md, (82); flag bits 4, 5, 6 and 7). What the trainer writes.
    BlendedSlices,
}

impl TableGrid {
    /// Cells per side.
    #[must_use]
    pub const fn cells(self) -> usize {
        if self.is_coded() {
            LATENT_TABLE_CELLS
        } else {
            LATENT_TABLE_VALUE_CELLS
        }
    }

    /// Whether each node is an 8-bit code.
    #[must_use]
    pub const fn is_coded(self) -> bool {
        !matches!(self, TableGrid::Values)
    }

    /// Whether the grid's axes are warped (docs/math.md, (81)).
    #[must_use]
    pub const fn is_warped(self) -> bool {
        matches!(self, TableGrid::WarpedCodes | TableGrid::BlendedSlices)
    }

    /// Whether the slices lie on the blended layout (docs/math.md, (82)).
    #[must_use]
    pub const fn is_blended(self) -> bool {
        matches!(self, TableGrid::BlendedSlices)
    }

    /// Incidence slices.
    #[must_use]
    pub const fn slices(self) -> usize {
        if self.is_blended() {
            LATENT_TABLE_BLENDED_SLICES
        } else {
            LATENT_TABLE_SLICES
        }
    }

    /// The slice position `s` in `[0, S - 1]` of `wi.z` (clamped to `[0, 1]`; NaN stays NaN):
    /// `(1 - sqrt(wi.z)) (S - 1)` (75), or on the blended layout `x (b + (1 - b) x) (S - 1)`,
    /// `x = sqrt(1 - sqrt(wi.z))` (82).
    #[inline(always)]
    #[must_use]
    pub fn slice_position(self, wi_z: f32) -> f32 {
        let root = sqrt(wi_z.clamp(0.0, 1.0));
        let last = (self.slices() - 1) as f32;
        if self.is_blended() {
            let x = sqrt(1.0 - root);
            x * (LATENT_TABLE_SLICE_BLEND + (1.0 - LATENT_TABLE_SLICE_BLEND) * x) * last
        } else {
            (1.0 - root) * last
        }
    }

    /// Nodes per side: `cells + 1`.
    #[must_use]
    pub const fn nodes(self) -> usize {
        self.cells() + 1
    }

    /// Nodes per slice.
    #[must_use]
    pub const fn slice_len(self) -> usize {
        self.nodes() * self.nodes()
    }

    /// Nodes of the whole table, slice after slice (slice 0 at normal incidence), each
    /// row-major in `(i, j)`, `i` along `u_0`, then on a warped grid the axis warps'
    /// [`Self::axis_len`]: the blob's order.
    #[must_use]
    pub const fn node_count(self) -> usize {
        self.slices() * self.slice_len() + self.axis_len()
    }

    /// Nodes of the axis warps, `g_0` then `g_1`, `C + 1` each (0 where the grid has none).
    #[must_use]
    pub const fn axis_len(self) -> usize {
        if self.is_warped() {
            2 * self.nodes()
        } else {
            0
        }
    }

    /// Bytes one node takes in a blob of `precision`.
    #[must_use]
    pub const fn node_bytes(self, precision: Precision) -> usize {
        if self.is_coded() {
            1
        } else {
            precision.bytes()
        }
    }
}

/// Nodes per side of the finest grid.
pub const MAX_NODES: usize = LATENT_TABLE_CELLS + 1;

/// Bytes that hold either grid's nodes: one code per node, or four bytes of f32 per node.
const STORE_LEN: usize = {
    let codes = MAX_SLICES * MAX_NODES * MAX_NODES + 2 * MAX_NODES;
    let values =
        LATENT_TABLE_SLICES * (LATENT_TABLE_VALUE_CELLS + 1) * (LATENT_TABLE_VALUE_CELLS + 1) * 4;
    if codes > values {
        codes
    } else {
        values
    }
};

/// The node value code `c` stands for (docs/math.md, (79)): `2^((c - 80) / 16)` as
/// `LATENT_TABLE_CODE_FRACTIONS[r] * 2^q`, `c - 80 = 16 q + r`, exact; codes are 1 to 255.
#[must_use]
pub const fn code_value_f32(code: u8) -> f32 {
    let steps = LATENT_TABLE_CODE_STEPS as i32;
    let e = code as i32 - LATENT_TABLE_CODE_ONE as i32;
    let (q, r) = (e.div_euclid(steps), e.rem_euclid(steps));
    // 2^q for |q| < 127: the exponent field alone.
    let scale = f32::from_bits(((127 + q) as u32) << 23);
    LATENT_TABLE_CODE_FRACTIONS[r as usize] * scale
}

/// The node value code `c` stands for in a model of `precision`: [`code_value_f32`],
/// rounded to f16 in an f16 model (as its weights are, so the generated code's parameter
/// block holds the same value).
#[must_use]
pub fn code_value(code: u8, precision: Precision) -> f32 {
    let v = code_value_f32(code);
    match precision {
        Precision::F32 => v,
        Precision::F16 => half::f16::from_f32(v).to_f32(),
    }
}

/// The code nearest to `value` in the logarithm, `round(16 log2 value) + 80`; `None` where
/// `value` is not positive and finite or that code is outside 1..=255. A code's value (also
/// rounded to f16) gives its code back.
#[must_use]
pub fn encode(value: f32) -> Option<u8> {
    if !(value > 0.0 && value <= LATENT_TABLE_VALUE_MAX) {
        return None;
    }
    let steps = ln(value) * (f32::from(LATENT_TABLE_CODE_STEPS) / core::f32::consts::LN_2);
    let code = libm::roundf(steps) + f32::from(LATENT_TABLE_CODE_ONE);
    if (1.0..=255.0).contains(&code) {
        Some(code as u8)
    } else {
        None
    }
}

/// The table's node values (positive and finite in every loaded model).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LatentTable {
    grid: TableGrid,
    /// The nodes in blob order: one code per node ([`TableGrid::Codes`]) or the
    /// little-endian bytes of each node's f32 value ([`TableGrid::Values`]); both fit
    /// the same bytes, so a model's size does not depend on its grid.
    store: [u8; STORE_LEN],
    /// The node value of every code at the model's precision ([`code_value`]).
    code_values: [f32; 256],
    /// Per slice `k`, the column integrals `M_k[i] = sum_j w_j v_k[i][j]` (trapezoid weights,
    /// `j` ascending), derived from the nodes by [`LatentTable::prepare`]: a call mixes 2 x
    /// `(C + 1)` of them instead of summing 2 x `(C + 1)^2` nodes. The generated code sums
    /// them per call in the same order, so both hold the same bits.
    columns: [f32; MAX_SLICES * MAX_NODES],
    /// The axis warps' nodes `g_0`, `g_1` (docs/math.md, (81)); every node 1 (the identity)
    /// where the grid has none.
    axes: [[f32; MAX_NODES]; 2],
    /// `sum_i w_i g_a[i]` per axis, derived by [`LatentTable::prepare`] in the order the
    /// generated code sums them.
    axis_totals: [f32; 2],
}

/// The two slices a `wi` mixes: `k` and `k + 1`, the second with weight `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TableSlice {
    k: usize,
    t: f32,
}

impl TableSlice {
    /// The slices of `wi.z` on `grid`: `s` = [`TableGrid::slice_position`], `k = min(floor(s),
    /// S - 2)`, `t = s - k` (docs/math.md, (75), (82)); `wi.z` is clamped to `[0, 1]`.
    #[inline]
    #[must_use]
    pub(crate) fn of(grid: TableGrid, wi_z: f32) -> Self {
        let s = grid.slice_position(wi_z);
        let k = (s as usize).min(grid.slices() - 2);
        TableSlice { k, t: s - k as f32 }
    }
}

/// The two slices a `wi` with `wi.z` mixes on `grid`, as the kernel mixes them: the lower
/// slice `k` and the weight `t` of slice `k + 1` (docs/math.md, (75)).
#[must_use]
pub fn slice_pair(grid: TableGrid, wi_z: f32) -> (usize, f32) {
    let sl = TableSlice::of(grid, wi_z);
    (sl.k, sl.t)
}

/// `wi.z` at the slice position `s` (in slices, `0 ..= S - 1`) on `grid`: the inverse of
/// [`TableGrid::slice_position`], `wi.z = (1 - f)^2` with `f = s / (S - 1)` (75), or on the
/// blended layout `wi.z = (1 - x^2)^2` with `x` the root of `(1 - b) x^2 + b x = f` (82).
#[must_use]
pub fn slice_incidence(grid: TableGrid, s: f64) -> f64 {
    let f = (s / (grid.slices() - 1) as f64).clamp(0.0, 1.0);
    let root = if grid.is_blended() {
        let (b, c) = (
            f64::from(LATENT_TABLE_SLICE_BLEND),
            1.0 - f64::from(LATENT_TABLE_SLICE_BLEND),
        );
        let x = (libm::sqrt(b * b + 4.0 * c * f) - b) / (2.0 * c);
        1.0 - x * x
    } else {
        1.0 - f
    };
    root * root
}

/// `0.5` at the grid's two ends, `1` inside: the trapezoid rule's weight of node `i` along
/// one axis of a grid of `cells` cells (the bilinear surface's integral is
/// `sum_ij w_i w_j v_ij / C^2`, (74)).
#[inline(always)]
#[must_use]
pub fn trapezoid(i: usize, cells: usize) -> f32 {
    if i == 0 || i == cells {
        0.5
    } else {
        1.0
    }
}

/// The cell of `x` in `[0, C]` and the position in it: `(min(floor(x), C - 1), x - cell)`.
#[inline(always)]
pub(crate) fn cell(x: f32, cells: usize) -> (usize, f32) {
    let i = (x.max(0.0) as usize).min(cells - 1);
    (i, x - i as f32)
}

/// The fraction `a` of a cell whose linear density runs from `lo` to `hi` (both positive)
/// that holds the area `r` (in units of the cell's width): the root of
/// `lo a + (hi - lo) a^2 / 2 = r`, `a = 2 r / (lo + sqrt(lo^2 + 2 (hi - lo) r))`, which
/// does not cancel (docs/math.md, (76)); clamped to `[0, 1]`.
#[inline(always)]
fn cell_fraction(lo: f32, hi: f32, r: f32) -> f32 {
    let disc = (lo * lo + 2.0 * (hi - lo) * r).max(0.0);
    (2.0 * r / (lo + sqrt(disc))).clamp(0.0, 1.0)
}

/// Inverts the CDF of the piecewise-linear density with node values `m` (the first
/// `cells + 1`) at `u` in `[0, 1]`: the cell whose cumulative area (the trapezoid rule)
/// first reaches `u` times the total, then [`cell_fraction`] in it; returns the point in
/// `[0, 1]`.
#[inline(always)]
pub(crate) fn invert_linear(m: &[f32; MAX_NODES], cells: usize, total: f32, u: f32) -> f32 {
    let mut r = u * total;
    let mut i = 0;
    while i + 1 < cells {
        let area = 0.5 * (m[i] + m[i + 1]);
        if r <= area {
            break;
        }
        r -= area;
        i += 1;
    }
    let a = cell_fraction(m[i], m[i + 1], r);
    ((i as f32 + a) / cells as f32).clamp(0.0, 1.0)
}

/// `sum_i w_i m_i` over the first `cells + 1` entries: `C^2` times the integral of the
/// mixed bilinear surface.
#[inline(always)]
pub fn total(m: &[f32; MAX_NODES], cells: usize) -> f32 {
    let mut sum = 0.0;
    for (i, mi) in m.iter().take(cells + 1).enumerate() {
        sum += trapezoid(i, cells) * mi;
    }
    sum
}

/// Every code's value at `precision`.
fn code_values(precision: Precision) -> [f32; 256] {
    let mut values = [1.0; 256];
    for (c, v) in values.iter_mut().enumerate() {
        *v = code_value(c as u8, precision);
    }
    values
}

/// [`code_value_f32`] of every code, at compile time.
const CODE_VALUES_F32: [f32; 256] = {
    let mut values = [1.0; 256];
    let mut c = 0;
    while c < 256 {
        values[c] = code_value_f32(c as u8);
        c += 1;
    }
    values
};

impl LatentTable {
    /// Every node 1 (code [`LATENT_TABLE_CODE_ONE`]): the uniform density, the identity map.
    pub const UNIFORM: LatentTable = LatentTable {
        grid: TableGrid::Codes,
        store: [LATENT_TABLE_CODE_ONE; STORE_LEN],
        code_values: CODE_VALUES_F32,
        columns: [LATENT_TABLE_CELLS as f32; MAX_SLICES * MAX_NODES],
        axes: [[1.0; MAX_NODES]; 2],
        axis_totals: [LATENT_TABLE_CELLS as f32; 2],
    };

    /// Cells per side.
    #[inline(always)]
    fn cells(&self) -> usize {
        self.grid.cells()
    }

    /// The two slices `wi.z` mixes on this table's layout.
    #[inline(always)]
    pub(crate) fn slice(&self, wi_z: f32) -> TableSlice {
        TableSlice::of(self.grid, wi_z)
    }

    /// Node `n` in blob order.
    #[inline(always)]
    fn value(&self, n: usize) -> f32 {
        if self.grid.is_coded() {
            self.store
                .get(n)
                .map_or(1.0, |&c| self.code_values[usize::from(c)])
        } else {
            self.store
                .get(4 * n..4 * n + 4)
                .and_then(|b| b.try_into().ok())
                .map_or(1.0, f32::from_le_bytes)
        }
    }

    /// Whether `value` may be a node of a table on `grid` (checked before [`Self::load`]):
    /// in `(0, LATENT_TABLE_VALUE_MAX]`, and on the coded grid within the codes' range.
    #[must_use]
    pub(crate) fn accepts(grid: TableGrid, value: f32) -> bool {
        if grid.is_coded() {
            encode(value).is_some()
        } else {
            value > 0.0 && value <= LATENT_TABLE_VALUE_MAX
        }
    }

    /// Replaces the nodes by `grid.node_count()` values from `next` (blob order, each accepted by
    /// [`Self::accepts`]): on the coded grid each is stored as its nearest code, as an f16
    /// blob rounds a weight to f16. Derives the column integrals.
    pub(crate) fn load(
        &mut self,
        grid: TableGrid,
        precision: Precision,
        next: &mut impl FnMut() -> f32,
    ) {
        self.grid = grid;
        self.code_values = code_values(precision);
        if grid.is_coded() {
            for c in self.store.iter_mut().take(grid.node_count()) {
                *c = encode(next()).unwrap_or(LATENT_TABLE_CODE_ONE);
            }
        } else {
            for b in self.store.chunks_exact_mut(4).take(grid.node_count()) {
                b.copy_from_slice(&next().to_le_bytes());
            }
        }
        self.prepare();
    }

    /// Derives the column integrals and the axis warps from the nodes.
    fn prepare(&mut self) {
        let (cells, nodes) = (self.cells(), self.grid.nodes());
        let first_axis = self.grid.slices() * self.grid.slice_len();
        for a in 0..2 {
            for i in 0..MAX_NODES {
                self.axes[a][i] = if self.grid.is_warped() && i < nodes {
                    self.value(first_axis + a * nodes + i)
                } else {
                    1.0
                };
            }
            self.axis_totals[a] = total(&self.axes[a], cells);
        }
        for k in 0..self.grid.slices() {
            for i in 0..nodes {
                let first = k * self.grid.slice_len() + i * nodes;
                let mut sum = 0.0;
                for j in 0..nodes {
                    sum += trapezoid(j, cells) * self.value(first + j);
                }
                if let Some(c) = self.columns.get_mut(k * MAX_NODES + i) {
                    *c = sum;
                }
            }
        }
    }

    /// The mixed node value `(1 - t) v_k[i][j] + t v_(k+1)[i][j]` (75).
    #[inline(always)]
    fn node(&self, sl: TableSlice, i: usize, j: usize) -> f32 {
        let at = sl.k * self.grid.slice_len() + i * self.grid.nodes() + j;
        (1.0 - sl.t) * self.value(at) + sl.t * self.value(at + self.grid.slice_len())
    }

    /// The column integrals of the mixed slice, `m_i = (1 - t) M_k[i] + t M_(k+1)[i]`
    /// (`docs/math.md`, (74), (75)): the marginal density of `u_0` at the nodes, times `C`
    /// over the total.
    #[inline(always)]
    fn columns(&self, sl: TableSlice) -> [f32; MAX_NODES] {
        let at = |k: usize, i: usize| self.columns.get(k * MAX_NODES + i).copied().unwrap_or(1.0);
        let mut m = [0.0; MAX_NODES];
        for (i, mi) in m.iter_mut().take(self.grid.nodes()).enumerate() {
            *mi = (1.0 - sl.t) * at(sl.k, i) + sl.t * at(sl.k + 1, i);
        }
        m
    }

    /// The point of `[0, 1]^2` the table draws for the uniform `u` (docs/math.md, (76)):
    /// `u_0` through the marginal CDF, `u_1` through the conditional CDF at the drawn
    /// `u_0`.
    #[inline]
    #[must_use]
    pub(crate) fn warp(&self, sl: TableSlice, u: [f32; 2]) -> [f32; 2] {
        let cells = self.cells();
        let m = self.columns(sl);
        let x0 = invert_linear(&m, cells, total(&m, cells), u[0]);
        let (i, a) = cell(x0 * cells as f32, cells);
        let mut q = [0.0; MAX_NODES];
        for (j, qj) in q.iter_mut().take(cells + 1).enumerate() {
            *qj = (1.0 - a) * self.node(sl, i, j) + a * self.node(sl, i + 1, j);
        }
        let x1 = invert_linear(&q, cells, total(&q, cells), u[1]);
        if self.grid.is_warped() {
            // Then through the axis warps (docs/math.md, (81)).
            let w = |a: usize, x: f32| {
                table_axes::forward(&self.axes[a], cells, self.axis_totals[a], x)
            };
            [w(0, x0), w(1, x1)]
        } else {
            [x0, x1]
        }
    }

    /// `ln` of the table's density at `x` in `[0, 1]^2` (docs/math.md, (74)): the mixed
    /// nodes' bilinear interpolation times `C^2` over their total.
    #[inline]
    #[must_use]
    pub(crate) fn ln_density(&self, sl: TableSlice, x: [f32; 2]) -> f32 {
        let cells = self.cells();
        if self.grid.is_warped() {
            // The table's point is w^-1 of x, and the warps' slopes divide (81).
            let axis = |a: usize| {
                let (g, t) = (&self.axes[a], self.axis_totals[a]);
                let back = table_axes::inverse(g, cells, t, x[a]);
                (back, table_axes::slope(g, cells, t, back))
            };
            let ((x0, s0), (x1, s1)) = (axis(0), axis(1));
            return self.ln_density_on_grid(sl, [x0, x1], s0 * s1);
        }
        self.ln_density_on_grid(sl, x, 1.0)
    }

    /// `ln` of the bilinear density at the table's point `x`, over `stretch` (the axis
    /// warps' slopes; 1, dividing nothing, without them).
    #[inline(always)]
    fn ln_density_on_grid(&self, sl: TableSlice, x: [f32; 2], stretch: f32) -> f32 {
        let cells = self.cells();
        let m = self.columns(sl);
        let (i, a) = cell(x[0] * cells as f32, cells);
        let (j, b) = cell(x[1] * cells as f32, cells);
        let lo = (1.0 - b) * self.node(sl, i, j) + b * self.node(sl, i, j + 1);
        let hi = (1.0 - b) * self.node(sl, i + 1, j) + b * self.node(sl, i + 1, j + 1);
        let bilinear = (1.0 - a) * lo + a * hi;
        let density = bilinear * (cells * cells) as f32 / total(&m, cells);
        if self.grid.is_warped() {
            ln(density / stretch)
        } else {
            ln(density)
        }
    }

    /// The node values in blob order (a code's value at the model's precision).
    pub(crate) fn visit(&self, f: &mut impl FnMut(f32)) {
        (0..self.grid.node_count()).for_each(|n| f(self.value(n)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table on `grid` whose slices differ: node values from a smooth positive function of
    /// `(k, i, j)` with a 20x range.
    fn bumpy(grid: TableGrid) -> LatentTable {
        let (c, nodes) = (grid.cells(), grid.nodes());
        let mut n = 0;
        let mut next = || {
            let (k, i, j) = (n / grid.slice_len(), (n / nodes) % nodes, n % nodes);
            n += 1;
            let (x, y) = (i as f32 / c as f32, j as f32 / c as f32);
            0.05 + (x - 0.3 - 0.01 * k as f32).powi(2) * 4.0 + y * y * (1.0 - x)
        };
        let mut t = LatentTable::UNIFORM;
        t.load(grid, Precision::F32, &mut next);
        t
    }

    const GRIDS: [TableGrid; 4] = [
        TableGrid::Codes,
        TableGrid::Values,
        TableGrid::WarpedCodes,
        TableGrid::BlendedSlices,
    ];

    fn density(t: &LatentTable, sl: TableSlice, x: [f32; 2]) -> f64 {
        f64::from(t.ln_density(sl, x)).exp()
    }

    #[test]
    fn the_density_integrates_to_one() {
        for grid in GRIDS {
            let t = bumpy(grid);
            for wi_z in [1.0, 0.7, 0.2, 0.013, 0.0] {
                let sl = TableSlice::of(grid, wi_z);
                let n = 400;
                let mut sum = 0.0;
                for a in 0..n {
                    for b in 0..n {
                        let x = [(a as f32 + 0.5) / n as f32, (b as f32 + 0.5) / n as f32];
                        sum += density(&t, sl, x);
                    }
                }
                let integral = sum / f64::from(n * n);
                assert!(
                    (integral - 1.0).abs() < 1e-4,
                    "{grid:?} wi.z {wi_z}: {integral}"
                );
            }
        }
    }

    #[test]
    fn the_warp_is_increasing_and_its_jacobian_is_the_density() {
        for grid in GRIDS {
            let t = bumpy(grid);
            let sl = TableSlice::of(grid, 0.4);
            let h = 1e-3f32;
            for a in 1..40 {
                for b in 1..40 {
                    let u = [a as f32 / 40.0, b as f32 / 40.0];
                    let x = t.warp(sl, u);
                    let x0p = t.warp(sl, [u[0] + h, u[1]]);
                    let x1p = t.warp(sl, [u[0], u[1] + h]);
                    // The map is triangular: u_1 moves only x_1, and both move forwards.
                    assert_eq!(x1p[0], x[0]);
                    assert!(x0p[0] > x[0] && x1p[1] > x[1], "not increasing at {u:?}");
                    // det = dx0/du0 dx1/du1 = 1 / density (the second column's x_0 part is 0).
                    let det =
                        f64::from(x0p[0] - x[0]) * f64::from(x1p[1] - x[1]) / f64::from(h * h);
                    let want = 1.0 / density(&t, sl, x);
                    assert!(
                        (det / want - 1.0).abs() < 0.03,
                        "{grid:?} u {u:?}: det {det} vs {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_uniform_table_is_the_identity() {
        let t = LatentTable::UNIFORM;
        let sl = TableSlice::of(TableGrid::Codes, 0.5);
        for a in 0..=20 {
            for b in 0..=20 {
                let u = [a as f32 / 20.0, b as f32 / 20.0];
                let x = t.warp(sl, u);
                assert!((x[0] - u[0]).abs() < 1e-6 && (x[1] - u[1]).abs() < 1e-6);
                assert!(t.ln_density(sl, u).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn slices_cover_normal_to_grazing_incidence() {
        for grid in GRIDS {
            assert_eq!(TableSlice::of(grid, 1.0), TableSlice { k: 0, t: 0.0 });
            let g = TableSlice::of(grid, 0.0);
            assert_eq!((g.k, g.t), (grid.slices() - 2, 1.0));
            assert_eq!(TableSlice::of(grid, f32::NAN).k, 0);
        }
        assert_eq!(TableGrid::WarpedCodes.slices(), 32);
        assert_eq!(TableGrid::BlendedSlices.slices(), 40);
    }

    /// `slice_incidence` inverts the slice position on both layouts; the blended one puts
    /// its first slice within 6 degrees of the normal (the even one at 20.5) and keeps its
    /// slices past 80 degrees at most 1.6 degrees apart, as the even one.
    #[test]
    fn slice_positions_invert_and_the_blended_layout_is_dense_at_both_ends() {
        for grid in [TableGrid::WarpedCodes, TableGrid::BlendedSlices] {
            let last = (grid.slices() - 1) as f64;
            for i in 0..=1000 {
                let s = last * f64::from(i) / 1000.0;
                let z = slice_incidence(grid, s);
                let back = f64::from(grid.slice_position(z as f32));
                assert!((back - s).abs() < 2e-3 * last, "{grid:?} s {s}: {back}");
            }
            let theta = |k: usize| libm::acos(slice_incidence(grid, k as f64)).to_degrees();
            let first = theta(1);
            let widest_past_80 = (1..grid.slices())
                .filter(|&k| theta(k) > 80.0)
                .map(|k| theta(k) - theta(k - 1))
                .fold(0.0, f64::max);
            if grid.is_blended() {
                assert!(first < 6.0, "{first}");
            } else {
                assert!(first > 20.0, "{first}");
            }
            assert!(widest_past_80 < 1.6, "{grid:?}: {widest_past_80}");
        }
    }

    #[test]
    fn the_edges_of_the_square_map_to_its_edges() {
        for grid in GRIDS {
            let t = bumpy(grid);
            let sl = TableSlice::of(grid, 0.1);
            assert_eq!(t.warp(sl, [0.0, 0.0]), [0.0, 0.0]);
            let x = t.warp(sl, [1.0, 1.0]);
            assert!(x[0] > 0.99999 && x[1] > 0.99999, "{x:?}");
        }
    }

    /// Every code's value, also rounded to f16, gives its code back; values between two
    /// codes go to the nearer one in the logarithm; the range ends are refused.
    #[test]
    fn codes_round_trip_and_refuse_what_they_cannot_hold() {
        for c in 1..=255u8 {
            assert_eq!(encode(code_value(c, Precision::F32)), Some(c));
            assert_eq!(encode(code_value(c, Precision::F16)), Some(c));
            let exact = libm::exp2((f64::from(c) - 80.0) / 16.0);
            assert_eq!(code_value_f32(c), exact as f32, "code {c}");
        }
        assert_eq!(code_value_f32(LATENT_TABLE_CODE_ONE), 1.0);
        let between = libm::exp2f(0.4 / 16.0);
        assert_eq!(encode(between), Some(LATENT_TABLE_CODE_ONE));
        assert_eq!(
            encode(libm::exp2f(0.6 / 16.0)),
            Some(LATENT_TABLE_CODE_ONE + 1)
        );
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY, 1e-3, 3000.0] {
            assert_eq!(encode(bad), None, "{bad}");
        }
    }

    /// Loading the values a table reads back stores the same table.
    #[test]
    fn a_table_reloads_from_its_own_values() {
        for grid in GRIDS {
            let t = bumpy(grid);
            let mut values = [0.0f32; STORE_LEN];
            let mut n = 0;
            t.visit(&mut |v| {
                values[n] = v;
                n += 1;
            });
            assert_eq!(n, grid.node_count());
            let mut again = LatentTable::UNIFORM;
            let mut it = values.iter();
            again.load(grid, Precision::F32, &mut || *it.next().unwrap());
            assert_eq!(again, t);
        }
    }
}
