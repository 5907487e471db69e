//! The velocity net with the two tangents of its state input, and the reverse pass
//! through both: the second derivatives the variance refinement needs, since the loss
//! holds `ln det(I + h dv/dx)` (docs/math.md, §11, (67)-(70)).
//!
//! The net is the student as the kernel lays it out (`[features(x), t, enc(wi)]` in,
//! SiLU hidden layers, linear read-out), on every chart: the features are `x` itself on
//! the flat ones (disk, half-vector) and `(theta, sin phi, cos phi)` on the spherical
//! ones, whose second derivatives the reverse pass carries ([`StateFeatures`]). The `wi`
//! part of the first layer is folded into a per-`wi` bias ([`condition`]), as in the
//! kernel.

use crate::mlp::{dot, Mlp};
use crate::tiles::{affine, linear, transpose};
use diffbsdf::spec::MAX_FEATURES;
use diffbsdf::{Domain, ModelDef};

/// Inputs of the first layer before the encoding: the state features and `t`.
pub(super) const fn state_inputs(domain: Domain) -> usize {
    domain.feature_count() + 1
}

/// The state features of `x` (the kernel's `Domain::features_with_derivative`) with
/// their first and second derivatives along `x_0`, `x_1`.
#[derive(Clone, Debug, Default)]
struct StateFeatures {
    count: usize,
    value: [f32; MAX_FEATURES],
    /// `first[j][f] = dF_f / dx_j`.
    first: [[f32; MAX_FEATURES]; 2],
    /// `second[j][k][f] = d2 F_f / dx_j dx_k`.
    second: [[[f32; MAX_FEATURES]; 2]; 2],
}

impl StateFeatures {
    fn at(domain: Domain, x: [f32; 2]) -> StateFeatures {
        let (value, first) = domain.features_with_derivative(x);
        let mut second = [[[0.0f32; MAX_FEATURES]; 2]; 2];
        if domain.is_spherical() {
            // (theta, sin phi, cos phi): d2/dphi2 = (0, -sin phi, -cos phi)
            second[1][1] = [0.0, -value[1], -value[2]];
        }
        StateFeatures {
            count: domain.feature_count(),
            value,
            first,
            second,
        }
    }
}

/// `sigmoid(z)`, `silu(z) = z s`, `silu'(z)` and `silu''(z)`.
fn silu_derivatives(z: f32) -> (f32, f32, f32, f32) {
    let s = 1.0 / (1.0 + (-z).exp());
    // silu' = s (1 + z (1 - s)),  silu'' = s (1 - s) (2 + z (1 - 2 s))
    (
        z * s,
        s * (1.0 + z * (1.0 - s)),
        s * (1.0 - s) * (2.0 + z * (1.0 - 2.0 * s)),
        s,
    )
}

/// The first layer's `wi` part and bias: `b0 + W0[:, state..] enc`, one value per output.
pub(super) fn condition(domain: Domain, net: &Mlp, enc: &[f32]) -> Vec<f32> {
    let state = state_inputs(domain);
    let at = net.layer(0);
    let w = &net.params()[at.w..at.b];
    let b = &net.params()[at.b..at.b + at.n_out];
    (0..at.n_out)
        .map(|o| {
            let row = &w[o * at.n_in + state..(o + 1) * at.n_in];
            b[o] + dot(row, &enc[..row.len()])
        })
        .collect()
}

/// The hidden and read-out layers' weights laid out for the register tiles
/// ([`crate::tiles::transpose`]), made once per weight update.
#[derive(Clone, Debug, Default)]
pub(super) struct Transposed {
    /// Per layer (the first's empty: it is evaluated row by row).
    layers: Vec<Vec<f32>>,
}

impl Transposed {
    /// `net`'s weights as [`forward`] reads them.
    pub(super) fn of(net: &Mlp) -> Transposed {
        let layers = (0..net.layers().len())
            .map(|l| {
                let mut wt = Vec::new();
                if l > 0 {
                    transpose(net.params(), net.layer(l), &mut wt);
                }
                wt
            })
            .collect();
        Transposed { layers }
    }
}

