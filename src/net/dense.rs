//! Fully connected layers. `Dense` stores its weights column by column (`w[i]` holds the
//! weights leaving input `i`), so `z += w[i] * x[i]` runs down a whole layer at once and
//! vectorises. `Readout` is the narrow last layer, stored row by row, evaluated as dot
//! products. Every multiply-add goes through `math::mul_add` (fused with the `fma` feature).

use crate::math::mul_add;

/// `z = b + W x` with `W` of `O` rows and `I` columns, stored transposed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dense<const I: usize, const O: usize> {
    pub(crate) w: [[f32; O]; I],
    pub(crate) b: [f32; O],
}

impl<const I: usize, const O: usize> Dense<I, O> {
    /// Every parameter zero.
    pub const ZERO: Self = Dense {
        w: [[0.0; O]; I],
        b: [0.0; O],
    };

    /// `W x + b`.
    #[inline(always)]
    pub fn forward(&self, x: &[f32; I]) -> [f32; O] {
        let mut z = self.b;
        for (col, &xi) in self.w.iter().zip(x) {
            for (zo, &wo) in z.iter_mut().zip(col) {
                *zo = mul_add(wo, xi, *zo);
            }
        }
        z
    }

    /// `W x + b` and the two tangents `W dx_j` (forward-mode derivative).
    #[inline(always)]
    pub fn forward_tangents(&self, x: &[f32; I], dx: &[[f32; I]; 2]) -> ([f32; O], [[f32; O]; 2]) {
        let mut z = self.b;
        let mut dz = [[0.0; O]; 2];
        for i in 0..I {
            let (xi, d0, d1) = (x[i], dx[0][i], dx[1][i]);
            let col = &self.w[i];
            for o in 0..O {
                z[o] = mul_add(col[o], xi, z[o]);
                dz[0][o] = mul_add(col[o], d0, dz[0][o]);
                dz[1][o] = mul_add(col[o], d1, dz[1][o]);
            }
        }
        (z, dz)
    }

    /// Weight from input `i` to output `o`.
    pub fn weight(&self, o: usize, i: usize) -> f32 {
        self.w.get(i).and_then(|c| c.get(o)).copied().unwrap_or(0.0)
    }

    /// Bias of output `o`.
    pub fn bias(&self, o: usize) -> f32 {
        self.b.get(o).copied().unwrap_or(0.0)
    }

    /// Every parameter in blob order: `W` row by row (output-major), then `b`.
    pub(crate) fn visit_mut(&mut self, f: &mut impl FnMut(&mut f32)) {
        for o in 0..O {
            for col in self.w.iter_mut() {
                f(&mut col[o]);
            }
        }
        self.b.iter_mut().for_each(f);
    }

    /// Reads every parameter in the order of [`Dense::visit_mut`].
    pub(crate) fn visit(&self, f: &mut impl FnMut(f32)) {
        for o in 0..O {
            for col in self.w.iter() {
                f(col[o]);
            }
        }
        self.b.iter().for_each(|&b| f(b));
    }
}

/// Lanes of the partial sums in a dot product (`spec::DOT_PARTIAL_SUMS`).
const LANES: usize = crate::spec::DOT_PARTIAL_SUMS;

/// `sum_i a[i] * b[i]` with `LANES` interleaved partial sums.
#[inline(always)]
fn dot<const N: usize>(a: &[f32; N], b: &[f32; N]) -> f32 {
    let mut acc = [0.0f32; LANES];
    let mut ca = a.chunks_exact(LANES);
    let mut cb = b.chunks_exact(LANES);
    for (xa, xb) in (&mut ca).zip(&mut cb) {
        for l in 0..LANES {
            acc[l] = mul_add(xa[l], xb[l], acc[l]);
        }
    }
    for (l, (x, y)) in ca.remainder().iter().zip(cb.remainder()).enumerate() {
        acc[l] = mul_add(*x, *y, acc[l]);
    }
    let mut half = [0.0f32; LANES / 2];
    for l in 0..LANES / 2 {
        half[l] = acc[l] + acc[l + LANES / 2];
    }
    (half[0] + half[2]) + (half[1] + half[3])
}

/// `z = b + W x` for a layer with few outputs, stored row by row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Readout<const I: usize, const O: usize> {
    pub(crate) w: [[f32; I]; O],
    pub(crate) b: [f32; O],
}

impl<const I: usize, const O: usize> Readout<I, O> {
    /// Every parameter zero.
    pub const ZERO: Self = Readout {
        w: [[0.0; I]; O],
        b: [0.0; O],
    };

    /// `W x + b`.
    #[inline(always)]
    pub fn forward(&self, x: &[f32; I]) -> [f32; O] {
        let mut z = self.b;
        for (zo, row) in z.iter_mut().zip(&self.w) {
            *zo += dot(row, x);
        }
        z
    }

    /// `W dx` (no bias): the derivative of the output along a tangent `dx`.
    #[inline(always)]
    pub fn tangent(&self, dx: &[f32; I]) -> [f32; O] {
        let mut z = [0.0; O];
        for (zo, row) in z.iter_mut().zip(&self.w) {
            *zo = dot(row, dx);
        }
        z
    }

    /// Weight from input `i` to output `o`.
    pub fn weight(&self, o: usize, i: usize) -> f32 {
        self.w.get(o).and_then(|r| r.get(i)).copied().unwrap_or(0.0)
    }

    /// Bias of output `o`.
    pub fn bias(&self, o: usize) -> f32 {
        self.b.get(o).copied().unwrap_or(0.0)
    }

    /// Every parameter in blob order: `W` row by row, then `b`.
    pub(crate) fn visit_mut(&mut self, f: &mut impl FnMut(&mut f32)) {
        for row in self.w.iter_mut() {
            row.iter_mut().for_each(&mut *f);
        }
        self.b.iter_mut().for_each(f);
    }

    /// Reads every parameter in the order of [`Readout::visit_mut`].
    pub(crate) fn visit(&self, f: &mut impl FnMut(f32)) {
        for row in self.w.iter() {
            row.iter().for_each(|&w| f(w));
        }
        self.b.iter().for_each(|&b| f(b));
    }
}
