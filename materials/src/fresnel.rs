//! Fresnel reflectance for dielectric and conducting interfaces.

use crate::Rgb;

/// Unpolarised Fresnel reflectance of a dielectric interface (Walter 2007 eq. 22, in the
/// exact Snell form). `cos_i` is the cosine between the incident direction and the normal
/// on the side of the incident direction; a negative `cos_i` means arriving from inside,
/// and `eta` (inside over outside) is inverted. Returns 1 on total internal reflection.
pub fn dielectric(cos_i: f64, eta: f64) -> f64 {
    let mut cos_i = cos_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

/// Unpolarised Fresnel reflectance of a conductor with complex index `eta + i k` (relative
/// to the outside medium) for one wavelength; exact expression (e.g. pbrt-v3
/// `FrConductor`, after Born & Wolf). `cos_i` is clamped to `[0, 1]`.
pub fn conductor(cos_i: f64, eta: f64, k: f64) -> f64 {
    let c = cos_i.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let (eta2, k2) = (eta * eta, k * k);
    let t0 = eta2 - k2 - s2;
    let a2pb2 = (t0 * t0 + 4.0 * eta2 * k2).max(0.0).sqrt();
    let a = (0.5 * (a2pb2 + t0)).max(0.0).sqrt();
    let t1 = a2pb2 + c2;
    let t2 = 2.0 * a * c;
    let rs = (t1 - t2) / (t1 + t2);
    let t3 = c2 * a2pb2 + s2 * s2;
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4);
    let r = 0.5 * (rs + rp);
    if r.is_finite() {
        r.clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// [`conductor`] per RGB channel.
pub fn conductor_rgb(cos_i: f64, eta: [f64; 3], k: [f64; 3]) -> Rgb {
    Rgb([
        conductor(cos_i, eta[0], k[0]),
        conductor(cos_i, eta[1], k[1]),
        conductor(cos_i, eta[2], k[2]),
    ])
}

/// Schlick's approximation `F0 + (1 - F0) (1 - cos)^5` (Schlick 1994).
pub fn schlick(cos_i: f64, f0: f64) -> f64 {
    let m = (1.0 - cos_i.clamp(0.0, 1.0)).max(0.0);
    let m2 = m * m;
    f0 + (1.0 - f0) * m2 * m2 * m
}

/// Schlick weight `(1 - cos)^5`.
pub fn schlick_weight(cos_i: f64) -> f64 {
    schlick(cos_i, 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conductor_with_zero_k_matches_dielectric() {
        for i in 0..=20 {
            let c = i as f64 / 20.0;
            let a = conductor(c, 1.5, 0.0);
            let b = dielectric(c, 1.5);
            assert!((a - b).abs() < 1e-9, "{c}: {a} vs {b}");
        }
    }

    #[test]
    fn normal_incidence() {
        let f0 = ((1.5_f64 - 1.0) / 2.5).powi(2);
        assert!((dielectric(1.0, 1.5) - f0).abs() < 1e-12);
        assert!((dielectric(-1.0, 1.5) - f0).abs() < 1e-12);
        assert_eq!(dielectric(-0.1, 1.5), 1.0);
    }
}
