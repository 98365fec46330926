//! Section 6.6.3 (point-set surfaces) / data support: the components of the output that the
//! input data does not support are dropped (ours), as `--min-component` drops specks on
//! images, and the certificate is told.
//!
//! The surface of a point set is the zero-set of the IMLS function of section 6.6.3 (within
//! the band of the data; the far field beyond). That zero-set may have closed components
//! that no data is on: a bubble within the noise of a scan (its normals integrate to zero,
//! while the data's normal is about constant over it), or a pocket where two parts of the
//! model come close. The mesher meshes them faithfully; `verify`'s `data-support` check
//! flags them. This rule removes them from the output.
//!
//! **The rule.** After meshing a point set or a mesh (the inputs with data to support the
//! output: `Input::support_data`), a component of the output is dropped when both hold:
//! 1. *Unsupported*, by the `data-support` check's own measures (the code is the check's,
//!    `verify::data_support::droppable_components`): less than 50% of its area within the
//!    band `b_i = 2 s_i + 3 ν` of the data (`SupportOptions::min_share`), or, with oriented
//!    data normals (point sets), an orientation agreement below 0.5 (`min_agreement`).
//! 2. *No data is lost*: at least one component is left; fewer than 10 data points
//!    (`min_data_component`, the size of the smallest data component the check requires
//!    covered) that the whole output covers (within `max(b_i, 2 s_i)`, the check's
//!    coverage) are not covered by what is left; and no data component that the whole
//!    output covers is left uncovered.
//!
//! All the unsupported components are tried together; if that loses data, one at a time,
//! smallest area first, each kept when adding it to the dropped ones would lose data.
//!
//! Why: a user who meshes a scan expects the surface the data shows, no more (no component
//! that no data is on) and no less (no part that some data is on). The thresholds are the
//! check's, so a component is dropped only when the certificate would fail on it, and the
//! certificate's verdict on what is left is unchanged in kind. Condition 2 keeps the main
//! surface even when it is unsupported itself (the sheet a scan with a missing patch
//! bridges the hole with may have little agreement): it stays, and the check still FAILs on
//! it. A real part of the object that only it covers (a thin part meshed inside out, a
//! separate piece of the scan) stays too, flagged, rather than vanish.
//!
//! Reported: each drop is a `DecisionKind::DropUnsupportedComponent` in
//! `Stats::topology_decisions` (triangles, area, size across, centroid, supported share,
//! agreement), printed by `cargo xtask mesh`; the `data-support` check then runs on the mesh
//! written and lists the dropped components in its detail and in
//! `verify.data_support.dropped_components`. `Request::keep_unsupported`
//! (`--keep-unsupported`) keeps them: the raw mesh of the IMLS surface.
//!
//! Invariants: deterministic; nothing changes (the output byte for byte) when no component
//! is dropped; only whole components are removed, the kept triangles keep their order and
//! their vertices their relative order; the sample loses the dropped vertices.

use super::input::Input;
use super::outcome::Outcome;
use crate::{DecisionKind, TopologyDecision};
use glam::DVec3;
use std::collections::HashSet;

/// Apply the rule of the module docs to `out` (meshed from `input` at size `sigma`, which
/// sets the band's floor on mesh inputs, see [`support_options`]).
pub(super) fn drop_unsupported(out: &mut Outcome, input: &Input, sigma: f64) {
    let Some(data) = &input.support_data else {
        return;
    };
    let t = std::time::Instant::now();
    let opts = support_options(input, sigma);
    let normals = input.support_normals.as_deref();
    let drops = verify::data_support::droppable_components(&out.mesh, data, normals, &opts);
    // The rule's time is part of the run's (and of "everything else").
    let dt = t.elapsed().as_secs_f64();
    out.stats.time_total_s += dt;
    out.stats.time_queue_s += dt;
    if drops.is_empty() {
        return;
    }
    let mesh = &mut out.mesh;
    let mut live = vec![true; mesh.triangles.len()];
    let mut decisions = Vec::new();
    for d in drops {
        let (lo, hi) = d
            .triangles
            .iter()
            .flat_map(|&i| mesh.triangles[i])
            .map(|v| mesh.vertices[v as usize])
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p), hi.max(p))
            });
        d.triangles.iter().for_each(|&i| live[i] = false);
        let corners = |i: usize| mesh.triangles[i].map(|v| mesh.vertices[v as usize]);
        out.dropped_triangles
            .extend(d.triangles.iter().map(|&i| corners(i)));
        decisions.push(TopologyDecision {
            kind: DecisionKind::DropUnsupportedComponent(d.support),
            center: 0.5 * (lo + hi),
            size: (hi - lo).length(),
            facets_removed: d.triangles.len(),
            facets_added: 0,
        });
    }
    crate::levels::repair::retain_marked(&mut mesh.triangles, &mut out.balls, &live);
    let before: Vec<DVec3> = mesh.vertices.clone();
    crate::levels::repair::compact(mesh);
    after_edit(out, &before);
    out.stats.topology_decisions.extend(decisions);
}

/// The figures of `out` after an edit of its mesh (the vertices `before` it): the sample
/// loses the vertices gone; vertex and facet counts, the smallest angle and, at a constant
/// size, the largest r / sigma measured again.
pub(super) fn after_edit(out: &mut Outcome, before: &[DVec3]) {
    let mesh = &out.mesh;
    let key = |p: &DVec3| p.to_array().map(f64::to_bits);
    let kept: HashSet<[u64; 3]> = mesh.vertices.iter().map(key).collect();
    let gone: HashSet<[u64; 3]> = before
        .iter()
        .map(key)
        .filter(|k| !kept.contains(k))
        .collect();
    out.sample.retain(|p| !gone.contains(&key(p)));
    let st = &mut out.stats;
    st.vertices = mesh.vertices.len();
    st.facets = mesh.triangles.len();
    let min_angle = mesh
        .triangles
        .iter()
        .map(|t| crate::criteria::min_angle_deg(t.map(|v| mesh.vertices[v as usize])))
        .fold(f64::INFINITY, f64::min);
    if min_angle.is_finite() {
        st.min_angle_deg = min_angle;
    }
    // At a constant size the largest r / sigma is measured again on what is left (with a
    // size field, the run's figure, over the mesh before the drop, stays).
    if let Some(m) = out
        .sigma
        .and_then(|s| out.balls.iter().map(|b| b.radius / s).reduce(f64::max))
    {
        crate::levels::repair::record_max_r_over_sigma(st, m);
    }
}

/// The components [`drop_unsupported`] dropped, as the `data-support` check measured them on
/// the raw output (from `stats.topology_decisions`).
pub(crate) fn dropped(stats: &crate::Stats) -> Vec<verify::data_support::ComponentSupport> {
    stats
        .topology_decisions
        .iter()
        .filter_map(|d| match &d.kind {
            DecisionKind::DropUnsupportedComponent(c) => Some(c.clone()),
            _ => None,
        })
        .collect()
}

/// The `data-support` measures of a run on `input` at size `sigma` (the check's and the
/// rule's): the defaults, with the band at least `sigma / 2` for a mesh's exact samples
/// (its output chords lie up to about that far from them at sharp edges).
pub(crate) fn support_options(input: &Input, sigma: f64) -> verify::SupportOptions {
    let min_band = if input.kind == super::InputKind::Polyhedron {
        0.5 * sigma
    } else {
        0.0
    };
    verify::SupportOptions {
        min_band,
        ..Default::default()
    }
}
