//! Batch calls on several threads: the batch is cut into contiguous index ranges, one per
//! thread, each run by the same per-element body as the one-thread call, so the results do
//! not depend on the thread count.
//!
//! Each range runs through [`each`], which picks at run time a copy of the kernel compiled
//! for AVX2 where the CPU has it: the library itself assumes only baseline x86-64. The two
//! copies compute the same bits: the kernel's arithmetic is IEEE operations in a fixed
//! order, never contracted into FMA, so vector width changes only speed.

use crate::status::diffbsdf_status as S;
use core::ops::Range;
use core::sync::atomic::{AtomicBool, Ordering};

/// The most threads one call starts, whatever it asks for.
const MAX_THREADS: usize = 256;

/// The fewest elements worth a thread of their own.
const MIN_PER_THREAD: usize = 256;

/// Set by [`crate::force_baseline`]: [`each`] then always runs the baseline copy.
static BASELINE_ONLY: AtomicBool = AtomicBool::new(false);

/// See [`crate::force_baseline`].
pub(crate) fn set_baseline_only(on: bool) {
    BASELINE_ONLY.store(on, Ordering::Relaxed);
}

/// The rows of one batch call: `row(i)` computes and writes row `i`. Rows are independent,
/// so any split of the batch into ranges gives the same outputs.
pub(crate) trait Rows: Sync {
    /// Computes and writes row `i` (`i < count` of the call).
    fn row(&self, i: usize) -> Result<(), S>;
}

/// The threads a call runs on: `requested` (0: every core available to the process), at
/// most [`MAX_THREADS`] and at most one per [`MIN_PER_THREAD`] elements, at least 1.
pub(crate) fn threads_for(requested: u32, count: usize) -> usize {
    let want = match requested {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n as usize,
    };
    want.min(MAX_THREADS)
        .min(count.div_ceil(MIN_PER_THREAD))
        .max(1)
}

/// Runs `rows.row(i)` for every `i` in `range`, stopping at the first error: in the AVX2
/// copy of this loop (the kernel inlined into it) where the CPU has AVX2, else in the
/// baseline one.
pub(crate) fn each<R: Rows>(range: Range<usize>, rows: &R) -> Result<(), S> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && !BASELINE_ONLY.load(Ordering::Relaxed) {
        // SAFETY: the CPU has AVX2 (checked just above).
        return unsafe { each_avx2(range, rows) };
    }
    each_baseline(range, rows)
}

/// The loop of [`each`]; the kernel's entry points are `#[inline(always)]` down to the
/// layers, so they are compiled into whichever copy calls them.
#[inline(always)]
fn each_baseline<R: Rows>(range: Range<usize>, rows: &R) -> Result<(), S> {
    // A plain loop, not a closure: a closure would be a function of its own, compiled
    // for baseline x86-64 whichever copy calls it.
    for i in range {
        rows.row(i)?;
    }
    Ok(())
}

/// [`each_baseline`] compiled with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn each_avx2<R: Rows>(range: Range<usize>, rows: &R) -> Result<(), S> {
    each_baseline(range, rows)
}

/// Runs every row of `0..count` over `threads` contiguous ranges; the calling thread runs
/// the first. A range whose thread cannot be started runs on the calling thread. With one
/// thread nothing is started and nothing allocated.
pub(crate) fn run<R: Rows>(count: usize, threads: usize, rows: &R) -> Result<(), S> {
    if threads <= 1 {
        return each(0..count, rows);
    }
    let chunk = count.div_ceil(threads).max(1);
    let ranges = (0..count)
        .step_by(chunk)
        .map(|start| start..(start + chunk).min(count));
    std::thread::scope(|scope| {
        let mut result = Ok(());
        let mut workers = Vec::new();
        let mut own = None;
        for range in ranges {
            if own.is_none() {
                own = Some(range);
                continue;
            }
            let spawned = std::thread::Builder::new().spawn_scoped(scope, {
                let range = range.clone();
                move || each(range, rows)
            });
            match spawned {
                Ok(handle) => workers.push(handle),
                Err(_) => result = result.and(each(range, rows)),
            }
        }
        if let Some(range) = own {
            result = result.and(each(range, rows));
        }
        for handle in workers {
            result = result.and(handle.join().unwrap_or(Err(S::DIFFBSDF_ERR_PANIC)));
        }
        result
    })
}
