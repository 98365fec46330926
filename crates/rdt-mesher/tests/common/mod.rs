//! Helpers shared by the integration tests.

pub mod analytic;

use rdt_mesher::{Criteria, MeshOptions};

/// The default options with the uniform size criterion `size` (angle 30).
pub fn uniform(size: f64) -> MeshOptions {
    MeshOptions {
        criteria: Criteria::uniform(size),
        ..Default::default()
    }
}
