//! The student's `N` Euler steps `x_{k+1} = x_k + h v(x_k, t_k)` with their
//! `sum_k ln det(I + h J_k)` (docs/math.md, (1)), kept for the reverse pass that
//! differentiates `a . x_N + c sum_k ln det_k` with respect to the weights (the adjoint
//! of the steps, docs/math.md (69)).

use super::net::{backward, forward, Cotangents, Tape, Transposed, VelocityJacobian};
use crate::mlp::Mlp;
use diffbsdf::Domain;

/// Newton iterations per step of [`Paths::invert`].
const INVERSE_ITERATIONS: usize = 12;
/// Newton stops when its update is at most this times `1 + |x|`.
const INVERSE_TOL: f32 = 1e-6;

/// Rows of a batch: the hidden layers' products run on register tiles over this many
/// points at once (their tapes stay in the second-level cache).
pub(super) const BATCH: usize = 64;

/// `Some` row result per point of a batch, `None` where it failed.
pub(super) type Ends = Vec<Option<([f32; 2], f64)>>;

/// A batch of trajectories' Jacobians and tapes, on one chart (whose `advance` and
/// `difference` wrap `phi` on the sphere, as the kernel's steps do; a wrap moves a
/// point by a constant, so it leaves every derivative unchanged). Every row computes what
/// it would alone, bit for bit ([`forward`]); the rows share the weights' loads.
#[derive(Clone, Debug)]
pub(super) struct Paths {
    domain: Domain,
    /// One tape per step of the last run.
    tapes: Vec<Tape>,
    /// `jacobians[k][row]`: the Jacobian of step `k`.
    jacobians: Vec<Vec<[[f32; 2]; 2]>>,
    /// Steps of the last run.
    steps: usize,
    /// The tape of the inverse's evaluations.
    scratch: Tape,
    /// The velocities and Jacobians of one evaluation.
    out: Vec<VelocityJacobian>,
    /// The reverse pass's cotangents.
    bar: Cotangents,
}

/// `det(I + h J)` of a 2x2 Jacobian.
fn step_det(h: f32, j: &[[f32; 2]; 2]) -> f32 {
    (1.0 + h * j[0][0]) * (1.0 + h * j[1][1]) - (h * j[0][1]) * (h * j[1][0])
}

impl Paths {
    /// An empty batch on `domain`'s chart.
    pub(super) fn new(domain: Domain) -> Paths {
        Paths {
            domain,
            tapes: Vec::new(),
            jacobians: Vec::new(),
            steps: 0,
            scratch: Tape::default(),
            out: Vec::new(),
            bar: Cotangents::default(),
        }
    }

    /// Runs `steps` Euler steps from every point of `x0`: per row, the end point and
    /// `sum_k ln det(I + h J_k)`; `None` where a step folds (`det <= 0`) or leaves the
    /// finite numbers.
    pub(super) fn run(
        &mut self,
        net: (&Mlp, &Transposed),
        cond: &[f32],
        x0: &[[f32; 2]],
        steps: usize,
    ) -> Ends {
        let h = 1.0 / steps as f32;
        let (domain, rows) = (self.domain, x0.len());
        self.steps = steps;
        self.tapes.resize(steps, Tape::default());
        self.jacobians.resize(steps, Vec::new());
        let mut x: Vec<[f32; 2]> = x0.iter().map(|&p| domain.advance(p, [0.0, 0.0])).collect();
        let mut ln_det = vec![Some(0.0f64); rows];
        for k in 0..steps {
            let t = k as f32 * h;
            forward(
                domain,
                net,
                cond,
                (&x, t),
                &mut self.tapes[k],
                &mut self.out,
            );
            self.jacobians[k].clear();
            for (r, &(v, j)) in self.out.iter().enumerate() {
                self.jacobians[k].push(j);
                let det = step_det(h, &j);
                ln_det[r] = ln_det[r]
                    .filter(|_| det > 0.0)
                    .map(|l| l + f64::from(det).ln());
                // A folded row goes on from the origin (its result is dropped).
                x[r] = match ln_det[r] {
                    Some(_) => domain.advance(x[r], [h * v[0], h * v[1]]),
                    None => [0.0, 0.0],
                };
            }
        }
        x.iter()
            .zip(ln_det)
            .map(|(x, ln_det)| {
                let ln_det = ln_det?;
                (x[0].is_finite() && x[1].is_finite() && ln_det.is_finite()).then_some((*x, ln_det))
            })
            .collect()
    }

