//! `diffbsdf._diffbsdf`: the Python extension module over the diffbsdf kernel.
//!
//! Batch methods take C-contiguous float32 numpy arrays of shape `(N, 3)` (directions) and
//! `(N, 2)` (random numbers), read them in place (no copy), release the GIL and split the
//! batch over threads (`std::thread::scope`, one contiguous chunk per thread). Outputs are
//! new numpy arrays written in place by the C library's slice batch functions
//! (`diffbsdf_ffi::slices`: the kernel's batch loop, run in its AVX2 copy where the CPU has
//! AVX2, the same bits as the kernel's own batch functions). The friendlier
//! conversions (any float dtype, non-contiguous input) live in the Python wrapper
//! `diffbsdf/__init__.py`; this module rejects anything else with a clear exception.
//!
//! `RawMaterial` (module `material`) exposes the reference materials of
//! `diffbsdf-materials` with the same array conventions.

mod material;

use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::{AnyModel, BatchError, BlobError, Precision, Sample};
use diffbsdf_ffi::slices;
use diffbsdf_materials::rgl::RglError;
use diffbsdf_materials::SpecError;
use numpy::ndarray::{Array1, Array2};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use std::fmt;
use std::num::NonZeroUsize;

pyo3::create_exception!(
    _diffbsdf,
    BlobFormatError,
    PyValueError,
    "The bytes are not a valid diffbsdf weight blob (bad magic, truncated, checksum, shape...)."
);

/// Below this many items per thread a batch is not split further (thread start-up costs
/// more than a few hundred samples).
const MIN_CHUNK: usize = 256;

/// Everything that can go wrong in this module, mapped to one Python exception each.
#[derive(Debug)]
enum BindError {
    /// The blob did not load.
    Blob(BlobError),
    /// An argument is not a numpy array of the required dtype / layout.
    Dtype { arg: &'static str, detail: String },
    /// An argument has the wrong shape.
    Shape { arg: &'static str, detail: String },
    /// Two arguments differ in length.
    Length { a: usize, b: usize },
    /// `steps` out of range (1 to `MAX_STEPS`).
    Steps(i64),
    /// `threads` out of range.
    Threads(i64),
    /// The kernel's batch call refused (cannot happen after the checks above).
    Batch(BatchError),
    /// A worker thread panicked (cannot happen: the kernel is panic-free).
    Worker,
    /// A material spec did not parse.
    Spec(SpecError),
    /// An RGL file did not load.
    Rgl(String, RglError),
}

impl fmt::Display for BindError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BindError::Blob(e) => write!(f, "invalid diffbsdf blob: {e}"),
            BindError::Dtype { arg, detail } => write!(f, "{arg}: {detail}"),
            BindError::Shape { arg, detail } => write!(f, "{arg}: {detail}"),
            BindError::Length { a, b } => {
                write!(f, "batch lengths differ: {a} and {b} rows")
            }
            BindError::Steps(s) => {
                write!(
                    f,
                    "steps must be >= 1 and <= {} (or None for the default), got {s}",
                    diffbsdf::spec::MAX_STEPS
                )
            }
            BindError::Threads(t) => write!(f, "threads must be >= 1 (or None), got {t}"),
            BindError::Batch(e) => write!(f, "batch call failed: {e}"),
            BindError::Worker => write!(f, "a worker thread failed"),
            BindError::Spec(e) => write!(f, "material spec: {e}"),
            BindError::Rgl(path, e) => write!(f, "RGL file {path}: {e}"),
        }
    }
}

impl From<BindError> for PyErr {
    fn from(e: BindError) -> PyErr {
        let msg = e.to_string();
        match e {
            BindError::Blob(_) => BlobFormatError::new_err(msg),
            BindError::Dtype { .. } => PyTypeError::new_err(msg),
            BindError::Shape { .. }
            | BindError::Length { .. }
            | BindError::Steps(_)
            | BindError::Threads(_)
            | BindError::Batch(_) => PyValueError::new_err(msg),
            BindError::Worker => pyo3::exceptions::PyRuntimeError::new_err(msg),
            BindError::Spec(SpecError::Rgl(RglError::Io(kind)))
            | BindError::Rgl(_, RglError::Io(kind)) => {
                if kind == std::io::ErrorKind::NotFound {
                    PyFileNotFoundError::new_err(msg)
                } else {
                    PyOSError::new_err(msg)
                }
            }
            BindError::Spec(_) | BindError::Rgl(..) => PyValueError::new_err(msg),
        }
    }
}

