//! Fitting the latent table (docs/math.md, §6.5): per incidence slice, where in `u` the
//! trained flow's samples carry too much or too little weight.
//!
//! For a draw `u` the flow's importance weight is `q(u) = Y(f) |cos theta_o| / pdf`; a
//! density `p(u)` in front of the flow turns it into `q / p`, whose second moment
//! `E[q^2 / p]` is least for `p` proportional to `sqrt(E[q^2 | u])`. Each slice's node
//! values start as that root mean square, estimated from draws spread over the node's
//! bilinear hat in `u` and over its slice's hat in incidence (so that the mixed density a
//! `wi` between two slices sees is fitted too). That is the minimiser for a density
//! constant per cell; the bilinear density is then fitted to the same draws by
//! multiplicative updates that lower `E[q^2 / T]` itself (docs/math.md, (78)), with `T`
//! normalised to integral 1 and mixed with the uniform density (`floor`), which bounds
//! every weight and keeps the map bijective.

use crate::error::TrainError;
use crate::metrics::sampler::{from_glam, to_glam, weight, Drawn};
use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::internals::base::table::{
    code_value_f32, encode, slice_incidence, slice_pair, total, trapezoid, MAX_NODES,
};
use diffbsdf::internals::base::table_axes;
use diffbsdf::{AnyModel, ModelDef, Sample, TableGrid};
use diffbsdf_ffi::slices::sample_batch;
use diffbsdf_materials::{DVec3, Material};
use rand::Rng;
use rand::SeedableRng;
use rand_pcg::Pcg64;
use rayon::prelude::*;

/// The grid the trainer fits: 32 cells per side, nodes stored as 8-bit codes, axes warped
/// (or not: [`TableConfig::axes`]), on 40 slices of the blended layout (or the 32 of
/// before: [`TableConfig::blended_slices`]).
const GRID: TableGrid = TableGrid::BlendedSlices;
/// Cells per side.
const C: usize = GRID.cells();
/// Nodes per side.
const NODES: usize = GRID.nodes();
/// Nodes per slice.
const SLICE_LEN: usize = GRID.slice_len();

/// How the table is fitted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableConfig {
    /// Draws per slice (0: no table).
    pub draws_per_slice: usize,
    /// Weight of the uniform density in every slice.
    pub floor: f64,
    /// Multiplicative updates of the node values towards the least `E[q^2 / T]` (78)
    /// after the root-mean-square start (0: the start alone), each slice on its own.
    pub iterations: usize,
    /// Joint updates of every slice after those, against the density the kernel evaluates
    /// for each draw's incidence: two slices mixed (docs/math.md, (80)).
    pub joint_iterations: usize,
    /// Whether the grid's axes are warped to where the flow's weight varies (docs/math.md,
    /// (81), [`TableGrid::WarpedCodes`]); the uniform coded grid otherwise.
    pub axes: bool,
    /// Shares of the fitted axis warps tried, each blended with even cells (`s g + 1 -
    /// s`), the one that leaves the least variance on held-out draws kept (0: even cells).
    pub axis_shares: &'static [f64],
    /// Whether the table has the 40 slices of the blended layout (docs/math.md, (82),
    /// [`TableGrid::BlendedSlices`]; its axes stored even where they are not warped); the
    /// 32 slices of (75) otherwise ([`TableGrid::WarpedCodes`], or [`TableGrid::Codes`]
    /// without warped axes).
    pub blended_slices: bool,
}

impl TableConfig {
    /// The default: 10^6 draws per slice (about 900 per node of the 33 x 33 grid), a
    /// uniform share of 5 %, 20 updates of (78) (docs/measured-materials.md, "The latent
    /// table" and "A finer table in 8-bit codes": 300 000 draws, 275 per node, measured
    /// 4-15 % more variance), then 10 joint updates of (80) ("Fitting the slices together":
    /// 0-9 % less variance; settled within about ten).
    pub const DEFAULT: TableConfig = TableConfig {
        draws_per_slice: 1_000_000,
        floor: 0.05,
        iterations: 20,
        joint_iterations: 10,
        axes: true,
        axis_shares: &[0.0, 0.25, 0.5, 0.75, 1.0],
        blended_slices: true,
    };
    /// No table.
    pub const OFF: TableConfig = TableConfig {
        draws_per_slice: 0,
        floor: 0.05,
        iterations: 0,
        joint_iterations: 0,
        axes: false,
        axis_shares: &[0.0],
        blended_slices: false,
    };

    /// The grid whose slices the draws are placed on: [`TableGrid::BlendedSlices`] or, with
    /// the 32 slices of (75), [`TableGrid::WarpedCodes`] (the same slices as
    /// [`TableGrid::Codes`]).
    #[must_use]
    pub const fn layout(&self) -> TableGrid {
        if self.blended_slices {
            TableGrid::BlendedSlices
        } else {
            TableGrid::WarpedCodes
        }
    }
}

/// What the fit did, on its own draws: the relative variance `E[q^2] / E[q]^2 - 1` of the
/// flow alone and `E[q^2 / T] / E[q]^2 - 1` with the stored table, each the mean over the
/// slices (in-sample: the nodes were fitted to these draws).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableFit {
    /// Mean relative variance of the flow alone.
    pub rv_flow: f64,
    /// Mean relative variance with the table.
    pub rv_table: f64,
    /// The share of the fitted axis warps kept (0: even cells, [`TableConfig::axis_shares`]).
    pub axis_share: f64,
}

