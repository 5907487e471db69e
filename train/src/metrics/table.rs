//! Plain-text rendering of a [`Report`].

use super::evaluate::{Report, SamplerSummary};
use std::fmt::Write;

fn fmt_opt(x: Option<f64>) -> String {
    x.map_or_else(|| "-".to_string(), |v| format!("{v:.4}"))
}

fn summary_line(name: &str, s: &SamplerSummary) -> String {
    format!(
        "{name:<10} {:>10.4} {:>10.4} ({:>4.0} deg) {:>10.2} {:>10.2} {:>8}\n",
        s.rv_mean,
        s.rv_worst,
        s.rv_worst_theta_deg,
        s.firefly_mean,
        s.firefly_worst,
        fmt_opt(s.kl_mean)
    )
}

/// The report as a text table.
pub fn render(r: &Report) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "material {}  domain {}  steps {}  blob {} B (f32) / {} B (f16)  samples/wi {}",
        r.material, r.domain, r.steps, r.blob_bytes_f32, r.blob_bytes_f16, r.samples_per_wi
    );
    let _ = writeln!(
        s,
        "sampler      RV mean   RV worst (at theta_i)  firefly mean  worst   KL mean"
    );
    s += &summary_line("learned", &r.learned);
    s += &summary_line("material", &r.material_sampler);
    s += &summary_line("cosine", &r.cosine);
    let _ = writeln!(
        s,
        "learned / material mean RV: {:.3}",
        r.rv_ratio_to_material
    );
    if let Some(o) = &r.off_grid {
        let _ = writeln!(
            s,
            "off the grid ({} incidences, theta_i in strata of [0, 89.5] deg, phi_i uniform): RV mean learned {:.4}, material {:.4}, ratio {:.3}; learned firefly worst {:.2}",
            o.incidences, o.learned_rv_mean, o.material_rv_mean, o.rv_ratio_to_material, o.learned_firefly_worst
        );
    }
    let c = &r.consistency;
    let _ = writeln!(
        s,
        "PDF consistency |pdf(wo) - pdf_sampled| / pdf_sampled: median {:.2e}  p99 {:.2e}  max {:.2e}  >1e-3: {:.4}%  inexact (pdf() = 0 or beyond f32 rounding): {}",
        c.median,
        c.p99,
        c.max,
        100.0 * c.above_1e3,
        c.inconsistent
    );
    let _ = writeln!(
        s,
        "min det(I + h dv/dx) over trajectories: {:.4}  (non-positive: {:.4}%)",
        c.min_det,
        100.0 * c.non_positive_det
    );
    if let Some(e) = &r.exactness {
        s += &e.summary();
    }
    if let Some(k) = &r.cost {
        let _ = writeln!(
            s,
            "time/sample: learned {:.0} ns (direction only {:.0} ns, pdf(wo) {:.0} ns), material sampler {:.0} ns; ratio {:.1}x",
            k.learned_sample_ns, k.learned_direction_ns, k.learned_pdf_ns, k.material_sample_ns, k.ratio_sample
        );
    }
    let _ = writeln!(s, "\n theta  phi |  RV learned  material    cosine | firefly learned material | KL learned material");
    for w in &r.rows {
        let _ = writeln!(
            s,
            "{:>6.0} {:>4.0} | {:>10.4} {:>9.4} {:>9.4} | {:>15.2} {:>8.2} | {:>10} {:>8}",
            w.theta_deg,
            w.phi_deg,
            w.learned.stats.rv,
            w.material.stats.rv,
            w.cosine.stats.rv,
            w.learned.stats.firefly,
            w.material.stats.firefly,
            fmt_opt(w.learned.kl),
            fmt_opt(w.material.kl)
        );
    }
    s
}
