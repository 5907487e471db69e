//! C ABI over the diffbsdf kernel. The committed header `include/diffbsdf.h` documents
//! every function; this file is its implementation.
//!
//! Contract at the boundary:
//! - no panic crosses it (`catch_unwind` around every body, reported as
//!   `DIFFBSDF_ERR_PANIC`);
//! - a null or misaligned pointer, or a length out of range, is an error code, never
//!   undefined behaviour on our side;
//! - invalid numeric input (non-unit directions, `u` outside [0, 1], NaN) is not an error:
//!   the call answers `DIFFBSDF_NO_SAMPLE` (or a PDF of 0), as the kernel does.
//!
//! Every sampling call, single or batch, runs through the same row bodies (`DirectionRows`,
//! `SampleRows`, `PdfRows`) and `parallel::each`, which uses a copy of the kernel compiled
//! for AVX2 where the CPU has it (same bits, about twice the speed of baseline x86-64).
//! Rows are read and written element by element through raw pointers, so an output buffer
//! may even alias an input buffer of the same layout; the `_parallel` forms split the batch
//! into contiguous ranges, one per thread. [`slices`] offers the same row loop to Rust
//! callers over slices (the Python package).
#![allow(non_camel_case_types)]
#![deny(unsafe_op_in_unsafe_fn)]

mod parallel;
pub mod slices;
mod status;

use diffbsdf::{AnyModel, NAME_CAPACITY};
pub use status::diffbsdf_status;

use core::ffi::c_char;
use core::mem::{align_of, size_of};
use diffbsdf::glam::{Vec2, Vec3};
use diffbsdf::{IncidentRange, Precision, Sample};
use parallel::Rows;
use status::diffbsdf_status as S;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Opaque model handle (a loaded blob of either compiled architecture).
#[derive(Debug)]
pub struct diffbsdf_model {
    inner: AnyModel,
}

/// A sampled direction and its PDF per unit solid angle; all zero when invalid.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct diffbsdf_sample_result {
    pub wo: [f32; 3],
    pub pdf: f32,
}

/// What a loaded model is.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct diffbsdf_info {
    /// 0: disk (BRDF, upper hemisphere), 1: sphere (full BSDF), 2: equatorial sphere (pole
    /// on the tangent y axis), 3: half vector on the disk (BRDF, upper hemisphere).
    pub domain: u32,
    /// 0: f32 weights, 1: f16 weights in the blob.
    pub precision: u32,
    /// Euler steps used when a call passes `steps = 0`.
    pub default_steps: u32,
    pub velocity_hidden_layers: u32,
    pub velocity_width: u32,
    pub param_count: u32,
    /// 1 when the model is isotropic (its nets see `wi` turned to `phi = 0`).
    pub isotropic: u32,
    /// The `wi` the model answers: 0 above the surface only (`wi.z >= 0`; other `wi` give
    /// no sample and PDF 0), 1 the whole sphere.
    pub incident_range: u32,
    /// The incident azimuths the nets see (docs/math.md, (83)): 0 every azimuth, 1 half
    /// the turn (a symmetry under a half turn about the normal), 2 a quarter (mirror
    /// symmetries in `x` and in `y`). Sampling and the PDF fold and unfold by themselves;
    /// this says which symmetry the model assumes of the material.
    pub incident_fold: u32,
    /// The model's name, NUL-terminated.
    pub name: [c_char; NAME_CAPACITY + 1],
}

const _: () = assert!(size_of::<diffbsdf_sample_result>() == size_of::<Sample>());

/// Crate version as `major * 10000 + minor * 100 + patch`.
const VERSION: u32 = version_number();

const fn parse(s: &str) -> u32 {
    let b = s.as_bytes();
    let mut i = 0;
    let mut v = 0u32;
    while i < b.len() {
        v = v * 10 + (b[i] - b'0') as u32;
        i += 1;
    }
    v
}

const fn version_number() -> u32 {
    parse(env!("CARGO_PKG_VERSION_MAJOR")) * 10_000
        + parse(env!("CARGO_PKG_VERSION_MINOR")) * 100
        + parse(env!("CARGO_PKG_VERSION_PATCH"))
}

const VERSION_STRING: &str = concat!(env!("CARGO_PKG_VERSION"), "\0");

/// Runs `f`, turning a panic into `DIFFBSDF_ERR_PANIC`.
fn guard(f: impl FnOnce() -> Result<S, S>) -> S {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(s)) | Ok(Err(s)) => s,
        Err(_) => S::DIFFBSDF_ERR_PANIC,
    }
}