/// The default thread count: `std::thread::available_parallelism`, 1 if unknown.
fn default_threads() -> usize {
    std::thread::available_parallelism().map_or(1, NonZeroUsize::get)
}

fn check_steps(steps: Option<i64>, default: u32) -> Result<u32, BindError> {
    match steps {
        None => Ok(default),
        Some(s) if s >= 1 && s <= i64::from(diffbsdf::spec::MAX_STEPS) => {
            u32::try_from(s).map_err(|_| BindError::Steps(s))
        }
        Some(s) => Err(BindError::Steps(s)),
    }
}

fn check_threads(threads: Option<i64>, default: usize) -> Result<usize, BindError> {
    match threads {
        None => Ok(default),
        Some(t) if t >= 1 => usize::try_from(t).map_err(|_| BindError::Threads(t)),
        Some(t) => Err(BindError::Threads(t)),
    }
}

/// A C-contiguous float32 `(N, cols)` array, borrowed read-only.
fn rows<'py>(
    arg: &'static str,
    obj: &Bound<'py, PyAny>,
    cols: usize,
) -> Result<numpy::PyReadonlyArray2<'py, f32>, BindError> {
    let arr = obj
        .downcast::<PyArray2<f32>>()
        .map_err(|_| match ndim_of(obj) {
            Some(ndim) if ndim != 2 => BindError::Shape {
                arg,
                detail: format!("expected shape (N, {cols}), got {}", shape_of(obj)),
            },
            Some(_) => BindError::Dtype {
                arg,
                detail: format!(
                    "expected dtype float32, got {} (the Python wrapper converts float arrays)",
                    obj.getattr("dtype")
                        .and_then(|d| d.str())
                        .map(|s| s.to_string())
                        .unwrap_or_else(|_| "?".to_owned())
                ),
            },
            None => BindError::Dtype {
                arg,
                detail: format!("expected a float32 numpy array of shape (N, {cols})"),
            },
        })?;
    let shape = arr.shape();
    if shape[1] != cols {
        return Err(BindError::Shape {
            arg,
            detail: format!(
                "expected shape (N, {cols}), got ({}, {})",
                shape[0], shape[1]
            ),
        });
    }
    if !arr.is_c_contiguous() {
        return Err(BindError::Dtype {
            arg,
            detail: "expected a C-contiguous array (use numpy.ascontiguousarray)".to_owned(),
        });
    }
    Ok(arr.readonly())
}

fn ndim_of(obj: &Bound<'_, PyAny>) -> Option<usize> {
    obj.getattr("ndim").ok()?.extract().ok()
}

fn shape_of(obj: &Bound<'_, PyAny>) -> String {
    obj.getattr("shape")
        .and_then(|s| s.str())
        .map(|s| s.to_string())
        .unwrap_or_else(|_| "?".to_owned())
}

/// Runs `f(start, len)` over `threads` contiguous chunks of `0..n` in parallel; chunk
/// results are independent, so the outcome does not depend on the thread count.
fn split<T: Send, F>(n: usize, threads: usize, outs: Vec<&mut [T]>, f: F) -> Result<(), BindError>
where
    F: Fn(usize, Vec<&mut [T]>) -> Result<(), BatchError> + Sync,
{
    let threads = threads.min(n.div_ceil(MIN_CHUNK)).max(1);
    if threads == 1 {
        return f(0, outs).map_err(BindError::Batch);
    }
    let chunk = n.div_ceil(threads);
    // Chunk every output slice the same way.
    let mut per_thread: Vec<Vec<&mut [T]>> = (0..threads).map(|_| Vec::new()).collect();
    for out in outs {
        let width = out.len().checked_div(n).unwrap_or(0);
        for (slot, piece) in per_thread.iter_mut().zip(out.chunks_mut(chunk * width)) {
            slot.push(piece);
        }
    }
    std::thread::scope(|s| {
        let handles: Vec<_> = per_thread
            .into_iter()
            .enumerate()
            .map(|(i, pieces)| {
                let f = &f;
                s.spawn(move || f(i * chunk, pieces))
            })
            .collect();
        let mut result = Ok(());
        for h in handles {
            match h.join() {
                Ok(Ok(())) => {}
                Ok(Err(e)) => result = Err(BindError::Batch(e)),
                Err(_) => result = Err(BindError::Worker),
            }
        }
        result
    })
}

