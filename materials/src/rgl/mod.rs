//! RGL measured BSDFs (Dupuy & Jakob 2018, "An Adaptive Parameterization for Efficient
//! Material Acquisition and Rendering"): the `.bsdf` `tensor_file` reader, evaluation, and
//! the tabular sampler (luminance table, then the VNDF warp) with its PDF.
//!
//! Both kinds of file the database ships are read: `_rgb` files directly, `_spec` files
//! (a `spectra` table over `wavelengths`) as the RGB of their spectra ([`spectral`]). An
//! anisotropic file may store its incident azimuths over half or a quarter of the turn
//! (a material symmetric under a half turn, or mirrored about both axes): directions are
//! folded into the stored range before the tables are read, and sampled directions
//! unfolded, as Mitsuba's `measured` plugin does.
//!
//! Contract: reading never panics; every malformed input is an [`RglError`]. See
//! `shared/RGL-FORMAT.md` for the format facts this follows.

pub mod cursor;
pub mod error;
pub mod spectral;
pub mod tensor;
pub mod warp2d;

pub use error::RglError;
pub use tensor::TensorFile;
pub use warp2d::Warp2D;

use crate::spherical::{from_spherical, reflect, Spherical};
use crate::symmetry::{apply_signs, fold_signs, IncidentFold};
use crate::{DVec3, Material, MaterialSample, Rgb};
use std::f64::consts::{FRAC_PI_2, PI};

/// Lower clamp of the `u -> solid angle` Jacobian `2 pi^2 u_x sin theta_m` (as Mitsuba's
/// `measured` plugin), avoiding a division by zero at the pole.
pub const JACOBIAN_CLAMP: f64 = 1e-6;

/// `u(theta) = sqrt(2 theta / pi)`.
fn theta_to_u(theta: f64) -> f64 {
    (2.0 * theta.max(0.0) / PI).sqrt()
}

/// `theta(u) = u^2 pi / 2`.
fn u_to_theta(u: f64) -> f64 {
    u * u * FRAC_PI_2
}

/// `u(phi) = (phi + pi) / (2 pi)`.
fn phi_to_u(phi: f64) -> f64 {
    (phi + PI) / (2.0 * PI)
}

/// `phi(u) = (2u - 1) pi`.
fn u_to_phi(u: f64) -> f64 {
    (2.0 * u - 1.0) * PI
}

/// How a file's stored incident azimuths fold directions (Mitsuba's `measured` plugin:
/// the span's share of `2 pi`, rounded); an error for a span that is not a whole, half or
/// quarter turn. Isotropic files do not fold.
fn azimuth_fold_of(phi_i: &[f64], isotropic: bool) -> Result<IncidentFold, RglError> {
    if isotropic {
        return Ok(IncidentFold::None);
    }
    let span = phi_i[phi_i.len() - 1] - phi_i[0];
    // Saturating cast: a NaN or huge share is none of the three.
    match (2.0 * PI / span).round() as i64 {
        1 => Ok(IncidentFold::None),
        2 => Ok(IncidentFold::HalfTurn),
        4 => Ok(IncidentFold::Quarter),
        _ => Err(RglError::BadAngles("phi_i")),
    }
}

/// A measured isotropic or anisotropic BSDF, RGB or spectral (read as RGB).
#[derive(Debug, Clone)]
pub struct RglMaterial {
    path: String,
    /// The `description` text of the file.
    pub description: String,
    isotropic: bool,
    fold: IncidentFold,
    jacobian: bool,
    ndf: Warp2D,
    sigma: Warp2D,
    vndf: Warp2D,
    luminance: Warp2D,
    rgb: Warp2D,
}

/// Shape of a field, checked against `expect` (`None` = any extent).
fn check_shape(
    f: &tensor::Field<'_>,
    name: &'static str,
    expect: &[Option<usize>],
) -> Result<(), RglError> {
    if f.shape.len() != expect.len()
        || f.shape
            .iter()
            .zip(expect)
            .any(|(s, e)| e.is_some_and(|e| e != *s))
    {
        return Err(RglError::BadShape(name));
    }
    Ok(())
}

impl RglMaterial {
    /// Reads a `.bsdf` file from disk.
    pub fn open(path: &str) -> Result<Self, RglError> {
        let bytes = std::fs::read(path).map_err(|e| RglError::Io(e.kind()))?;
        let mut m = Self::from_bytes(&bytes)?;
        m.path = path.to_string();
        Ok(m)
    }

