//! The sweep as markdown: a headline, where accuracy stops improving, and the full table.

use super::sweep::Point;

/// Within this factor of a curve's best mean RV, more steps count as no improvement.
pub const PLATEAU: f64 = 1.05;
/// Before the exactness sweep existed, a point counted as exact when no measured step
/// was non-invertible and 99 % of its forward/inverse PDFs agreed to this.
pub const EXACT_P99: f64 = 1e-3;

/// Whether the point's PDFs are the densities it samples: every sample of its exactness
/// sweep keeps the contract (`metrics::exactness`, as `fit` checks it), and no measured
/// step folds. Points of a report measured before the sweep existed use the former rule
/// (`EXACT_P99`).
pub fn exact(p: &Point) -> bool {
    let swept = if p.exact_checked > 0 {
        p.exact_failures == 0
    } else {
        p.consistency_p99 <= EXACT_P99
    };
    swept && p.non_positive_det == 0.0
}

fn num(x: f64) -> String {
    if !x.is_finite() {
        "inf".into()
    } else if x == 0.0 {
        "0".into()
    } else if !(1e-3..1e4).contains(&x.abs()) {
        format!("{x:.1e}")
    } else if x.abs() >= 100.0 {
        format!("{x:.0}")
    } else if x.abs() >= 10.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.3}")
    }
}

fn opt(x: Option<f64>) -> String {
    x.map_or("-".into(), num)
}

/// The points of one curve (model and precision), in sweep order.
pub fn curves(points: &[Point]) -> Vec<Vec<&Point>> {
    let mut out: Vec<Vec<&Point>> = Vec::new();
    for p in points {
        match out
            .iter_mut()
            .find(|c| c[0].model == p.model && c[0].precision == p.precision)
        {
            Some(c) => c.push(p),
            None => out.push(vec![p]),
        }
    }
    out
}

/// The fewest steps whose mean RV is within [`PLATEAU`] of the curve's best, among its
/// exact points.
pub fn plateau<'a>(curve: &[&'a Point]) -> Option<&'a Point> {
    let best = curve
        .iter()
        .filter(|p| exact(p))
        .map(|p| p.rv_mean)
        .filter(|r| r.is_finite())
        .fold(f64::INFINITY, f64::min);
    curve
        .iter()
        .filter(|p| exact(p) && p.rv_mean <= best * PLATEAU)
        .min_by_key(|p| p.steps)
        .copied()
}

/// One line per curve: where more steps stop paying.
fn plateau_lines(points: &[Point]) -> String {
    let mut s = String::from(
        "| model | weights | shipped N | fewest exact N | N where mean RV is within 5 % of its best (exact points) | RV there | best RV (at N) | time x material there |\n|---|---|---|---|---|---|---|---|\n",
    );
    for c in curves(points) {
        let Some(p) = plateau(&c) else { continue };
        let fewest_exact = c
            .iter()
            .filter(|q| exact(q))
            .map(|q| q.steps)
            .min()
            .map_or("-".to_string(), |n| n.to_string());
        let best = c
            .iter()
            .filter(|q| exact(q) && q.rv_mean.is_finite())
            .min_by(|a, b| a.rv_mean.total_cmp(&b.rv_mean))
            .copied()
            .unwrap_or(p);
        s += &format!(
            "| `{}` | {} | {} | {} | {} | {} | {} ({}) | {} |\n",
            p.model,
            p.precision,
            p.shipped_steps,
            fewest_exact,
            p.steps,
            num(p.rv_mean),
            num(best.rv_mean),
            best.steps,
            num(p.cost.ratio_sample)
        );
    }
    s
}

/// The headline sentence for the shipped point of `model` (f32), if it was measured.
pub fn headline(points: &[Point], model: &str) -> Option<String> {
    let p = points
        .iter()
        .find(|p| p.model == model && p.precision == "f32" && p.steps == p.shipped_steps)?;
    Some(format!(
        "`{}` ({}, N = {}): a direction costs {}x the material's own sample ({} ns vs {} ns), with its PDF {}x, the PDF of a given direction {}x; mean RV {} (material's sampler {}), worst {}.",
        p.model,
        p.domain,
        p.steps,
        num(p.ratio_direction),
        num(p.cost.learned_direction_ns),
        num(p.cost.material_sample_ns),
        num(p.cost.ratio_sample),
        num(p.ratio_pdf),
        num(p.rv_mean),
        num(p.material_rv_mean),
        num(p.rv_worst)
    ))
}

/// The full table, one row per point.
pub fn table(points: &[Point]) -> String {
    let mut s = String::from(
        "| model | domain | weights | N | direction ns | direction + PDF ns | PDF(wo) ns | material ns | x material (dir / dir+PDF / PDF) | RV mean / worst | mat. RV | firefly mean / worst | KL / mat. KL | valid | PDF consistency p99 / max | det <= 0 | exactness sweep: failures / samples |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for p in points {
        let c = &p.cost;
        s += &format!(
            "| `{}` | {} | {} | {}{} | {} | {} | {} | {} | {} / {} / {} | {} / {} | {} | {} / {} | {} / {} | {:.2} % | {} / {} | {:.2} % | {} / {} |\n",
            p.model,
            p.domain,
            p.precision,
            p.steps,
            if p.steps == p.shipped_steps { "*" } else { "" },
            num(c.learned_direction_ns),
            num(c.learned_sample_ns),
            num(c.learned_pdf_ns),
            num(c.material_sample_ns),
            num(p.ratio_direction),
            num(c.ratio_sample),
            num(p.ratio_pdf),
            num(p.rv_mean),
            num(p.rv_worst),
            num(p.material_rv_mean),
            num(p.firefly_mean),
            num(p.firefly_worst),
            opt(p.kl_mean),
            opt(p.material_kl_mean),
            100.0 * p.valid_mean,
            num(p.consistency_p99),
            num(p.consistency_max),
            100.0 * p.non_positive_det,
            p.exact_failures,
            p.exact_checked
        );
    }
    s
}

/// The whole report body (without the title and the command, which the caller adds).
pub fn render(points: &[Point], headline_model: &str) -> String {
    let mut s = String::new();
    if let Some(h) = headline(points, headline_model) {
        s += &format!("**Headline.** {h}\n\n");
    }
    s += "## Where accuracy stops improving\n\n";
    s += "Only exact points count: every sample of the point's exactness sweep (the check `fit` runs before it ships a step count, here with fewer samples: see the table's last column) keeps `pdf()` equal to the sampled PDF, and no measured step has `det(I + h dv/dx) <= 0` (fewer steps than a model was trained with can fold its flow; then the PDF is no longer the density sampled). RV is estimated from a finite sample per `wi`: where rare large weights occur (grazing `wi`, sharp or measured lobes) one sample can move a mean RV severalfold, so differences of that kind between neighbouring points are noise, not a trend.\n\n";
    s += &plateau_lines(points);
    s += "\n## All points\n\n`*` marks each model's shipped step count. Times are per call on one thread, measured in the same run as the material's own sampler (at theta_i = 45 deg); read the ratios, bare times depend on the machine. The direction-only and direction + PDF entry points return the same directions (bit-identical paths), so one accuracy serves both; the PDF-of-a-direction entry point's accuracy is the forward/inverse consistency.\n\n";
    s += &table(points);
    s
}