    /// Per row, the start point `x0` whose path ends at `ends[row]` (Newton on each step
    /// backwards, from the explicit guess `x_{k+1} - h v(x_{k+1})`), with `sum_k ln
    /// det_k`; `None` where a solve fails. Leaves the batch as [`Paths::run`] from those
    /// starts leaves it (a failed row run from the origin).
    pub(super) fn invert(
        &mut self,
        net: (&Mlp, &Transposed),
        cond: &[f32],
        ends: &[[f32; 2]],
        steps: usize,
    ) -> Ends {
        let h = 1.0 / steps as f32;
        let domain = self.domain;
        let mut y: Vec<Option<[f32; 2]>> = ends
            .iter()
            .map(|&e| Some(domain.advance(e, [0.0, 0.0])))
            .collect();
        for k in (0..steps).rev() {
            self.invert_step(net, cond, &mut y, (h, k as f32 * h));
        }
        let starts: Vec<[f32; 2]> = y.iter().map(|p| p.unwrap_or([0.0, 0.0])).collect();
        let again = self.run(net, cond, &starts, steps);
        again
            .iter()
            .zip(&y)
            .zip(ends)
            .map(|((again, y), end)| {
                let (y, (back, ln_det)) = (y.as_ref()?, again.as_ref()?);
                let miss = domain.difference(*back, *end);
                let miss = miss[0].abs().max(miss[1].abs());
                (miss <= 1e-4 * (1.0 + end[0].abs().max(end[1].abs()))).then_some((*y, *ln_det))
            })
            .collect()
    }

    /// `v` and `J` at `points` at `t` into `self.out` (the inverse's scratch tape).
    fn evaluate(&mut self, net: (&Mlp, &Transposed), cond: &[f32], at: (&[[f32; 2]], f32)) {
        forward(self.domain, net, cond, at, &mut self.scratch, &mut self.out);
    }

