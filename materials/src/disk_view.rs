//! A reflection-only material seen through a radial change of its projected disk: the
//! disk point `y` of this material's direction stands for the inner material's disk point
//! `x = y R(|y|) / |y|`, for a map `R` of the radius ([`RadialMap`]: the zoom of `zoom.rs`,
//! the profile warp of `radial.rs`).
//!
//! With `J = dA_x / dA_y` the map's determinant, densities per unit solid angle change by
//! `F = (d.z / d'.z) J` (`d` this material's direction, `d'` the inner one), and
//! `f_d(wi, d) = f(wi, d') J`, so importance weights are unchanged.

use crate::{DVec3, Material, MaterialSample, Rgb};

/// Below this disk radius a point is the centre, where `|x| / |y|` is the map's limit.
const CENTRE: f64 = 1e-12;

/// A one-to-one map of the radius of the unit disk onto itself.
pub trait RadialMap: Send + Sync + std::fmt::Debug {
    /// Short name of the view, e.g. `"zoom"`.
    fn name(&self) -> &'static str;
    /// The view's spec before the inner material's, e.g. `"zoom:3"`.
    fn spec_prefix(&self) -> String;
    /// The inner radius `R(rho)` of the radius `rho` and `J` there.
    fn inner_radius(&self, rho: f64) -> (f64, f64);
    /// The radius `rho` of the inner radius `r` (the inverse of [`RadialMap::inner_radius`])
    /// and `J` there.
    fn outer_radius(&self, r: f64) -> (f64, f64);
    /// `lim R(rho) / rho` at the centre.
    fn centre_ratio(&self) -> f64;
}

/// A reflection-only material seen through the radial map `M`.
#[derive(Debug)]
pub struct DiskView<M: RadialMap> {
    inner: Box<dyn Material>,
    map: M,
}

impl<M: RadialMap> DiskView<M> {
    /// `inner` through `map`; `None` for a transmissive material.
    pub fn with_map(inner: Box<dyn Material>, map: M) -> Option<DiskView<M>> {
        (!inner.is_transmissive()).then_some(DiskView { inner, map })
    }

    /// The radial map.
    pub fn map(&self) -> &M {
        &self.map
    }

    /// `d` moved along its ray from disk radius `from` to `to` (`ratio` = `to / from` at
    /// the centre); `None` on or below the horizon.
    fn rescale(d: DVec3, from: f64, to: f64, ratio: f64) -> Option<DVec3> {
        let s = if from > CENTRE { to / from } else { ratio };
        let (x, y) = (d.x * s, d.y * s);
        let z = (1.0 - x * x - y * y).max(0.0).sqrt();
        (z > 0.0).then_some(DVec3::new(x, y, z))
    }

    /// The inner direction of `d` and `J`; `None` below the surface.
    fn inner_of(&self, d: DVec3) -> Option<(DVec3, f64)> {
        if !(d.z > 0.0) {
            return None;
        }
        let rho = (d.x * d.x + d.y * d.y).sqrt().min(1.0);
        let (r, j) = self.map.inner_radius(rho);
        Some((Self::rescale(d, rho, r, self.map.centre_ratio())?, j))
    }
}

impl<M: RadialMap> Material for DiskView<M> {
    fn name(&self) -> &'static str {
        self.map.name()
    }

    fn spec(&self) -> String {
        format!("{}:{}", self.map.spec_prefix(), self.inner.spec())
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
        let r = (s.wo.x * s.wo.x + s.wo.y * s.wo.y).sqrt().min(1.0);
        let (rho, j) = self.map.outer_radius(r);
        let d = Self::rescale(s.wo, r, rho, 1.0 / self.map.centre_ratio())?;
        let pdf = s.pdf * (d.z / s.wo.z) * j;
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

/// Test support for the views: what every one must keep.
#[cfg(test)]
pub(crate) mod checks {
    use crate::{parse_spec, DVec3};
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    /// Over 20 000 draws at one `wi`, `spec`'s sampler agrees with its own `pdf` and
    /// `eval` to `tol` relative, and its mean weight (the albedo) is `inner`'s to 2 %:
    /// the view changes densities, never importance weights.
    pub(crate) fn assert_view_keeps_weights(spec: &str, inner: &str, tol: f64) {
        let m = parse_spec(spec).unwrap();
        let inner = parse_spec(inner).unwrap();
        let wi = DVec3::new(0.6, 0.0, 0.8);
        let mut rng = Pcg64::seed_from_u64(7);
        let (mut a, mut b) = (0.0, 0.0);
        for _ in 0..20_000 {
            let u: [f64; 3] = [rng.gen(), rng.gen(), rng.gen()];
            if let Some(s) = m.sample(wi, u) {
                let pdf = m.pdf(wi, s.wo);
                assert!(
                    (pdf - s.pdf).abs() <= tol * s.pdf,
                    "{spec}: {pdf} vs {}",
                    s.pdf
                );
                let w = m.eval_cos(wi, s.wo).luminance() / s.pdf;
                assert!(
                    (w - s.weight.luminance()).abs() <= tol * w.max(1.0),
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
