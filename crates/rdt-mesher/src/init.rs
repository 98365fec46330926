//! Initial samples: persistent facets (section 6.2, with section 6.4.2's bipolar variant).

use crate::refine::{MeshError, MeshOptions};
use glam::DVec3;
use oracle::Surface;

/// The initial sample E_i of section 6.2 built around the control points E'_i.
/// (Placeholder: returns the control points; see issue 7.)
pub fn persistent_facet_points(
    _surface: &dyn Surface,
    control: &[DVec3],
    _opts: &MeshOptions,
) -> Result<Vec<DVec3>, MeshError> {
    Ok(control.to_vec())
}