/// Null and alignment check of a pointer to `T`.
fn check<T>(p: *const T) -> Result<(), S> {
    if p.is_null() {
        Err(S::DIFFBSDF_ERR_NULL)
    } else if !(p as usize).is_multiple_of(align_of::<T>()) {
        Err(S::DIFFBSDF_ERR_MISALIGNED)
    } else {
        Ok(())
    }
}

/// Checks that `count` elements of `per` floats fit in an allocation.
fn check_count(count: usize, per: usize) -> Result<(), S> {
    match count.checked_mul(per * size_of::<f32>()) {
        Some(bytes) if bytes <= isize::MAX as usize => Ok(()),
        _ => Err(S::DIFFBSDF_ERR_LENGTH),
    }
}

/// # Safety
/// `model` checked by [`check`]; it points to a model initialised by this library.
unsafe fn model_ref<'a>(model: *const diffbsdf_model) -> Result<&'a AnyModel, S> {
    check(model)?;
    // SAFETY: non-null and aligned (checked); the caller promises it was initialised by
    // `diffbsdf_model_init` or `diffbsdf_model_new` and not freed.
    Ok(unsafe { &(*model).inner })
}

/// # Safety
/// `p` must point to `N` readable floats (checked for null and alignment here).
unsafe fn read<const N: usize>(p: *const f32) -> Result<[f32; N], S> {
    check(p)?;
    let mut out = [0.0; N];
    for (i, o) in out.iter_mut().enumerate() {
        // SAFETY: the caller guarantees N floats at p.
        *o = unsafe { p.add(i).read() };
    }
    Ok(out)
}

/// # Safety
/// `p` must point to `N` writable floats (checked for null and alignment here).
unsafe fn write<const N: usize>(p: *mut f32, v: [f32; N]) -> Result<(), S> {
    check(p)?;
    for (i, x) in v.into_iter().enumerate() {
        // SAFETY: the caller guarantees N floats at p.
        unsafe { p.add(i).write(x) };
    }
    Ok(())
}

fn load(blob: *const u8, blob_len: usize) -> Result<AnyModel, S> {
    check(blob)?;
    if blob_len > isize::MAX as usize {
        return Err(S::DIFFBSDF_ERR_LENGTH);
    }
    // SAFETY: non-null, and the caller guarantees `blob_len` readable bytes.
    let bytes = unsafe { core::slice::from_raw_parts(blob, blob_len) };
    AnyModel::from_blob(bytes).map_err(S::from)
}

/// With `true`, every later call runs the baseline x86-64 copy of the kernel even where the
/// CPU has AVX2; `false` lets calls choose again. For tests, which check that the two
/// copies give the same bits. A Rust function, not part of the C ABI.
#[doc(hidden)]
pub fn force_baseline(on: bool) {
    parallel::set_baseline_only(on);
}

/// The library version, `major * 10000 + minor * 100 + patch`.
#[no_mangle]
pub extern "C" fn diffbsdf_version() -> u32 {
    VERSION
}

/// The library version as a NUL-terminated string.
#[no_mangle]
pub extern "C" fn diffbsdf_version_string() -> *const c_char {
    VERSION_STRING.as_ptr().cast()
}

/// A static NUL-terminated description of a status code.
#[no_mangle]
pub extern "C" fn diffbsdf_status_message(status: i32) -> *const c_char {
    let found = S::ALL.iter().find(|s| **s as i32 == status);
    let msg: &'static [u8] = match found {
        Some(s) => s.message(),
        None => b"unknown status code\0",
    };
    msg.as_ptr().cast()
}

/// Bytes a caller must provide to `diffbsdf_model_init`.
#[no_mangle]
pub extern "C" fn diffbsdf_model_size() -> usize {
    size_of::<diffbsdf_model>()
}

/// Alignment a caller must provide to `diffbsdf_model_init`.
#[no_mangle]
pub extern "C" fn diffbsdf_model_align() -> usize {
    align_of::<diffbsdf_model>()
}

/// Loads a blob into caller memory `mem` of `mem_len` bytes.
///
/// # Safety
/// `mem` must point to `mem_len` writable bytes; `blob` to `blob_len` readable bytes.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_model_init(
    mem: *mut diffbsdf_model,
    mem_len: usize,
    blob: *const u8,
    blob_len: usize,
) -> S {
    guard(|| {
        check(mem.cast_const())?;
        if mem_len < size_of::<diffbsdf_model>() {
            return Err(S::DIFFBSDF_ERR_LENGTH);
        }
        let inner = load(blob, blob_len)?;
        // SAFETY: non-null, aligned, large enough (checked); the model has no drop glue so
        // overwriting whatever was there is fine.
        unsafe { mem.write(diffbsdf_model { inner }) };
        Ok(S::DIFFBSDF_OK)
    })
}

