//! A deterministic random generator (ours) for seeds, sampling and tests: the workspace's
//! one SplitMix64, defined in `geom` and re-exported here for the backends.

pub use geom::SplitMix64;
