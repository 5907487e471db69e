//! `RawMaterial`: the reference materials of `diffbsdf-materials` (analytic and RGL
//! measured) with batch `eval`, `eval_luminance`, `sample` and `pdf`, so a learned model
//! can be compared with its target from Python.
//!
//! Directions are checked the way the kernel checks them (finite, `| |w|^2 - 1 | <=
//! UNIT_TOLERANCE`) and then normalised in f64; a row that fails, or a `u` outside [0, 1],
//! gives zeros (`valid = False` for `sample`). The materials compute in f64; the outputs
//! are float32.

use crate::{check_len, check_threads, default_threads, not_contiguous, rows, split, BindError};
use crate::{Col, Flags, Rows3};
use diffbsdf::spec::UNIT_TOLERANCE;
use diffbsdf_materials::rgl::RglMaterial;
use diffbsdf_materials::{parse_spec, DVec3, Material};
use numpy::ndarray::{Array1, Array2};
use numpy::IntoPyArray;
use pyo3::prelude::*;

/// A reference material (`Box<dyn diffbsdf_materials::Material>`).
#[pyclass(module = "diffbsdf._diffbsdf", frozen)]
pub(crate) struct RawMaterial {
    material: Box<dyn Material>,
}

/// A float32 row as a unit f64 direction, or `None` (not finite, or not unit within the
/// kernel's tolerance).
fn direction(w: &[f32]) -> Option<DVec3> {
    let v = DVec3::new(f64::from(w[0]), f64::from(w[1]), f64::from(w[2]));
    let l2 = v.length_squared();
    (v.is_finite() && (l2 - 1.0).abs() <= f64::from(UNIT_TOLERANCE)).then(|| v / l2.sqrt())
}

fn uniforms(u: &[f32]) -> Option<[f64; 3]> {
    let ok = |x: f32| (0.0..=1.0).contains(&x);
    (ok(u[0]) && ok(u[1]) && ok(u[2])).then(|| [u[0], u[1], u[2]].map(f64::from))
}

/// What `sample` writes per row.
#[derive(Clone, Copy, Default)]
struct Drawn {
    wo: [f32; 3],
    pdf: f32,
    valid: bool,
}

/// Borrowed `(N, 3)` rows of two arguments, checked to be the same length.
type Pair<'a> = (&'a [f32], &'a [f32], usize);

fn pair<'a>(a: &'a [f32], b: &'a [f32]) -> Result<Pair<'a>, BindError> {
    check_len(a.len() / 3, b.len() / 3)?;
    Ok((a, b, a.len() / 3))
}

impl RawMaterial {
    /// `f(i)` for each row `i` of `(wi, x)` where `x` is `wo` or `u`, `width` outputs per
    /// row, split over threads with the GIL released.
    fn per_row<T, F>(
        &self,
        py: Python<'_>,
        n: usize,
        width: usize,
        threads: Option<i64>,
        f: F,
    ) -> Result<Vec<T>, BindError>
    where
        T: Copy + Default + Send,
        F: Fn(&dyn Material, usize, &mut [T]) + Sync,
    {
        let threads = check_threads(threads, default_threads())?;
        let mut out = vec![T::default(); n * width];
        let m = self.material.as_ref();
        py.detach(|| {
            split(n, threads, vec![out.as_mut_slice()], |start, mut pieces| {
                let piece = pieces.pop().unwrap_or_default();
                for (k, row) in piece.chunks_mut(width).enumerate() {
                    f(m, start + k, row);
                }
                Ok(())
            })
        })?;
        Ok(out)
    }
}

#[pymethods]
impl RawMaterial {
    /// A material from the one-string spec of `diffbsdf material` (e.g.
    /// `conductor:ggx,alpha=0.3,metal=Cu`, `rgl:/path/file_rgb.bsdf`).
    #[staticmethod]
    fn from_spec(spec: &str) -> PyResult<Self> {
        let material = parse_spec(spec).map_err(BindError::Spec)?;
        Ok(RawMaterial { material })
    }

    /// An RGL measured material (`*_rgb.bsdf`, Dupuy & Jakob 2018) from a file.
    #[staticmethod]
    fn rgl(path: &str) -> PyResult<Self> {
        let m = RglMaterial::open(path).map_err(|e| BindError::Rgl(path.to_owned(), e))?;
        Ok(RawMaterial {
            material: Box::new(m),
        })
    }