/// `(N, 3)` float32 directions.
type Rows3<'py> = Bound<'py, PyArray2<f32>>;
/// `(N,)` float32 PDFs.
type Col<'py> = Bound<'py, PyArray1<f32>>;
/// `(N,)` validity flags.
type Flags<'py> = Bound<'py, PyArray1<bool>>;

/// A loaded diffbsdf model (`diffbsdf.AnyModel` of the kernel).
#[pyclass(module = "diffbsdf._diffbsdf", frozen)]
struct RawModel {
    model: AnyModel,
}

#[pymethods]
impl RawModel {
    /// Loads a blob from bytes.
    #[staticmethod]
    fn from_bytes(blob: &Bound<'_, PyBytes>) -> PyResult<Self> {
        let model = AnyModel::from_blob(blob.as_bytes()).map_err(BindError::Blob)?;
        Ok(RawModel { model })
    }

    #[getter]
    fn domain(&self) -> &'static str {
        self.model.def().domain.name()
    }

    #[getter]
    fn default_steps(&self) -> u32 {
        u32::from(self.model.def().default_steps)
    }

    #[getter]
    fn isotropic(&self) -> bool {
        self.model.def().isotropic
    }

    #[getter]
    fn incident_range(&self) -> &'static str {
        match self.model.def().incident {
            diffbsdf::IncidentRange::UpperHemisphere => "upper_hemisphere",
            diffbsdf::IncidentRange::WholeSphere => "whole_sphere",
        }
    }

    #[getter]
    fn precision(&self) -> &'static str {
        match self.model.def().precision {
            Precision::F32 => "f32",
            Precision::F16 => "f16",
        }
    }

    #[getter]
    fn name(&self) -> String {
        self.model.def().name.as_str().to_owned()
    }

    /// `(freqs, width, hidden_layers)` of the base and the velocity net.
    #[getter]
    fn shape(&self) -> ((u8, u16, u8), (u8, u16, u8)) {
        let d = self.model.def();
        (
            (d.base.freqs, d.base.width, d.base.hidden_layers),
            (d.velocity.freqs, d.velocity.width, d.velocity.hidden_layers),
        )
    }

    /// `(wo (N,3), pdf (N,), valid (N,))`; invalid rows have `wo = 0`, `pdf = 0`.
    #[pyo3(signature = (wi, u, steps=None, threads=None))]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        u: &Bound<'py, PyAny>,
        steps: Option<i64>,
        threads: Option<i64>,
    ) -> PyResult<(Rows3<'py>, Col<'py>, Flags<'py>)> {
        let steps = check_steps(steps, self.default_steps())?;
        let threads = check_threads(threads, default_threads())?;
        let wi = rows("wi", wi, 3)?;
        let u = rows("u", u, 2)?;
        let wi_s = as_vec3(wi.as_slice().map_err(|_| not_contiguous("wi"))?);
        let u_s = as_vec2(u.as_slice().map_err(|_| not_contiguous("u"))?);
        check_len(wi_s.len(), u_s.len())?;
        let n = wi_s.len();
        let mut samples = vec![Sample::INVALID; n];
        let model = &self.model;
        py.detach(|| {
            split(
                n,
                threads,
                vec![samples.as_mut_slice()],
                |start, mut out| {
                    let out = out.pop().unwrap_or_default();
                    let end = start + out.len();
                    slices::sample_batch(model, &wi_s[start..end], &u_s[start..end], steps, out)
                },
            )
        })?;
        let mut wo = Array2::<f32>::zeros((n, 3));
        let mut pdf = Array1::<f32>::zeros(n);
        let mut valid = Array1::<bool>::from_elem(n, false);
        for (i, s) in samples.iter().enumerate() {
            wo[[i, 0]] = s.wo.x;
            wo[[i, 1]] = s.wo.y;
            wo[[i, 2]] = s.wo.z;
            pdf[i] = s.pdf;
            valid[i] = s.is_valid();
        }
        Ok((
            wo.into_pyarray(py),
            pdf.into_pyarray(py),
            valid.into_pyarray(py),
        ))
    }

    /// `(wo (N,3), valid (N,))` without PDFs; invalid rows have `wo = 0`.
    #[pyo3(signature = (wi, u, steps=None, threads=None))]
    fn sample_direction<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        u: &Bound<'py, PyAny>,
        steps: Option<i64>,
        threads: Option<i64>,
    ) -> PyResult<(Rows3<'py>, Flags<'py>)> {
        let steps = check_steps(steps, self.default_steps())?;
        let threads = check_threads(threads, default_threads())?;
        let wi = rows("wi", wi, 3)?;
        let u = rows("u", u, 2)?;
        let wi_s = as_vec3(wi.as_slice().map_err(|_| not_contiguous("wi"))?);
        let u_s = as_vec2(u.as_slice().map_err(|_| not_contiguous("u"))?);
        check_len(wi_s.len(), u_s.len())?;
        let n = wi_s.len();
        let mut wo = Array2::<f32>::zeros((n, 3));
        let wo_flat = wo.as_slice_mut().ok_or(BindError::Worker)?;
        let model = &self.model;
        py.detach(|| {
            split(n, threads, vec![wo_flat], |start, mut out| {
                let out = out.pop().unwrap_or_default();
                let out: &mut [Vec3] = bytemuck::cast_slice_mut(out);
                let end = start + out.len();
                slices::sample_direction_batch(
                    model,
                    &wi_s[start..end],
                    &u_s[start..end],
                    steps,
                    out,
                )
            })
        })?;
        let valid: Array1<bool> = wo
            .rows()
            .into_iter()
            .map(|r| r.iter().any(|&c| c != 0.0))
            .collect();
        Ok((wo.into_pyarray(py), valid.into_pyarray(py)))
    }

    /// `pdf (N,)` of `wo` given `wi` (per unit solid angle; 0 outside the model's support).
    #[pyo3(signature = (wi, wo, steps=None, threads=None))]
    fn pdf<'py>(
        &self,
        py: Python<'py>,
        wi: &Bound<'py, PyAny>,
        wo: &Bound<'py, PyAny>,
        steps: Option<i64>,
        threads: Option<i64>,
    ) -> PyResult<Col<'py>> {
        let steps = check_steps(steps, self.default_steps())?;
        let threads = check_threads(threads, default_threads())?;
        let wi = rows("wi", wi, 3)?;
        let wo = rows("wo", wo, 3)?;
        let wi_s = as_vec3(wi.as_slice().map_err(|_| not_contiguous("wi"))?);
        let wo_s = as_vec3(wo.as_slice().map_err(|_| not_contiguous("wo"))?);
        check_len(wi_s.len(), wo_s.len())?;
        let n = wi_s.len();
        let mut pdf = Array1::<f32>::zeros(n);
        let pdf_flat = pdf.as_slice_mut().ok_or(BindError::Worker)?;
        let model = &self.model;
        py.detach(|| {
            split(n, threads, vec![pdf_flat], |start, mut out| {
                let out = out.pop().unwrap_or_default();
                let end = start + out.len();
                slices::pdf_batch(model, &wi_s[start..end], &wo_s[start..end], steps, out)
            })
        })?;
        Ok(pdf.into_pyarray(py))
    }
}

