//! Errors of a meshing run (ours): what is wrong, in the library's terms.

use glam::DVec3;
use oracle::OracleError;

/// Errors of a meshing run.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// A constant size bound that is not a positive finite number.
    #[error(
        "invalid size bound sigma = {0}: Criteria::size must be a positive finite number (e.g. Sizing::Constant(0.05))"
    )]
    InvalidSize(f64),
    /// A size function with a value that is not positive and finite at a point of S.
    #[error("the size function returned {value} at ({}, {}, {}): sigma must be positive and finite on S", .at.x, .at.y, .at.z)]
    InvalidSizeField {
        /// The value returned.
        value: f64,
        /// Where.
        at: DVec3,
    },
    /// An angle bound outside [0, 35) degrees.
    #[error(
        "invalid angle bound {0} degrees: use a value in [0, 35) (30 has a termination proof; 0 disables it)"
    )]
    InvalidAngle(f64),
    /// A Lipschitz constant of a size field that is not a finite number >= 0.
    #[error(
        "invalid Lipschitz constant {0} of the size field: Sizing::Lipschitz needs a finite constant >= 0 (or use Sizing::Field)"
    )]
    InvalidLipschitz(f64),
    /// A distance bound that is not a positive finite number.
    #[error("invalid distance bound {0}: it must be positive and finite")]
    InvalidDistance(f64),
    /// Nothing would stop the refinement.
    #[error(
        "no criterion given: set Criteria::size, Criteria::min_angle_deg or Criteria::max_distance, or keep MeshOptions::manifold"
    )]
    NoCriterion,
    /// No point of S to start from.
    #[error(
        "no point of the surface was found inside the bounding sphere (center ({}, {}, {}), radius {radius}); check the bounding sphere or pass seed points",
        .center.x,
        .center.y,
        .center.z
    )]
    NoSeeds {
        /// Center of the surface's bounding sphere.
        center: DVec3,
        /// Its radius.
        radius: f64,
    },
    /// The initial sample does not span 3D.
    #[error(
        "the initial sample is degenerate (all {0} seed points are coplanar); pass more seed points"
    )]
    DegenerateSeeds(usize),
    /// The oracle failed (e.g. a NaN value).
    #[error(transparent)]
    Oracle(#[from] OracleError),
    /// The Delaunay triangulation refused a point.
    #[error("Delaunay triangulation: {0}")]
    Delaunay(#[from] delaunay3::Error),
}
