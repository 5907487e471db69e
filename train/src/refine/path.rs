//! The student's `N` Euler steps `x_{k+1} = x_k + h v(x_k, t_k)` with their
//! `sum_k ln det(I + h J_k)` (docs/math.md, (1)), kept for the reverse pass that
//! differentiates `a . x_N + c sum_k ln det_k` with respect to the weights (the adjoint
//! of the steps, docs/math.md (69)).

use super::net::{backward, forward, Tape};
use crate::mlp::Mlp;
use diffbsdf::Domain;

/// Newton iterations per step of [`Path::invert`].
const INVERSE_ITERATIONS: usize = 12;
/// Newton stops when its update is at most this times `1 + |x|`.
const INVERSE_TOL: f32 = 1e-6;

/// One trajectory's points, Jacobians and tapes, on one chart (whose `advance` and
/// `difference` wrap `phi` on the sphere, as the kernel's steps do; a wrap moves a
/// point by a constant, so it leaves every derivative unchanged).
#[derive(Clone, Debug)]
pub(super) struct Path {
    domain: Domain,
    tapes: Vec<Tape>,
    points: Vec<[f32; 2]>,
    jacobians: Vec<[[f32; 2]; 2]>,
}

/// `det(I + h J)` of a 2x2 Jacobian.
fn step_det(h: f32, j: &[[f32; 2]; 2]) -> f32 {
    (1.0 + h * j[0][0]) * (1.0 + h * j[1][1]) - (h * j[0][1]) * (h * j[1][0])
}

impl Path {
    /// An empty path on `domain`'s chart.
    pub(super) fn new(domain: Domain) -> Path {
        Path {
            domain,
            tapes: Vec::new(),
            points: Vec::new(),
            jacobians: Vec::new(),
        }
    }

    /// Runs `steps` Euler steps from `x0`: the end point and `sum_k ln det(I + h J_k)`;
    /// `None` where a step folds (`det <= 0`) or leaves the finite numbers.
    pub(super) fn run(
        &mut self,
        net: &Mlp,
        cond: &[f32],
        x0: [f32; 2],
        steps: usize,
    ) -> Option<([f32; 2], f64)> {
        let h = 1.0 / steps as f32;
        self.tapes.resize(steps, Tape::default());
        self.points.clear();
        self.jacobians.clear();
        let domain = self.domain;
        let (mut x, mut ln_det) = (domain.advance(x0, [0.0, 0.0]), 0.0f64);
        for k in 0..steps {
            let (v, j) = forward(domain, net, cond, x, k as f32 * h, &mut self.tapes[k]);
            let det = step_det(h, &j);
            if !(det > 0.0) {
                return None;
            }
            ln_det += f64::from(det).ln();
            self.points.push(x);
            self.jacobians.push(j);
            x = domain.advance(x, [h * v[0], h * v[1]]);
        }
        (x[0].is_finite() && x[1].is_finite() && ln_det.is_finite()).then_some((x, ln_det))
    }

    /// The start point `x0` whose path ends at `end` (Newton on each step backwards, from
    /// the explicit guess `x_{k+1} - h v(x_{k+1})`); `None` where a solve fails. Leaves
    /// the path as [`Path::run`] from that start leaves it.
    pub(super) fn invert(
        &mut self,
        net: &Mlp,
        cond: &[f32],
        end: [f32; 2],
        steps: usize,
    ) -> Option<([f32; 2], f64)> {
        let h = 1.0 / steps as f32;
        let domain = self.domain;
        self.tapes.resize(steps.max(1), Tape::default());
        let mut y = domain.advance(end, [0.0, 0.0]);
        for k in (0..steps).rev() {
            let t = k as f32 * h;
            let (v, _) = forward(domain, net, cond, y, t, &mut self.tapes[0]);
            let mut x = domain.advance(y, [-h * v[0], -h * v[1]]);
            let mut converged = false;
            for _ in 0..INVERSE_ITERATIONS {
                let (v, j) = forward(domain, net, cond, x, t, &mut self.tapes[0]);
                let det = step_det(h, &j);
                if !(det > 0.0) {
                    return None;
                }
                // x <- x - (I + h J)^-1 (x + h v - y)
                let r = domain.difference(domain.advance(x, [h * v[0], h * v[1]]), y);
                let d = [
                    ((1.0 + h * j[1][1]) * r[0] - h * j[0][1] * r[1]) / det,
                    ((1.0 + h * j[0][0]) * r[1] - h * j[1][0] * r[0]) / det,
                ];
                x = domain.advance(x, [-d[0], -d[1]]);
                if d[0].abs().max(d[1].abs()) <= INVERSE_TOL * (1.0 + x[0].abs().max(x[1].abs())) {
                    converged = true;
                    break;
                }
            }
            if !converged {
                return None;
            }
            y = x;
        }
        let (again, ln_det) = self.run(net, cond, y, steps)?;
        let miss = domain.difference(again, end);
        let miss = miss[0].abs().max(miss[1].abs());
        (miss <= 1e-4 * (1.0 + end[0].abs().max(end[1].abs()))).then_some((y, ln_det))
    }