fn not_contiguous(arg: &'static str) -> BindError {
    BindError::Dtype {
        arg,
        detail: "expected a C-contiguous array (use numpy.ascontiguousarray)".to_owned(),
    }
}

fn check_len(a: usize, b: usize) -> Result<(), BindError> {
    if a == b {
        Ok(())
    } else {
        Err(BindError::Length { a, b })
    }
}

/// `(N*3)` floats as `N` vectors (the shape was checked, so the length divides).
fn as_vec3(flat: &[f32]) -> &[Vec3] {
    bytemuck::cast_slice(flat)
}

fn as_vec2(flat: &[f32]) -> &[Vec2] {
    bytemuck::cast_slice(flat)
}

/// The thread count batch calls use when not told otherwise.
#[pyfunction]
fn available_threads() -> usize {
    default_threads()
}

#[pymodule]
fn _diffbsdf(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<RawModel>()?;
    m.add_class::<material::RawMaterial>()?;
    m.add_function(wrap_pyfunction!(available_threads, m)?)?;
    m.add("BlobFormatError", m.py().get_type::<BlobFormatError>())?;
    m.add("KERNEL_VERSION", env!("CARGO_PKG_VERSION"))?;
    m.add("MAX_STEPS", diffbsdf::spec::MAX_STEPS)?;
    Ok(())
}
