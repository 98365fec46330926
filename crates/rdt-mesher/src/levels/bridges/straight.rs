//! Straight tubes of the bridges (ours, images; issue 14): the kinds of intermediate rings,
//! how many rings a straight tube between two triangles gets, and the straight variants
//! tried for a pair (see `super` for where straight tubes are tried).

use glam::DVec3;

/// The intermediate rings of a tube: `n` rings of points of S, or `n` straight ones.
#[derive(Clone, Copy, Debug)]
pub(super) enum Rings {
    OnS(usize),
    Straight(usize),
}

/// The straight tubes tried for the pair of triangles `ta`, `tb`: [`straight_rings`] rings,
/// one fewer (at least 1) and one more, each with the loops as they are and superimposed.
pub(super) fn straight_variants(
    mesh: &meshio::TriMesh,
    ta: usize,
    tb: usize,
) -> impl Iterator<Item = (usize, usize, Rings, bool)> {
    let n = straight_rings(mesh, ta, tb);
    (n.saturating_sub(1).max(1)..=n + 1)
        .flat_map(move |r| [false, true].map(move |s| (ta, tb, Rings::Straight(r), s)))
}

/// Most intermediate rings of a straight tube (see [`straight_rings`]).
pub(super) const MAX_STRAIGHT: usize = 32;

/// The rings of a straight tube between triangles `ta` and `tb` (tried after those on S:
/// rings from one triangle's shape to the other's, off S, across a neck thinner than the
/// voxel where S has no wall to put them on) whose stages are about 0.8 times as long as
/// the triangles' mean edge: the two triangles of a stage then have their smallest angles
/// near 40 degrees. At least 1, at most [`MAX_STRAIGHT`].
pub(super) fn straight_rings(mesh: &meshio::TriMesh, ta: usize, tb: usize) -> usize {
    let t = |k: usize| mesh.triangles[k].map(|v| mesh.vertices[v as usize]);
    let (a, b) = (t(ta), t(tb));
    let edges = |x: [DVec3; 3]| x[0].distance(x[1]) + x[1].distance(x[2]) + x[2].distance(x[0]);
    let e = (edges(a) + edges(b)) / 6.0;
    let len = ((a[0] + a[1] + a[2]) - (b[0] + b[1] + b[2])).length() / 3.0;
    let n = (len / (0.8 * e)).round() - 1.0;
    if n.is_finite() {
        (n.max(1.0) as usize).min(MAX_STRAIGHT)
    } else {
        1
    }
}