/// The activations of one evaluation of a batch of rows (points at one `t`), kept for the
/// reverse pass. Per layer, row-major: values `[row][unit]`, tangents `[j][row][unit]`.
#[derive(Clone, Debug, Default)]
pub(super) struct Tape {
    /// Rows evaluated.
    rows: usize,
    /// The state features of every row's `x`.
    features: Vec<StateFeatures>,
    /// The evaluated `t`.
    t: f32,
    /// Pre-activations of every layer (the read-out last).
    pre: Vec<Vec<f32>>,
    /// Their two tangents along `x_0` and `x_1`.
    pre_tan: Vec<Vec<f32>>,
    /// SiLU of every hidden layer.
    post: Vec<Vec<f32>>,
    /// Its two tangents.
    post_tan: Vec<Vec<f32>>,
}

impl Tape {
    /// Layer `l`'s pre-activation of `row` (`n` units).
    fn pre(&self, l: usize, row: usize, n: usize) -> &[f32] {
        &self.pre[l][row * n..(row + 1) * n]
    }

    /// Its tangent `j`.
    fn pre_tan(&self, l: usize, j: usize, row: usize, n: usize) -> &[f32] {
        let at = (j * self.rows + row) * n;
        &self.pre_tan[l][at..at + n]
    }

    /// Hidden layer `l`'s SiLU of `row`.
    fn post(&self, l: usize, row: usize, n: usize) -> &[f32] {
        &self.post[l][row * n..(row + 1) * n]
    }

    /// Its tangent `j`.
    fn post_tan(&self, l: usize, j: usize, row: usize, n: usize) -> &[f32] {
        let at = (j * self.rows + row) * n;
        &self.post_tan[l][at..at + n]
    }
}

/// `v(x, t)` and its Jacobian `J[r][j] = dv_r / dx_j`.
pub(super) type VelocityJacobian = ([f32; 2], [[f32; 2]; 2]);

/// Evaluates `v` and `dv/dx` at every point of `xs` at `t`, for the conditioned first
/// layer `cond`, into `out` (one per point). Each row's value has the bits of that point
/// evaluated alone: the rows share only the weights (the hidden layers' products are the
/// register tiles', whose sums keep `dot`'s order).
pub(super) fn forward(
    domain: Domain,
    (net, transposed): (&Mlp, &Transposed),
    cond: &[f32],
    (xs, t): (&[[f32; 2]], f32),
    tape: &mut Tape,
    out: &mut Vec<VelocityJacobian>,
) {
    let (layers, rows) = (net.layers().len(), xs.len());
    tape.rows = rows;
    tape.t = t;
    tape.features.clear();
    tape.features
        .extend(xs.iter().map(|&x| StateFeatures::at(domain, x)));
    tape.pre.resize(layers, Vec::new());
    tape.pre_tan.resize(layers, Vec::new());
    tape.post.resize(layers - 1, Vec::new());
    tape.post_tan.resize(layers - 1, Vec::new());
    let params = net.params();
    for l in 0..layers {
        let at = net.layer(l);
        let n = at.n_out;
        tape.pre[l].resize(rows * n, 0.0);
        tape.pre_tan[l].resize(2 * rows * n, 0.0);
        if l == 0 {
            first_layer(net, cond, tape);
        } else {
            let wt = &transposed.layers[l];
            // z = W a + b; dz/dx_j = W da/dx_j
            affine(params, at, wt, &tape.post[l - 1], &mut tape.pre[l]);
            linear(at, wt, &tape.post_tan[l - 1], &mut tape.pre_tan[l]);
        }
        if net.layers()[l].activated {
            activate(tape, l, n);
        }
    }
    let read_out = &tape.pre[layers - 1];
    let tangents = &tape.pre_tan[layers - 1];
    out.clear();
    out.extend((0..rows).map(|r| {
        let (v, v0, v1) = (
            &read_out[2 * r..],
            &tangents[2 * r..],
            &tangents[2 * (rows + r)..],
        );
        ([v[0], v[1]], [[v0[0], v1[0]], [v0[1], v1[1]]])
    }));
}