    /// Parses a `.bsdf` file held in memory.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, RglError> {
        let tf = TensorFile::parse(bytes)?;
        let description = match tf.field("description") {
            Ok(f) => String::from_utf8_lossy(f.bytes)
                .trim_end_matches('\0')
                .to_string(),
            Err(_) => String::new(),
        };
        let phi_f = tf.field("phi_i")?;
        check_shape(phi_f, "phi_i", &[None])?;
        let phi_i = phi_f.f32_values("phi_i")?;
        let theta_f = tf.field("theta_i")?;
        check_shape(theta_f, "theta_i", &[None])?;
        let theta_i = theta_f.f32_values("theta_i")?;
        let (np, nt) = (phi_i.len(), theta_i.len());
        if np == 0 || nt == 0 {
            return Err(RglError::BadShape("theta_i"));
        }
        if theta_i
            .iter()
            .any(|t| !(-1e-6..=FRAC_PI_2 + 1e-4).contains(t))
        {
            return Err(RglError::BadAngles("theta_i"));
        }
        let isotropic = np <= 2;
        let fold = azimuth_fold_of(&phi_i, isotropic)?;
        let jacobian = match tf.field("jacobian") {
            Ok(f) => f.bytes.first().copied().unwrap_or(0) != 0,
            Err(_) => false,
        };

        let table2 = |name: &'static str| -> Result<Warp2D, RglError> {
            let f = tf.field(name)?;
            check_shape(f, name, &[None, None])?;
            Warp2D::new(
                name,
                f.f32_values(name)?,
                f.shape[1],
                f.shape[0],
                vec![],
                false,
            )
        };
        let ndf = table2("ndf")?;
        let sigma = table2("sigma")?;

        let params = vec![phi_i.clone(), theta_i.clone()];
        let vf = tf.field("vndf")?;
        check_shape(vf, "vndf", &[Some(np), Some(nt), None, None])?;
        let vndf = Warp2D::new(
            "vndf",
            vf.f32_values("vndf")?,
            vf.shape[3],
            vf.shape[2],
            params.clone(),
            true,
        )?;
        let lf = tf.field("luminance")?;
        check_shape(lf, "luminance", &[Some(np), Some(nt), None, None])?;
        let luminance = Warp2D::new(
            "luminance",
            lf.f32_values("luminance")?,
            lf.shape[3],
            lf.shape[2],
            params.clone(),
            true,
        )?;
        let (rgb_values, nx, ny) = Self::rgb_table(&tf, np, nt)?;
        let rgb = Warp2D::new(
            "rgb",
            rgb_values,
            nx,
            ny,
            vec![phi_i, theta_i, vec![0.0, 1.0, 2.0]],
            false,
        )?;
        Ok(Self {
            path: String::new(),
            description,
            isotropic,
            fold,
            jacobian,
            ndf,
            sigma,
            vndf,
            luminance,
            rgb,
        })
    }

    /// The reflectance table `[np, nt, 3, ny, nx]` with its `nx` and `ny`: the file's
    /// `rgb`, or, in a spectral file, its `spectra` over `wavelengths` projected to RGB.
    fn rgb_table(
        tf: &TensorFile<'_>,
        np: usize,
        nt: usize,
    ) -> Result<(Vec<f64>, usize, usize), RglError> {
        if let Ok(rf) = tf.field("rgb") {
            check_shape(rf, "rgb", &[Some(np), Some(nt), Some(3), None, None])?;
            return Ok((rf.f32_values("rgb")?, rf.shape[4], rf.shape[3]));
        }
        let (Ok(sf), Ok(wf)) = (tf.field("spectra"), tf.field("wavelengths")) else {
            return Err(RglError::MissingField("rgb"));
        };
        check_shape(wf, "wavelengths", &[None])?;
        let wavelengths = wf.f32_values("wavelengths")?;
        let w = wavelengths.len();
        check_shape(sf, "spectra", &[Some(np), Some(nt), Some(w), None, None])?;
        let weights = spectral::rgb_weights(&wavelengths)?;
        let (nx, ny) = (sf.shape[4], sf.shape[3]);
        let nodes = nx.checked_mul(ny).ok_or(RglError::Overflow)?;
        let rgb = spectral::spectra_to_rgb(&sf.f32_values("spectra")?, &weights, nodes);
        Ok((rgb, nx, ny))
    }

    /// `(phi_i, theta_i)` parameters, the unit-square half vector `u_wm` and `wi . wm` for
    /// a pair of upper-hemisphere directions, both folded into the stored azimuths; `None`
    /// when either is below the horizon.
    fn half_vector(&self, wi: DVec3, wo: DVec3) -> Option<([f64; 2], [f64; 2], f64)> {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return None;
        }
        let signs = fold_signs(self.fold, wi);
        let (wi, wo) = (apply_signs(signs, wi), apply_signs(signs, wo));
        let wm = (wi + wo).try_normalize()?;
        let (theta_i, phi_i) = (wi.theta(), wi.phi());
        let phi_m = if self.isotropic {
            wm.phi() - phi_i
        } else {
            wm.phi()
        };
        let mut uy = phi_to_u(phi_m);
        uy -= uy.floor();
        Some(([phi_i, theta_i], [theta_to_u(wm.theta()), uy], wi.dot(wm)))
    }

    /// The Jacobian `|d omega_o / d u_wm| = 2 pi^2 u_x sin theta_m * 4 (wi.wm)`, with the
    /// first factor clamped below by [`JACOBIAN_CLAMP`].
    fn jacobian(u_wm: [f64; 2], wi_dot_wm: f64) -> f64 {
        let theta_m = u_to_theta(u_wm[0]);
        (2.0 * PI * PI * u_wm[0] * theta_m.sin()).max(JACOBIAN_CLAMP) * 4.0 * wi_dot_wm
    }

    /// `f(wi, wo) |cos theta_o|` per channel (the file's native quantity, RGL-FORMAT.md
    /// "Evaluation"): `max(0, rgb(s)) ndf(u_wm) / (4 sigma(u_wi))`, `s` = inverse VNDF warp.
    pub fn eval_cos_rgb(&self, wi: DVec3, wo: DVec3) -> Rgb {
        let Some((params, u_wm, _)) = self.half_vector(wi, wo) else {
            return Rgb::ZERO;
        };
        let Some((s, _)) = self.vndf.invert(u_wm, &params) else {
            return Rgb::ZERO;
        };
        let mut out = [0.0; 3];
        for (c, o) in out.iter_mut().enumerate() {
            *o = self.rgb.eval(s, &[params[0], params[1], c as f64]).max(0.0);
        }
        let mut scale = 1.0;
        if self.jacobian {
            let u_wi = [theta_to_u(params[1]), {
                let u = phi_to_u(params[0]);
                u - u.floor()
            }];
            let sigma = self.sigma.eval(u_wi, &[]);
            scale = if sigma > 0.0 {
                self.ndf.eval(u_wm, &[]) / (4.0 * sigma)
            } else {
                0.0
            };
        }
        let v = Rgb(out) * scale;
        if v.is_finite() {
            v
        } else {
            Rgb::ZERO
        }
    }
}

