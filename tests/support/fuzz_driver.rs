//! The loop every fuzz test shares: the input count and seed from the environment, inputs
//! spread over threads, each checked under `catch_unwind`; a panicking input is saved under
//! the target's temporary folder and reported with the mutations that made it. Included by
//! `tests/fuzz_blob.rs` and `materials/tests/fuzz_rgl.rs`.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::sync::Mutex;

/// `DIFFBSDF_FUZZ_INPUTS` (or `default`) inputs and `DIFFBSDF_FUZZ_SEED` (or `default`).
pub fn inputs_and_seed(default_inputs: usize, default_seed: u64) -> (usize, u64) {
    let var = |name: &str| std::env::var(name).ok();
    (
        var("DIFFBSDF_FUZZ_INPUTS")
            .and_then(|s| s.parse().ok())
            .unwrap_or(default_inputs),
        var("DIFFBSDF_FUZZ_SEED")
            .and_then(|s| s.parse().ok())
            .unwrap_or(default_seed),
    )
}

/// Runs `check` on `make(index)` for every index below `inputs`, on up to 8 threads; stops
/// after 10 failures. Returns the threads used and the seconds taken; panics with every
/// failing input (saved as `TMPDIR/NAME_seedS_inputI.EXT`) if any input panicked.
pub fn run(
    name: &str,
    extension: &str,
    tmp_dir: &str,
    seed: u64,
    inputs: usize,
    make: impl Fn(usize) -> (Vec<u8>, Vec<String>) + Sync,
    check: impl Fn(&[u8], usize) + Sync,
) -> (usize, f64) {
    let failures = Mutex::new(Vec::<String>::new());
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(8);
    let start = std::time::Instant::now();
    std::thread::scope(|scope| {
        for t in 0..threads {
            let (make, check, failures) = (&make, &check, &failures);
            scope.spawn(move || {
                for index in (t..inputs).step_by(threads) {
                    if failures.lock().unwrap().len() >= 10 {
                        return;
                    }
                    let (bytes, log) = make(index);
                    let run = catch_unwind(AssertUnwindSafe(|| check(&bytes, index)));
                    if let Err(payload) = run {
                        let msg = payload
                            .downcast_ref::<String>()
                            .cloned()
                            .or_else(|| payload.downcast_ref::<&str>().map(|s| s.to_string()))
                            .unwrap_or_default();
                        let path = PathBuf::from(tmp_dir)
                            .join(format!("{name}_seed{seed}_input{index}.{extension}"));
                        let _ = std::fs::write(&path, &bytes);
                        failures.lock().unwrap().push(format!(
                            "input {index} (seed {seed}, {} bytes, saved to {}): {msg}\n  mutations: {}",
                            bytes.len(),
                            path.display(),
                            log.join("; ")
                        ));
                    }
                }
            });
        }
    });
    let secs = start.elapsed().as_secs_f64();
    let failures = failures.into_inner().unwrap();
    assert!(
        failures.is_empty(),
        "{name}: {} failing inputs:\n{}",
        failures.len(),
        failures.join("\n")
    );
    (threads, secs)
}