/// `model` with a latent table fitted against `material` (a model that has one gets a new
/// one fitted to its flow alone), and what the fit did on its draws. Needs standard
/// coordinates.
pub fn fit_latent_table(
    model: &AnyModel,
    material: &dyn Material,
    cfg: &TableConfig,
    seed: u64,
) -> Result<(AnyModel, TableFit), TrainError> {
    let def = *model.def();
    if !def.standardized {
        return Err(TrainError::Mismatch);
    }
    let flow = without_table(model)?;
    let draws: Vec<Vec<SliceDraw>> = (0..cfg.layout().slices())
        .into_par_iter()
        .map(|k| slice_draws(&flow, material, cfg, seed, k))
        .collect();
    // The axis warps (81): the widths the draws call for, blended with even cells by
    // the share that leaves the least variance on held-out draws.
    let (axes, axis_share) = if cfg.axes {
        choose_axes(&draws, cfg)
    } else {
        (None, 0.0)
    };
    let draws = match &axes {
        Some(axes) => read_back(&draws, Some(axes), |_| true),
        None => draws,
    };
    let values = fit_values(&draws, cfg);
    let stored: Vec<Vec<f32>> = values.iter().map(|v| stored_values(v, cfg)).collect();
    let fit = TableFit {
        axis_share,
        ..fit_report(&draws, &stored)
    };
    let mut params = vec![0.0f32; flow.def().param_count()];
    flow.params(&mut params).map_err(TrainError::Blob)?;
    params.extend(stored.into_iter().flatten());
    let grid = match (axes, cfg.blended_slices) {
        (Some(axes), blended) => {
            params.extend(axes.iter().flat_map(|g| g.iter().take(NODES).copied()));
            if blended {
                GRID
            } else {
                TableGrid::WarpedCodes
            }
        }
        (None, true) => {
            // Even cells: every axis node 1, the identity warp.
            params.extend([1.0f32; 2 * NODES]);
            GRID
        }
        (None, false) => TableGrid::Codes,
    };
    debug_assert_eq!(params.len(), flow.def().param_count() + grid.node_count());
    let table_def = ModelDef {
        latent_table: Some(grid),
        ..def
    };
    let tabled = AnyModel::from_params(table_def, &params).map_err(TrainError::Blob)?;
    Ok((tabled, fit))
}

/// The same model without its latent table (itself where it has none).
pub fn without_table(model: &AnyModel) -> Result<AnyModel, TrainError> {
    let def = *model.def();
    let mut params = vec![0.0f32; def.param_count()];
    model.params(&mut params).map_err(TrainError::Blob)?;
    params.truncate(def.param_count() - def.table_len());
    let flow_def = ModelDef {
        latent_table: None,
        ..def
    };
    AnyModel::from_params(flow_def, &params).map_err(TrainError::Blob)
}

/// Every slice's node values fitted to its draws: the root-mean-square start and
/// `cfg.iterations` updates (78) each, then `cfg.joint_iterations` joint updates (80).
fn fit_values(draws: &[Vec<SliceDraw>], cfg: &TableConfig) -> Vec<Vec<f64>> {
    let mut values: Vec<Vec<f64>> = draws
        .par_iter()
        .map(|d| {
            let mut v = root_mean_square(d);
            for _ in 0..cfg.iterations {
                descend(&mut v, d, cfg.floor);
            }
            v
        })
        .collect();
    for _ in 0..cfg.joint_iterations {
        joint_descend(draws, &mut values, cfg.floor);
    }
    values
}

/// The mean over the slices of the relative variance of the flow alone and with the
/// stored table, on `draws`.
fn fit_report(draws: &[Vec<SliceDraw>], stored: &[Vec<f32>]) -> TableFit {
    let stored: Vec<Vec<f64>> = stored
        .iter()
        .map(|v| v.iter().map(|&x| f64::from(x)).collect())
        .collect();
    let per: Vec<(f64, f64)> = draws
        .par_iter()
        .map(|d| {
            (
                relative_variance(d, |x| x.stretch),
                relative_variance(d, |x| mixed_density(x, &stored)),
            )
        })
        .collect();
    let count = per.len().max(1) as f64;
    TableFit {
        rv_flow: per.iter().map(|p| p.0).sum::<f64>() / count,
        rv_table: per.iter().map(|p| p.1).sum::<f64>() / count,
        axis_share: 0.0,
    }
}

/// The draws of every slice that `keep` keeps (by index), read back through the axis
/// warps where there are some ([`SliceDraw::unwarp`]).
fn read_back(
    draws: &[Vec<SliceDraw>],
    axes: Option<&AxisNodes>,
    keep: impl Fn(usize) -> bool + Sync,
) -> Vec<Vec<SliceDraw>> {
    draws
        .par_iter()
        .map(|d| {
            d.iter()
                .enumerate()
                .filter(|(i, _)| keep(*i))
                .map(|(_, x)| {
                    let mut x = x.clone();
                    if let Some(axes) = axes {
                        x.unwarp(axes);
                    }
                    x
                })
                .collect()
        })
        .collect()
}

