//! Surface Delaunay balls (section 2, definition 2.2): the ball B(c, r) of a restricted facet,
//! centred on S at a point of the facet's dual Voronoi edge and passing through the facet's
//! vertices. The mesher reports them, `verify` checks condition 1 of definition 2.2 on them.

use glam::DVec3;

/// A surface Delaunay ball of a restricted facet: centred on S, through the facet's vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct SurfaceBall {
    /// Index of the facet (triangle) in its mesh.
    pub facet: usize,
    /// Centre, a point of S.
    pub center: DVec3,
    /// Radius: the distance from `center` to the facet's vertices.
    pub radius: f64,
}

impl SurfaceBall {
    /// Balls given as (center, radius) in facet order: ball `i` belongs to triangle `i` (the
    /// form in which a mesher such as `rdt_mesher` reports them).
    ///
    /// ```
    /// use geom::SurfaceBall;
    /// let b = SurfaceBall::per_facet([(glam::DVec3::ZERO, 0.5)]);
    /// assert_eq!((b[0].facet, b[0].radius), (0, 0.5));
    /// ```
    pub fn per_facet(balls: impl IntoIterator<Item = (DVec3, f64)>) -> Vec<SurfaceBall> {
        balls
            .into_iter()
            .enumerate()
            .map(|(facet, (center, radius))| SurfaceBall {
                facet,
                center,
                radius,
            })
            .collect()
    }
}
