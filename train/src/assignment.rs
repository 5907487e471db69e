//! The linear assignment problem: the permutation `p` of `0..n` that minimises
//! `sum_r cost[r][p[r]]` (Kuhn 1955, Munkres 1957), by shortest augmenting paths with
//! row and column potentials in O(n^3). Used by the teacher's mini-batch optimal-transport
//! coupling ([`crate::flow_fit`]), where `n` is a few dozen.

/// Reusable buffers of [`Assignment::solve`] for problems up to any size.
#[derive(Clone, Debug, Default)]
pub struct Assignment {
    /// Row potentials, 1-based (`u[0]` belongs to the virtual row).
    u: Vec<f64>,
    /// Column potentials, 1-based.
    v: Vec<f64>,
    /// `owner[c]`: the 1-based row assigned to column `c` (0: none).
    owner: Vec<usize>,
    /// The previous column on the shortest path to each column.
    way: Vec<usize>,
    /// Reduced distance to each column along the current search.
    dist: Vec<f64>,
    /// Columns already on the search tree.
    used: Vec<bool>,
}

impl Assignment {
    /// Writes into `perm[r]` the column assigned to row `r` of the `n x n` row-major
    /// `cost` (every entry finite); `perm` must hold `n` entries.
    pub fn solve(&mut self, n: usize, cost: &[f64], perm: &mut [usize]) {
        debug_assert_eq!(cost.len(), n * n);
        debug_assert_eq!(perm.len(), n);
        self.reset(n);
        for row in 1..=n {
            self.augment(n, cost, row);
        }
        for c in 1..=n {
            let r = self.owner[c];
            if r > 0 {
                perm[r - 1] = c - 1;
            }
        }
    }

    fn reset(&mut self, n: usize) {
        self.u.clear();
        self.u.resize(n + 1, 0.0);
        self.v.clear();
        self.v.resize(n + 1, 0.0);
        self.owner.clear();
        self.owner.resize(n + 1, 0);
        self.way.clear();
        self.way.resize(n + 1, 0);
    }

    /// Adds `row` to the matching along the cheapest augmenting path in reduced costs
    /// `cost[r][c] - u[r] - v[c]`, keeping every reduced cost non-negative.
    fn augment(&mut self, n: usize, cost: &[f64], row: usize) {
        self.owner[0] = row;
        self.dist.clear();
        self.dist.resize(n + 1, f64::INFINITY);
        self.used.clear();
        self.used.resize(n + 1, false);
        let mut col = 0;
        loop {
            self.used[col] = true;
            let r = self.owner[col];
            let (mut delta, mut next) = (f64::INFINITY, 0);
            for c in 1..=n {
                if self.used[c] {
                    continue;
                }
                let reduced = cost[(r - 1) * n + (c - 1)] - self.u[r] - self.v[c];
                if reduced < self.dist[c] {
                    self.dist[c] = reduced;
                    self.way[c] = col;
                }
                if self.dist[c] < delta {
                    delta = self.dist[c];
                    next = c;
                }
            }
            for c in 0..=n {
                if self.used[c] {
                    self.u[self.owner[c]] += delta;
                    self.v[c] -= delta;
                } else {
                    self.dist[c] -= delta;
                }
            }
            col = next;
            if self.owner[col] == 0 {
                break;
            }
        }
        // Flip the path back to the virtual column.
        while col != 0 {
            let prev = self.way[col];
            self.owner[col] = self.owner[prev];
            col = prev;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    fn total(n: usize, cost: &[f64], perm: &[usize]) -> f64 {
        (0..n).map(|r| cost[r * n + perm[r]]).sum()
    }

    /// Every permutation of `0..n` by Heap's algorithm, the smallest total.
    fn brute_force(n: usize, cost: &[f64]) -> f64 {
        let mut p: Vec<usize> = (0..n).collect();
        let mut c = vec![0; n];
        let mut best = total(n, cost, &p);
        let mut i = 0;
        while i < n {
            if c[i] < i {
                if i % 2 == 0 {
                    p.swap(0, i);
                } else {
                    p.swap(c[i], i);
                }
                best = best.min(total(n, cost, &p));
                c[i] += 1;
                i = 0;
            } else {
                c[i] = 0;
                i += 1;
            }
        }
        best
    }

    #[test]
    fn matches_brute_force_on_random_problems() {
        let mut rng = Pcg64::seed_from_u64(3);
        let mut solver = Assignment::default();
        for n in 1..=7 {
            for _ in 0..40 {
                let cost: Vec<f64> = (0..n * n).map(|_| rng.gen_range(-2.0..5.0)).collect();
                let mut perm = vec![usize::MAX; n];
                solver.solve(n, &cost, &mut perm);
                let mut seen = perm.clone();
                seen.sort_unstable();
                assert_eq!(seen, (0..n).collect::<Vec<_>>(), "not a permutation");
                let best = brute_force(n, &cost);
                assert!((total(n, &cost, &perm) - best).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn pairs_sorted_points_in_one_dimension_in_order() {
        // For |a - b|^2 on a line the optimal plan is monotone.
        let mut rng = Pcg64::seed_from_u64(5);
        let n = 32;
        let a: Vec<f64> = (0..n).map(|_| rng.gen::<f64>()).collect();
        let b: Vec<f64> = (0..n).map(|_| rng.gen::<f64>()).collect();
        let cost: Vec<f64> = a
            .iter()
            .flat_map(|x| b.iter().map(move |y| (x - y) * (x - y)))
            .collect();
        let mut perm = vec![0; n];
        Assignment::default().solve(n, &cost, &mut perm);
        for r in 0..n {
            for s in 0..n {
                if a[r] < a[s] {
                    assert!(b[perm[r]] <= b[perm[s]], "crossing pair at {r}, {s}");
                }
            }
        }
    }
}
