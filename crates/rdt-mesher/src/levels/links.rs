//! Oriented vertex links (ours, for the topological repair after section 6.6.1's patch): a
//! triangle set is an oriented 2-manifold with boundary exactly when the link of every vertex,
//! as directed edges (b -> c for a triangle (v, b, c)), is one simple directed path or one
//! simple directed cycle of at least three edges; it is closed when every link is a cycle.

/// What the link of one vertex is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Link {
    /// One directed cycle (at least three edges): an interior vertex.
    Cycle,
    /// One directed path: a boundary vertex; `first` starts the path (the boundary edge
    /// v -> first has no twin).
    Path { first: u32 },
    /// Anything else: a non-manifold or inconsistently oriented vertex.
    Bad,
}

/// The directed links of every vertex of `tris` (compressed rows: `start[v]..start[v + 1]`
/// indexes `edges`), for vertices `0..n`.
pub(crate) struct Links {
    start: Vec<u32>,
    edges: Vec<[u32; 2]>,
}

impl Links {
    /// The links of `tris` over `n` vertices (every index `< n`).
    pub fn new(tris: &[[u32; 3]], n: usize) -> Links {
        let (start, mut edges) = crate::topology::link_buckets(tris, n);
        for v in 0..n {
            edges[start[v] as usize..start[v + 1] as usize].sort_unstable();
        }
        Links { start, edges }
    }

    /// The link edges of `v`, sorted.
    pub fn of(&self, v: u32) -> &[[u32; 2]] {
        &self.edges[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }

    /// Whether `v` has any triangle.
    pub fn used(&self, v: u32) -> bool {
        !self.of(v).is_empty()
    }

    /// What the link of `v` is (see [`Link`]); `Bad` for an unused vertex.
    pub fn kind(&self, v: u32) -> Link {
        classify(self.of(v))
    }
}

/// The directed link edge of triangle `t` at its vertex `v` (b -> c for (v, b, c)).
pub(crate) fn link_edge(t: [u32; 3], v: u32) -> [u32; 2] {
    let i = t.iter().position(|&x| x == v).expect("v is a vertex of t");
    [t[(i + 1) % 3], t[(i + 2) % 3]]
}

/// [`Link`] of a sorted list of directed link edges.
pub(crate) fn classify(l: &[[u32; 2]]) -> Link {
    if l.is_empty() {
        return Link::Bad;
    }
    // Out-degree <= 1: the sources are distinct (the list is sorted by source).
    if l.windows(2).any(|w| w[0][0] == w[1][0]) {
        return Link::Bad;
    }
    let next =
        |x: u32| -> Option<u32> { l.binary_search_by(|e| e[0].cmp(&x)).ok().map(|i| l[i][1]) };
    // In-degree <= 1 (the targets sorted: on the stack for the usual short links).
    let mut stack = [0u32; 32];
    let mut heap = Vec::new();
    let targets: &mut [u32] = if l.len() <= stack.len() {
        &mut stack[..l.len()]
    } else {
        heap.resize(l.len(), 0);
        &mut heap
    };
    targets.iter_mut().zip(l).for_each(|(t, e)| *t = e[1]);
    targets.sort_unstable();
    if targets.windows(2).any(|w| w[0] == w[1]) {
        return Link::Bad;
    }
    // Sources that are nobody's target start paths: at most one.
    let mut starts = l
        .iter()
        .map(|e| e[0])
        .filter(|s| targets.binary_search(s).is_err());
    let (first, path) = match (starts.next(), starts.next()) {
        (None, _) => (l[0][0], false),
        (Some(s), None) => (s, true),
        _ => return Link::Bad,
    };
    // Walk from `first`: every edge must be reached (one piece).
    let mut at = first;
    let mut walked = 0usize;
    while let Some(n) = next(at) {
        walked += 1;
        at = n;
        if at == first || walked > l.len() {
            break;
        }
    }
    if walked != l.len() {
        return Link::Bad;
    }
    if path {
        Link::Path { first }
    } else if l.len() >= 3 {
        Link::Cycle
    } else {
        Link::Bad
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TET: [[u32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

    #[test]
    fn closed_tetrahedron_has_cycles_only() {
        let l = Links::new(&TET, 4);
        assert!((0..4).all(|v| l.kind(v) == Link::Cycle));
    }

    #[test]
    fn open_and_bad_links() {
        // One facet removed: its three vertices are on the boundary.
        let l = Links::new(&TET[1..], 4);
        assert_eq!(l.kind(3), Link::Cycle);
        assert!((0..3).all(|v| matches!(l.kind(v), Link::Path { .. })));
        // A facet flipped: inconsistent orientation at all of its vertices.
        let mut t = TET;
        t[0] = [0, 1, 2];
        let l = Links::new(&t, 4);
        assert_eq!(l.kind(0), Link::Bad);
        // Two tetrahedra sharing vertex 0: two cycles.
        let mut t = TET.to_vec();
        t.extend(
            TET.iter()
                .map(|f| f.map(|v| if v == 0 { 0 } else { v + 3 })),
        );
        let l = Links::new(&t, 7);
        assert_eq!(l.kind(0), Link::Bad);
        assert_eq!(l.kind(4), Link::Cycle);
        // A pillow (a facet and its reverse): 2-cycles.
        let l = Links::new(&[[0, 1, 2], [0, 2, 1]], 3);
        assert_eq!(l.kind(0), Link::Bad);
    }
}