/// The axis warps to keep (`None` for even cells) and their share: for each share `s` of
/// `cfg.axis_shares`, the nodes `s g + 1 - s` of the fitted widths `g` ([`fit_axes`]); the
/// table fitted to the even-numbered draws of every slice and scored (mean relative
/// variance over the slices) on the odd-numbered ones; the share that scores least wins,
/// `s = 0` being even cells.
fn choose_axes(draws: &[Vec<SliceDraw>], cfg: &TableConfig) -> (Option<AxisNodes>, f64) {
    let widths = fit_axes(draws);
    // (held-out variance, axes, share) of the best share so far.
    let mut best: Option<(f64, Option<AxisNodes>, f64)> = None;
    for &share in cfg.axis_shares {
        let axes = (share > 0.0).then(|| blended(&widths, share));
        let train = read_back(draws, axes.as_ref(), |i| i % 2 == 0);
        let held = read_back(draws, axes.as_ref(), |i| i % 2 == 1);
        let values = fit_values(&train, cfg);
        let stored: Vec<Vec<f32>> = values.iter().map(|v| stored_values(v, cfg)).collect();
        let score = fit_report(&held, &stored).rv_table;
        if best.as_ref().is_none_or(|b| score < b.0) {
            best = Some((score, axes, share));
        }
    }
    best.map_or((None, 0.0), |b| (b.1, b.2))
}

/// The two axis warps' stored nodes, `g_0` and `g_1` (docs/math.md, (81)).
type AxisNodes = [[f32; MAX_NODES]; 2];

/// The stored axis nodes `share g + 1 - share` of the fitted nodes `g`.
fn blended(g: &[[f64; MAX_NODES]; 2], share: f64) -> [[f32; MAX_NODES]; 2] {
    let mut axes = [[1.0f32; MAX_NODES]; 2];
    for (a, ga) in axes.iter_mut().zip(g) {
        for (x, &w) in a.iter_mut().zip(ga).take(NODES) {
            *x = stored_value(share * w + (1.0 - share));
        }
    }
    axes
}

/// One draw of a slice: the node of its cell's lower corner, its place in the cell and
/// the flow's squared weight.
#[derive(Clone)]
struct SliceDraw {
    node: usize,
    a: f64,
    b: f64,
    q2: f64,
    /// The axis warps' slopes at the draw, `w_0' w_1'`, by which [`SliceDraw::unwarp`]
    /// multiplied `q2` (1 without warps): the density 1 in `u` is this in the table's
    /// coordinates.
    stretch: f64,
    /// The lower of the two slices the draw's incidence mixes, and the upper one's weight.
    lo: usize,
    t: f64,
}

impl SliceDraw {
    /// A draw at the point `p` of the square (the grid's cell and the place in it) with
    /// weight `q`, mixing slices `lo` and `lo + 1` with weight `t`.
    fn new(p: [f64; 2], q: f64, lo: usize, t: f64) -> Self {
        let mut d = SliceDraw {
            node: 0,
            a: 0.0,
            b: 0.0,
            q2: q * q,
            stretch: 1.0,
            lo,
            t,
        };
        d.place([p[0] * C as f64, p[1] * C as f64]);
        d
    }

    /// Puts the draw at `x`, in cells of the grid: its cell's lower node and its place in
    /// the cell.
    fn place(&mut self, x: [f64; 2]) {
        let (i, j) = ((x[0] as usize).min(C - 1), (x[1] as usize).min(C - 1));
        self.node = i * NODES + j;
        self.a = x[0] - i as f64;
        self.b = x[1] - j as f64;
    }

    /// The draw's four nodes and their bilinear weights.
    fn corners(&self) -> [(usize, f64); 4] {
        let (n, a, b) = (self.node, self.a, self.b);
        [
            (n, (1.0 - a) * (1.0 - b)),
            (n + NODES, a * (1.0 - b)),
            (n + 1, (1.0 - a) * b),
            (n + NODES + 1, a * b),
        ]
    }

    /// The bilinear surface of the node values `v` at the draw.
    fn surface(&self, v: &[f64]) -> f64 {
        self.corners().iter().map(|&(n, w)| w * v[n]).sum()
    }

    /// The draw's point of the square (`(i + a) / C`, `(j + b) / C`).
    fn point(&self) -> [f64; 2] {
        let (i, j) = (self.node / NODES, self.node % NODES);
        [
            (i as f64 + self.a) / C as f64,
            (j as f64 + self.b) / C as f64,
        ]
    }

    /// Places the draw at `w^-1` of its point, the table's own coordinates, and
    /// multiplies its squared weight by the warps' slopes there: with `T(p) = T_table(x)
    /// / (w_0'(x_0) w_1'(x_1))`, `E[q^2 / T]` over draws uniform in `p` is `E[q^2 w_0'
    /// w_1' / T_table]` (docs/math.md, (81)). The kernel's own functions, in f32.
    fn unwarp(&mut self, axes: &[[f32; MAX_NODES]; 2]) {
        let p = self.point();
        let mut x = [0.0f64; 2];
        let mut stretch = 1.0;
        for (a, g) in axes.iter().enumerate() {
            let t = total(g, C);
            let back = table_axes::inverse(g, C, t, p[a] as f32);
            stretch *= f64::from(table_axes::slope(g, C, t, back));
            x[a] = f64::from(back) * C as f64;
        }
        self.place(x);
        self.q2 *= stretch;
        self.stretch = stretch;
    }
}

