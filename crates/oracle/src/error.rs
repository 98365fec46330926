//! The query-time error of the oracles (ours).

/// Errors raised by oracles at query time.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum OracleError {
    /// The value at the point `(x, y, z)` is NaN.
    #[error("the surface function returned NaN at ({0}, {1}, {2}); fix the function or its domain")]
    NaN(f64, f64, f64),
}