/// The first layer, row by row: `z = cond + sum_f W[:, f] F_f(x) + W[:, nf] t`,
/// `dz/dx_j = sum_f W[:, f] dF_f/dx_j`.
fn first_layer(net: &Mlp, cond: &[f32], tape: &mut Tape) {
    let (at, rows, t) = (net.layer(0), tape.rows, tape.t);
    let w = &net.params()[at.w..at.b];
    let n = at.n_out;
    for (r, features) in tape.features.iter().enumerate() {
        let nf = features.count;
        for o in 0..n {
            let row = &w[o * at.n_in..o * at.n_in + nf + 1];
            let mut value = cond[o];
            let (mut d0, mut d1) = (0.0f32, 0.0f32);
            for (f, w) in row[..nf].iter().enumerate() {
                value += w * features.value[f];
                d0 += w * features.first[0][f];
                d1 += w * features.first[1][f];
            }
            tape.pre[0][r * n + o] = value + row[nf] * t;
            tape.pre_tan[0][r * n + o] = d0;
            tape.pre_tan[0][(rows + r) * n + o] = d1;
        }
    }
}

/// Hidden layer `l` (`n` units): `h = silu(z)`, `dh_j = silu'(z) dz_j`.
fn activate(tape: &mut Tape, l: usize, n: usize) {
    let rows = tape.rows;
    let (z, z_tan) = (&tape.pre[l], &tape.pre_tan[l]);
    let (h, h_tan) = (&mut tape.post[l], &mut tape.post_tan[l]);
    h.resize(rows * n, 0.0);
    h_tan.resize(2 * rows * n, 0.0);
    for (k, &zk) in z.iter().enumerate() {
        let (value, slope, _, _) = silu_derivatives(zk);
        h[k] = value;
        h_tan[k] = slope * z_tan[k];
        h_tan[rows * n + k] = slope * z_tan[rows * n + k];
    }
}

/// The reverse pass's cotangents, kept between calls so that it allocates nothing.
#[derive(Clone, Debug, Default)]
pub(super) struct Cotangents {
    /// Of the current layer's pre-activation.
    z: Vec<f32>,
    /// Of its two tangents.
    z_tan: [Vec<f32>; 2],
    /// Of the layer's input.
    a: Vec<f32>,
    /// Of its two tangents.
    a_tan: [Vec<f32>; 2],
}

/// Reverse pass of [`forward`] for one of its rows (at the `x` and `t` its tape holds):
/// given `dL/dv` and `dL/dJ` (same layout as `J`), adds `dL/dparams` to `grad` (the first
/// layer's `wi` columns and bias excepted: their cotangent `dL/dcond` is added to
/// `cond_grad`) and returns `dL/dx`.
pub(super) fn backward(
    (net, bar): (&Mlp, &mut Cotangents),
    (tape, row): (&Tape, usize),
    (v_bar, j_bar): VelocityJacobian,
    grad: &mut [f32],
    cond_grad: &mut [f32],
) -> [f32; 2] {
    let layers = net.layers().len();
    let params = net.params();
    let Cotangents {
        z: z_bar,
        z_tan: t_bar,
        a: a_bar,
        a_tan: a_tan_bar,
    } = bar;
    z_bar.clear();
    z_bar.extend_from_slice(&v_bar);
    t_bar[0].clear();
    t_bar[0].extend_from_slice(&[j_bar[0][0], j_bar[1][0]]);
    t_bar[1].clear();
    t_bar[1].extend_from_slice(&[j_bar[0][1], j_bar[1][1]]);
    let mut x_bar = [0.0f32; 2];
    for l in (0..layers).rev() {
        let at = net.layer(l);
        let w = &params[at.w..at.b];
        if l == 0 {
            let (features, t) = (&tape.features[row], tape.t);
            let nf = features.count;
            for o in 0..at.n_out {
                let (g, g0, g1) = (z_bar[o], t_bar[0][o], t_bar[1][o]);
                let gw = &mut grad[at.w + o * at.n_in..at.w + o * at.n_in + nf + 1];
                let row = &w[o * at.n_in..o * at.n_in + nf];
                for f in 0..nf {
                    // dz/dW[o][f] = F_f, and dz_j/dW[o][f] = dF_f/dx_j
                    gw[f] += g * features.value[f]
                        + g0 * features.first[0][f]
                        + g1 * features.first[1][f];
                    // z and z_j move with x through F and dF
                    for (k, xb) in x_bar.iter_mut().enumerate() {
                        *xb += row[f]
                            * (g * features.first[k][f]
                                + g0 * features.second[0][k][f]
                                + g1 * features.second[1][k][f]);
                    }
                }
                gw[nf] += g * t;
                cond_grad[o] += g;
            }
            break;
        }
        let n_in = at.n_in;
        let a = tape.post(l - 1, row, n_in);
        let a_tan = [
            tape.post_tan(l - 1, 0, row, n_in),
            tape.post_tan(l - 1, 1, row, n_in),
        ];
        let [a0_bar, a1_bar] = &mut *a_tan_bar;
        for v in [&mut *a_bar, &mut *a0_bar, &mut *a1_bar] {
            v.clear();
            v.resize(n_in, 0.0);
        }
        let (a_bar, a0_bar, a1_bar) =
            (&mut a_bar[..n_in], &mut a0_bar[..n_in], &mut a1_bar[..n_in]);
        let (gw, gb) = grad[at.w..at.b + at.n_out].split_at_mut(at.b - at.w);
        let cotangents = [&z_bar[..], &t_bar[0][..], &t_bar[1][..]];
        layer_backward(
            w,
            cotangents,
            [a, a_tan[0], a_tan[1]],
            (gw, gb),
            [a_bar, a0_bar, a1_bar],
        );
        // Through h = silu(z), dh_j = silu'(z) dz_j.
        let z = tape.pre(l - 1, row, n_in);
        let z_tan = [
            tape.pre_tan(l - 1, 0, row, n_in),
            tape.pre_tan(l - 1, 1, row, n_in),
        ];
        z_bar.clear();
        t_bar[0].clear();
        t_bar[1].clear();
        for i in 0..n_in {
            let (_, s1, s2, _) = silu_derivatives(z[i]);
            z_bar.push(a_bar[i] * s1 + s2 * (a0_bar[i] * z_tan[0][i] + a1_bar[i] * z_tan[1][i]));
            t_bar[0].push(a0_bar[i] * s1);
            t_bar[1].push(a1_bar[i] * s1);
        }
    }
    x_bar
}