    /// One step of [`Paths::invert`] at `t` for every live row of `y` (`x_{k+1}` in,
    /// `x_k` out; `None` where the solve fails). Newton runs on the rows still unsolved,
    /// each row's iterates those it would have alone.
    fn invert_step(
        &mut self,
        net: (&Mlp, &Transposed),
        cond: &[f32],
        y: &mut [Option<[f32; 2]>],
        (h, t): (f32, f32),
    ) {
        let domain = self.domain;
        let mut active: Vec<usize> = (0..y.len()).filter(|&r| y[r].is_some()).collect();
        let mut points: Vec<[f32; 2]> = active.iter().filter_map(|&r| y[r]).collect();
        self.evaluate(net, cond, (&points, t));
        let mut x = vec![[0.0f32; 2]; y.len()];
        for ((&r, &p), &(v, _)) in active.iter().zip(&points).zip(&self.out) {
            x[r] = domain.advance(p, [-h * v[0], -h * v[1]]);
        }
        let mut solved: Vec<Option<[f32; 2]>> = vec![None; y.len()];
        for _ in 0..INVERSE_ITERATIONS {
            if active.is_empty() {
                break;
            }
            points.clear();
            points.extend(active.iter().map(|&r| x[r]));
            self.evaluate(net, cond, (&points, t));
            let mut still = Vec::with_capacity(active.len());
            for (&r, &(v, j)) in active.iter().zip(&self.out) {
                let (Some(target), det) = (y[r], step_det(h, &j)) else {
                    continue;
                };
                if !(det > 0.0) {
                    y[r] = None;
                    continue;
                }
                // x <- x - (I + h J)^-1 (x + h v - y)
                let res = domain.difference(domain.advance(x[r], [h * v[0], h * v[1]]), target);
                let d = [
                    ((1.0 + h * j[1][1]) * res[0] - h * j[0][1] * res[1]) / det,
                    ((1.0 + h * j[0][0]) * res[1] - h * j[1][0] * res[0]) / det,
                ];
                x[r] = domain.advance(x[r], [-d[0], -d[1]]);
                let size = 1.0 + x[r][0].abs().max(x[r][1].abs());
                if d[0].abs().max(d[1].abs()) <= INVERSE_TOL * size {
                    solved[r] = Some(x[r]);
                } else {
                    still.push(r);
                }
            }
            active = still;
        }
        // Rows not solved within the iterations fail.
        for (yr, s) in y.iter_mut().zip(solved) {
            *yr = s;
        }
    }
    /// After [`Paths::invert`], for `row`: adds to `grad` (and `cond_grad`) `a` times the
    /// gradient of `ln p(x_N) = ln p0(x0) - sum_k ln det_k` at the fixed end point `x_N`,
    /// where `x0` moves with the weights (`d x0 = -M^-1 d x_N|x0`, `M = d x_N / d x0`),
    /// given `grad ln p0(x0)`; `None` (nothing added) where `M` is singular.
    pub(super) fn fixed_end_backward(
        &mut self,
        (net, row): (&Mlp, usize),
        ln_p0_gradient: [f32; 2],
        a: f32,
        grad: &mut [f32],
        cond_grad: &mut [f32],
    ) -> Option<()> {
        let m = self.end_jacobian(row);
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        if !(det.abs() > 0.0) || !det.is_finite() {
            return None;
        }
        let r = self.backward((net, row), [0.0, 0.0], -a, grad, cond_grad);
        let g = [a * ln_p0_gradient[0] + r[0], a * ln_p0_gradient[1] + r[1]];
        // lambda M = g: the cotangent of x_N that moving x0 back to the fixed end costs
        let lambda = [
            (g[0] * m[1][1] - g[1] * m[1][0]) / det,
            (g[1] * m[0][0] - g[0] * m[0][1]) / det,
        ];
        self.backward((net, row), [-lambda[0], -lambda[1]], 0.0, grad, cond_grad);
        Some(())
    }