/// Loads a blob into a new heap allocation; free it with `diffbsdf_model_free`. Returns
/// null on error, with the reason in `*status` when `status` is not null.
///
/// # Safety
/// `blob` must point to `blob_len` readable bytes; `status` is null or writable.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_model_new(
    blob: *const u8,
    blob_len: usize,
    status: *mut i32,
) -> *mut diffbsdf_model {
    let mut out = core::ptr::null_mut();
    let s = guard(|| {
        let inner = load(blob, blob_len)?;
        out = Box::into_raw(Box::new(diffbsdf_model { inner }));
        Ok(S::DIFFBSDF_OK)
    });
    if check(status.cast_const()).is_ok() {
        // SAFETY: non-null and aligned; the caller promises it is writable.
        unsafe { status.write(s as i32) };
    }
    out
}

/// Frees a model from `diffbsdf_model_new`; null is ignored.
///
/// # Safety
/// `model` is null or came from `diffbsdf_model_new` and was not freed yet.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_model_free(model: *mut diffbsdf_model) {
    if check(model.cast_const()).is_ok() {
        let _ = catch_unwind(AssertUnwindSafe(|| {
            // SAFETY: the caller promises it came from Box::into_raw in diffbsdf_model_new.
            drop(unsafe { Box::from_raw(model) });
        }));
    }
}

/// Describes a loaded model.
///
/// # Safety
/// `model` is a loaded model; `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_model_info(
    model: *const diffbsdf_model,
    out: *mut diffbsdf_info,
) -> S {
    guard(|| {
        // SAFETY: forwarded contract.
        let m = unsafe { model_ref(model) }?;
        check(out.cast_const())?;
        let def = m.def();
        let mut name = [0 as c_char; NAME_CAPACITY + 1];
        for (n, b) in name.iter_mut().zip(def.name.as_bytes()) {
            *n = *b as c_char;
        }
        let info = diffbsdf_info {
            domain: u32::from(def.domain.code()),
            precision: match def.precision {
                Precision::F32 => 0,
                Precision::F16 => 1,
            },
            default_steps: def.default_steps as u32,
            velocity_hidden_layers: def.velocity.hidden_layers as u32,
            velocity_width: def.velocity.width as u32,
            param_count: def.param_count() as u32,
            isotropic: def.isotropic as u32,
            incident_range: match def.incident {
                IncidentRange::UpperHemisphere => 0,
                IncidentRange::WholeSphere => 1,
            },
            incident_fold: u32::from(def.fold.code()),
            name,
        };
        // SAFETY: non-null and aligned (checked), writable by contract.
        unsafe { out.write(info) };
        Ok(S::DIFFBSDF_OK)
    })
}

/// A direction for `wi[3]` and `u[2]`, written to `wo[3]` (zeros when invalid).
///
/// # Safety
/// Pointers as documented in the header.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_sample_direction(
    model: *const diffbsdf_model,
    wi: *const f32,
    u: *const f32,
    steps: u32,
    wo: *mut f32,
) -> S {
    guard(|| {
        // SAFETY: forwarded contract for every pointer.
        let model = unsafe { model_ref(model) }?;
        check_batch(1, [(wi, 3), (u, 2)], (wo.cast_const(), 3))?;
        let rows = DirectionRows {
            model,
            steps,
            wi,
            u,
            wo,
        };
        parallel::each(0..1, &rows)?;
        // A valid direction is a unit vector; an invalid one is written as zeros.
        let d = unsafe { read::<3>(wo) }?;
        Ok(if d != [0.0; 3] {
            S::DIFFBSDF_OK
        } else {
            S::DIFFBSDF_NO_SAMPLE
        })
    })
}

/// A direction and its PDF for `wi[3]` and `u[2]` (all zero when invalid).
///
/// # Safety
/// Pointers as documented in the header.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_sample(
    model: *const diffbsdf_model,
    wi: *const f32,
    u: *const f32,
    steps: u32,
    out: *mut diffbsdf_sample_result,
) -> S {
    guard(|| {
        // SAFETY: forwarded contract for every pointer.
        let model = unsafe { model_ref(model) }?;
        check_batch(1, [(wi, 3), (u, 2)], (out.cast_const().cast(), 4))?;
        check(out.cast_const())?;
        let rows = SampleRows {
            model,
            steps,
            wi,
            u,
            out,
        };
        parallel::each(0..1, &rows)?;
        // SAFETY: non-null, aligned (checked), written just above.
        let pdf = unsafe { out.read() }.pdf;
        Ok(if pdf > 0.0 {
            S::DIFFBSDF_OK
        } else {
            S::DIFFBSDF_NO_SAMPLE
        })
    })
}

