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

    /// [`Dense::forward`] of `K` inputs at once, laid out lanes innermost (`x[i][s]`: input
    /// `i` of sample `s`, so that one vector holds `K` samples): each lane runs the same
    /// operations in the same order as alone (bit for bit), while the layer's `O`
    /// independent sums fill the multiply-add pipeline and each weight, loaded once, serves
    /// every lane.
    ///
    /// The outputs go in blocks of 8, whose `8 x K` sums stay in
    /// registers over all `I` inputs.
    #[inline(always)]
    pub fn forward_lanes<const K: usize>(&self, x: &[[f32; K]; I]) -> [[f32; K]; O] {
        let mut z = [[0.0; K]; O];
        let blocks = O / OUT_BLOCK;
        for j in 0..blocks {
            let o0 = j * OUT_BLOCK;
            let mut acc = [[0.0f32; K]; OUT_BLOCK];
            for (a, &b) in acc.iter_mut().zip(self.b.iter().skip(o0)) {
                *a = [b; K];
            }
            for (col, xi) in self.w.iter().zip(x) {
                let Some(w) = col
                    .get(o0..o0 + OUT_BLOCK)
                    .and_then(|w| <&[f32; OUT_BLOCK]>::try_from(w).ok())
                else {
                    continue;
                };
                for (a, &wo) in acc.iter_mut().zip(w) {
                    for (zs, &xs) in a.iter_mut().zip(xi) {
                        *zs = mul_add(wo, xs, *zs);
                    }
                }
            }
            for (zo, a) in z.iter_mut().skip(o0).zip(acc) {
                *zo = a;
            }
        }
        // Outputs past the last whole block, one at a time.
        for (o, zo) in z.iter_mut().enumerate().skip(blocks * OUT_BLOCK) {
            let mut a = [self.b.get(o).copied().unwrap_or(0.0); K];
            for (col, xi) in self.w.iter().zip(x) {
                let wo = col.get(o).copied().unwrap_or(0.0);
                for (zs, &xs) in a.iter_mut().zip(xi) {
                    *zs = mul_add(wo, xs, *zs);
                }
            }
            *zo = a;
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

/// Outputs per block of [`Dense::forward_lanes`]: 8 sums of 8 lanes are 8 AVX registers.
const OUT_BLOCK: usize = 8;

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

/// [`dot`] of `a` with `K` vectors laid out lanes innermost (`x[i][s]`), each lane's sum in
/// [`dot`]'s order: partial sum `l` takes the inputs `i = l (mod LANES)`, then the same
/// tree.
#[inline(always)]
fn dot_lanes<const N: usize, const K: usize>(a: &[f32; N], x: &[[f32; K]; N]) -> [f32; K] {
    let mut acc = [[0.0f32; K]; LANES];
    for (i, (&ai, xi)) in a.iter().zip(x).enumerate() {
        if let Some(al) = acc.get_mut(i % LANES) {
            for (s, &xs) in al.iter_mut().zip(xi) {
                *s = mul_add(ai, xs, *s);
            }
        }
    }
    let mut out = [0.0f32; K];
    for (s, o) in out.iter_mut().enumerate() {
        let half = |l: usize| acc[l][s] + acc[l + LANES / 2][s];
        *o = (half(0) + half(2)) + (half(1) + half(3));
    }
    out
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

    /// [`Readout::forward`] of `K` inputs laid out lanes innermost ([`Dense::forward_lanes`]),
    /// each lane bit for bit as alone.
    #[inline(always)]
    pub fn forward_lanes<const K: usize>(&self, x: &[[f32; K]; I]) -> [[f32; K]; O] {
        let mut z = [[0.0; K]; O];
        for ((zo, row), &b) in z.iter_mut().zip(&self.w).zip(&self.b) {
            for (zs, d) in zo.iter_mut().zip(dot_lanes(row, x)) {
                *zs = b + d;
            }
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