impl Material for RglMaterial {
    fn name(&self) -> &'static str {
        "rgl"
    }

    fn spec(&self) -> String {
        format!("rgl:{}", self.path)
    }

    /// `f` (no cosine): [`RglMaterial::eval_cos_rgb`] divided by `cos theta_o`.
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        self.eval_cos_rgb(wi, wo) * (1.0 / wo.z)
    }

    fn eval_cos(&self, wi: DVec3, wo: DVec3) -> Rgb {
        self.eval_cos_rgb(wi, wo)
    }

    /// Luminance-table sample in warped space, VNDF warp to the half vector, mirror
    /// reflection (RGL-FORMAT.md "Sampling and PDF"), in the stored azimuths (`wi` folded,
    /// the sampled `wo` unfolded). Reflections below the horizon are lost.
    fn sample(&self, wi_in: DVec3, u: [f64; 3]) -> Option<MaterialSample> {
        if wi_in.z <= 0.0 {
            return None;
        }
        let signs = fold_signs(self.fold, wi_in);
        let wi = apply_signs(signs, wi_in);
        let params = [wi.phi(), wi.theta()];
        let (s, _) = self.luminance.sample([u[0], u[1]], &params)?;
        let (u_m, _) = self.vndf.sample(s, &params)?;
        let mut phi_m = u_to_phi(u_m[1]);
        if self.isotropic {
            phi_m += params[0];
        }
        let wm = from_spherical(u_to_theta(u_m[0]), phi_m);
        let wo = apply_signs(signs, reflect(wi, wm).try_normalize()?);
        if wo.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wi_in, wo);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(MaterialSample {
            wo,
            pdf,
            weight: self.eval_cos_rgb(wi_in, wo) * (1.0 / pdf),
        })
    }

    /// `vndf_pdf(u_wm) lum(s) / jacobian`, with `s` from the inverse VNDF warp.
    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let Some((params, u_wm, wi_dot_wm)) = self.half_vector(wi, wo) else {
            return 0.0;
        };
        let Some((s, vndf_pdf)) = self.vndf.invert(u_wm, &params) else {
            return 0.0;
        };
        let lum = self.luminance.eval(s, &params);
        let p = vndf_pdf * lum / Self::jacobian(u_wm, wi_dot_wm);
        if p.is_finite() && p > 0.0 {
            p
        } else {
            0.0
        }
    }

    fn is_transmissive(&self) -> bool {
        false
    }

    fn is_isotropic(&self) -> bool {
        self.isotropic
    }

    /// The fold of the file's stored incident azimuths.
    fn azimuth_fold(&self) -> IncidentFold {
        self.fold
    }
}