/// Fine bins per axis of the histograms the axis warps are chosen on.
const AXIS_BINS: usize = 512;

/// The two axis warps' stored nodes (docs/math.md, (81)): per axis, `C` cells of the
/// square chosen on a grid of [`AXIS_BINS`] so that the per-cell means of each slice's
/// normalised weight vary the most (the variance a piecewise-constant table on those cells
/// would remove, summed over the slices and over the other axis' cells), by dynamic
/// programming, each axis in turn with the other's cells fixed (twice); then each node of
/// `g` the mean width (times `C`) of the two cells beside it (1 for even cells).
fn fit_axes(draws: &[Vec<SliceDraw>]) -> [[f64; MAX_NODES]; 2] {
    let uniform: Vec<f64> = (0..=C).map(|i| i as f64 / C as f64).collect();
    let mut cuts = [uniform.clone(), uniform];
    // Each slice's weights over their mean, so every slice counts alike.
    let scale: Vec<f64> = draws
        .iter()
        .map(|d| {
            let sum: f64 = d.iter().map(|x| x.q2.sqrt()).sum();
            if sum > 0.0 {
                d.len() as f64 / sum
            } else {
                0.0
            }
        })
        .collect();
    for _ in 0..2 {
        for axis in 0..2 {
            cuts[axis] = best_cuts(draws, &scale, axis, &cuts[1 - axis]);
        }
    }
    let mut axes = [[1.0f64; MAX_NODES]; 2];
    for (g, c) in axes.iter_mut().zip(&cuts) {
        let width = |i: usize| (c[i + 1] - c[i]) * C as f64;
        for (i, gi) in g.iter_mut().enumerate().take(NODES) {
            let w = if i == 0 {
                width(0)
            } else if i == C {
                width(C - 1)
            } else {
                0.5 * (width(i - 1) + width(i))
            };
            *gi = w;
        }
    }
    axes
}

/// The `C + 1` cuts along `axis` (0 and 1 at the ends, on the fine grid) that maximise
/// what a line per cell explains of the weight, summed over every slice and every band of
/// the other axis between `other`'s cuts: per cell and band, the weighted least-squares
/// line through the fine bins' mean weights (the bilinear table is linear along each axis
/// within a cell), its explained sum of squares `sy^2 / n + (sxy - sx sy / n)^2 / (sxx -
/// sx^2 / n)`; the optimal partition by dynamic programming over the fine bins.
fn best_cuts(draws: &[Vec<SliceDraw>], scale: &[f64], axis: usize, other: &[f64]) -> Vec<f64> {
    let f = AXIS_BINS;
    let bands = C * draws.len();
    // Per band (slice, cell of the other axis) and fine bin: the count and the sum of q.
    let mut sum = vec![0.0f64; bands * f];
    let mut count = vec![0.0f64; bands * f];
    for (k, (d, s)) in draws.iter().zip(scale).enumerate() {
        for x in d {
            let p = x.point();
            let bin = ((p[axis] * f as f64) as usize).min(f - 1);
            let band = other.partition_point(|&c| c <= p[1 - axis]).clamp(1, C) - 1;
            let at = (k * C + band) * f + bin;
            sum[at] += (x.q2 / x.stretch).sqrt() * s;
            count[at] += 1.0;
        }
    }
    // Prefix sums per band of n, n x, n x^2, s and s x (x the bin's centre in bins).
    let stride = f + 1;
    let mut pre = vec![[0.0f64; 5]; bands * stride];
    for b in 0..bands {
        for i in 0..f {
            let (n, sy) = (count[b * f + i], sum[b * f + i]);
            let x = i as f64 + 0.5;
            let last = pre[b * stride + i];
            pre[b * stride + i + 1] = [
                last[0] + n,
                last[1] + n * x,
                last[2] + n * x * x,
                last[3] + sy,
                last[4] + sy * x,
            ];
        }
    }
    let score: Vec<f64> = (0..=f)
        .into_par_iter()
        .flat_map_iter(|lo| {
            let pre = &pre;
            (0..=f).map(move |hi| {
                if hi <= lo {
                    return f64::NEG_INFINITY;
                }
                let mut total = 0.0;
                for b in 0..bands {
                    let (h, l) = (pre[b * stride + hi], pre[b * stride + lo]);
                    let [n, sx, sxx, sy, sxy] = core::array::from_fn(|m| h[m] - l[m]);
                    if n > 0.0 {
                        total += sy * sy / n;
                        let vxx = sxx - sx * sx / n;
                        if vxx > 1e-9 * n {
                            let c = sxy - sx * sy / n;
                            total += c * c / vxx;
                        }
                    }
                }
                total
            })
        })
        .collect();
    // best[k][hi]: the most score of k cells covering [0, hi).
    let mut best = vec![f64::NEG_INFINITY; f + 1];
    best[0] = 0.0;
    let mut from = vec![vec![0usize; f + 1]; C + 1];
    for row in from.iter_mut().skip(1) {
        let mut next = vec![f64::NEG_INFINITY; f + 1];
        for (hi, slot) in next.iter_mut().enumerate().skip(1) {
            for (lo, &b) in best.iter().enumerate().take(hi) {
                let v = b + score[lo * (f + 1) + hi];
                if v > *slot {
                    *slot = v;
                    row[hi] = lo;
                }
            }
        }
        best = next;
    }
    let mut cuts = vec![1.0f64; C + 1];
    let mut hi = f;
    for k in (1..=C).rev() {
        hi = from[k][hi];
        cuts[k - 1] = hi as f64 / f as f64;
    }
    cuts[0] = 0.0;
    cuts
}

