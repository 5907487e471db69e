//! Statistics of importance weights `w = f |cos theta_o| / pdf` (0 for invalid samples).

use serde::Serialize;

/// Summary of the weights at one `wi`.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct WeightStats {
    /// `E[w]` (the directional albedo in luminance when the sampler is unbiased).
    pub mean: f64,
    /// Relative variance `E[w^2] / E[w]^2 - 1`.
    pub rv: f64,
    /// 99.99th percentile of `w / E[w]`.
    pub firefly: f64,
    /// Fraction of samples that were valid.
    pub valid: f64,
}

impl WeightStats {
    /// From all weights (invalid samples included as 0). Sorts `w`.
    pub fn from_weights(w: &mut [f64]) -> Self {
        let n = w.len().max(1) as f64;
        let mean = w.iter().sum::<f64>() / n;
        let m2 = w.iter().map(|x| x * x).sum::<f64>() / n;
        let valid = w.iter().filter(|x| **x > 0.0).count() as f64 / n;
        if !(mean > 0.0) {
            return WeightStats {
                mean: 0.0,
                rv: f64::INFINITY,
                firefly: f64::INFINITY,
                valid,
            };
        }
        w.sort_by(|a, b| a.total_cmp(b));
        let k = ((w.len() as f64 * 0.9999).ceil() as usize).clamp(1, w.len()) - 1;
        WeightStats {
            mean,
            rv: m2 / (mean * mean) - 1.0,
            firefly: w[k] / mean,
            valid,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_weights_are_perfect() {
        let mut w = vec![0.5; 1000];
        let s = WeightStats::from_weights(&mut w);
        assert!(s.rv.abs() < 1e-12 && (s.firefly - 1.0).abs() < 1e-12 && s.valid == 1.0);
    }

    #[test]
    fn half_zero_weights_have_rv_one() {
        let mut w: Vec<f64> = (0..1000)
            .map(|i| if i % 2 == 0 { 2.0 } else { 0.0 })
            .collect();
        let s = WeightStats::from_weights(&mut w);
        assert!((s.rv - 1.0).abs() < 1e-12 && (s.firefly - 2.0).abs() < 1e-12);
    }
}