/// One hidden or read-out layer of [`backward`] (`z = W a + b`, `dz_j = W da_j`): adds
/// `z_bar a^T + sum_j t_bar_j da_j^T` to the weights' gradient `gw`, `z_bar` to the
/// bias's `gb`, and `W^T` times each cotangent to `a_bar`, `da_j_bar` (outputs in order).
/// Compiled twice, for the build's target and with AVX2 where the CPU has it: the loops
/// are elementwise, so both copies give the same bits.
#[inline]
fn layer_backward(
    w: &[f32],
    [g, g0, g1]: [&[f32]; 3],
    [a, a0, a1]: [&[f32]; 3],
    (gw, gb): (&mut [f32], &mut [f32]),
    [a_bar, a0_bar, a1_bar]: [&mut [f32]; 3],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        #[allow(unsafe_code)]
        // SAFETY: the CPU has AVX2, the only feature the copy is compiled with.
        unsafe {
            layer_backward_avx2(
                w,
                [g, g0, g1],
                [a, a0, a1],
                (gw, gb),
                [a_bar, a0_bar, a1_bar],
            );
        }
        return;
    }
    layer_backward_body(
        w,
        [g, g0, g1],
        [a, a0, a1],
        (gw, gb),
        [a_bar, a0_bar, a1_bar],
    );
}

/// [`layer_backward`] compiled with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn layer_backward_avx2(
    w: &[f32],
    g: [&[f32]; 3],
    a: [&[f32]; 3],
    grads: (&mut [f32], &mut [f32]),
    a_bar: [&mut [f32]; 3],
) {
    layer_backward_body(w, g, a, grads, a_bar);
}

#[inline(always)]
fn layer_backward_body(
    w: &[f32],
    g: [&[f32]; 3],
    a: [&[f32]; 3],
    grads: (&mut [f32], &mut [f32]),
    [a_bar, a0_bar, a1_bar]: [&mut [f32]; 3],
) {
    // The student's width (the kernel's definition) as a constant: its input cotangents
    // stay in registers.
    const WIDTH: usize = ModelDef::paper_disk().velocity.width as usize;
    if a[0].len() == WIDTH {
        let mut sums = [[0.0f32; WIDTH]; 3];
        let [s, s0, s1] = &mut sums;
        accumulate(w, g, a, grads, [s, s0, s1]);
        a_bar[..WIDTH].copy_from_slice(s);
        a0_bar[..WIDTH].copy_from_slice(s0);
        a1_bar[..WIDTH].copy_from_slice(s1);
    } else {
        accumulate(w, g, a, grads, [a_bar, a0_bar, a1_bar]);
    }
}

