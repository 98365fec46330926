//! Validation (ours): checks every invariant of the crate docs (combinatorial, orientation,
//! local Delaunay under the perturbation), as spade's `sanity_check`.

use crate::ids::{CellId, VertexId};
use crate::predicates::{Sign, orient3d};
use crate::tds::{DEAD, FACET};
use crate::triangulation::Triangulation;

/// A violated invariant, as reported by [`Triangulation::validate`].
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
pub enum ValidationError {
    /// A neighbor is not a live cell.
    #[error("cell {cell}: neighbor {index} is {neighbor}, which is not a live cell")]
    BadNeighbor {
        /// The cell.
        cell: CellId,
        /// The local index of the neighbor.
        index: u8,
        /// The neighbor.
        neighbor: CellId,
    },
    /// A neighbor does not point back or does not share the facet.
    #[error(
        "cell {cell}: neighbor {index} ({neighbor}) does not point back or shares a wrong facet"
    )]
    Asymmetric {
        /// The cell.
        cell: CellId,
        /// The local index of the neighbor.
        index: u8,
        /// The neighbor.
        neighbor: CellId,
    },
    /// A cell's vertex tuple is malformed.
    #[error("cell {cell} {vertices:?} has a repeated, out-of-range or doubly infinite vertex")]
    BadVertices {
        /// The cell.
        cell: CellId,
        /// Its vertices.
        vertices: [VertexId; 4],
    },
    /// A finite cell is not positively oriented.
    #[error("finite cell {cell} {vertices:?} is not positively oriented")]
    BadOrientation {
        /// The cell.
        cell: CellId,
        /// Its vertices.
        vertices: [VertexId; 4],
    },
    /// The hull is not convex or an infinite cell is misoriented.
    #[error(
        "hull facet of infinite cell {cell} does not face the hull interior or is not convex (facet {index})"
    )]
    BadHull {
        /// The infinite cell.
        cell: CellId,
        /// The facet's local index.
        index: u8,
    },
    /// A vertex's cell does not contain it.
    #[error("vertex {vertex} has no incident cell (vertex_cell = {cell})")]
    VertexWithoutCell {
        /// The vertex.
        vertex: VertexId,
        /// Its recorded cell.
        cell: CellId,
    },
    /// A facet is not locally Delaunay.
    #[error("facet {index} of cell {cell} is not locally Delaunay")]
    NotDelaunay {
        /// The cell.
        cell: CellId,
        /// The facet's local index.
        index: u8,
    },
    /// The cell counters or the free list disagree with the slots.
    #[error("cell counts disagree: {0}")]
    Counts(String),
}

impl Triangulation {
    /// Checks every invariant listed in the crate docs; returns the first violation.
    /// The same as [`Triangulation::validate`].
    pub fn is_valid(&self) -> Result<(), ValidationError> {
        self.validate()
    }

    /// Checks every invariant listed in the crate docs; returns the first violation.
    pub fn validate(&self) -> Result<(), ValidationError> {
        if !self.built {
            if self.tds.n_live != 0 {
                return Err(ValidationError::Counts("cells before 3D".into()));
            }
            return Ok(());
        }
        let (mut live, mut finite) = (0, 0);
        for c in (0..self.tds.cells.len()).map(CellId::from_index) {
            if self.tds.cell(c).v[0] == DEAD {
                continue;
            }
            live += 1;
            if self.check_cell(c)? {
                finite += 1;
            }
        }
        let tds = &self.tds;
        if live != tds.n_live || finite != tds.n_finite || live + tds.free.len() != tds.cells.len()
        {
            return Err(ValidationError::Counts(format!(
                "live {live} (counter {}), finite {finite} (counter {}), free {}, slots {}",
                tds.n_live,
                tds.n_finite,
                tds.free.len(),
                tds.cells.len()
            )));
        }
        for v in self.vertices() {
            let c = tds.vertex_cell[v.index()];
            if !tds.is_cell(c) || !tds.cell(c).v.contains(&v) {
                return Err(ValidationError::VertexWithoutCell { vertex: v, cell: c });
            }
        }
        if !tds.is_cell(tds.infinite_cell) || !self.is_infinite(tds.infinite_cell) {
            return Err(ValidationError::Counts(
                "infinite_cell is not an infinite cell".into(),
            ));
        }
        Ok(())
    }

    /// Checks the live cell `c` and its four facets; returns whether it is finite.
    #[allow(clippy::needless_range_loop)]
    fn check_cell(&self, c: CellId) -> Result<bool, ValidationError> {
        let nv = self.points.len();
        let cell = self.tds.cell(c);
        let v = cell.v;
        let n_inf = v.iter().filter(|&&w| w == VertexId::INFINITE).count();
        let distinct = (0..4).all(|i| (i + 1..4).all(|j| v[i] != v[j]));
        if n_inf > 1
            || !distinct
            || v.iter()
                .any(|&w| w != VertexId::INFINITE && w.index() >= nv)
        {
            return Err(ValidationError::BadVertices {
                cell: c,
                vertices: v,
            });
        }
        if n_inf == 0 {
            let q = v.map(|w| self.pt(w));
            if orient3d(q[0], q[1], q[2], q[3]) != Sign::Positive {
                return Err(ValidationError::BadOrientation {
                    cell: c,
                    vertices: v,
                });
            }
        }
        for i in 0..4 {
            let n = cell.n[i];
            if !self.tds.is_cell(n) {
                return Err(ValidationError::BadNeighbor {
                    cell: c,
                    index: i as u8,
                    neighbor: n,
                });
            }
            let nc = self.tds.cell(n);
            let back: Vec<usize> = (0..4).filter(|&j| nc.n[j] == c).collect();
            let asym = ValidationError::Asymmetric {
                cell: c,
                index: i as u8,
                neighbor: n,
            };
            if back.len() != 1 {
                return Err(asym);
            }
            let j = back[0];
            // Shared facet: the vertices other than i in c are those other than j in n.
            let mut fa: Vec<VertexId> = (0..4).filter(|&k| k != i).map(|k| v[k]).collect();
            let mut fb: Vec<VertexId> = (0..4).filter(|&k| k != j).map(|k| nc.v[k]).collect();
            fa.sort_unstable();
            fb.sort_unstable();
            if fa != fb || nc.v[j] == v[i] {
                return Err(asym);
            }
            let w = nc.v[j];
            if n_inf == 1 && v[i] == VertexId::INFINITE {
                // Hull facet: the finite cell behind it must be on the inner side.
                let [a, b, d] = FACET[i].map(|k| self.pt(v[k]));
                if orient3d(a, b, d, self.pt(w)) != Sign::Negative {
                    return Err(ValidationError::BadHull {
                        cell: c,
                        index: i as u8,
                    });
                }
            }
            if w != VertexId::INFINITE && self.in_conflict(c, self.pt(w)) {
                if n_inf == 1 && nc.v.contains(&VertexId::INFINITE) {
                    return Err(ValidationError::BadHull {
                        cell: c,
                        index: i as u8,
                    });
                }
                return Err(ValidationError::NotDelaunay {
                    cell: c,
                    index: i as u8,
                });
            }
        }
        Ok(n_inf == 0)
    }
}
