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
use diffbsdf::spec::MAX_FEATURES;
use diffbsdf::Domain;

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

/// The activations of one evaluation, kept for the reverse pass.
#[derive(Clone, Debug, Default)]
pub(super) struct Tape {
    /// The state features of the evaluated `x`.
    features: StateFeatures,
    /// The evaluated `t`.
    t: f32,
    /// Pre-activations of every layer (the read-out last).
    pre: Vec<Vec<f32>>,
    /// Their two tangents along `x_0` and `x_1`.
    pre_tan: Vec<[Vec<f32>; 2]>,
    /// SiLU of every hidden layer.
    post: Vec<Vec<f32>>,
    /// Its two tangents.
    post_tan: Vec<[Vec<f32>; 2]>,
}

/// `v(x, t)` and its Jacobian `J[r][j] = dv_r / dx_j`.
pub(super) type VelocityJacobian = ([f32; 2], [[f32; 2]; 2]);

/// Evaluates `v` and `dv/dx` at `(x, t)` for the conditioned first layer `cond`.
pub(super) fn forward(
    domain: Domain,
    net: &Mlp,
    cond: &[f32],
    x: [f32; 2],
    t: f32,
    tape: &mut Tape,
) -> VelocityJacobian {
    let layers = net.layers().len();
    tape.pre.resize(layers, Vec::new());
    tape.pre_tan.resize(layers, [Vec::new(), Vec::new()]);
    tape.post.resize(layers - 1, Vec::new());
    tape.post_tan.resize(layers - 1, [Vec::new(), Vec::new()]);
    let params = net.params();
    tape.features = StateFeatures::at(domain, x);
    tape.t = t;
    let features = &tape.features;
    let nf = features.count;
    for l in 0..layers {
        let at = net.layer(l);
        let w = &params[at.w..at.b];
        let b = &params[at.b..at.b + at.n_out];
        let (z, [z0, z1]) = (&mut tape.pre[l], &mut tape.pre_tan[l]);
        z.resize(at.n_out, 0.0);
        z0.resize(at.n_out, 0.0);
        z1.resize(at.n_out, 0.0);
        if l == 0 {
            for o in 0..at.n_out {
                let row = &w[o * at.n_in..o * at.n_in + nf + 1];
                // z = cond + sum_f W[:, f] F_f(x) + W[:, nf] t; dz/dx_j = sum_f W[:, f] dF_f/dx_j
                let mut value = cond[o];
                let (mut d0, mut d1) = (0.0f32, 0.0f32);
                for (f, w) in row[..nf].iter().enumerate() {
                    value += w * features.value[f];
                    d0 += w * features.first[0][f];
                    d1 += w * features.first[1][f];
                }
                z[o] = value + row[nf] * t;
                z0[o] = d0;
                z1[o] = d1;
            }
        } else {
            let (a, [a0, a1]) = (&tape.post[l - 1], &tape.post_tan[l - 1]);
            for o in 0..at.n_out {
                let row = &w[o * at.n_in..(o + 1) * at.n_in];
                z[o] = b[o] + dot(row, a);
                z0[o] = dot(row, a0);
                z1[o] = dot(row, a1);
            }
        }
        if net.layers()[l].activated {
            let (h, [h0, h1]) = (&mut tape.post[l], &mut tape.post_tan[l]);
            h.clear();
            h0.clear();
            h1.clear();
            for o in 0..at.n_out {
                let (value, slope, _, _) = silu_derivatives(z[o]);
                h.push(value);
                h0.push(slope * z0[o]);
                h1.push(slope * z1[o]);
            }
        }
    }
    let (v, [v0, v1]) = (&tape.pre[layers - 1], &tape.pre_tan[layers - 1]);
    ([v[0], v[1]], [[v0[0], v1[0]], [v0[1], v1[1]]])
}

/// Reverse pass of [`forward`] (at the `x` and `t` its tape holds): given `dL/dv` and
/// `dL/dJ` (same layout as `J`), adds `dL/dparams` to `grad` (the first layer's `wi`
/// columns and bias excepted: their cotangent `dL/dcond` is added to `cond_grad`) and
/// returns `dL/dx`.
pub(super) fn backward(
    net: &Mlp,
    tape: &Tape,
    (v_bar, j_bar): VelocityJacobian,
    grad: &mut [f32],
    cond_grad: &mut [f32],
) -> [f32; 2] {
    let layers = net.layers().len();
    let params = net.params();
    // Cotangents of the current layer's pre-activation and its two tangents.
    let mut z_bar = v_bar.to_vec();
    let mut t_bar = [
        vec![j_bar[0][0], j_bar[1][0]],
        vec![j_bar[0][1], j_bar[1][1]],
    ];
    let mut x_bar = [0.0f32; 2];
    for l in (0..layers).rev() {
        let at = net.layer(l);
        let w = &params[at.w..at.b];
        if l == 0 {
            let (features, t) = (&tape.features, tape.t);
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
        let (a, a_tan) = (&tape.post[l - 1], &tape.post_tan[l - 1]);
        let mut a_bar = vec![0.0f32; at.n_in];
        let mut a_tan_bar = [vec![0.0f32; at.n_in], vec![0.0f32; at.n_in]];
        for o in 0..at.n_out {
            let row = &w[o * at.n_in..(o + 1) * at.n_in];
            let (g, g0, g1) = (z_bar[o], t_bar[0][o], t_bar[1][o]);
            grad[at.b + o] += g;
            let gw = &mut grad[at.w + o * at.n_in..at.w + (o + 1) * at.n_in];
            for i in 0..at.n_in {
                // z = W a + b, dz_j = W da_j: dW += z_bar a^T + sum_j t_bar_j da_j^T
                gw[i] += g * a[i] + g0 * a_tan[0][i] + g1 * a_tan[1][i];
                a_bar[i] += row[i] * g;
                a_tan_bar[0][i] += row[i] * g0;
                a_tan_bar[1][i] += row[i] * g1;
            }
        }
        // Through h = silu(z), dh_j = silu'(z) dz_j.
        let (z, z_tan) = (&tape.pre[l - 1], &tape.pre_tan[l - 1]);
        z_bar.clear();
        t_bar[0].clear();
        t_bar[1].clear();
        for i in 0..at.n_in {
            let (_, s1, s2, _) = silu_derivatives(z[i]);
            z_bar.push(
                a_bar[i] * s1
                    + s2 * (a_tan_bar[0][i] * z_tan[0][i] + a_tan_bar[1][i] * z_tan[1][i]),
            );
            t_bar[0].push(a_tan_bar[0][i] * s1);
            t_bar[1].push(a_tan_bar[1][i] * s1);
        }
    }
    x_bar
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

    /// `L = a.v + sum B o J` for fixed `a`, `B`: a scalar of both outputs.
    fn scalar(domain: Domain, net: &Mlp, enc: &[f32], x: [f32; 2], t: f32) -> f64 {
        let cond = condition(domain, net, enc);
        let (v, j) = forward(domain, net, &cond, x, t, &mut Tape::default());
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
        let mut tape = Tape::default();
        forward(domain, &net, &cond, x, t, &mut tape);
        let mut grad = vec![0.0f32; net.params().len()];
        let mut cond_grad = vec![0.0f32; cond.len()];
        let seed = ([0.7f32, -1.3], [[0.4f32, -0.9], [1.1, 0.25]]);
        let x_bar = backward(&net, &tape, seed, &mut grad, &mut cond_grad);
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
}
