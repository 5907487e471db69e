//! A hemisphere material seen through a radial zoom of the projected disk
//! ([`crate::disk_view`]): `R(r) = (e^(k r) - 1) / (e^k - 1)`, which magnifies the centre
//! by `(e^k - 1) / k` and compresses the rim by `k e^k / (e^k - 1)`, with determinant
//! `J = R'(r) R(r) / r`.

use crate::disk_view::{DiskView, RadialMap};
use crate::Material;

/// The zoomed view of a reflection-only material.
pub type Zoom = DiskView<ZoomMap>;

/// The zoom's radial map, of strength `k > 0`.
#[derive(Clone, Copy, Debug)]
pub struct ZoomMap {
    k: f64,
}

impl Zoom {
    /// Wraps `inner` with zoom strength `k > 0`; `None` for a transmissive material.
    pub fn new(inner: Box<dyn Material>, k: f64) -> Option<Zoom> {
        (k > 0.0).then_some(())?;
        DiskView::with_map(inner, ZoomMap { k })
    }
}

impl ZoomMap {
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
            self.centre_ratio()
        };
        d * t
    }
}

impl RadialMap for ZoomMap {
    fn name(&self) -> &'static str {
        "zoom"
    }

    fn spec_prefix(&self) -> String {
        format!("zoom:{}", self.k)
    }

    fn inner_radius(&self, rho: f64) -> (f64, f64) {
        (self.radius(rho), self.det(rho))
    }

    fn outer_radius(&self, r: f64) -> (f64, f64) {
        let rho = self.radius_inverse(r);
        (rho, self.det(rho))
    }

    fn centre_ratio(&self) -> f64 {
        self.k / self.k.exp_m1()
    }
}

#[cfg(test)]
mod tests {
    use crate::disk_view::checks::assert_view_keeps_weights;

    /// The sampler's PDF and weights agree with `pdf` and `eval` in the zoomed chart, and
    /// the mean weight (the albedo) is the inner material's.
    #[test]
    fn weights_densities_and_albedo_survive_the_zoom() {
        for (spec, inner) in [
            (
                "zoom:4:halfway:conductor:ggx,alpha=0.05,metal=Cu",
                "halfway:conductor:ggx,alpha=0.05,metal=Cu",
            ),
            ("zoom:2:lambertian", "lambertian"),
        ] {
            assert_view_keeps_weights(spec, inner, 1e-8);
        }
    }
}
