//! The three matrix products of a layer over a chunk of rows, in register tiles sized for
//! 16 vector registers, each compiled twice: for the build's target and, on x86-64, with
//! AVX2 (chosen at run time where the CPU has it). Both copies give the same bits.
//!
//! Every sum keeps the order of the row-at-a-time pass ([`crate::mlp::Mlp::forward_tape`],
//! [`crate::mlp::Mlp::backward`]); no fused multiply-add:
//!
//! - [`affine`]: `z[r][o] = b[o] + dot(W[o], a[r])`, where `dot` is the kernel's 8
//!   interleaved partial sums (sum `l` takes the inputs `i = l (mod 8)` in order) reduced
//!   as `((s0 + s4) + (s2 + s6)) + ((s1 + s5) + (s3 + s7))`;
//! - [`weight_grad`]: `gW[o][i] += dz[r][o] a[r][i]`, rows in order;
//! - [`transpose_times`]: `da[r][i] = sum_o dz[r][o] W[o][i]`, outputs in order from 0.
//!
//! A tile holds `R` rows (or outputs) times `C` vectors of 8 in registers: per step it loads
//! `C` vectors and `R` broadcasts for `R C` multiply-adds, so the loads no longer bound it.

#[cfg(target_arch = "x86_64")]
use crate::lanes::Avx;
use crate::lanes::{Lanes, Portable, LANES};
use crate::mlp::LayerAt;

// The reduction below names the eight partial sums.
const _: () = assert!(LANES == 8);
/// Rows (outputs, for the weight gradient) per register tile.
const TILE_ROWS: usize = 6;
/// Vectors of 8 per register tile.
const TILE_VECS: usize = 2;

