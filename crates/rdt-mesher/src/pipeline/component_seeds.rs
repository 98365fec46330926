//! A control point on every component of an implicit function (section 6.4.3: the control
//! points E'_i need a point on each component of S; ours: a grid scan finds them).
//!
//! The oracle's seeds come from a 33^3 grid over the bounding sphere's cube and 64 random
//! lines. A component smaller than that grid's step and missed by the lines gets no control
//! point, and the refinement never reaches it: a sphere of radius 0.05 beside a unit sphere
//! in a ball of radius 6 was left out at every `--size`, with no word. Here `f` is sampled on
//! a finer grid ([`verify::grid_scan::DEFAULT_NODES`] nodes per axis) and read as an image;
//! each component of its voxel scan that none of the control points lies on gets one more
//! control point: the scan's point of it projected onto S by the oracle.
//!
//! # Invariant
//! Control points are only added, never moved, and only points of S (oracle projections): a
//! function whose components all hold a control point keeps the control points it had, so its
//! mesh is unchanged.

use glam::DVec3;

use super::{Input, InputKind};
use crate::MeshOptions;

/// At most this many control points are added (a scan of a surface thinner than its step
/// breaks into many pieces: one point each is enough to start every piece).
const MAX_ADDED: usize = 256;

/// The control points and their cap for `base` (the mesher's options but these two) on an
/// implicit input: `None` when nothing is added (the mesher picks its own, as before).
/// A note names what was added.
pub(crate) fn added(
    input: &Input<'_>,
    base: &MeshOptions,
    notes: &mut Vec<String>,
) -> Option<(Vec<DVec3>, usize)> {
    if input.kind != InputKind::Implicit || input.control_points.is_some() {
        return None;
    }
    let surface = input.surface();
    let (img, step) =
        verify::grid_scan::grid_image(surface, verify::grid_scan::DEFAULT_NODES).ok()?;
    let topo = img.topology();
    let mut control = crate::init::control_points(surface, base);
    let mut seeded = vec![false; topo.component_seeds.len()];
    for p in &control {
        if let Some(c) = img.component_of(*p).filter(|&c| c < seeded.len()) {
            seeded[c] = true;
        }
    }
    let added: Vec<DVec3> = (0..seeded.len())
        .filter(|&c| !seeded[c] && !topo.component_vanishing.get(c).copied().unwrap_or(false))
        .filter_map(|c| {
            let p = topo.component_seeds[c];
            surface
                .project(p)
                .filter(|q| q.is_finite() && (*q - p).length() <= 2.0 * step)
        })
        .take(MAX_ADDED)
        .collect();
    if added.is_empty() {
        return None;
    }
    let at = added
        .iter()
        .take(3)
        .map(|p| format!("({:.4}, {:.4}, {:.4})", p.x, p.y, p.z))
        .collect::<Vec<_>>()
        .join(", ");
    notes.push(format!(
        "{} components of f found by a grid scan (step {step:.3e}) had no seed point: one \
         control point added on each (at {at}{})",
        added.len(),
        if added.len() > 3 { ", ..." } else { "" }
    ));
    control.extend(added);
    let cap = control.len().max(base.max_control_points);
    Some((control, cap))
}