    /// `d x_N / d x0 = prod_k (I + h J_k)` of `row`'s path in the last run.
    pub(super) fn end_jacobian(&self, row: usize) -> [[f32; 2]; 2] {
        let h = 1.0 / self.steps.max(1) as f32;
        let mut m = [[1.0f32, 0.0], [0.0, 1.0]];
        for jacobians in &self.jacobians[..self.steps] {
            let j = &jacobians[row];
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

    /// After [`Paths::run`], for `row` (whose run succeeded): adds to `grad` (and
    /// `cond_grad`, the first layer's `wi` part) the gradient of `end_bar . x_N + c sum_k
    /// ln det_k` with respect to the weights, and returns its gradient with respect to
    /// `x0`.
    pub(super) fn backward(
        &mut self,
        (net, row): (&Mlp, usize),
        end_bar: [f32; 2],
        c: f32,
        grad: &mut [f32],
        cond_grad: &mut [f32],
    ) -> [f32; 2] {
        let h = 1.0 / self.steps as f32;
        let mut x_bar = end_bar;
        for k in (0..self.steps).rev() {
            let j = &self.jacobians[k][row];
            let a = [
                [1.0 + h * j[0][0], h * j[0][1]],
                [h * j[1][0], 1.0 + h * j[1][1]],
            ];
            let s = c * h / step_det(h, j);
            // d ln det(A) / dJ = h A^-T
            let j_bar = [[s * a[1][1], -s * a[1][0]], [-s * a[0][1], s * a[0][0]]];
            let v_bar = [h * x_bar[0], h * x_bar[1]];
            let net = (net, &mut self.bar);
            let through_net = backward(net, (&self.tapes[k], row), (v_bar, j_bar), grad, cond_grad);
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
        let (end, ln_det) = Paths::new(domain).run((net, &Transposed::of(net)), &cond, &[x0], 4)[0]
            .expect("an unfolded path");
        0.6 * end[0] as f64 - 1.7 * end[1] as f64 + 0.8 * ln_det
    }

    #[test]
    fn reverse_pass_matches_finite_differences() {
        for domain in DOMAINS {
            let (net, enc) = test_net(domain, 5);
            let x0 = [0.9f32, -0.3];
            let cond = condition(domain, &net, &enc);
            let mut paths = Paths::new(domain);
            // The point as the last row of a batch.
            let ends = paths.run((&net, &Transposed::of(&net)), &cond, &[[0.2, 0.1], x0], 4);
            ends[1].expect("an unfolded path");
            let mut grad = vec![0.0f32; net.params().len()];
            let mut cond_grad = vec![0.0f32; cond.len()];
            paths.backward((&net, 1), [0.6, -1.7], 0.8, &mut grad, &mut cond_grad);
            condition_backward(domain, &net, &enc, &cond_grad, &mut grad);
            check_gradient(&net, &grad, |n| objective(domain, n, &enc, x0));
        }
    }

    /// `ln p(end)` with `ln p0(x0) = -|x0|^2 / 2` through the inverse.
    fn density(domain: Domain, net: &Mlp, enc: &[f32], end: [f32; 2]) -> f64 {
        let cond = condition(domain, net, enc);
        let (x0, ln_det) = Paths::new(domain).invert((net, &Transposed::of(net)), &cond, &[end], 4)
            [0]
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
        let mut paths = Paths::new(domain);
        let weights = (&net, &Transposed::of(&net));
        let (end, ln_det) = paths.run(weights, &cond, &[x0], 4)[0].expect("an unfolded path");
        let (back, ln_det_back) =
            paths.invert(weights, &cond, &[end], 4)[0].expect("an invertible path");
        assert!(
            (back[0] - x0[0]).abs() < 1e-5 && (back[1] - x0[1]).abs() < 1e-5,
            "{domain:?}: {back:?}"
        );
        assert!((ln_det - ln_det_back).abs() < 1e-5);
        let mut grad = vec![0.0f32; net.params().len()];
        let mut cond_grad = vec![0.0f32; cond.len()];
        paths
            .fixed_end_backward(
                (&net, 0),
                [-back[0], -back[1]],
                1.0,
                &mut grad,
                &mut cond_grad,
            )
            .expect("a regular path");
        condition_backward(domain, &net, &enc, &cond_grad, &mut grad);
        check_gradient(&net, &grad, |n| density(domain, n, &enc, end));
    }

    /// A batch's rows run and invert as each point does alone, bit for bit, failures
    /// included (a point far outside the flow's range, a non-finite one).
    #[test]
    fn rows_of_a_batch_run_and_invert_as_single_points() {
        for domain in DOMAINS {
            let (net, enc) = test_net(domain, 11);
            let cond = condition(domain, &net, &enc);
            let weights = (&net, &Transposed::of(&net));
            let mut points: Vec<[f32; 2]> = (0..21)
                .map(|i| [(i as f32 * 0.9).sin() * 1.5, (i as f32 * 0.4).cos()])
                .collect();
            points.push([40.0, -35.0]);
            points.push([f32::NAN, 0.3]);
            let mut batch = Paths::new(domain);
            let ran = batch.run(weights, &cond, &points, 4);
            let ends: Vec<[f32; 2]> = ran.iter().map(|e| e.map_or([9.0, 9.0], |e| e.0)).collect();
            let inverted = batch.invert(weights, &cond, &ends, 4);
            assert!(
                inverted.iter().filter(|r| r.is_some()).count() >= 15,
                "{domain:?}"
            );
            for r in 0..points.len() {
                let mut alone = Paths::new(domain);
                let one = alone.run(weights, &cond, &points[r..r + 1], 4);
                assert_eq!(
                    format!("{:?}", ran[r]),
                    format!("{:?}", one[0]),
                    "{domain:?} run {r}"
                );
                let one = alone.invert(weights, &cond, &ends[r..r + 1], 4);
                assert_eq!(
                    format!("{:?}", inverted[r]),
                    format!("{:?}", one[0]),
                    "{domain:?} invert {r}"
                );
                if inverted[r].is_some() {
                    assert_eq!(
                        batch.end_jacobian(r),
                        alone.end_jacobian(0),
                        "{domain:?} M {r}"
                    );
                }
            }
        }
    }
}