/// Defines `$name` (safe, dispatching) over `$body`, an `#[inline(always)]` function generic
/// in its [`Lanes`]: compiled once with [`Portable`] lanes for the build's target and once
/// with [`Avx`] lanes inside an AVX2 function.
macro_rules! dispatched {
    ($(#[$doc:meta])* fn $name:ident / $avx2:ident = $body:ident($($arg:ident: $ty:ty),*)) => {
        $(#[$doc])*
        pub(crate) fn $name($($arg: $ty),*) {
            #[cfg(target_arch = "x86_64")]
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2, the only feature `$avx2` is compiled with.
                #[allow(unsafe_code)]
                unsafe { $avx2($($arg),*) };
                return;
            }
            $body::<Portable>($($arg),*)
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        fn $avx2($($arg: $ty),*) {
            $body::<Avx>($($arg),*)
        }
    };
}

dispatched! {
    /// `z[r][o] = b[o] + dot(W[o], a[r])` for every row of `a` (`rows x n_in`, row-major);
    /// `wt` holds `W` in blocks of eight outputs ([`transpose`]).
    fn affine / affine_avx2 = affine_body(params: &[f32], at: LayerAt, wt: &[f32], a: &[f32], z: &mut [f32])
}

dispatched! {
    /// `z[r][o] = dot(W[o], a[r])` (the product without the bias: the tangents of a
    /// layer's input); `wt` as for [`affine`].
    fn linear / linear_avx2 = linear_body(at: LayerAt, wt: &[f32], a: &[f32], z: &mut [f32])
}

dispatched! {
    /// `grad_W[o][i] += dz[r][o] a[r][i]` over the rows in order.
    fn weight_grad / weight_grad_avx2 = weight_grad_body(dz: &[f32], a: &[f32], at: LayerAt, rows: usize, grad: &mut [f32])
}

dispatched! {
    /// `da[r][i] = sum_o dz[r][o] W[o][i]`, the outputs in order.
    fn transpose_times / transpose_times_avx2 = transpose_times_body(params: &[f32], at: LayerAt, dz: &[f32], rows: usize, da: &mut [f32])
}

/// `W` of layer `at` in blocks of [`LANES`] outputs, each block `[in][LANES]`:
/// `wt[(k n_in + i) LANES + j] = W[k LANES + j][i]`, outputs past the last zero.
pub(crate) fn transpose(params: &[f32], at: LayerAt, wt: &mut Vec<f32>) {
    let blocks = at.n_out.div_ceil(LANES);
    wt.clear();
    wt.resize(blocks * at.n_in * LANES, 0.0);
    for o in 0..at.n_out {
        let (k, j) = (o / LANES, o % LANES);
        for i in 0..at.n_in {
            wt[(k * at.n_in + i) * LANES + j] = params[at.w + o * at.n_in + i];
        }
    }
}

/// The register tile a product runs on a stretch of its rows and vectors.
#[derive(Clone, Copy, Debug)]
enum Shape {
    /// [`TILE_ROWS`] rows by [`TILE_VECS`] vectors.
    Full,
    /// [`TILE_ROWS`] rows by one vector (the last, odd vector).
    Narrow,
    /// One row by one vector (the last rows, fewer than a tile).
    Single,
}

/// Covers `rows` rows (or outputs) by `vecs` vectors of 8 with register tiles, calling
/// `run(shape, first row, first vector)` for each; every entry is in exactly one tile.
#[inline(always)]
fn for_each_tile(rows: usize, vecs: usize, mut run: impl FnMut(Shape, usize, usize)) {
    let mut r = 0;
    while r < rows {
        let tile_rows = (rows - r).min(TILE_ROWS);
        let mut k = 0;
        while k < vecs {
            let tile_vecs = (vecs - k).min(TILE_VECS);
            match (tile_rows, tile_vecs) {
                (TILE_ROWS, TILE_VECS) => run(Shape::Full, r, k),
                (TILE_ROWS, _) => run(Shape::Narrow, r, k),
                _ => {
                    for rr in r..r + tile_rows {
                        for kk in k..k + tile_vecs {
                            run(Shape::Single, rr, kk);
                        }
                    }
                }
            }
            k += tile_vecs;
        }
        r += tile_rows;
    }
}

#[inline(always)]
fn affine_body<V: Lanes>(params: &[f32], at: LayerAt, wt: &[f32], a: &[f32], z: &mut [f32]) {
    product_body::<V>(Some(&params[at.b..at.b + at.n_out]), at, wt, a, z);
}

#[inline(always)]
fn linear_body<V: Lanes>(at: LayerAt, wt: &[f32], a: &[f32], z: &mut [f32]) {
    product_body::<V>(None, at, wt, a, z);
}

/// [`affine`] with the bias `b`, [`linear`] without (`None`).
#[inline(always)]
fn product_body<V: Lanes>(b: Option<&[f32]>, at: LayerAt, wt: &[f32], a: &[f32], z: &mut [f32]) {
    let (n_in, n_out) = (at.n_in, at.n_out);
    let rows = a.len() / n_in.max(1);
    let blocks = n_out.div_ceil(LANES);
    for_each_tile(
        rows,
        blocks,
        #[inline(always)]
        |shape, r, k| match shape {
            Shape::Full => affine_tile::<V, TILE_ROWS, TILE_VECS>(b, wt, n_in, n_out, a, z, r, k),
            Shape::Narrow => affine_tile::<V, TILE_ROWS, 1>(b, wt, n_in, n_out, a, z, r, k),
            Shape::Single => affine_tile::<V, 1, 1>(b, wt, n_in, n_out, a, z, r, k),
        },
    );
}

/// A row's inputs `8 j + l` as `[j][l]`, and its last inputs (fewer than 8).
type RowChunks<'a> = (&'a [[f32; LANES]], &'a [f32]);
/// A block's weights (8 outputs per input) at inputs `8 j + l` as `[j][l]`, and at its last
/// inputs.
type BlockChunks<'a> = (&'a [[[f32; LANES]; LANES]], &'a [[f32; LANES]]);

/// Rows `r0..r0 + R`, output blocks `k0..k0 + C` of [`affine`]: each partial sum `l` of
/// `dot` in turn, in registers, then the reduction.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn affine_tile<V: Lanes, const R: usize, const C: usize>(
    b: Option<&[f32]>,
    wt: &[f32],
    n_in: usize,
    n_out: usize,
    a: &[f32],
    z: &mut [f32],
    r0: usize,
    k0: usize,
) {
    let full = n_in / LANES;
    // Inputs `8 j + l` as `[j][l]`: the rows, and each block's weights (8 outputs each).
    let rows: [RowChunks; R] = core::array::from_fn(|rr| {
        let row = &a[(r0 + rr) * n_in..][..n_in];
        let (chunks, rest) = row.split_at(full * LANES);
        (bytemuck::cast_slice(chunks), rest)
    });
    let blocks: [BlockChunks; C] = core::array::from_fn(|c| {
        let block = &wt[(k0 + c) * n_in * LANES..][..n_in * LANES];
        let (chunks, rest) = block.split_at(full * LANES * LANES);
        (bytemuck::cast_slice(chunks), bytemuck::cast_slice(rest))
    });
    // The partial sums in the order of `dot`'s reduction, each combined as soon as its
    // pair is done: ((s0 + s4) + (s2 + s6)) + ((s1 + s5) + (s3 + s7)).
    let sum = |l: usize| partial_sums::<V, R, C>(&rows, &blocks, full, l);
    let left = pair_add(pair_add(sum(0), sum(4)), pair_add(sum(2), sum(6)));
    let right = pair_add(pair_add(sum(1), sum(5)), pair_add(sum(3), sum(7)));
    let total = pair_add(left, right);
    for (rr, total_r) in total.iter().enumerate() {
        for (c, sums) in total_r.iter().enumerate() {
            let first = (k0 + c) * LANES;
            let last = (first + LANES).min(n_out);
            let z_row = &mut z[(r0 + rr) * n_out..];
            let sums = sums.to_array();
            for o in first..last {
                z_row[o] = match b {
                    Some(b) => b[o] + sums[o - first],
                    None => sums[o - first],
                };
            }
        }
    }
}

/// Partial sum `l` of `dot` (the inputs `8 j + l`, in order) for a tile of rows and
/// output blocks.
#[inline(always)]
fn partial_sums<V: Lanes, const R: usize, const C: usize>(
    rows: &[RowChunks; R],
    blocks: &[BlockChunks; C],
    full: usize,
    l: usize,
) -> [[V; C]; R] {
    let mut acc = [[V::zero(); C]; R];
    for j in 0..full {
        let mut w = [V::zero(); C];
        for (wc, block) in w.iter_mut().zip(blocks) {
            *wc = V::load(&block.0[j][l]);
        }
        for (acc_r, row) in acc.iter_mut().zip(rows) {
            let x = V::splat(row.0[j][l]);
            for (acc_rc, wc) in acc_r.iter_mut().zip(w) {
                *acc_rc = acc_rc.add_product(x, wc);
            }
        }
    }
    // The last inputs (fewer than 8) end partial sums 0, 1, ...: `i = 8 full + l`.
    for (acc_r, row) in acc.iter_mut().zip(rows) {
        if let Some(&x) = row.1.get(l) {
            for (acc_rc, block) in acc_r.iter_mut().zip(blocks) {
                if let Some(&w) = block.1.get(l) {
                    *acc_rc = acc_rc.add_product(V::splat(x), V::load(&w));
                }
            }
        }
    }
    acc
}

/// `a + b`, tile by tile.
#[inline(always)]
fn pair_add<V: Lanes, const R: usize, const C: usize>(
    a: [[V; C]; R],
    b: [[V; C]; R],
) -> [[V; C]; R] {
    let mut sum = a;
    for (sum_r, b_r) in sum.iter_mut().zip(b) {
        for (s, bv) in sum_r.iter_mut().zip(b_r) {
            *s = s.add(bv);
        }
    }
    sum
}

#[inline(always)]
fn weight_grad_body<V: Lanes>(dz: &[f32], a: &[f32], at: LayerAt, rows: usize, grad: &mut [f32]) {
    let (n_in, n_out) = (at.n_in, at.n_out);
    let gw = &mut grad[at.w..at.b];
    let full = n_in - n_in % LANES;
    let op = GradOperands {
        dz,
        a,
        n_in,
        n_out,
        rows,
    };
    for_each_tile(
        n_out,
        full / LANES,
        #[inline(always)]
        |shape, o, v| {
            let c = v * LANES;
            match shape {
                Shape::Full => grad_tile::<V, TILE_ROWS, TILE_VECS>(op, gw, o, c),
                Shape::Narrow => grad_tile::<V, TILE_ROWS, 1>(op, gw, o, c),
                Shape::Single => grad_tile::<V, 1, 1>(op, gw, o, c),
            }
        },
    );
    // The last inputs (fewer than a vector): eight outputs at a time down the rows, then
    // the last outputs one entry at a time; rows in order.
    let mut o = 0;
    while o + LANES <= n_out {
        for i in full..n_in {
            grad_column::<V>(op, gw, o, i);
        }
        o += LANES;
    }
    for oo in o..n_out {
        for i in full..n_in {
            let mut g = gw[oo * n_in + i];
            for r in 0..rows {
                g += dz[r * n_out + oo] * a[r * n_in + i];
            }
            gw[oo * n_in + i] = g;
        }
    }
}

/// The operands of [`weight_grad`]: `dz` (`rows x n_out`) and `a` (`rows x n_in`).
#[derive(Clone, Copy, Debug)]
struct GradOperands<'a> {
    dz: &'a [f32],
    a: &'a [f32],
    n_in: usize,
    n_out: usize,
    rows: usize,
}

