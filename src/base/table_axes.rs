//! The latent table's axis warps (docs/math.md, (81)): per axis of the square, a positive
//! piecewise-linear density `g` on the table's `C` cells, shared by every incidence slice.
//! Its CDF `w` carries the table's square onto the square the start point is read from,
//! so the table's cells, even in the table's own coordinates, are narrow where `w` rises
//! slowly: the resolution goes where the flow's weight varies fastest. The table's density
//! becomes `T(w(x)) = T_table(x) / (w0'(x0) w1'(x1))`, continuous since `g` is.
//!
//! Every formula is the table's own 1D machinery (the inversion of (76) for `w^-1`), written as
//! the generated GLSL, WGSL and C write it.

use super::table::{cell, invert_linear, MAX_NODES};

/// `w(x)`: the area of `g` from 0 to `x` over its total (`total = sum_i w_i g_i`, the
/// trapezoid rule in units of a cell), `x` in `[0, 1]`, clamped to `[0, 1]`: the whole
/// cells below `x`'s cell, then `a g_i + a^2 (g_(i+1) - g_i) / 2` in it.
#[inline(always)]
#[must_use]
pub fn forward(g: &[f32; MAX_NODES], cells: usize, total: f32, x: f32) -> f32 {
    let (i, a) = cell(x * cells as f32, cells);
    let mut before = 0.0;
    for k in 0..i {
        before += 0.5 * (g[k] + g[k + 1]);
    }
    let within = a * (g[i] + 0.5 * (g[i + 1] - g[i]) * a);
    ((before + within) / total).clamp(0.0, 1.0)
}

/// `w^-1(y)`: the table's own inversion of a piecewise-linear CDF (docs/math.md, (76)).
#[inline(always)]
#[must_use]
pub fn inverse(g: &[f32; MAX_NODES], cells: usize, total: f32, y: f32) -> f32 {
    invert_linear(g, cells, total, y)
}

/// `w'(x) = g(x) C / total`, `g(x)` the linear interpolation of the nodes.
#[inline(always)]
#[must_use]
pub fn slope(g: &[f32; MAX_NODES], cells: usize, total: f32, x: f32) -> f32 {
    let (i, a) = cell(x * cells as f32, cells);
    ((1.0 - a) * g[i] + a * g[i + 1]) * cells as f32 / total
}

#[cfg(test)]
mod tests {
    use super::super::table::total;
    use super::*;

    fn bumpy() -> [f32; MAX_NODES] {
        core::array::from_fn(|i| 1.0 + 0.6 * (i as f32 * 0.37).sin())
    }

    /// `w` runs from 0 to 1, increasing, `w^-1` undoes it, and `w'` is its slope.
    #[test]
    fn the_warp_is_an_increasing_map_of_the_interval_with_its_slope() {
        let g = bumpy();
        let c = MAX_NODES - 1;
        let t = total(&g, c);
        assert_eq!(forward(&g, c, t, 0.0), 0.0);
        assert!((forward(&g, c, t, 1.0) - 1.0).abs() < 1e-6);
        let n = 2000;
        let mut last = 0.0;
        for k in 1..n {
            let x = k as f32 / n as f32;
            let y = forward(&g, c, t, x);
            assert!(y > last, "not increasing at {x}");
            last = y;
            let back = inverse(&g, c, t, y);
            assert!((back - x).abs() < 2e-5, "{x} -> {y} -> {back}");
            let h = 1e-3;
            if x > h && x < 1.0 - h {
                let numeric = (forward(&g, c, t, x + h) - forward(&g, c, t, x - h)) / (2.0 * h);
                let s = slope(&g, c, t, x);
                assert!(
                    (numeric / s - 1.0).abs() < 0.02,
                    "slope at {x}: {numeric} vs {s}"
                );
            }
        }
    }

    /// Uniform nodes are the identity, with slope 1.
    #[test]
    fn uniform_nodes_are_the_identity() {
        let g = [3.0; MAX_NODES];
        let c = MAX_NODES - 1;
        let t = total(&g, c);
        for k in 0..=100 {
            let x = k as f32 / 100.0;
            assert!((forward(&g, c, t, x) - x).abs() < 1e-6);
            assert!((slope(&g, c, t, x) - 1.0).abs() < 1e-6);
        }
    }
}
