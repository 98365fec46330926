//! Seed tetrahedra (ours) for small components: four points of a component whose
//! circumcentre lies in the region it encloses, so its facets are restricted at once.

use crate::Surface;
use crate::image::ImageSurface;
use glam::DVec3;

/// The first crossing of S on the ray from voxel position `m` along `u` (unit, voxel space),
/// within `len` voxels: quarter-voxel steps, then bisection down to adjacent floats (so the
/// point is on S to rounding, like the grid-edge crossings). In world space.
pub(super) fn first_crossing(
    s: &ImageSurface,
    aff: glam::DAffine3,
    m: DVec3,
    u: DVec3,
    len: f64,
) -> Option<DVec3> {
    let steps = (len * 4.0).ceil().max(1.0) as usize;
    let mut a = aff.transform_point3(m);
    let mut fa = s.value(a);
    for i in 1..=steps {
        let b = aff.transform_point3(m + u * (len * i as f64 / steps as f64));
        let fb = s.value(b);
        if (fa < 0.0) != (fb < 0.0) {
            let c =
                crate::roots::bisect(|p| s.value(p), crate::roots::Ends::new(a, fa, b, fb), 0.0);
            return c.is_finite().then_some(c);
        }
        (a, fa) = (b, fb);
    }
    None
}

/// Of the 4-point subsets of `pts` (points of one small component) that make a tetrahedron
/// of radius-edge ratio at most 4, the one whose circumcentre lies deepest in the enclosed
/// region (`sign * value > 0`: `sign = -1` for an inside blob, `1` for a cavity) and within
/// the points' bounding box: with these four points in the initial sample, that circumcentre
/// is a Voronoi vertex inside the component, so the four facets of the tetrahedron are
/// restricted at once. `None` if no subset qualifies.
pub(super) fn seed_tet(s: &ImageSurface, pts: &[DVec3], sign: f64) -> Option<[DVec3; 4]> {
    let (lo, hi) = pts
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    let n = pts.len();
    let mut best: Option<(f64, [usize; 4])> = None;
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                for l in k + 1..n {
                    let (a, b, c) = (pts[j] - pts[i], pts[k] - pts[i], pts[l] - pts[i]);
                    let det = a.dot(b.cross(c));
                    let scale = a.length() * b.length() * c.length();
                    if !(det.abs() > 1e-3 * scale) {
                        continue;
                    }
                    let cc = pts[i]
                        + (b.cross(c) * a.length_squared()
                            + c.cross(a) * b.length_squared()
                            + a.cross(b) * c.length_squared())
                            / (2.0 * det);
                    if !(cc.cmpge(lo).all() && cc.cmple(hi).all()) {
                        continue;
                    }
                    let r2 = (cc - pts[i]).length_squared();
                    let e2 = [a, b, c, b - a, c - a, c - b]
                        .iter()
                        .map(|e| e.length_squared())
                        .fold(f64::INFINITY, f64::min);
                    if !(16.0 * e2 >= r2) {
                        continue;
                    }
                    let score = sign * s.value(cc);
                    if score > 0.0 && best.is_none_or(|b| score > b.0) {
                        best = Some((score, [i, j, k, l]));
                    }
                }
            }
        }
    }
    best.map(|(_, ix)| ix.map(|i| pts[i]))
}
