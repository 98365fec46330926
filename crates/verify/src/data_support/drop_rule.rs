//! The drop rule's measures (for section 6.6.3's point-set surface, whose IMLS zero-set may
//! have components the data does not support): which unsupported components of a mesh can go
//! without losing any data, by the `data-support` check's own measures (the parent module's
//! band, component support and coverage). The rule is the mesher's, stated in
//! `rdt_mesher::pipeline`'s `unsupported` module and the GUIDE.

use super::{
    ComponentSupport, DataBand, SupportOptions, component_measures, covered_points, data_groups,
};
use glam::DVec3;
use meshio::TriMesh;

/// A component that [`droppable_components`] drops: its support and its triangles.
#[derive(Clone, Debug, PartialEq)]
pub struct Droppable {
    /// Its figures, as the check measures them.
    pub support: ComponentSupport,
    /// Its triangles (indices into the mesh's).
    pub triangles: Vec<usize>,
}

/// The unsupported components of `mesh` that can be dropped without losing any data (for
/// section 6.6.3's point-set surface, whose IMLS zero-set may have components that the data
/// does not support; the mesher's rule, stated in `rdt_mesher::pipeline`'s `unsupported`
/// module and the GUIDE): the components that
/// 1. are unsupported by the measures of this check ([`ComponentSupport::supported`] with
///    `opts.min_share` and `opts.min_agreement`: less than half the area within the band of
///    the data, or with data normals an orientation agreement below 0.5), and
/// 2. can go together without the data losing anything: at least one component is left;
///    fewer than `opts.min_data_component` (10) data points covered by the whole mesh are
///    not covered by what is left (the check's coverage: within `max(b_i, 2 s_i)`); and no
///    data component covered by the whole mesh (at least `opts.min_share` of its points)
///    is left uncovered.
///
/// Condition 2 is tried first on all the unsupported components at once; if it fails, they
/// are taken one at a time, smallest area first, each kept out when adding it would break
/// condition 2 (so the main surface stays, even when unsupported itself, e.g. a sheet
/// bridging a hole with little agreement). At most [`MAX_DROP_TRIES`] are tried one at a
/// time. Empty, and nothing measured, when the mesh has fewer than 2 components; empty when
/// the data has fewer than 2 points. Deterministic.
pub fn droppable_components(
    mesh: &TriMesh,
    data: &[DVec3],
    normals: Option<&[DVec3]>,
    opts: &SupportOptions,
) -> Vec<Droppable> {
    // One component (or none) can never go: nothing to measure (the common case, free).
    if crate::topology::vertex_components(mesh).len() < 2 {
        return Vec::new();
    }
    let Some(band) = DataBand::new(data, opts) else {
        return Vec::new();
    };
    let normals = normals.filter(|n| n.len() == data.len());
    let (comps, comp_of_triangle, _, _) = component_measures(mesh, &band, normals);
    let mut candidates: Vec<usize> = (0..comps.len())
        .filter(|&k| !comps[k].supported(opts.min_share, opts.min_agreement))
        .collect();
    if candidates.is_empty() {
        return Vec::new();
    }
    candidates.sort_by(|&a, &b| comps[a].area.total_cmp(&comps[b].area).then(a.cmp(&b)));
    let full = covered_points(mesh, &band);
    let groups = data_groups(&band, opts.min_data_component);
    let share = |cov: &[bool], g: &[usize]| {
        g.iter().filter(|&&i| cov[i]).count() as f64 / g.len().max(1) as f64
    };
    let acceptable = |drop: &[bool]| -> bool {
        if drop.iter().all(|&d| d) {
            return false;
        }
        let kept = TriMesh {
            vertices: mesh.vertices.clone(),
            triangles: (mesh.triangles.iter().zip(&comp_of_triangle))
                .filter(|&(_, &k)| !drop[k])
                .map(|(t, _)| *t)
                .collect(),
        };
        let cov = covered_points(&kept, &band);
        let lost = full.iter().zip(&cov).filter(|&(&f, &c)| f && !c).count();
        lost < opts.min_data_component.max(1)
            && groups
                .iter()
                .all(|g| share(&full, g) < opts.min_share || share(&cov, g) >= opts.min_share)
    };
    let mut drop = vec![false; comps.len()];
    candidates.iter().for_each(|&k| drop[k] = true);
    if !acceptable(&drop) {
        drop.iter_mut().for_each(|d| *d = false);
        for &k in candidates.iter().take(MAX_DROP_TRIES) {
            drop[k] = true;
            if !acceptable(&drop) {
                drop[k] = false;
            }
        }
    }
    let mut triangles = vec![Vec::new(); comps.len()];
    for (t, &k) in comp_of_triangle.iter().enumerate() {
        if drop[k] {
            triangles[k].push(t);
        }
    }
    comps
        .into_iter()
        .zip(triangles)
        .zip(drop)
        .filter(|(_, d)| *d)
        .map(|((support, triangles), _)| Droppable { support, triangles })
        .collect()
}

/// Unsupported components tried one at a time by [`droppable_components`] (each try
/// measures the coverage of the data again).
pub const MAX_DROP_TRIES: usize = 32;