/// A slice's surface value `b` as a density: divided by its integral `total`, the uniform
/// density where the slice has none (as [`stored_values`] stores it).
fn shaped(b: f64, total: f64) -> f64 {
    if total > 0.0 {
        b / total
    } else {
        1.0
    }
}

/// The node's weight in the bilinear surface's integral over the unit square: the
/// kernel's trapezoid weights per axis over `C^2` (docs/math.md, (74)).
fn node_weight(n: usize) -> f64 {
    f64::from(trapezoid(n / NODES, C)) * f64::from(trapezoid(n % NODES, C)) / (C * C) as f64
}

/// The bilinear surface's integral over the unit square.
fn integral(v: &[f64]) -> f64 {
    v.iter().enumerate().map(|(n, x)| node_weight(n) * x).sum()
}

/// A slice's stored node values: the fitted surface `v` normalised to integral 1, mixed
/// with the uniform density (`cfg.floor`) and rounded to the stored codes.
fn stored_values(v: &[f64], cfg: &TableConfig) -> Vec<f32> {
    let total = integral(v);
    v.iter()
        .map(|&x| stored_value((1.0 - cfg.floor) * shaped(x, total) + cfg.floor))
        .collect()
}

/// The density the kernel evaluates for a draw from the stored slices: its two slices'
/// bilinear surfaces mixed (docs/math.md, (75)).
fn mixed_density(d: &SliceDraw, stored: &[Vec<f64>]) -> f64 {
    (1.0 - d.t) * d.surface(&stored[d.lo]) + d.t * d.surface(&stored[d.lo + 1])
}

/// The node value the blob stores for `x`: its nearest code's value, within the codes'
/// range (docs/math.md, (79)).
fn stored_value(x: f64) -> f32 {
    let (lo, hi) = (code_value_f32(1), code_value_f32(u8::MAX));
    let clamped = (x as f32).clamp(lo, hi);
    encode(clamped).map_or(clamped, code_value_f32)
}

/// `E[q^2 / T] / E[q]^2 - 1` over the draws, `T` the density `density` gives a draw in the
/// table's coordinates (the draw's `stretch`: the flow alone); 0 where every weight is 0.
fn relative_variance(draws: &[SliceDraw], density: impl Fn(&SliceDraw) -> f64) -> f64 {
    let (mut first, mut second) = (0.0, 0.0);
    for d in draws {
        first += (d.q2 / d.stretch).sqrt();
        second += d.q2 / density(d);
    }
    if first > 0.0 {
        draws.len() as f64 * second / (first * first) - 1.0
    } else {
        0.0
    }
}

/// Draws per call of the kernel's batch.
const BATCH: usize = 4096;

/// The slice's draws: incidence from the slice's hat, `u` uniform. The flow's samples come
/// in batches through `diffbsdf_ffi::slices` (the kernel's copy compiled with AVX2 where
/// the CPU has it, the same bits as one `sample` call at a time).
fn slice_draws(
    flow: &AnyModel,
    material: &dyn Material,
    cfg: &TableConfig,
    seed: u64,
    k: usize,
) -> Vec<SliceDraw> {
    let mut rng = Pcg64::seed_from_u64(seed ^ (0x7AB1_E000 + k as u64));
    let isotropic = flow.def().isotropic;
    let mut draws = Vec::with_capacity(cfg.draws_per_slice);
    let mut incidences = Vec::with_capacity(BATCH);
    let mut points = Vec::with_capacity(BATCH);
    let mut mix = Vec::with_capacity(BATCH);
    let mut samples = vec![Sample::INVALID; BATCH];
    while draws.len() < cfg.draws_per_slice {
        let n = BATCH.min(cfg.draws_per_slice - draws.len());
        incidences.clear();
        points.clear();
        mix.clear();
        for _ in 0..n {
            let (wi, u, m) = slice_point(&mut rng, cfg.layout(), k, isotropic);
            incidences.push(wi);
            points.push(u);
            mix.push(m);
        }
        let wi: Vec<Vec3> = incidences.iter().map(|&w| to_glam(w)).collect();
        let u: Vec<Vec2> = points
            .iter()
            .map(|u| Vec2::new(u[0] as f32, u[1] as f32))
            .collect();
        let out = &mut samples[..n];
        if sample_batch(flow, &wi, &u, 0, out).is_err() {
            out.fill(Sample::INVALID);
        }
        for (((&wi, u), s), (lo, t)) in incidences.iter().zip(&points).zip(out.iter()).zip(&mix) {
            let drawn = s.is_valid().then(|| Drawn {
                wo: from_glam(s.wo),
                pdf: f64::from(s.pdf),
            });
            let q = weight(material, wi, drawn);
            draws.push(SliceDraw::new(*u, q, *lo, *t));
        }
    }
    draws
}