/// The PDF (per unit solid angle) of direction `wo[3]` for `wi[3]`, 0 when invalid.
///
/// # Safety
/// Pointers as documented in the header.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_pdf(
    model: *const diffbsdf_model,
    wi: *const f32,
    wo: *const f32,
    steps: u32,
    pdf: *mut f32,
) -> S {
    guard(|| {
        // SAFETY: forwarded contract for every pointer.
        let model = unsafe { model_ref(model) }?;
        check_batch(1, [(wi, 3), (wo, 3)], (pdf.cast_const(), 1))?;
        let rows = PdfRows {
            model,
            steps,
            wi,
            wo,
            pdf,
        };
        parallel::each(0..1, &rows)?;
        Ok(S::DIFFBSDF_OK)
    })
}

fn to_c(s: Option<Sample>) -> diffbsdf_sample_result {
    s.map(|s| diffbsdf_sample_result {
        wo: s.wo.to_array(),
        pdf: s.pdf,
    })
    .unwrap_or_default()
}

/// Checks the pointers of a batch call.
fn check_batch(
    count: usize,
    ins: [(*const f32, usize); 2],
    out: (*const f32, usize),
) -> Result<(), S> {
    for (p, per) in ins.into_iter().chain([out]) {
        check(p)?;
        check_count(count, per)?;
    }
    Ok(())
}

/// Batch form of `diffbsdf_sample_direction`: `wi` and `wo` hold `3 * count` floats, `u`
/// `2 * count`. Invalid samples are written as zeros.
///
/// # Safety
/// Pointers as documented in the header.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_sample_direction_batch(
    model: *const diffbsdf_model,
    wi: *const f32,
    u: *const f32,
    count: usize,
    steps: u32,
    wo: *mut f32,
) -> S {
    // SAFETY: forwarded contract.
    unsafe { diffbsdf_sample_direction_batch_parallel(model, wi, u, count, steps, 1, wo) }
}

/// Batch form of `diffbsdf_sample`: `out` holds `count` samples.
///
/// # Safety
/// Pointers as documented in the header.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_sample_batch(
    model: *const diffbsdf_model,
    wi: *const f32,
    u: *const f32,
    count: usize,
    steps: u32,
    out: *mut diffbsdf_sample_result,
) -> S {
    // SAFETY: forwarded contract.
    unsafe { diffbsdf_sample_batch_parallel(model, wi, u, count, steps, 1, out) }
}

/// Batch form of `diffbsdf_pdf`: `wi`, `wo` hold `3 * count` floats, `pdf` `count`.
///
/// # Safety
/// Pointers as documented in the header.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_pdf_batch(
    model: *const diffbsdf_model,
    wi: *const f32,
    wo: *const f32,
    count: usize,
    steps: u32,
    pdf: *mut f32,
) -> S {
    // SAFETY: forwarded contract.
    unsafe { diffbsdf_pdf_batch_parallel(model, wi, wo, count, steps, 1, pdf) }
}

/// [`diffbsdf_sample_direction_batch`] on `threads` threads (0: every core available).
///
/// # Safety
/// Pointers as documented in the header.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_sample_direction_batch_parallel(
    model: *const diffbsdf_model,
    wi: *const f32,
    u: *const f32,
    count: usize,
    steps: u32,
    threads: u32,
    wo: *mut f32,
) -> S {
    guard(|| {
        // SAFETY: forwarded contract.
        let model = unsafe { model_ref(model) }?;
        check_batch(count, [(wi, 3), (u, 2)], (wo.cast_const(), 3))?;
        let rows = DirectionRows {
            model,
            steps,
            wi,
            u,
            wo,
        };
        parallel::run(count, parallel::threads_for(threads, count), &rows)?;
        Ok(S::DIFFBSDF_OK)
    })
}

/// [`diffbsdf_sample_batch`] on `threads` threads (0: every core available).
///
/// # Safety
/// Pointers as documented in the header.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_sample_batch_parallel(
    model: *const diffbsdf_model,
    wi: *const f32,
    u: *const f32,
    count: usize,
    steps: u32,
    threads: u32,
    out: *mut diffbsdf_sample_result,
) -> S {
    guard(|| {
        // SAFETY: forwarded contract.
        let model = unsafe { model_ref(model) }?;
        check_batch(count, [(wi, 3), (u, 2)], (out.cast_const().cast(), 4))?;
        check(out.cast_const())?;
        let rows = SampleRows {
            model,
            steps,
            wi,
            u,
            out,
        };
        parallel::run(count, parallel::threads_for(threads, count), &rows)?;
        Ok(S::DIFFBSDF_OK)
    })
}