    /// After [`Path::invert`]: adds to `grad` (and `cond_grad`) `a` times the gradient of
    /// `ln p(x_N) = ln p0(x0) - sum_k ln det_k` at the fixed end point `x_N`, where `x0`
    /// moves with the weights (`d x0 = -M^-1 d x_N|x0`, `M = d x_N / d x0`), given
    /// `grad ln p0(x0)`; `None` (nothing added) where `M` is singular.
    pub(super) fn fixed_end_backward(
        &self,
        net: &Mlp,
        ln_p0_gradient: [f32; 2],
        a: f32,
        grad: &mut [f32],
        cond_grad: &mut [f32],
    ) -> Option<()> {
        let m = self.end_jacobian();
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        if !(det.abs() > 0.0) || !det.is_finite() {
            return None;
        }
        let r = self.backward(net, [0.0, 0.0], -a, grad, cond_grad);
        let g = [a * ln_p0_gradient[0] + r[0], a * ln_p0_gradient[1] + r[1]];
        // lambda M = g: the cotangent of x_N that moving x0 back to the fixed end costs
        let lambda = [
            (g[0] * m[1][1] - g[1] * m[1][0]) / det,
            (g[1] * m[0][0] - g[0] * m[0][1]) / det,
        ];
        self.backward(net, [-lambda[0], -lambda[1]], 0.0, grad, cond_grad);
        Some(())
    }

    /// `d x_N / d x0 = prod_k (I + h J_k)` of the path last run.
    pub(super) fn end_jacobian(&self) -> [[f32; 2]; 2] {
        let h = 1.0 / self.points.len().max(1) as f32;
        let mut m = [[1.0f32, 0.0], [0.0, 1.0]];
        for j in &self.jacobians {
            let a = [
                [1.0 + h * j[0][0], h * j[0][1]],
                [h * j[1][0], 1.0 + h * j[1][1]],
            ];
            m = [
                [
                    a[0][0] * m[0][0] + a[0][1] * m[1][0],
                    a[0][0] * m[0][1] + a[0][1] * m[1][1],
                ],
                [
                    a[1][0] * m[0][0] + a[1][1] * m[1][0],
                    a[1][0] * m[0][1] + a[1][1] * m[1][1],
                ],
            ];
        }
        m
    }

    /// After [`Path::run`]: adds to `grad` (and `cond_grad`, the first layer's `wi` part)
    /// the gradient of `end_bar . x_N + c sum_k ln det_k` with respect to the weights, and
    /// returns its gradient with respect to `x0`.
    pub(super) fn backward(
        &self,
        net: &Mlp,
        end_bar: [f32; 2],
        c: f32,
        grad: &mut [f32],
        cond_grad: &mut [f32],
    ) -> [f32; 2] {
        let steps = self.points.len();
        let h = 1.0 / steps as f32;
        let mut x_bar = end_bar;
        for k in (0..steps).rev() {
            let j = &self.jacobians[k];
            let a = [
                [1.0 + h * j[0][0], h * j[0][1]],
                [h * j[1][0], 1.0 + h * j[1][1]],
            ];
            let s = c * h / step_det(h, j);
            // d ln det(A) / dJ = h A^-T
            let j_bar = [[s * a[1][1], -s * a[1][0]], [-s * a[0][1], s * a[0][0]]];
            let v_bar = [h * x_bar[0], h * x_bar[1]];
            let through_net = backward(net, &self.tapes[k], (v_bar, j_bar), grad, cond_grad);
            // x_{k+1} = x_k + h v(x_k): the identity plus the net's share
            x_bar = [x_bar[0] + through_net[0], x_bar[1] + through_net[1]];
        }
        x_bar
    }
}

#[cfg(test)]
mod tests {
    use super::super::net::{condition, condition_backward, state_inputs};
    use super::*;
    use crate::pipeline::paper_def;
    use diffbsdf::{Domain, Net};
    use rand::SeedableRng;
    use rand_pcg::Pcg64;