/// One draw's incidence (from slice `k`'s hat in incidence on `layout`'s slices, reflected
/// at the ends) and its uniform `u`.
fn slice_point(
    rng: &mut Pcg64,
    layout: TableGrid,
    k: usize,
    isotropic: bool,
) -> (DVec3, [f64; 2], (usize, f64)) {
    let last = (layout.slices() - 1) as f64;
    let s = k as f64 + rng.gen::<f64>() - rng.gen::<f64>();
    let s = (s.abs()).min(2.0 * last - s.abs());
    let z = slice_incidence(layout, s).max(1e-4);
    let phi = if isotropic {
        0.0
    } else {
        rng.gen::<f64>() * std::f64::consts::TAU
    };
    let r = (1.0 - z * z).max(0.0).sqrt();
    let wi = DVec3::new(r * phi.cos(), r * phi.sin(), z);
    let (lo, t) = slice_pair(layout, z as f32);
    (wi, [rng.gen::<f64>(), rng.gen::<f64>()], (lo, f64::from(t)))
}

/// The root of the bilinearly weighted mean of `q^2` around each node: the least
/// `E[q^2 / T]` for a density constant per cell, the updates' start.
fn root_mean_square(draws: &[SliceDraw]) -> Vec<f64> {
    let mut second = vec![0.0f64; SLICE_LEN];
    let mut mass = vec![0.0f64; SLICE_LEN];
    for d in draws {
        // Draws read back through axis warps lie `stretch` times denser than uniform.
        for (n, w) in d.corners() {
            second[n] += w * d.q2;
            mass[n] += w / d.stretch;
        }
    }
    (0..SLICE_LEN)
        .map(|n| {
            if mass[n] > 0.0 {
                (second[n] / mass[n]).sqrt()
            } else {
                0.0
            }
        })
        .collect()
}

/// One multiplicative update towards the least `F = E[q^2 / T]`, `T = (1 - f) B / I + f`
/// with `B` the bilinear surface of `v` and `I` its integral (docs/math.md, (78)): at the
/// minimum `I E[q^2 w_n / T^2] = c_n E[q^2 B / T^2]` for every node `n` (`w_n` its
/// bilinear weight, `c_n` its weight in `I`), so each value is multiplied by the square
/// root of that ratio.
fn descend(v: &mut [f64], draws: &[SliceDraw], floor: f64) {
    let total = integral(v);
    if total <= 0.0 {
        return;
    }
    let mut toward = vec![0.0f64; SLICE_LEN];
    let mut whole = 0.0;
    for d in draws {
        let b = d.surface(v);
        let t = (1.0 - floor) * b / total + floor;
        let r = d.q2 / (t * t);
        for (n, w) in d.corners() {
            toward[n] += r * w;
        }
        whole += r * b;
    }
    if whole <= 0.0 {
        return;
    }
    for (n, x) in v.iter_mut().enumerate() {
        let ratio = toward[n] * total / (node_weight(n) * whole);
        if ratio > 0.0 {
            *x *= ratio.sqrt();
        }
    }
}

