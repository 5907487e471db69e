//! A hemisphere material seen through a radial zoom of the projected disk: the disk point
//! `y` of this material's direction stands for the inner material's disk point
//! `x = y R(|y|) / |y|`, `R(r) = (e^(k r) - 1) / (e^k - 1)`, which magnifies the centre by
//! `(e^k - 1) / k` and compresses the rim by `k e^k / (e^k - 1)`.
//!
//! Densities per unit solid angle change by `F = (d.z / d'.z) J` with
//! `J = R'(r) R(r) / r` the map's determinant (`d` this material's direction, `d'` the
//! inner one), and `f_d(wi, d) = f(wi, d') J`, so importance weights are unchanged.

use crate::{DVec3, Material, MaterialSample, Rgb};

/// The zoomed view of a reflection-only material.
#[derive(Debug)]
pub struct Zoom {
    inner: Box<dyn Material>,
    k: f64,
}

impl Zoom {
    /// Wraps `inner` with zoom strength `k > 0`; `None` for a transmissive material.
    pub fn new(inner: Box<dyn Material>, k: f64) -> Option<Zoom> {
        (!inner.is_transmissive() && k > 0.0).then_some(Zoom { inner, k })
    }

    fn radius(&self, r: f64) -> f64 {
        (self.k * r).exp_m1() / self.k.exp_m1()
    }

    fn radius_inverse(&self, rx: f64) -> f64 {
        (rx * self.k.exp_m1()).ln_1p() / self.k
    }

    /// `J = R'(r) R(r) / r` at `r = |y|` (the limit `R'(0)^2` at the centre).
    fn det(&self, r: f64) -> f64 {
        let d = self.k * (self.k * r).exp() / self.k.exp_m1();
        let t = if r > 1e-12 {
            self.radius(r) / r
        } else {
            self.k / self.k.exp_m1()
        };
        d * t
    }

    /// The inner direction of `d` and `J`; `None` below the surface.
    fn inner_of(&self, d: DVec3) -> Option<(DVec3, f64)> {
        if !(d.z > 0.0) {
            return None;
        }
        let r = (d.x * d.x + d.y * d.y).sqrt().min(1.0);
        let rx = self.radius(r);
        let s = if r > 1e-12 {
            rx / r
        } else {
            self.k / self.k.exp_m1()
        };
        let (x, y) = (d.x * s, d.y * s);
        let z = (1.0 - x * x - y * y).max(0.0).sqrt();
        (z > 0.0).then_some((DVec3::new(x, y, z), self.det(r)))
    }
}

impl Material for Zoom {
    fn name(&self) -> &'static str {
        "zoom"
    }

    fn spec(&self) -> String {
        format!("zoom:{}:{}", self.k, self.inner.spec())
    }

    fn eval(&self, wi: DVec3, d: DVec3) -> Rgb {
        match self.inner_of(d) {
            Some((dp, j)) => self.inner.eval(wi, dp) * j,
            None => Rgb::ZERO,
        }
    }

    fn sample(&self, wi: DVec3, u: [f64; 3]) -> Option<MaterialSample> {
        let s = self.inner.sample(wi, u)?;
        if !(s.wo.z > 0.0) {
            return None;
        }
        let rx = (s.wo.x * s.wo.x + s.wo.y * s.wo.y).sqrt();
        let r = self.radius_inverse(rx);
        let sc = if rx > 1e-12 {
            r / rx
        } else {
            self.k.exp_m1() / self.k
        };
        let (x, y) = (s.wo.x * sc, s.wo.y * sc);
        let z = (1.0 - x * x - y * y).max(0.0).sqrt();
        if !(z > 0.0) {
            return None;
        }
        let d = DVec3::new(x, y, z);
        let pdf = s.pdf * (d.z / s.wo.z) * self.det(r);
        (pdf > 0.0 && pdf.is_finite()).then_some(MaterialSample {
            wo: d,
            pdf,
            weight: s.weight,
        })
    }

    fn pdf(&self, wi: DVec3, d: DVec3) -> f64 {
        match self.inner_of(d) {
            Some((dp, j)) => self.inner.pdf(wi, dp) * (d.z / dp.z) * j,
            None => 0.0,
        }
    }

    fn is_transmissive(&self) -> bool {
        false
    }

    fn is_isotropic(&self) -> bool {
        self.inner.is_isotropic()
    }
}

#[cfg(test)]
mod tests {
    use crate::parse_spec;
    use crate::DVec3;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// The sampler's PDF and weights agree with `pdf` and `eval` in the zoomed chart, and
    /// the mean weight (the albedo) is the inner material's.
    #[test]
    fn weights_densities_and_albedo_survive_the_zoom() {
        for spec in [
            "zoom:4:halfway:conductor:ggx,alpha=0.05,metal=Cu",
            "zoom:2:lambertian",
        ] {
            let m = parse_spec(spec).unwrap();
            let inner = parse_spec(spec.splitn(3, ':').nth(2).unwrap()).unwrap();
            let wi = DVec3::new(0.6, 0.0, 0.8);
            let mut rng = Pcg64::seed_from_u64(7);
            let (mut a, mut b) = (0.0, 0.0);
            for _ in 0..20_000 {
                let u: [f64; 3] = [rng.gen(), rng.gen(), rng.gen()];
                if let Some(s) = m.sample(wi, u) {
                    let pdf = m.pdf(wi, s.wo);
                    assert!(
                        (pdf - s.pdf).abs() <= 1e-8 * s.pdf,
                        "{spec}: {pdf} vs {}",
                        s.pdf
                    );
                    let w = m.eval_cos(wi, s.wo).luminance() / s.pdf;
                    assert!(
                        (w - s.weight.luminance()).abs() <= 1e-8 * w.max(1.0),
                        "{spec}"
                    );
                    a += w;
                }
                if let Some(s) = inner.sample(wi, u) {
                    b += s.weight.luminance();
                }
            }
            assert!((a - b).abs() < 0.02 * b, "{spec}: {a} vs {b}");
        }
    }
}
