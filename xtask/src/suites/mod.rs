//! The suites (ours): the regression suite, the timing tables and the paper's Table 1, each
//! over many surfaces, and the whole test suite in one command.

pub mod bench;
mod hard_volumes;
pub mod paper_table;
pub mod regress;
pub mod regress_images;
pub mod scans;
pub mod test_all;
