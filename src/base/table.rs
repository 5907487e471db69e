//! The latent table (docs/math.md, §6.5; [`crate::ModelDef::latent_table`]): a density on
//! the unit square of `u` that the base distribution is drawn through, so that a model can
//! put more of its samples where its flow alone falls short of the target.
//!
//! Per incidence slice the table holds `(C + 1)^2` positive node values `v[i][j]`,
//! `C` = [`crate::spec::LATENT_TABLE_CELLS`], at `u = (i / C, j / C)`; its density is their bilinear
//! interpolation over the integral of that surface (74). A `wi` between two slices mixes
//! their node values linearly (75), which keeps the density bilinear on the same grid.
//! Sampling inverts the marginal CDF of `u_0` and then the conditional CDF of `u_1`, each
//! piecewise quadratic, by a scan over the cells and one quadratic per coordinate (76):
//! a continuous, increasing map of `[0, 1]^2` onto itself whose density is (74) exactly.
//! Every formula is a sum, a product, a division or a square root, written as the generated
//! GLSL, WGSL and C write it.

use crate::math::{ln, sqrt};
use crate::spec::{LATENT_TABLE_CELLS as C, LATENT_TABLE_SLICES as S};

/// Node values per side of a slice: `C + 1`.
pub const NODES: usize = C + 1;
/// Node values per slice.
pub const SLICE_LEN: usize = NODES * NODES;
/// Node values of the whole table, slice after slice, each row-major in `(i, j)`.
pub const TABLE_LEN: usize = S * SLICE_LEN;

/// The table's node values (positive and finite in every loaded model).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LatentTable {
    pub(crate) values: [f32; TABLE_LEN],
    /// Per slice `k`, the column integrals `M_k[i] = sum_j w_j v_k[i][j]` (trapezoid weights,
    /// `j` ascending), derived from `values` by [`LatentTable::prepare`]: a call mixes 2 x 17
    /// of them instead of summing 2 x 289 nodes. The generated code sums them per call in
    /// the same order, so both hold the same bits.
    columns: [f32; S * NODES],
}

/// The two slices a `wi` mixes: `k` and `k + 1`, the second with weight `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TableSlice {
    k: usize,
    t: f32,
}

impl TableSlice {
    /// The slices of `wi.z`: `s = (1 - sqrt(wi.z)) (S - 1)`, `k = min(floor(s), S - 2)`,
    /// `t = s - k` (docs/math.md, (75)); `wi.z` is clamped to `[0, 1]`.
    #[inline]
    #[must_use]
    pub(crate) fn of(wi_z: f32) -> Self {
        let s = (1.0 - sqrt(wi_z.clamp(0.0, 1.0))) * (S - 1) as f32;
        let k = (s as usize).min(S - 2);
        TableSlice { k, t: s - k as f32 }
    }
}

/// `wi.z` at the slice position `s` (in slices, `0 ..= S - 1`): the inverse of
/// the slices' `s = (1 - sqrt(wi.z)) (S - 1)`, `wi.z = (1 - s / (S - 1))^2`.
#[must_use]
pub fn slice_incidence(s: f64) -> f64 {
    let f = (s / (S - 1) as f64).clamp(0.0, 1.0);
    (1.0 - f) * (1.0 - f)
}

/// `0.5` at the grid's two ends, `1` inside: the trapezoid rule's weight of node `i` along
/// one axis (the bilinear surface's integral is `sum_ij w_i w_j v_ij / C^2`, (74)).
#[inline(always)]
#[must_use]
pub fn trapezoid(i: usize) -> f32 {
    if i == 0 || i == C {
        0.5
    } else {
        1.0
    }
}

