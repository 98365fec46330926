//! Cleaning a broken input mesh before its winding number is taken (not in the paper: the
//! input side of section 6.6.4 for meshes that are not closed manifolds).
//!
//! Two stated rules, each a no-op on a closed, consistently oriented mesh without duplicate
//! faces (so such inputs keep their oracle, and their output, unchanged):
//! 1. **Duplicate faces** (the same three welded vertices, in either order) are kept once,
//!    the first in input order. A duplicate would add a second jump of the winding number
//!    across its triangle (and a face with its reverse would cancel).
//! 2. **Orientation**: the faces are split into patches connected through edges with exactly
//!    two faces; in each patch the faces are oriented consistently by a breadth-first walk
//!    from its first face, and the patch keeps the orientation that the larger part of its
//!    area already had (the minority is flipped). A flipped face would reverse the winding
//!    number's jump across it and make the solid {w > 1/2} pinch along its rim. A
//!    non-orientable patch (a Möbius band) keeps the walk's choice at its conflicting edges.
//!
//! Invariant: the output faces are a subset of the input faces (as vertex sets), in input
//! order, some reversed.

use glam::DVec3;

/// What [`clean`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Cleaned {
    /// Faces dropped as duplicates of an earlier face.
    pub duplicate_faces: usize,
    /// Faces reversed to agree with their patch.
    pub flipped_faces: usize,
}

/// Apply the rules of the module documentation to `faces` (welded vertex indices and input
/// index), in place.
pub(super) fn clean(faces: &mut Vec<([u32; 3], u32)>, vertices: &[DVec3]) -> Cleaned {
    let duplicate_faces = drop_duplicates(faces);
    let flipped_faces = orient(faces, vertices);
    Cleaned {
        duplicate_faces,
        flipped_faces,
    }
}

/// Rule 1: keep the first face of each vertex set.
fn drop_duplicates(faces: &mut Vec<([u32; 3], u32)>) -> usize {
    let mut keys: Vec<([u32; 3], usize)> = faces
        .iter()
        .enumerate()
        .map(|(i, (t, _))| {
            let mut k = *t;
            k.sort_unstable();
            (k, i)
        })
        .collect();
    keys.sort_unstable();
    let mut dup = vec![false; faces.len()];
    for w in keys.windows(2) {
        if w[0].0 == w[1].0 {
            dup[w[1].1] = true; // sorted by (key, index): the later index is the duplicate
        }
    }
    let n = dup.iter().filter(|&&d| d).count();
    if n > 0 {
        let mut i = 0;
        faces.retain(|_| {
            i += 1;
            !dup[i - 1]
        });
    }
    n
}

/// Rule 2: consistent orientation per patch, majority of area kept. Returns the faces
/// reversed.
fn orient(faces: &mut [([u32; 3], u32)], vertices: &[DVec3]) -> usize {
    let nf = faces.len();
    // (min, max, min→max along the face, face)
    let mut edges: Vec<(u32, u32, bool, u32)> = Vec::with_capacity(3 * nf);
    for (fi, (t, _)) in faces.iter().enumerate() {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            edges.push((u.min(v), u.max(v), u < v, fi as u32));
        }
    }
    edges.sort_unstable();
    // Neighbours through manifold edges: (other face, same direction?).
    let mut adj: Vec<Vec<(u32, bool)>> = vec![Vec::new(); nf];
    let mut any_same = false;
    for run in edges.chunk_by(|x, y| x.0 == y.0 && x.1 == y.1) {
        if let [a, b] = run {
            let same = a.2 == b.2;
            any_same |= same;
            adj[a.3 as usize].push((b.3, same));
            adj[b.3 as usize].push((a.3, same));
        }
    }
    if !any_same {
        return 0; // already consistent along every manifold edge
    }
    let area = |t: [u32; 3]| {
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        (b - a).cross(c - a).length()
    };
    let mut flip: Vec<Option<bool>> = vec![None; nf];
    let mut queue = std::collections::VecDeque::new();
    let mut patch = Vec::new();
    for start in 0..nf {
        if flip[start].is_some() {
            continue;
        }
        flip[start] = Some(false);
        queue.push_back(start);
        patch.clear();
        while let Some(f) = queue.pop_front() {
            patch.push(f);
            let ff = flip[f] == Some(true);
            for &(g, same) in &adj[f] {
                if flip[g as usize].is_none() {
                    // Same direction along the shared edge: g must be reversed relative to f.
                    flip[g as usize] = Some(ff ^ same);
                    queue.push_back(g as usize);
                }
            }
        }
        let (mut kept, mut flipped) = (0.0, 0.0);
        for &f in &patch {
            if flip[f] == Some(true) {
                flipped += area(faces[f].0);
            } else {
                kept += area(faces[f].0);
            }
        }
        if flipped > kept {
            for &f in &patch {
                flip[f] = flip[f].map(|x| !x);
            }
        }
    }
    let mut n = 0;
    for (f, fl) in faces.iter_mut().zip(&flip) {
        if *fl == Some(true) {
            f.0.swap(1, 2);
            n += 1;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tet() -> (Vec<DVec3>, Vec<([u32; 3], u32)>) {
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let f = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
            .iter()
            .enumerate()
            .map(|(i, t)| (*t, i as u32))
            .collect();
        (v, f)
    }

    #[test]
    fn clean_mesh_is_unchanged() {
        let (v, mut f) = tet();
        let before = f.clone();
        assert_eq!(clean(&mut f, &v), Cleaned::default());
        assert_eq!(f, before);
    }

    #[test]
    fn flipped_face_is_restored_and_duplicates_dropped() {
        let (v, mut f) = tet();
        let before = f.clone();
        f[1].0.swap(1, 2); // flip one face
        f.push(([3, 1, 0], 4)); // a duplicate (reversed) of face 1
        let c = clean(&mut f, &v);
        assert_eq!((c.duplicate_faces, c.flipped_faces), (1, 1));
        assert_eq!(f, before);
    }
}
