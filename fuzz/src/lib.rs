//! (ours) Fuzz targets: each function takes arbitrary bytes and must return without a panic,
//! a hang or an unbounded allocation. The same file is compiled into the workspace's corpus
//! replay test (`xtask/tests/fuzz_corpus.rs`), so every corpus input runs in `cargo test`.
#[path = "targets.rs"]
pub mod targets;
