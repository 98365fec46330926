//! The suites (ours): the regression suite, the timing tables and the paper's Table 1, each
//! over many surfaces.

pub mod bench;
pub mod paper_table;
pub mod regress;