    /// The two kinds of chart: flat (features `x`) and spherical (wrapped `phi`).
    const DOMAINS: [Domain; 2] = [Domain::HalfVector, Domain::Sphere];

    /// A random student on `domain` with a readout large enough to bend the paths, and a
    /// fixed `wi` encoding.
    fn test_net(domain: Domain, seed: u64) -> (Mlp, Vec<f32>) {
        let def = paper_def(domain);
        let mut rng = Pcg64::seed_from_u64(seed);
        let mut net = Mlp::new(&def, Net::Velocity, &mut rng);
        net.scale_last_layer(2.0);
        let enc = (0..net.inputs() - state_inputs(domain))
            .map(|i| (i as f32 * 0.61 + seed as f32).cos())
            .collect();
        (net, enc)
    }

    /// Every fifth entry of `grad` against central differences of `f` in the weights.
    fn check_gradient(net: &Mlp, grad: &[f32], f: impl Fn(&Mlp) -> f64) {
        let eps = 1e-2f32;
        for k in (0..grad.len()).step_by(5) {
            let (mut plus, mut minus) = (net.clone(), net.clone());
            plus.params_mut()[k] += eps;
            minus.params_mut()[k] -= eps;
            let fd = (f(&plus) - f(&minus)) / (2.0 * eps as f64);
            let g = grad[k] as f64;
            assert!(
                (fd - g).abs() < 3e-3 * (1.0 + g.abs()),
                "param {k}: {g} vs {fd}"
            );
        }
    }

    fn objective(domain: Domain, net: &Mlp, enc: &[f32], x0: [f32; 2]) -> f64 {
        let cond = condition(domain, net, enc);
        let (end, ln_det) = Path::new(domain)
            .run(net, &cond, x0, 4)
            .expect("an unfolded path");
        0.6 * end[0] as f64 - 1.7 * end[1] as f64 + 0.8 * ln_det
    }

    #[test]
    fn reverse_pass_matches_finite_differences() {
        for domain in DOMAINS {
            let (net, enc) = test_net(domain, 5);
            let x0 = [0.9f32, -0.3];
            let cond = condition(domain, &net, &enc);
            let mut path = Path::new(domain);
            path.run(&net, &cond, x0, 4).expect("an unfolded path");
            let mut grad = vec![0.0f32; net.params().len()];
            let mut cond_grad = vec![0.0f32; cond.len()];
            path.backward(&net, [0.6, -1.7], 0.8, &mut grad, &mut cond_grad);
            condition_backward(domain, &net, &enc, &cond_grad, &mut grad);
            check_gradient(&net, &grad, |n| objective(domain, n, &enc, x0));
        }
    }

    /// `ln p(end)` with `ln p0(x0) = -|x0|^2 / 2` through the inverse.
    fn density(domain: Domain, net: &Mlp, enc: &[f32], end: [f32; 2]) -> f64 {
        let cond = condition(domain, net, enc);
        let (x0, ln_det) = Path::new(domain)
            .invert(net, &cond, end, 4)
            .expect("an invertible path");
        -0.5 * (x0[0] as f64 * x0[0] as f64 + x0[1] as f64 * x0[1] as f64) - ln_det
    }

    #[test]
    fn inverse_returns_the_start_and_its_density_gradient_matches_finite_differences() {
        for domain in DOMAINS {
            inverse_on(domain);
        }
    }

    fn inverse_on(domain: Domain) {
        let (net, enc) = test_net(domain, 9);
        let cond = condition(domain, &net, &enc);
        let x0 = [0.7f32, 0.45];
        let mut path = Path::new(domain);
        let (end, ln_det) = path.run(&net, &cond, x0, 4).expect("an unfolded path");
        let (back, ln_det_back) = path
            .invert(&net, &cond, end, 4)
            .expect("an invertible path");
        assert!(
            (back[0] - x0[0]).abs() < 1e-5 && (back[1] - x0[1]).abs() < 1e-5,
            "{domain:?}: {back:?}"
        );
        assert!((ln_det - ln_det_back).abs() < 1e-5);
        let mut grad = vec![0.0f32; net.params().len()];
        let mut cond_grad = vec![0.0f32; cond.len()];
        path.fixed_end_backward(&net, [-back[0], -back[1]], 1.0, &mut grad, &mut cond_grad)
            .expect("a regular path");
        condition_backward(domain, &net, &enc, &cond_grad, &mut grad);
        check_gradient(&net, &grad, |n| density(domain, n, &enc, end));
    }
}