/// Outputs `o0..o0 + 8` at input `i` of [`weight_grad`], in one register across the rows.
#[inline(always)]
fn grad_column<V: Lanes>(op: GradOperands, gw: &mut [f32], o0: usize, i: usize) {
    let (dz, a, n_in, n_out, rows) = (op.dz, op.a, op.n_in, op.n_out, op.rows);
    let start: [f32; LANES] = core::array::from_fn(|k| gw[(o0 + k) * n_in + i]);
    let mut acc = V::load(&start);
    for (dz_row, a_row) in dz.chunks_exact(n_out).zip(a.chunks_exact(n_in)).take(rows) {
        acc = acc.add_product(V::load(&dz_row[o0..]), V::splat(a_row[i]));
    }
    for (k, g) in acc.to_array().iter().enumerate() {
        gw[(o0 + k) * n_in + i] = *g;
    }
}

/// Outputs `o0..o0 + R`, inputs `c0..c0 + 8 C` of [`weight_grad`], in registers across the
/// rows.
#[inline(always)]
fn grad_tile<V: Lanes, const R: usize, const C: usize>(
    op: GradOperands,
    gw: &mut [f32],
    o0: usize,
    c0: usize,
) {
    let (dz, a, n_in, n_out, rows) = (op.dz, op.a, op.n_in, op.n_out, op.rows);
    let mut acc = [[V::zero(); C]; R];
    for (j, acc_j) in acc.iter_mut().enumerate() {
        for (c, acc_jc) in acc_j.iter_mut().enumerate() {
            *acc_jc = V::load(&gw[(o0 + j) * n_in + c0 + c * LANES..]);
        }
    }
    for r in 0..rows {
        let a_row = &a[r * n_in + c0..];
        let mut av = [V::zero(); C];
        for (c, avc) in av.iter_mut().enumerate() {
            *avc = V::load(&a_row[c * LANES..]);
        }
        let d = &dz[r * n_out + o0..r * n_out + o0 + R];
        for (acc_j, &dj) in acc.iter_mut().zip(d) {
            let dv = V::splat(dj);
            for (acc_jc, avc) in acc_j.iter_mut().zip(av) {
                *acc_jc = acc_jc.add_product(avc, dv);
            }
        }
    }
    for (j, acc_j) in acc.iter().enumerate() {
        for (c, acc_jc) in acc_j.iter().enumerate() {
            acc_jc.store(&mut gw[(o0 + j) * n_in + c0 + c * LANES..]);
        }
    }
}