    #[getter]
    fn name(&self) -> &'static str {
        self.material.name()
    }

    #[getter]
    fn spec(&self) -> String {
        self.material.spec()
    }

    #[getter]
    fn transmissive(&self) -> bool {
        self.material.is_transmissive()
    }

    #[getter]
    fn isotropic(&self) -> bool {
        self.material.is_isotropic()
    }

    /// `f(wi, wo) |cos theta_o|` per RGB channel, `(N, 3)` float32.
    #[pyo3(signature = (wi, wo, threads=None))]
    fn eval<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
        threads: Option<i64>,
    ) -> PyResult<Rows3<'py>> {
        let wi = rows("wi", wi, 3)?;
        let wo = rows("wo", wo, 3)?;
        let (a, b, n) = pair(
            wi.as_slice().map_err(|_| not_contiguous("wi"))?,
            wo.as_slice().map_err(|_| not_contiguous("wo"))?,
        )?;
        let out = self.per_row(py, n, 3, threads, |m, i, row: &mut [f32]| {
            let r = &a[3 * i..3 * i + 3];
            let o = &b[3 * i..3 * i + 3];
            if let (Some(wi), Some(wo)) = (direction(r), direction(o)) {
                let f = m.eval_cos(wi, wo);
                for (dst, src) in row.iter_mut().zip(f.0) {
                    *dst = src as f32;
                }
            }
        })?;
        let arr = Array2::from_shape_vec((n, 3), out).map_err(|_| BindError::Worker)?;
        Ok(arr.into_pyarray(py))
    }

    /// Luminance (Rec. 709) of `f(wi, wo) |cos theta_o|`, `(N,)` float32.
    #[pyo3(signature = (wi, wo, threads=None))]
    fn eval_luminance<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
        threads: Option<i64>,
    ) -> PyResult<Col<'py>> {
        let wi = rows("wi", wi, 3)?;
        let wo = rows("wo", wo, 3)?;
        let (a, b, n) = pair(
            wi.as_slice().map_err(|_| not_contiguous("wi"))?,
            wo.as_slice().map_err(|_| not_contiguous("wo"))?,
        )?;
        let out = self.per_row(py, n, 1, threads, |m, i, row: &mut [f32]| {
            let r = &a[3 * i..3 * i + 3];
            let o = &b[3 * i..3 * i + 3];
            if let (Some(wi), Some(wo)) = (direction(r), direction(o)) {
                row[0] = (m.eval_luminance(wi, wo) * wo.z.abs()) as f32;
            }
        })?;
        Ok(Array1::from_vec(out).into_pyarray(py))
    }

    /// The material's own sampler: `(wo (N,3), pdf (N,), valid (N,))` for `u` of shape
    /// `(N, 3)` (`u[:, 2]` picks a lobe); invalid rows have `wo = 0`, `pdf = 0`.
    #[pyo3(signature = (wi, u, threads=None))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        u: &Bound<'py, PyAny>,
        threads: Option<i64>,
    ) -> PyResult<(Rows3<'py>, Col<'py>, Flags<'py>)> {
        let wi = rows("wi", wi, 3)?;
        let u = rows("u", u, 3)?;
        let (a, b, n) = pair(
            wi.as_slice().map_err(|_| not_contiguous("wi"))?,
            u.as_slice().map_err(|_| not_contiguous("u"))?,
        )?;
        let drawn = self.per_row(py, n, 1, threads, |m, i, row: &mut [Drawn]| {
            let r = &a[3 * i..3 * i + 3];
            let uu = &b[3 * i..3 * i + 3];
            let Some((wi, u)) = direction(r).zip(uniforms(uu)) else {
                return;
            };
            if let Some(s) = m.sample(wi, u) {
                let pdf = s.pdf as f32;
                if pdf > 0.0 && pdf.is_finite() && s.wo.is_finite() {
                    row[0] = Drawn {
                        wo: s.wo.as_vec3().to_array(),
                        pdf,
                        valid: true,
                    };
                }
            }
        })?;
        let mut wo = Array2::<f32>::zeros((n, 3));
        let mut pdf = Array1::<f32>::zeros(n);
        let mut valid = Array1::<bool>::from_elem(n, false);
        for (i, d) in drawn.iter().enumerate() {
            wo[[i, 0]] = d.wo[0];
            wo[[i, 1]] = d.wo[1];
            wo[[i, 2]] = d.wo[2];
            pdf[i] = d.pdf;
            valid[i] = d.valid;
        }
        Ok((
            wo.into_pyarray(py),
            pdf.into_pyarray(py),
            valid.into_pyarray(py),
        ))
    }

    /// The density of the material's sampler at `wo`, per unit solid angle, `(N,)`.
    #[pyo3(signature = (wi, wo, threads=None))]
    fn pdf<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
        threads: Option<i64>,
    ) -> PyResult<Col<'py>> {
        let wi = rows("wi", wi, 3)?;
        let wo = rows("wo", wo, 3)?;
        let (a, b, n) = pair(
            wi.as_slice().map_err(|_| not_contiguous("wi"))?,
            wo.as_slice().map_err(|_| not_contiguous("wo"))?,
        )?;
        let out = self.per_row(py, n, 1, threads, |m, i, row: &mut [f32]| {
            let r = &a[3 * i..3 * i + 3];
            let o = &b[3 * i..3 * i + 3];
            if let (Some(wi), Some(wo)) = (direction(r), direction(o)) {
                row[0] = m.pdf(wi, wo) as f32;
            }
        })?;
        Ok(Array1::from_vec(out).into_pyarray(py))
    }
}
