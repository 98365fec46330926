//! Component accounting against the voxel scan (ours; P1 for images, section 6.6.2): which
//! surface components of an image's level set the mesh has, which it split, which it lacks.
//!
//! The voxel scan ([`oracle::image::Topology`]) finds the components of the trilinear level
//! set exactly (union-find on the grid's sign runs). Each connected piece of the mesh is
//! assigned the scan component that most of its vertices lie on
//! ([`ImageSurface::component_of`]; ties to the lowest index), so:
//! - a component with one piece is *meshed*; with mesh vertices on it but no piece of its own
//!   (a piece assigned to a neighbour it nearly touches), *joined*; with two or more pieces,
//!   *split* (a neck cut by the topological repair, or a neck thinner than the size bound);
//! - a component with no vertex on it is *dropped* when it was removed on request (`--min-component`:
//!   a vertex of each removed piece is passed in [`account`]'s `dropped`) and *missed*
//!   otherwise; every missed component is listed with a point on it and its size;
//! - a component of zero volume (an outside region whose voxels all have the iso value:
//!   a puncture of the inside, [`oracle::image::Topology::component_vanishing`]) with no
//!   piece is *vanishing*: it is not a surface, nothing is expected of the mesh there;
//! - a piece whose vertices lie on no component (none of its cells' corners straddle the
//!   iso level) is *unassigned*.
//!
//! The assignment is exact where a vertex's cell has one inside and one outside region (the
//! scan's regions), and takes the nearest such pair of corners otherwise.

use meshio::TriMesh;
use oracle::image::ImageSurface;
use serde::Serialize;

use crate::{Status, pass_fail};

/// What happened to one scan component.
#[derive(Clone, Copy, Debug, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Fate {
    /// One mesh piece.
    Meshed,
    /// Two or more mesh pieces.
    Split,
    /// Mesh vertices on it but no piece of its own: part of a neighbour's piece.
    Joined,
    /// Removed by a stated rule of the mesher (`--min-component`, a sliver piece), passed in
    /// `Options::dropped_points`.
    Dropped,
    /// No mesh piece and not removed on request.
    Missed,
    /// Zero volume (voxels equal to the iso value, enclosed by the inside): not a surface.
    Vanishing,
}

/// Extra pieces of a split component listed (with a vertex each).
pub const LISTED_PIECES: usize = 4;

/// One scan component and its mesh pieces.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ScanComponent {
    /// Index into the scan's components ([`oracle::image::Topology::component_seeds`]).
    pub index: usize,
    /// A point of S on it (world space).
    pub seed: [f64; 3],
    /// Voxel edges crossed by it (about its area in voxel faces).
    pub crossing_edges: usize,
    /// Mesh pieces assigned to it.
    pub pieces: usize,
    /// A vertex of each of its pieces but the largest (at most [`LISTED_PIECES`], largest
    /// first; split components only): where the extra pieces are.
    pub other_pieces_at: Vec<[f64; 3]>,
    /// What happened to it.
    pub fate: Fate,
}

/// The accounting: counts, and the components that are not meshed as one piece.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ScanComponents {
    /// Components found by the voxel scan.
    pub scan: usize,
    /// Connected pieces of the mesh.
    pub mesh_pieces: usize,
    /// Scan components with exactly one piece.
    pub meshed: usize,
    /// Scan components with two or more pieces.
    pub split: usize,
    /// Scan components with vertices on them but no piece of their own.
    pub joined: usize,
    /// Scan components removed by a stated rule of the mesher: on request
    /// (`--min-component`) or as slivers (see `dropped_slivers`).
    pub dropped: usize,
    /// Of `dropped`, those whose pieces the repair removed as slivers (pieces with no
    /// interior vertex: components the size does not resolve), not on request.
    pub dropped_slivers: usize,
    /// Scan components with no piece, not removed on request.
    pub missed: usize,
    /// Scan components of zero volume (not surfaces), without a piece.
    pub vanishing: usize,
    /// Mesh pieces on no scan component.
    pub unassigned_pieces: usize,
    /// Every missed, joined, dropped, split and vanishing component (in that order; the
    /// largest first within each).
    pub components: Vec<ScanComponent>,
    /// The sum of the genera of the level set's components, from the voxel grid
    /// ([`ImageSurface::scan_genus`]; `None` with zero-volume components).
    pub scan_genus: Option<usize>,
    /// The sum of the genera of the mesh's pieces (`None` unless every piece is a closed
    /// manifold), from `verify`'s topology checks ([`ScanComponents::with_mesh_genus`];
    /// `None` from [`account`] alone).
    pub mesh_genus: Option<usize>,
}

