//! A bilinearly interpolated 2D table on `[0,1]^2`, conditioned on parameters with linear
//! interpolation between slices, with exact sampling and inversion by marginal and
//! conditional CDFs (the structure of Mitsuba's `Marginal2D`, written from the maths).
//!
//! Values sit on the vertices of an `nx x ny` grid (`x` = last dimension); the function is
//! bilinear inside each patch. The trapezoid rule is therefore exact: row integrals are
//! linear in `y` and the conditional density in `x` is linear inside a patch, so both CDF
//! inversions are quadratic solves.

use super::RglError;

/// At most this many parameter dimensions.
const MAX_PARAMS: usize = 3;

/// A table of 2D slices indexed by parameters.
#[derive(Debug, Clone)]
pub struct Warp2D {
    nx: usize,
    ny: usize,
    params: Vec<Vec<f64>>,
    data: Vec<f64>,
    /// Cumulative integral along x per row (`slices * ny * nx`), empty if not sampled.
    conditional: Vec<f64>,
    /// Cumulative integral of the row integrals along y (`slices * ny`).
    marginal: Vec<f64>,
}

/// Solves `a0 t + (a1 - a0) t^2 / 2 = c` for `t` in `[0, 1]`: the inverse CDF of the
/// linear density `a0 (1 - t) + a1 t` on one patch.
fn solve_linear_cdf(a0: f64, a1: f64, c: f64) -> f64 {
    let disc = (a0 * a0 + 2.0 * (a1 - a0) * c).max(0.0);
    let den = a0 + disc.sqrt();
    if den > 0.0 {
        (2.0 * c / den).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Cell index and local coordinate for a position in `[0,1]` on `n` vertices.
fn locate(u: f64, n: usize) -> (usize, f64) {
    let p = u.clamp(0.0, 1.0) * (n - 1) as f64;
    let i = (p.floor() as usize).min(n - 2);
    (i, (p - i as f64).clamp(0.0, 1.0))
}

/// Slice indices and interpolation weights for parameter values (at most `2^MAX_PARAMS`).
type Weights = ([(usize, f64); 1 << MAX_PARAMS], usize);

impl Warp2D {
    /// Builds a table. `data` has layout `[params..., ny, nx]`; `sampled` normalises every
    /// slice to integrate to 1 and builds the CDFs.
    pub fn new(
        name: &'static str,
        data: Vec<f64>,
        nx: usize,
        ny: usize,
        params: Vec<Vec<f64>>,
        sampled: bool,
    ) -> Result<Self, RglError> {
        if nx < 2 || ny < 2 || params.len() > MAX_PARAMS || params.iter().any(|p| p.is_empty()) {
            return Err(RglError::BadShape(name));
        }
        let slices: usize = params.iter().map(Vec::len).product();
        let expect = slices
            .checked_mul(nx)
            .and_then(|v| v.checked_mul(ny))
            .ok_or(RglError::Overflow)?;
        if data.len() != expect {
            return Err(RglError::BadShape(name));
        }
        for p in &params {
            if p.windows(2).any(|w| !(w[1] > w[0])) {
                return Err(RglError::BadAngles(name));
            }
        }
        let mut w = Self {
            nx,
            ny,
            params,
            data,
            conditional: Vec::new(),
            marginal: Vec::new(),
        };
        if sampled {
            w.build_cdfs(name, slices)?;
        }
        Ok(w)
    }

    fn build_cdfs(&mut self, name: &'static str, slices: usize) -> Result<(), RglError> {
        let (nx, ny) = (self.nx, self.ny);
        let (hx, hy) = (1.0 / (nx - 1) as f64, 1.0 / (ny - 1) as f64);
        self.conditional = vec![0.0; slices * ny * nx];
        self.marginal = vec![0.0; slices * ny];
        for k in 0..slices {
            let base = k * nx * ny;
            // Normalise the slice: the integral of the bilinear interpolant.
            let slice = &mut self.data[base..base + nx * ny];
            for v in slice.iter_mut() {
                *v = v.max(0.0);
            }
            let mut total = 0.0;
            for y in 0..ny - 1 {
                for x in 0..nx - 1 {
                    let i = y * nx + x;
                    total += 0.25 * (slice[i] + slice[i + 1] + slice[i + nx] + slice[i + nx + 1]);
                }
            }
            total *= hx * hy;
            if !(total > 0.0 && total.is_finite()) {
                return Err(RglError::NotNormalizable(name));
            }
            for v in slice.iter_mut() {
                *v /= total;
            }
            for y in 0..ny {
                let row = &self.data[base + y * nx..base + (y + 1) * nx];
                let cond = &mut self.conditional[base + y * nx..base + (y + 1) * nx];
                for x in 1..nx {
                    cond[x] = cond[x - 1] + 0.5 * hx * (row[x - 1] + row[x]);
                }
            }
            let mb = k * ny;
            for y in 1..ny {
                let r0 = self.conditional[base + y * nx - 1];
                let r1 = self.conditional[base + (y + 1) * nx - 1];
                self.marginal[mb + y] = self.marginal[mb + y - 1] + 0.5 * hy * (r0 + r1);
            }
        }
        Ok(())
    }

    /// Interpolation weights over slices for the parameter values `p` (clamped to the
    /// measured range; a dimension with one entry is constant).
    fn weights(&self, p: &[f64]) -> Weights {
        let mut out = [(0usize, 0.0f64); 1 << MAX_PARAMS];
        out[0] = (0, 1.0);
        let mut n = 1;
        for (d, grid) in self.params.iter().enumerate() {
            let v = p.get(d).copied().unwrap_or(0.0);
            let (i, t) = if grid.len() == 1 {
                (0, 0.0)
            } else {
                let v = if v.is_finite() { v } else { grid[0] };
                let v = v.clamp(grid[0], grid[grid.len() - 1]);
                let i = grid.partition_point(|g| *g <= v).clamp(1, grid.len() - 1) - 1;
                let t = ((v - grid[i]) / (grid[i + 1] - grid[i])).clamp(0.0, 1.0);
                (i, t)
            };
            let len = grid.len();
            let mut m = 0;
            let mut next = [(0usize, 0.0f64); 1 << MAX_PARAMS];
            for &(s, w) in &out[..n] {
                next[m] = (s * len + i, w * (1.0 - t));
                m += 1;
                if t > 0.0 {
                    next[m] = (s * len + i + 1, w * t);
                    m += 1;
                }
            }
            out = next;
            n = m;
        }
        (out, n)
    }

    fn mix(arr: &[f64], w: &Weights, stride: usize, idx: usize) -> f64 {
        w.0[..w.1]
            .iter()
            .map(|&(s, wt)| wt * arr.get(s * stride + idx).copied().unwrap_or(0.0))
            .sum()
    }

    fn value(&self, w: &Weights, x: usize, y: usize) -> f64 {
        Self::mix(&self.data, w, self.nx * self.ny, y * self.nx + x)
    }

    fn bilinear(&self, w: &Weights, u: [f64; 2]) -> f64 {
        let (j, tx) = locate(u[0], self.nx);
        let (i, ty) = locate(u[1], self.ny);
        let v00 = self.value(w, j, i);
        let v10 = self.value(w, j + 1, i);
        let v01 = self.value(w, j, i + 1);
        let v11 = self.value(w, j + 1, i + 1);
        (1.0 - ty) * ((1.0 - tx) * v00 + tx * v10) + ty * ((1.0 - tx) * v01 + tx * v11)
    }

    /// The interpolated table value at `u` for parameters `p` (the density, for a sampled
    /// table).
    pub fn eval(&self, u: [f64; 2], p: &[f64]) -> f64 {
        self.bilinear(&self.weights(p), u)
    }

    fn is_sampled(&self) -> bool {
        !self.marginal.is_empty()
    }

    fn marg(&self, w: &Weights, y: usize) -> f64 {
        Self::mix(&self.marginal, w, self.ny, y)
    }

    fn cond(&self, w: &Weights, y: usize, x: usize) -> f64 {
        Self::mix(&self.conditional, w, self.nx * self.ny, y * self.nx + x)
    }

    /// Maps a uniform point `s` of `[0,1]^2` to a point distributed by the table; returns
    /// it with its density. `None` for a table built without CDFs.
    pub fn sample(&self, s: [f64; 2], p: &[f64]) -> Option<([f64; 2], f64)> {
        if !self.is_sampled() {
            return None;
        }
        let w = self.weights(p);
        let (nx, ny) = (self.nx, self.ny);
        let (hx, hy) = (1.0 / (nx - 1) as f64, 1.0 / (ny - 1) as f64);
        // Marginal in y: the largest row interval whose CDF start is <= target.
        let total = self.marg(&w, ny - 1);
        let ty_target = s[1].clamp(0.0, 1.0) * total;
        let (mut lo, mut hi) = (0usize, ny - 2);
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if self.marg(&w, mid) <= ty_target {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        let i = lo;
        let r0 = self.cond(&w, i, nx - 1);
        let r1 = self.cond(&w, i + 1, nx - 1);
        let ty = solve_linear_cdf(r0, r1, (ty_target - self.marg(&w, i)) / hy);
        // Conditional in x on the interpolated row.
        let g = |x: usize| (1.0 - ty) * self.cond(&w, i, x) + ty * self.cond(&w, i + 1, x);
        let tx_target = s[0].clamp(0.0, 1.0) * g(nx - 1);
        let (mut lo, mut hi) = (0usize, nx - 2);
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if g(mid) <= tx_target {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        let j = lo;
        let v0 = (1.0 - ty) * self.value(&w, j, i) + ty * self.value(&w, j, i + 1);
        let v1 = (1.0 - ty) * self.value(&w, j + 1, i) + ty * self.value(&w, j + 1, i + 1);
        let tx = solve_linear_cdf(v0, v1, (tx_target - g(j)) / hx);
        let u = [(j as f64 + tx) * hx, (i as f64 + ty) * hy];
        let pdf = ((1.0 - tx) * v0 + tx * v1) / total;
        Some((u, pdf))
    }

    /// Inverse of [`Self::sample`]: the uniform point that maps to `u`, and the density
    /// at `u`. `None` for a table built without CDFs.
    pub fn invert(&self, u: [f64; 2], p: &[f64]) -> Option<([f64; 2], f64)> {
        if !self.is_sampled() {
            return None;
        }
        let w = self.weights(p);
        let (nx, ny) = (self.nx, self.ny);
        let (hx, hy) = (1.0 / (nx - 1) as f64, 1.0 / (ny - 1) as f64);
        let (j, tx) = locate(u[0], nx);
        let (i, ty) = locate(u[1], ny);
        let total = self.marg(&w, ny - 1);
        let r0 = self.cond(&w, i, nx - 1);
        let r1 = self.cond(&w, i + 1, nx - 1);
        let sy = (self.marg(&w, i) + hy * (r0 * ty + 0.5 * (r1 - r0) * ty * ty)) / total;
        let g = |x: usize| (1.0 - ty) * self.cond(&w, i, x) + ty * self.cond(&w, i + 1, x);
        let v0 = (1.0 - ty) * self.value(&w, j, i) + ty * self.value(&w, j, i + 1);
        let v1 = (1.0 - ty) * self.value(&w, j + 1, i) + ty * self.value(&w, j + 1, i + 1);
        let row = g(nx - 1);
        let sx = if row > 0.0 {
            (g(j) + hx * (v0 * tx + 0.5 * (v1 - v0) * tx * tx)) / row
        } else {
            0.0
        };
        let pdf = ((1.0 - tx) * v0 + tx * v1) / total;
        Some(([sx.clamp(0.0, 1.0), sy.clamp(0.0, 1.0)], pdf))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> Warp2D {
        let (nx, ny) = (5, 4);
        let mut data = Vec::new();
        for k in 0..2 {
            for y in 0..ny {
                for x in 0..nx {
                    data.push(1.0 + ((x * 7 + y * 3 + k * 5) % 11) as f64);
                }
            }
        }
        Warp2D::new("t", data, nx, ny, vec![vec![0.0, 1.0]], true).unwrap()
    }

    #[test]
    fn sample_then_invert_is_identity() {
        let t = table();
        for a in 0..20 {
            for b in 0..20 {
                let s = [(a as f64 + 0.3) / 20.0, (b as f64 + 0.6) / 20.0];
                let p = [0.37];
                let (u, pdf) = t.sample(s, &p).unwrap();
                let (s2, pdf2) = t.invert(u, &p).unwrap();
                assert!((s[0] - s2[0]).abs() < 1e-10 && (s[1] - s2[1]).abs() < 1e-10);
                assert!((pdf - pdf2).abs() < 1e-10 * pdf);
                assert!((pdf - t.eval(u, &p)).abs() < 1e-10 * pdf);
            }
        }
    }

    #[test]
    fn density_integrates_to_one() {
        let t = table();
        let n = 400;
        let mut s = 0.0;
        for a in 0..n {
            for b in 0..n {
                s += t.eval(
                    [(a as f64 + 0.5) / n as f64, (b as f64 + 0.5) / n as f64],
                    &[0.8],
                );
            }
        }
        assert!((s / (n * n) as f64 - 1.0).abs() < 1e-4);
    }
}
