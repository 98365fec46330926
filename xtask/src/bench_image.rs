//! Image group of `cargo xtask bench` (filled in by the image work).
use crate::bench::{BenchArgs, Row};
pub fn bench_image(_a: &BenchArgs, _rows: &mut Vec<Row>) -> anyhow::Result<()> {
    Ok(())
}