impl ScanComponents {
    /// The accounting with the mesh's total genus from its topology (`None` unless every
    /// component is a closed manifold).
    pub fn with_mesh_genus(mut self, topology: &crate::Topology) -> Self {
        self.mesh_genus = topology
            .genera()
            .into_iter()
            .map(|g| g.and_then(|g| usize::try_from(g).ok()))
            .sum();
        self
    }

    /// Whether scan component `i` has a mesh piece.
    pub fn has_piece(&self, i: usize) -> bool {
        !self.components.iter().any(|c| {
            c.index == i && matches!(c.fate, Fate::Missed | Fate::Dropped | Fate::Vanishing)
        })
    }

    /// Whether scan component `i` needs no piece: removed on request, or of zero volume.
    pub fn excused(&self, i: usize) -> bool {
        self.components
            .iter()
            .any(|c| c.index == i && matches!(c.fate, Fate::Dropped | Fate::Vanishing))
    }

    /// One line: `450 found by the voxel scan: 440 meshed, 3 split, 2 dropped, 5 missed`.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "{} found by the voxel scan: {} meshed",
            self.scan, self.meshed
        );
        for (n, what) in [
            (self.split, "split into pieces"),
            (self.joined, "joined to a neighbour's piece"),
            (
                self.dropped - self.dropped_slivers,
                "dropped (--min-component)",
            ),
            (
                self.dropped_slivers,
                "dropped as slivers (pieces with no interior vertex: the size does not resolve \
                 them; a smaller --size keeps them)",
            ),
            (self.missed, "missed"),
            (
                self.vanishing,
                "of zero volume (voxels equal to the iso value: not surfaces)",
            ),
            (self.unassigned_pieces, "mesh pieces on no component"),
        ] {
            if n > 0 {
                s += &format!(", {n} {what}");
            }
        }
        s
    }
}

/// The accounting of `mesh` against `image`'s voxel scan; `dropped`: a point of each mesh
/// piece removed on request, `slivers`: of each removed by the repair as a sliver (their
/// components count as dropped, not missed, when no vertex of the mesh is on them; the
/// slivers' also in `dropped_slivers`).
pub fn account(
    mesh: &TriMesh,
    image: &ImageSurface,
    dropped: &[glam::DVec3],
    slivers: &[glam::DVec3],
) -> ScanComponents {
    let topo = image.topology();
    let n = topo.component_seeds.len();
    let pieces = crate::topology::vertex_components(mesh);
    let mut per = vec![0usize; n];
    // Per component, its pieces as (vertex count, a vertex).
    let mut where_: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n];
    let mut touched = vec![false; n];
    let mut unassigned = 0;
    for piece in &pieces {
        let mut votes: Vec<(usize, usize)> = Vec::new();
        for &v in piece {
            if let Some(c) = image.component_of(mesh.vertices[v]).filter(|&c| c < n) {
                touched[c] = true;
                match votes.iter_mut().find(|x| x.0 == c) {
                    Some(x) => x.1 += 1,
                    None => votes.push((c, 1)),
                }
            }
        }
        // Most votes, lowest index on ties.
        match votes
            .iter()
            .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0)))
        {
            Some(&(c, _)) => {
                per[c] += 1;
                where_[c].push((piece.len(), piece[0]));
            }
            _ => unassigned += 1,
        }
    }
    // 1: on request; 2: a sliver only (a request wins where both are).
    let mut was_dropped = vec![0u8; n];
    for (points, why) in [(slivers, 2), (dropped, 1)] {
        for &p in points {
            if let Some(c) = image.component_of(p).filter(|&c| c < n) {
                was_dropped[c] = why;
            }
        }
    }
    let mut components: Vec<ScanComponent> = (0..n)
        .filter_map(|i| {
            let vanishing = topo.component_vanishing.get(i).copied().unwrap_or(false);
            let fate = match per[i] {
                0 if vanishing => Fate::Vanishing,
                0 if touched[i] => Fate::Joined,
                0 if was_dropped[i] > 0 => Fate::Dropped,
                0 => Fate::Missed,
                1 => return None,
                _ => Fate::Split,
            };
            Some(ScanComponent {
                index: i,
                seed: topo.component_seeds[i].to_array(),
                crossing_edges: topo.component_edges.get(i).copied().unwrap_or(0),
                pieces: per[i],
                other_pieces_at: {
                    let mut w = where_[i].clone();
                    w.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
                    w.iter()
                        .skip(1)
                        .take(LISTED_PIECES)
                        .map(|&(_, v)| mesh.vertices[v].to_array())
                        .collect()
                },
                fate,
            })
        })
        .collect();
    let rank = |f: Fate| match f {
        Fate::Missed => 0,
        Fate::Joined => 1,
        Fate::Dropped => 2,
        Fate::Split => 3,
        Fate::Vanishing => 4,
        Fate::Meshed => 5,
    };
    components.sort_by(|a, b| {
        (rank(a.fate), std::cmp::Reverse(a.crossing_edges), a.index).cmp(&(
            rank(b.fate),
            std::cmp::Reverse(b.crossing_edges),
            b.index,
        ))
    });
    let count = |f: Fate| components.iter().filter(|c| c.fate == f).count();
    ScanComponents {
        scan: n,
        mesh_pieces: pieces.len(),
        meshed: (0..n).filter(|&i| per[i] == 1).count(),
        split: count(Fate::Split),
        joined: count(Fate::Joined),
        dropped: count(Fate::Dropped),
        dropped_slivers: components
            .iter()
            .filter(|c| c.fate == Fate::Dropped && was_dropped[c.index] == 2)
            .count(),
        missed: count(Fate::Missed),
        vanishing: count(Fate::Vanishing),
        unassigned_pieces: unassigned,
        components,
        scan_genus: image.scan_genus(),
        mesh_genus: None,
    }
}

