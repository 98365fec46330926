//! Initial samples: control points and their rays (section 6.4.3, `control`), or persistent
//! facets (section 6.2, with section 6.4.2's bipolar variant: `persistent`).

mod control;
pub(crate) use control::control_points;
mod persistent;

pub use persistent::{PersistentInit, persistent_facet_points, persistent_facets};