/// The cell of `x` in `[0, C]` and the position in it: `(min(floor(x), C - 1), x - cell)`.
#[inline(always)]
fn cell(x: f32) -> (usize, f32) {
    let i = (x.max(0.0) as usize).min(C - 1);
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

/// Inverts the CDF of the piecewise-linear density with node values `m` at `u` in
/// `[0, 1]`: the cell whose cumulative area (the trapezoid rule) first reaches `u` times
/// the total, then [`cell_fraction`] in it; returns the point in `[0, 1]`.
#[inline(always)]
fn invert_linear(m: &[f32; NODES], total: f32, u: f32) -> f32 {
    let mut r = u * total;
    let mut i = 0;
    while i + 1 < C {
        let area = 0.5 * (m[i] + m[i + 1]);
        if r <= area {
            break;
        }
        r -= area;
        i += 1;
    }
    let a = cell_fraction(m[i], m[i + 1], r);
    ((i as f32 + a) / C as f32).clamp(0.0, 1.0)
}

impl LatentTable {
    /// Every node 1: the uniform density, the identity map.
    pub const UNIFORM: LatentTable = LatentTable {
        values: [1.0; TABLE_LEN],
        columns: [C as f32; S * NODES],
    };

    /// Derives the column integrals from the node values; called after every change of
    /// them.
    pub(crate) fn prepare(&mut self) {
        for (k, slice) in self.values.chunks_exact(SLICE_LEN).enumerate() {
            for (i, row) in slice.chunks_exact(NODES).enumerate() {
                let mut sum = 0.0;
                for (j, &v) in row.iter().enumerate() {
                    sum += trapezoid(j) * v;
                }
                if let Some(c) = self.columns.get_mut(k * NODES + i) {
                    *c = sum;
                }
            }
        }
    }

    /// The mixed node value `(1 - t) v_k[i][j] + t v_(k+1)[i][j]` (75).
    #[inline(always)]
    fn node(&self, sl: TableSlice, i: usize, j: usize) -> f32 {
        let at = |k: usize| {
            self.values
                .get(k * SLICE_LEN + i * NODES + j)
                .copied()
                .unwrap_or(1.0)
        };
        (1.0 - sl.t) * at(sl.k) + sl.t * at(sl.k + 1)
    }

    /// The column integrals of the mixed slice, `m_i = (1 - t) M_k[i] + t M_(k+1)[i]`
    /// (`docs/math.md`, (74), (75)): the marginal density of `u_0` at the nodes, times `C`
    /// over the total.
    #[inline(always)]
    fn columns(&self, sl: TableSlice) -> [f32; NODES] {
        let at = |k: usize, i: usize| self.columns.get(k * NODES + i).copied().unwrap_or(1.0);
        let mut m = [0.0; NODES];
        for (i, mi) in m.iter_mut().enumerate() {
            *mi = (1.0 - sl.t) * at(sl.k, i) + sl.t * at(sl.k + 1, i);
        }
        m
    }

    /// `sum_i w_i m_i`: `C^2` times the integral of the mixed bilinear surface.
    #[inline(always)]
    fn total(m: &[f32; NODES]) -> f32 {
        let mut sum = 0.0;
        for (i, mi) in m.iter().enumerate() {
            sum += trapezoid(i) * mi;
        }
        sum
    }

    /// The point of `[0, 1]^2` the table draws for the uniform `u` (docs/math.md, (76)):
    /// `u_0` through the marginal CDF, `u_1` through the conditional CDF at the drawn
    /// `u_0`.
    #[inline]
    #[must_use]
    pub(crate) fn warp(&self, sl: TableSlice, u: [f32; 2]) -> [f32; 2] {
        let m = self.columns(sl);
        let x0 = invert_linear(&m, Self::total(&m), u[0]);
        let (i, a) = cell(x0 * C as f32);
        let mut q = [0.0; NODES];
        for (j, qj) in q.iter_mut().enumerate() {
            *qj = (1.0 - a) * self.node(sl, i, j) + a * self.node(sl, i + 1, j);
        }
        let x1 = invert_linear(&q, Self::total(&q), u[1]);
        [x0, x1]
    }

    /// `ln` of the table's density at `x` in `[0, 1]^2` (docs/math.md, (74)): the mixed
    /// nodes' bilinear interpolation times `C^2` over their total.
    #[inline]
    #[must_use]
    pub(crate) fn ln_density(&self, sl: TableSlice, x: [f32; 2]) -> f32 {
        let m = self.columns(sl);
        let (i, a) = cell(x[0] * C as f32);
        let (j, b) = cell(x[1] * C as f32);
        let lo = (1.0 - b) * self.node(sl, i, j) + b * self.node(sl, i, j + 1);
        let hi = (1.0 - b) * self.node(sl, i + 1, j) + b * self.node(sl, i + 1, j + 1);
        let bilinear = (1.0 - a) * lo + a * hi;
        ln(bilinear * (C * C) as f32 / Self::total(&m))
    }

    /// The node values in blob order.
    pub(crate) fn visit(&self, f: &mut impl FnMut(f32)) {
        self.values.iter().for_each(|&v| f(v));
    }

    /// The node values in blob order, to be written.
    pub(crate) fn visit_mut(&mut self, f: &mut impl FnMut(&mut f32)) {
        self.values.iter_mut().for_each(f);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table whose slices differ: node values from a smooth positive function of
    /// `(k, i, j)` with a 20x range.
    fn bumpy() -> LatentTable {
        let mut t = LatentTable::UNIFORM;
        for k in 0..S {
            for i in 0..NODES {
                for j in 0..NODES {
                    let (x, y) = (i as f32 / C as f32, j as f32 / C as f32);
                    let v = 0.05 + (x - 0.3 - 0.01 * k as f32).powi(2) * 4.0 + y * y * (1.0 - x);
                    t.values[k * SLICE_LEN + i * NODES + j] = v;
                }
            }
        }
        t.prepare();
        t
    }

    fn density(t: &LatentTable, sl: TableSlice, x: [f32; 2]) -> f64 {
        f64::from(t.ln_density(sl, x)).exp()
    }

    #[test]
    fn the_density_integrates_to_one() {
        let t = bumpy();
        for wi_z in [1.0, 0.7, 0.2, 0.013, 0.0] {
            let sl = TableSlice::of(wi_z);
            let n = 400;
            let mut sum = 0.0;
            for a in 0..n {
                for b in 0..n {
                    let x = [(a as f32 + 0.5) / n as f32, (b as f32 + 0.5) / n as f32];
                    sum += density(&t, sl, x);
                }
            }
            let integral = sum / f64::from(n * n);
            assert!((integral - 1.0).abs() < 1e-4, "wi.z {wi_z}: {integral}");
        }
    }

    #[test]
    fn the_warp_is_increasing_and_its_jacobian_is_the_density() {
        let t = bumpy();
        let sl = TableSlice::of(0.4);
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
                let det = f64::from(x0p[0] - x[0]) * f64::from(x1p[1] - x[1]) / f64::from(h * h);
                let want = 1.0 / density(&t, sl, x);
                assert!(
                    (det / want - 1.0).abs() < 0.02,
                    "u {u:?}: det {det} vs {want}"
                );
            }
        }
    }

    #[test]
    fn the_uniform_table_is_the_identity() {
        let t = LatentTable::UNIFORM;
        let sl = TableSlice::of(0.5);
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
        assert_eq!(TableSlice::of(1.0), TableSlice { k: 0, t: 0.0 });
        let g = TableSlice::of(0.0);
        assert_eq!((g.k, g.t), (S - 2, 1.0));
        assert_eq!(TableSlice::of(f32::NAN).k, 0);
    }

    #[test]
    fn the_edges_of_the_square_map_to_its_edges() {
        let t = bumpy();
        let sl = TableSlice::of(0.1);
        assert_eq!(t.warp(sl, [0.0, 0.0]), [0.0, 0.0]);
        let x = t.warp(sl, [1.0, 1.0]);
        assert!(x[0] > 0.99999 && x[1] > 0.99999, "{x:?}");
    }
}