/// Images: the scan's components against the mesh's pieces, one to one (the part of the
/// paper's homeomorphism, theorem 4.4 and after, that the voxel scan can check: the trilinear
/// level set's components are known exactly). A component in two pieces (*split*), one with
/// no piece of its own (*joined* to a neighbour's) or a piece on no component is a wrong
/// topology whatever the sampling: FAIL, with where. Components dropped on request or of
/// zero volume are excused; a missed one fails `components-sampled`.
pub(crate) fn scan_topology_check(r: &mut crate::Report, acc: &ScanComponents) {
    let wrong: Vec<String> = acc
        .components
        .iter()
        .filter(|c| matches!(c.fate, Fate::Split | Fate::Joined))
        .take(3)
        .map(|c| {
            let at = |p: &[f64; 3]| format!("({:.4}, {:.4}, {:.4})", p[0], p[1], p[2]);
            let what = match c.fate {
                Fate::Split => format!(
                    "split into {} pieces, the smaller at {}",
                    c.pieces,
                    c.other_pieces_at
                        .iter()
                        .map(at)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
                _ => "joined to a neighbour's piece".to_string(),
            };
            format!(
                "the component at {} ({} voxel edges crossed) {what}",
                at(&c.seed),
                c.crossing_edges
            )
        })
        .collect();
    let bad = acc.split + acc.joined + acc.unassigned_pieces;
    let detail = if bad == 0 {
        format!(
            "{} mesh pieces for the voxel scan's {} components: one piece each (the scan's \
             components of the trilinear level set{})",
            acc.mesh_pieces,
            acc.scan,
            if acc.dropped + acc.vanishing + acc.missed > 0 {
                ", but those dropped, of zero volume or missed"
            } else {
                ""
            }
        )
    } else {
        format!(
            "{} mesh pieces for the voxel scan's {} components: {} split, {} joined to a \
             neighbour's piece, {} pieces on no component: not the topology of S{}{}",
            acc.mesh_pieces,
            acc.scan,
            acc.split,
            acc.joined,
            acc.unassigned_pieces,
            if wrong.is_empty() { "" } else { "; " },
            wrong.join("; ")
        )
    };
    r.push("scan-topology", pass_fail(bad == 0), detail);
    let (status, detail) = scan_genus(acc);
    r.push("scan-genus", status, detail);
}

/// How the mesh's total genus stands against a scan's (the decision shared by `scan-genus`
/// and `grid-genus`; each words it in its own terms).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum GenusComparison {
    /// The scan has zero-volume components, whose genera it does not tell apart.
    ScanUnknown,
    /// The mesh is not a closed manifold.
    MeshUnknown,
    /// Equal totals.
    Equal(usize),
    /// Fewer handles in the mesh, but dropped or missed components may hold them.
    FewerExcused {
        mesh: usize,
        scan: usize,
        gone: usize,
    },
    /// Fewer handles in the mesh.
    Fewer { mesh: usize, scan: usize },
    /// More handles in the mesh.
    More { mesh: usize, scan: usize },
}

