//! The suites (ours): the regression suite, the timing tables and the paper's Table 1, each
//! over many surfaces.

pub mod bench;
mod hard_volumes;
pub mod paper_table;
pub mod regress;
pub mod regress_images;