/// [`diffbsdf_pdf_batch`] on `threads` threads (0: every core available).
///
/// # Safety
/// Pointers as documented in the header.
#[no_mangle]
pub unsafe extern "C" fn diffbsdf_pdf_batch_parallel(
    model: *const diffbsdf_model,
    wi: *const f32,
    wo: *const f32,
    count: usize,
    steps: u32,
    threads: u32,
    pdf: *mut f32,
) -> S {
    guard(|| {
        // SAFETY: forwarded contract.
        let model = unsafe { model_ref(model) }?;
        check_batch(count, [(wi, 3), (wo, 3)], (pdf.cast_const(), 1))?;
        let rows = PdfRows {
            model,
            steps,
            wi,
            wo,
            pdf,
        };
        parallel::run(count, parallel::threads_for(threads, count), &rows)?;
        Ok(S::DIFFBSDF_OK)
    })
}

/// Row `i` of two input arrays holding `A` and `B` floats per row.
///
/// # Safety
/// Row `i` lies within both arrays.
#[inline(always)]
unsafe fn row_inputs<const A: usize, const B: usize>(
    a: *const f32,
    b: *const f32,
    i: usize,
) -> Result<([f32; A], [f32; B]), S> {
    // SAFETY: forwarded contract.
    unsafe { Ok((read::<A>(a.add(A * i))?, read::<B>(b.add(B * i))?)) }
}

/// The rows of a `sample_direction` batch: pointers checked by the caller, valid for the
/// batch's `count` rows for the whole call (the header's contract).
struct DirectionRows<'a> {
    model: &'a AnyModel,
    steps: u32,
    wi: *const f32,
    u: *const f32,
    wo: *mut f32,
}

impl Rows for DirectionRows<'_> {
    #[inline(always)]
    fn row(&self, i: usize) -> Result<(), S> {
        // SAFETY: `i < count`: within every buffer (the header's contract); each thread
        // writes only its own rows.
        let (a, b) = unsafe { row_inputs::<3, 2>(self.wi, self.u, i) }?;
        let d = self
            .model
            .sample_direction_steps(Vec3::from(a), Vec2::from(b), self.steps);
        // SAFETY: as above.
        unsafe { write(self.wo.add(3 * i), d.unwrap_or(Vec3::ZERO).to_array()) }
    }
}

/// The rows of a `sample` batch (see [`DirectionRows`]).
struct SampleRows<'a> {
    model: &'a AnyModel,
    steps: u32,
    wi: *const f32,
    u: *const f32,
    out: *mut diffbsdf_sample_result,
}

impl Rows for SampleRows<'_> {
    #[inline(always)]
    fn row(&self, i: usize) -> Result<(), S> {
        // SAFETY: `i < count`: within every buffer (the header's contract); each thread
        // writes only its own rows.
        let (a, b) = unsafe { row_inputs::<3, 2>(self.wi, self.u, i) }?;
        let s = to_c(
            self.model
                .sample_steps(Vec3::from(a), Vec2::from(b), self.steps),
        );
        // SAFETY: as above.
        unsafe { self.out.add(i).write(s) };
        Ok(())
    }
}

/// The rows of a `pdf` batch (see [`DirectionRows`]).
struct PdfRows<'a> {
    model: &'a AnyModel,
    steps: u32,
    wi: *const f32,
    wo: *const f32,
    pdf: *mut f32,
}

impl Rows for PdfRows<'_> {
    #[inline(always)]
    fn row(&self, i: usize) -> Result<(), S> {
        // SAFETY: `i < count`: within every buffer (the header's contract); each thread
        // writes only its own rows.
        let (a, b) = unsafe { row_inputs::<3, 3>(self.wi, self.wo, i) }?;
        let p = self
            .model
            .pdf_steps(Vec3::from(a), Vec3::from(b), self.steps);
        // SAFETY: as above.
        unsafe { self.pdf.add(i).write(p) };
        Ok(())
    }
}

// SAFETY: the threads of one call only read the inputs and write disjoint rows of the
// outputs, and `parallel::run` joins them all before the call returns, within which the
// caller keeps every buffer valid (the header's contract); the model is read only.
unsafe impl Sync for DirectionRows<'_> {}
// SAFETY: as for `DirectionRows`.
unsafe impl Sync for SampleRows<'_> {}
// SAFETY: as for `DirectionRows`.
unsafe impl Sync for PdfRows<'_> {}