/// One joint update of every slice's node values `v_k` (the second of each pair; the first
/// the slice's draws) towards the least `E[q^2 / T]` over all draws, `T` the density the
/// kernel evaluates at each draw's incidence, its two slices mixed:
/// `T = (1 - f) ((1 - t) B_lo / I_lo + t B_hi / I_hi) + f` (docs/math.md, (80)). At the
/// minimum, for every node `n` of slice `k`, `I_k E[m_k q^2 w_n / T^2] = c_n E[m_k q^2 B_k
/// / T^2]` with `m_k` the draw's weight of slice `k` (`1 - t` or `t`, 0 where it does not
/// mix `k`), so each value is multiplied by the square root of that ratio, every slice
/// from the same current values. A draw of slice `k`'s hat mixes `k` and a neighbour, so
/// the update of `k` reads the draws of `k - 1 ..= k + 1`.
fn joint_descend(draws: &[Vec<SliceDraw>], values: &mut [Vec<f64>], floor: f64) {
    let totals: Vec<f64> = values.iter().map(|v| integral(v)).collect();
    let slices = values.len();
    let updated: Vec<Vec<f64>> = (0..slices)
        .into_par_iter()
        .map(|k| {
            let mut toward = vec![0.0f64; SLICE_LEN];
            let mut whole = 0.0;
            let near = k.saturating_sub(1)..=(k + 1).min(slices - 1);
            for d in draws[near].iter().flatten() {
                let (lo, hi) = (d.lo, d.lo + 1);
                if lo != k && hi != k {
                    continue;
                }
                let (b_lo, b_hi) = (d.surface(&values[lo]), d.surface(&values[hi]));
                let t = (1.0 - floor)
                    * ((1.0 - d.t) * shaped(b_lo, totals[lo]) + d.t * shaped(b_hi, totals[hi]))
                    + floor;
                let r = d.q2 / (t * t);
                let (m, b) = if lo == k {
                    (1.0 - d.t, b_lo)
                } else {
                    (d.t, b_hi)
                };
                for (n, w) in d.corners() {
                    toward[n] += r * m * w;
                }
                whole += r * m * b;
            }
            let mut v = values[k].clone();
            // A slice with no mass stays uniform (its stored density).
            if whole > 0.0 && totals[k] > 0.0 {
                for (n, x) in v.iter_mut().enumerate() {
                    let ratio = toward[n] * totals[k] / (node_weight(n) * whole);
                    if ratio > 0.0 {
                        *x *= ratio.sqrt();
                    }
                }
            }
            v
        })
        .collect();
    for (p, v) in values.iter_mut().zip(updated) {
        *p = v;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use diffbsdf::spec::LATENT_TABLE_SLICES as S;

    /// `E[q^2 / T]` over the draws for the node values `v` (the quantity (78) lowers).
    fn second_moment(v: &[f64], draws: &[SliceDraw], floor: f64) -> f64 {
        let total = integral(v);
        let sum: f64 = draws
            .iter()
            .map(|d| {
                let b = d.surface(v);
                d.q2 / ((1.0 - floor) * b / total + floor)
            })
            .sum();
        sum / draws.len() as f64
    }

    /// Draws whose weight `q` is the bilinear surface of `g`, `u` uniform.
    fn draws_of(g: &[f64], count: usize) -> Vec<SliceDraw> {
        let mut rng = Pcg64::seed_from_u64(3);
        (0..count)
            .map(|_| {
                let mut d = SliceDraw::new([rng.gen(), rng.gen()], 0.0, 0, 0.0);
                let q = d.surface(g);
                d.q2 = q * q;
                d
            })
            .collect()
    }

    /// A weight that is itself bilinear on the table's grid: the least `E[q^2 / T]` without a
    /// floor is `E[q]^2`, at `T = q / E[q]`. The root-mean-square start misses it (the mean
    /// over a node's hat is not the node's value); the updates lower the second moment at
    /// every step, never below what the draws allow, and close most of the gap to that
    /// bound.
    #[test]
    fn updates_reach_a_bilinear_optimum() {
        let g: Vec<f64> = (0..SLICE_LEN)
            .map(|n| {
                let (x, y) = ((n / NODES) as f64 / C as f64, (n % NODES) as f64 / C as f64);
                0.2 + 4.0 * (-12.0 * ((x - 0.3).powi(2) + (y - 0.6).powi(2))).exp()
            })
            .collect();
        let draws = draws_of(&g, 400_000);
        let mean: f64 = draws.iter().map(|d| d.q2.sqrt()).sum::<f64>() / draws.len() as f64;
        let bound = mean * mean;
        let mut v = root_mean_square(&draws);
        let start = second_moment(&v, &draws, 0.0);
        let mut moment = start;
        for _ in 0..40 {
            descend(&mut v, &draws, 0.0);
            let next = second_moment(&v, &draws, 0.0);
            assert!(next <= moment * (1.0 + 1e-12), "{next} after {moment}");
            moment = next;
        }
        // Cauchy-Schwarz over the draws themselves: mean(q^2 / T) mean(T) >= mean(q)^2,
        // exactly for any T (mean(T) is 1 only up to the draws' noise, which the 1 089
        // nodes of the grid can fit).
        let total = integral(&v);
        let mean_t: f64 =
            draws.iter().map(|d| d.surface(&v) / total).sum::<f64>() / draws.len() as f64;
        assert!(
            moment * mean_t >= bound * (1.0 - 1e-12),
            "{moment} x {mean_t} vs {bound}"
        );
        assert!((mean_t - 1.0).abs() < 0.01, "mean density {mean_t}");
        assert!(
            moment - bound < 0.1 * (start - bound),
            "start {start}, end {moment}, bound {bound}"
        );
    }

    /// With a floor the updates still lower the second moment and keep every value finite
    /// and non-negative.
    #[test]
    fn updates_lower_the_moment_with_a_floor() {
        let g: Vec<f64> = (0..SLICE_LEN)
            .map(|n| if n % 7 == 0 { 30.0 } else { 0.5 })
            .collect();
        let draws = draws_of(&g, 100_000);
        let mut v = root_mean_square(&draws);
        let start = second_moment(&v, &draws, 0.05);
        for _ in 0..20 {
            descend(&mut v, &draws, 0.05);
        }
        let end = second_moment(&v, &draws, 0.05);
        assert!(end < start, "{end} vs {start}");
        assert!(v.iter().all(|x| x.is_finite() && *x >= 0.0));
    }

    /// [`joint_descend`] on the draws and values of `per`.
    fn joint(per: &mut [(Vec<SliceDraw>, Vec<f64>)], floor: f64) {
        let draws: Vec<Vec<SliceDraw>> = per.iter().map(|p| p.0.clone()).collect();
        let mut values: Vec<Vec<f64>> = per.iter().map(|p| p.1.clone()).collect();
        joint_descend(&draws, &mut values, floor);
        for (p, v) in per.iter_mut().zip(values) {
            p.1 = v;
        }
    }

    /// `E[q^2 / T]` over every slice's draws with `T` the two slices mixed as in
    /// [`joint_descend`] (the values unrounded).
    fn joint_moment(per: &[(Vec<SliceDraw>, Vec<f64>)], floor: f64) -> f64 {
        let totals: Vec<f64> = per.iter().map(|p| integral(&p.1)).collect();
        let (mut sum, mut count) = (0.0, 0);
        for (draws, _) in per {
            for d in draws {
                let at = |k: usize| -> f64 {
                    d.corners()
                        .iter()
                        .map(|&(n, w)| w * per[k].1[n])
                        .sum::<f64>()
                        / totals[k]
                };
                let t = (1.0 - floor) * ((1.0 - d.t) * at(d.lo) + d.t * at(d.lo + 1)) + floor;
                sum += d.q2 / t;
                count += 1;
            }
        }
        sum / count as f64
    }

    /// The joint updates lower the second moment of the mixed density at every step, from
    /// the slices fitted on their own, where the weight's shape moves across the slices
    /// (so that a slice fitted alone to its hat is not the best mix at any incidence).
    #[test]
    fn joint_updates_lower_the_mixed_moment() {
        let mut rng = Pcg64::seed_from_u64(9);
        let per: Vec<(Vec<SliceDraw>, Vec<f64>)> = (0..S)
            .map(|k| {
                let draws: Vec<SliceDraw> = (0..4000)
                    .map(|_| {
                        let s = k as f64 + rng.gen::<f64>() - rng.gen::<f64>();
                        let s = s.abs().min(2.0 * (S - 1) as f64 - s.abs());
                        let lo = (s as usize).min(S - 2);
                        let p: [f64; 2] = [rng.gen(), rng.gen()];
                        let (x, y) = (p[0] * C as f64, p[1] * C as f64);
                        // A peak whose place in `u` moves with the incidence.
                        let centre = s / (S - 1) as f64 * C as f64;
                        let q =
                            0.2 + 10.0 * (-((x - centre).powi(2) + (y - 8.0).powi(2)) / 8.0).exp();
                        SliceDraw::new(p, q, lo, s - lo as f64)
                    })
                    .collect();
                let mut v = root_mean_square(&draws);
                for _ in 0..20 {
                    descend(&mut v, &draws, 0.05);
                }
                (draws, v)
            })
            .collect();
        let mut per = per;
        // A slice whose flow draws nothing (every weight 0) stays finite and leaves its
        // neighbours' updates finite.
        let mut empty = per.clone();
        for d in empty[5].0.iter_mut() {
            d.q2 = 0.0;
        }
        empty[5].1 = root_mean_square(&empty[5].0);
        joint(&mut empty, 0.05);
        assert!(empty.iter().all(|p| p.1.iter().all(|x| x.is_finite())));
        assert_eq!(
            stored_values(&empty[5].1, &TableConfig::DEFAULT)[0],
            stored_value(1.0)
        );
        let mut last = joint_moment(&per, 0.05);
        let start = last;
        for step in 0..5 {
            joint(&mut per, 0.05);
            let now = joint_moment(&per, 0.05);
            assert!(now < last, "step {step}: {now} after {last}");
            last = now;
        }
        assert!(last < 0.99 * start, "{start} -> {last}");
        assert!(per
            .iter()
            .all(|p| p.1.iter().all(|x| x.is_finite() && *x >= 0.0)));
    }

    /// Where the weight varies on a scale finer than the uniform grid's cells (a narrow
    /// ridge across `u_0` at 0.40-0.43, the same in every slice), the fitted warp of axis 0
    /// puts at least a quarter of its cells there (even cells: 1.6), each under a quarter
    /// of an even cell; along axis 1, where nothing varies, no cell is that narrow. Reading the draws back through the warp keeps
    /// `E[q^2 / T]` for the uniform density: the stretch undoes itself.
    #[test]
    fn axis_warps_crowd_cells_where_the_weight_varies() {
        let mut rng = Pcg64::seed_from_u64(9);
        let ridge = |x: f64| 1.0 + 30.0 * (-((x - 0.415) / 0.004).powi(2)).exp();
        let draws: Vec<Vec<SliceDraw>> = (0..4)
            .map(|_| {
                (0..60_000)
                    .map(|_| {
                        let p: [f64; 2] = [rng.gen(), rng.gen()];
                        SliceDraw::new(p, ridge(p[0]), 0, 0.0)
                    })
                    .collect()
            })
            .collect();
        let axes = blended(&fit_axes(&draws), 1.0);
        // The cells' bounds on the square, w_0(i / C).
        let g0 = &axes[0];
        let bounds: Vec<f64> = (0..=C)
            .map(|i| {
                f64::from(table_axes::forward(
                    g0,
                    C,
                    total(g0, C),
                    i as f32 / C as f32,
                ))
            })
            .collect();
        let on_ridge = bounds
            .windows(2)
            .filter(|w| (0.39..0.44).contains(&(0.5 * (w[0] + w[1]))))
            .count();
        assert!(
            on_ridge >= C / 4,
            "{on_ridge} cells on the ridge: {bounds:?}"
        );
        // The ridge's cells are under a quarter of an even cell; along axis 1 none is.
        let narrowest =
            |g: &[f32; MAX_NODES]| g.iter().take(NODES).fold(f32::MAX, |m, &x| m.min(x));
        assert!(narrowest(&axes[0]) < 0.25, "{:?}", axes[0]);
        assert!(narrowest(&axes[1]) > 0.25, "{:?}", axes[1]);
        let mut moved = draws[0].clone();
        moved.iter_mut().for_each(|d| d.unwarp(&axes));
        let before: f64 = draws[0].iter().map(|d| d.q2).sum();
        let after: f64 = moved.iter().map(|d| d.q2 / d.stretch).sum();
        assert!((after / before - 1.0).abs() < 1e-9, "{before} vs {after}");
    }
}