#[inline(always)]
fn transpose_times_body<V: Lanes>(
    params: &[f32],
    at: LayerAt,
    dz: &[f32],
    rows: usize,
    da: &mut [f32],
) {
    let (n_in, n_out) = (at.n_in, at.n_out);
    let w = &params[at.w..at.b];
    let full = n_in - n_in % LANES;
    for_each_tile(
        rows,
        full / LANES,
        #[inline(always)]
        |shape, r, v| {
            let c = v * LANES;
            match shape {
                Shape::Full => times_tile::<V, TILE_ROWS, TILE_VECS>(w, dz, da, n_in, n_out, r, c),
                Shape::Narrow => times_tile::<V, TILE_ROWS, 1>(w, dz, da, n_in, n_out, r, c),
                Shape::Single => times_tile::<V, 1, 1>(w, dz, da, n_in, n_out, r, c),
            }
        },
    );
    // The last inputs (fewer than a vector) one entry at a time, outputs in order.
    for k in 0..rows {
        for i in full..n_in {
            let mut s = 0.0f32;
            for o in 0..n_out {
                s += dz[k * n_out + o] * w[o * n_in + i];
            }
            da[k * n_in + i] = s;
        }
    }
}

/// Rows `r0..r0 + R`, inputs `c0..c0 + 8 C` of [`transpose_times`], in registers across
/// the outputs.
#[inline(always)]
fn times_tile<V: Lanes, const R: usize, const C: usize>(
    w: &[f32],
    dz: &[f32],
    da: &mut [f32],
    n_in: usize,
    n_out: usize,
    r0: usize,
    c0: usize,
) {
    let mut acc = [[V::zero(); C]; R];
    for o in 0..n_out {
        let w_row = &w[o * n_in + c0..];
        let mut wv = [V::zero(); C];
        for (c, wvc) in wv.iter_mut().enumerate() {
            *wvc = V::load(&w_row[c * LANES..]);
        }
        for (rr, acc_r) in acc.iter_mut().enumerate() {
            let dv = V::splat(dz[(r0 + rr) * n_out + o]);
            for (acc_rc, wc) in acc_r.iter_mut().zip(wv) {
                *acc_rc = acc_rc.add_product(dv, wc);
            }
        }
    }
    for (rr, acc_r) in acc.iter().enumerate() {
        for (c, acc_rc) in acc_r.iter().enumerate() {
            acc_rc.store(&mut da[(r0 + rr) * n_in + c0 + c * LANES..]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// The dispatched products (the AVX2 copy where the CPU has it) and the copy compiled
    /// for the build's target give the same bits, on ragged shapes.
    #[test]
    fn both_copies_agree_bit_for_bit() {
        let mut rng = Pcg64::seed_from_u64(5);
        for (n_in, n_out, rows) in [(37usize, 96usize, 13usize), (96, 2, 7), (5, 9, 6)] {
            let mut v =
                |n: usize| -> Vec<f32> { (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect() };
            let params = v(n_out * n_in + n_out);
            let at = LayerAt {
                n_in,
                n_out,
                w: 0,
                b: n_out * n_in,
            };
            let (a, dz, grad0) = (v(rows * n_in), v(rows * n_out), v(params.len()));
            let mut wt = Vec::new();
            transpose(&params, at, &mut wt);
            let bits = |x: &[f32]| x.iter().map(|f| f.to_bits()).collect::<Vec<_>>();

            let (mut z1, mut z2) = (vec![0.0; rows * n_out], vec![0.0; rows * n_out]);
            affine(&params, at, &wt, &a, &mut z1);
            affine_body::<Portable>(&params, at, &wt, &a, &mut z2);
            assert_eq!(bits(&z1), bits(&z2), "affine {n_in}x{n_out}");

            // Without the bias: the dispatched copy, the target's, and `dot` itself.
            let (mut l1, mut l2) = (vec![0.0; rows * n_out], vec![0.0; rows * n_out]);
            linear(at, &wt, &a, &mut l1);
            linear_body::<Portable>(at, &wt, &a, &mut l2);
            let by_dot: Vec<f32> = (0..rows * n_out)
                .map(|k| {
                    let (r, o) = (k / n_out, k % n_out);
                    let w_row = &params[o * n_in..(o + 1) * n_in];
                    crate::mlp::dot(w_row, &a[r * n_in..(r + 1) * n_in])
                })
                .collect();
            assert_eq!(bits(&l1), bits(&l2), "linear {n_in}x{n_out}");
            assert_eq!(
                bits(&l1),
                bits(&by_dot),
                "linear against dot {n_in}x{n_out}"
            );

            let (mut g1, mut g2) = (grad0.clone(), grad0.clone());
            weight_grad(&dz, &a, at, rows, &mut g1);
            weight_grad_body::<Portable>(&dz, &a, at, rows, &mut g2);
            assert_eq!(bits(&g1), bits(&g2), "weight gradient {n_in}x{n_out}");

            let (mut d1, mut d2) = (vec![0.0; rows * n_in], vec![0.0; rows * n_in]);
            transpose_times(&params, at, &dz, rows, &mut d1);
            transpose_times_body::<Portable>(&params, at, &dz, rows, &mut d2);
            assert_eq!(bits(&d1), bits(&d2), "W^T dz {n_in}x{n_out}");
        }
    }
}
