//! Memory accounting of a run (ours, issue 21): the heap bytes of each structure of the
//! mesher at the end of the refinement, when they are largest, measured from the capacities
//! of their vectors (allocated, not only used), so that bytes per vertex can be traced to a
//! structure. Not counted: the output (mesh, balls, sample), built after, and the allocator's
//! own overhead; the process's peak resident size can only be larger.

use crate::state::Mesher;

/// Heap bytes of one structure.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MemoryUse {
    /// What it holds.
    pub structure: &'static str,
    /// Bytes allocated.
    pub bytes: usize,
}

impl Mesher<'_> {
    /// The heap bytes of every structure now (see the module docs).
    pub(crate) fn memory(&self) -> Vec<MemoryUse> {
        let mut out: Vec<MemoryUse> = self
            .tri
            .memory()
            .into_iter()
            .map(|(structure, bytes)| MemoryUse { structure, bytes })
            .collect();
        let (facets, indexes) = self.restricted.heap_bytes();
        out.extend([
            MemoryUse {
                structure: "Voronoi vertices",
                bytes: self.voronoi.heap_bytes(),
            },
            MemoryUse {
                structure: "restricted facets",
                bytes: facets,
            },
            MemoryUse {
                structure: "restricted indexes",
                bytes: indexes,
            },
            MemoryUse {
                structure: "queue",
                bytes: self.queue.heap_bytes(),
            },
            MemoryUse {
                structure: "vertex sizes",
                bytes: self.vertex_sizes.heap_bytes(),
            },
        ]);
        out
    }
}
