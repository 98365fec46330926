//! Shared by the oracle integration tests.
#![allow(dead_code)]

/// `f()` run on a fresh rayon pool of `threads` threads (determinism tests compare pools).
pub fn with_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}