impl GenusComparison {
    /// The comparison of `acc`'s two totals.
    pub(crate) fn of(acc: &ScanComponents) -> GenusComparison {
        let (scan, mesh) = match (acc.scan_genus, acc.mesh_genus) {
            (None, _) => return GenusComparison::ScanUnknown,
            (_, None) => return GenusComparison::MeshUnknown,
            (Some(s), Some(m)) => (s, m),
        };
        let gone = acc.dropped + acc.missed;
        if mesh == scan {
            GenusComparison::Equal(mesh)
        } else if mesh < scan && gone > 0 {
            GenusComparison::FewerExcused { mesh, scan, gone }
        } else if mesh < scan {
            GenusComparison::Fewer { mesh, scan }
        } else {
            GenusComparison::More { mesh, scan }
        }
    }
}

/// The line of a mesh that is not a closed manifold (no genus to compare).
pub(crate) const NOT_A_MANIFOLD: &str = "not compared: the mesh is not a closed manifold";

/// `scan-genus`: the mesh's total genus against the level set's, which the grid's Euler
/// characteristic gives exactly (theorem 4.4's homeomorphism keeps it). A mesh with more
/// handles than S is wrong whatever was dropped; with fewer, it is wrong unless components
/// were dropped or missed (their genera are not known apart: INFO).
fn scan_genus(acc: &ScanComponents) -> (Status, String) {
    match GenusComparison::of(acc) {
        GenusComparison::ScanUnknown => (
            Status::Info,
            "not compared: the scan found components of zero volume, whose genera it does \
             not tell apart"
                .into(),
        ),
        GenusComparison::MeshUnknown => (Status::Info, NOT_A_MANIFOLD.into()),
        GenusComparison::Equal(mesh) => (
            Status::Pass,
            format!("total genus {mesh}, the level set's (from the grid's Euler characteristic)"),
        ),
        GenusComparison::FewerExcused { mesh, scan, gone } => (
            Status::Info,
            format!(
                "total genus {mesh} against the level set's {scan}: not compared, {gone} \
                 components dropped or missed may hold the difference"
            ),
        ),
        GenusComparison::Fewer { mesh, scan } => (
            Status::Fail,
            format!(
                "total genus {mesh} where the level set's is {scan} (from the grid's Euler \
                 characteristic): {} handles of S are not resolved at this size (not the \
                 topology of S; a smaller --size resolves more)",
                scan - mesh
            ),
        ),
        GenusComparison::More { mesh, scan } => (
            Status::Fail,
            format!(
                "total genus {mesh} where the level set's is {scan} (from the grid's Euler \
                 characteristic): {} handles that S does not have (not the topology of S)",
                mesh - scan
            ),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn acc(scan: Option<usize>, mesh: Option<usize>, dropped: usize) -> ScanComponents {
        ScanComponents {
            scan: 3,
            mesh_pieces: 3 - dropped,
            meshed: 3 - dropped,
            split: 0,
            joined: 0,
            dropped,
            dropped_slivers: 0,
            missed: 0,
            vanishing: 0,
            unassigned_pieces: 0,
            components: Vec::new(),
            scan_genus: scan,
            mesh_genus: mesh,
        }
    }

    /// Equal: PASS. Fewer handles: FAIL, unless a dropped component may hold them (INFO).
    /// More handles: FAIL whatever was dropped. Unknown on either side: INFO, saying why.
    #[test]
    fn the_genus_verdict_follows_what_can_be_compared() {
        let v = |a: ScanComponents| scan_genus(&a);
        assert_eq!(v(acc(Some(4), Some(4), 0)).0, Status::Pass);
        let (st, d) = v(acc(Some(4), Some(3), 0));
        assert!(
            st == Status::Fail && d.contains("1 handles of S are not resolved"),
            "{d}"
        );
        assert_eq!(v(acc(Some(4), Some(3), 1)).0, Status::Info);
        let (st, d) = v(acc(Some(4), Some(6), 1));
        assert!(
            st == Status::Fail && d.contains("2 handles that S does not have"),
            "{d}"
        );
        let (st, d) = v(acc(None, Some(6), 0));
        assert!(st == Status::Info && d.contains("zero volume"), "{d}");
        let (st, d) = v(acc(Some(1), None, 0));
        assert!(
            st == Status::Info && d.contains("not a closed manifold"),
            "{d}"
        );
    }
}
