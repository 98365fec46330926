//! Restricted Delaunay refinement (in progress).