/// The loops of [`layer_backward`], into the input cotangents `s` (zeroed, one entry per
/// input).
#[inline(always)]
fn accumulate(
    w: &[f32],
    [g, g0, g1]: [&[f32]; 3],
    [a, a0, a1]: [&[f32]; 3],
    (gw, gb): (&mut [f32], &mut [f32]),
    [s, s0, s1]: [&mut [f32]; 3],
) {
    let n_in = s.len();
    let (a, a0, a1) = (&a[..n_in], &a0[..n_in], &a1[..n_in]);
    let (s0, s1) = (&mut s0[..n_in], &mut s1[..n_in]);
    for (o, (gb, gw)) in gb.iter_mut().zip(gw.chunks_exact_mut(n_in)).enumerate() {
        let row = &w[o * n_in..(o + 1) * n_in];
        let (g, g0, g1) = (g[o], g0[o], g1[o]);
        *gb += g;
        for i in 0..n_in {
            gw[i] += g * a[i] + g0 * a0[i] + g1 * a1[i];
            s[i] += row[i] * g;
            s0[i] += row[i] * g0;
            s1[i] += row[i] * g1;
        }
    }
}

/// Adds the `wi` columns' and the bias's share of `cond_grad` to `grad`.
pub(super) fn condition_backward(
    domain: Domain,
    net: &Mlp,
    enc: &[f32],
    cond_grad: &[f32],
    grad: &mut [f32],
) {
    let state = state_inputs(domain);
    let at = net.layer(0);
    for (o, g) in cond_grad.iter().enumerate() {
        grad[at.b + o] += g;
        let row = &mut grad[at.w + o * at.n_in + state..at.w + (o + 1) * at.n_in];
        for (gw, e) in row.iter_mut().zip(enc) {
            *gw += g * e;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::paper_def;
    use diffbsdf::{Domain, Net};
    use rand::SeedableRng;
    use rand_pcg::Pcg64;

    /// `v` and `J` at one point alone.
    fn at_point(
        domain: Domain,
        net: &Mlp,
        cond: &[f32],
        x: [f32; 2],
        t: f32,
        tape: &mut Tape,
    ) -> VelocityJacobian {
        let mut out = Vec::new();
        forward(
            domain,
            (net, &Transposed::of(net)),
            cond,
            (&[x], t),
            tape,
            &mut out,
        );
        out[0]
    }

    /// `L = a.v + sum B o J` for fixed `a`, `B`: a scalar of both outputs.
    fn scalar(domain: Domain, net: &Mlp, enc: &[f32], x: [f32; 2], t: f32) -> f64 {
        let cond = condition(domain, net, enc);
        let (v, j) = at_point(domain, net, &cond, x, t, &mut Tape::default());
        let (a, b) = ([0.7f64, -1.3], [[0.4f64, -0.9], [1.1, 0.25]]);
        a[0] * v[0] as f64
            + a[1] * v[1] as f64
            + (0..2)
                .flat_map(|r| (0..2).map(move |c| (r, c)))
                .map(|(r, c)| b[r][c] * j[r][c] as f64)
                .sum::<f64>()
    }

    /// The reverse pass on a flat chart (features `x`) and a spherical one (features
    /// `(theta, sin phi, cos phi)`, whose second derivatives enter `dL/dx`).
    #[test]
    fn reverse_pass_matches_finite_differences() {
        reverse_pass_on(Domain::HalfVector, [0.4, -0.8]);
        reverse_pass_on(Domain::Sphere, [1.1, -2.3]);
    }

    fn reverse_pass_on(domain: Domain, x: [f32; 2]) {
        let def = paper_def(domain);
        let mut rng = Pcg64::seed_from_u64(3);
        let net = Mlp::new(&def, Net::Velocity, &mut rng);
        let enc: Vec<f32> = (0..net.inputs() - state_inputs(domain))
            .map(|i| (i as f32 * 0.37).sin())
            .collect();
        let t = 0.3f32;
        let cond = condition(domain, &net, &enc);
        // The point as the middle row of a batch.
        let xs = [[x[1], x[0]], x, [0.1, 0.2]];
        let mut tape = Tape::default();
        forward(
            domain,
            (&net, &Transposed::of(&net)),
            &cond,
            (&xs, t),
            &mut tape,
            &mut Vec::new(),
        );
        let mut grad = vec![0.0f32; net.params().len()];
        let mut cond_grad = vec![0.0f32; cond.len()];
        let seed = ([0.7f32, -1.3], [[0.4f32, -0.9], [1.1, 0.25]]);
        let bar = &mut Cotangents::default();
        let x_bar = backward((&net, bar), (&tape, 1), seed, &mut grad, &mut cond_grad);
        condition_backward(domain, &net, &enc, &cond_grad, &mut grad);
        let eps = 1e-2f32;
        // Every parameter of the first and last layer and a stride through the rest.
        let checks: Vec<usize> = (0..grad.len()).step_by(7).collect();
        for k in checks {
            let (mut plus, mut minus) = (net.clone(), net.clone());
            plus.params_mut()[k] += eps;
            minus.params_mut()[k] -= eps;
            let fd = (scalar(domain, &plus, &enc, x, t) - scalar(domain, &minus, &enc, x, t))
                / (2.0 * eps as f64);
            let g = grad[k] as f64;
            assert!(
                (fd - g).abs() < 2e-4 + 1e-2 * g.abs(),
                "{domain:?} param {k}: {g} vs {fd}"
            );
        }
        for j in 0..2 {
            let (mut xp, mut xm) = (x, x);
            xp[j] += eps;
            xm[j] -= eps;
            let fd = (scalar(domain, &net, &enc, xp, t) - scalar(domain, &net, &enc, xm, t))
                / (2.0 * eps as f64);
            let g = x_bar[j] as f64;
            assert!(
                (fd - g).abs() < 2e-4 + 1e-2 * g.abs(),
                "{domain:?} x_{j}: {g} vs {fd}"
            );
        }
    }

    /// Every row of a batch has the bits of its point evaluated alone, forward and back.
    #[test]
    fn rows_of_a_batch_have_the_bits_of_single_points() {
        for domain in [Domain::HalfVector, Domain::Sphere] {
            let def = paper_def(domain);
            let net = Mlp::new(&def, Net::Velocity, &mut Pcg64::seed_from_u64(8));
            let enc: Vec<f32> = (0..net.inputs() - state_inputs(domain))
                .map(|i| (i as f32 * 0.53).cos())
                .collect();
            let cond = condition(domain, &net, &enc);
            let xs: Vec<[f32; 2]> = (0..13)
                .map(|i| [(i as f32 * 0.77).sin(), (i as f32 * 1.31).cos() * 2.0])
                .collect();
            let (mut tape, mut out) = (Tape::default(), Vec::new());
            forward(
                domain,
                (&net, &Transposed::of(&net)),
                &cond,
                (&xs, 0.55),
                &mut tape,
                &mut out,
            );
            let seed = ([0.3f32, -0.6], [[1.2f32, 0.1], [-0.4, 0.8]]);
            for (r, &x) in xs.iter().enumerate() {
                let mut alone = Tape::default();
                let single = at_point(domain, &net, &cond, x, 0.55, &mut alone);
                assert_eq!(
                    format!("{:?}", out[r]),
                    format!("{single:?}"),
                    "{domain:?} row {r}"
                );
                let mut g = [
                    vec![0.0f32; net.params().len()],
                    vec![0.0f32; net.params().len()],
                ];
                let mut c = [vec![0.0f32; cond.len()], vec![0.0f32; cond.len()]];
                let [g0, g1] = &mut g;
                let [c0, c1] = &mut c;
                let bar = &mut Cotangents::default();
                let x0 = backward((&net, bar), (&tape, r), seed, g0, c0);
                let x1 = backward((&net, bar), (&alone, 0), seed, g1, c1);
                let bits = |v: &[f32]| v.iter().map(|f| f.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&x0), bits(&x1), "{domain:?} row {r}: dL/dx");
                assert_eq!(bits(g0), bits(g1), "{domain:?} row {r}: dL/dparams");
                assert_eq!(bits(c0), bits(c1), "{domain:?} row {r}: dL/dcond");
            }
        }
    }
}
