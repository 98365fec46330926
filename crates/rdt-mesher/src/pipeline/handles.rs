//! Section 6.6.3 (point-set surfaces) / data support: the handles of the output that the
//! input data does not show are cut (ours), after the unsupported components are dropped
//! (`unsupported`), and the certificate is told.
//!
//! The IMLS zero-set of a noisy scan can join two close sheets by a thin tube or pierce a
//! thin part with a small tunnel: a handle the model does not have, which `verify`'s
//! `data-support` check finds (`verify::data_support::unsupported_handles`: a tunnel within
//! half the data's band, or whose neighbourhood faces against the data normals). A user who
//! meshes a scan expects the surface the data shows, so the handle is cut, as topological
//! noise removal does (Guskov & Wood 2001): the stars of the vertices of the handle's
//! geodesic ball (the ball at which it was found: the tube and a ring around it; if that
//! round fails, of a loop through the tunnel, `ShortHandle::loop_vertices`) are
//! removed, and each boundary loop left is closed on its own side by the topological
//! repair's closing (`levels::repair`, rules 1 to 3, with its exact intersection rounds), so
//! the output stays a closed, oriented 2-manifold without self-intersections. The triangles
//! below the angle bound that the closings make are then edited as after the repair on
//! images (`levels::skinny`, every vertex kept on S).
//!
//! A round cuts every handle found, and is kept only if the total genus falls and the
//! component count does not change (a cut that would split a component, or not remove a
//! handle, is undone and the rounds end); at most [`ROUNDS`] rounds.
//!
//! Reported: each closing of a round is a `DecisionKind::CutUnsupportedHandle` in
//! `Stats::topology_decisions` (loops closed, and the handle nearest it as the check
//! measured it), printed by `cargo xtask mesh`. `Request::keep_unsupported`
//! (`--keep-unsupported`) keeps the handles: the raw mesh of the IMLS surface.
//!
//! Invariants: deterministic; nothing changes when no handle is found (the output byte for
//! byte); only the triangles around the handles change.

use super::input::Input;
use super::outcome::Outcome;
use crate::{DecisionKind, TopologyDecision};
use glam::DVec3;
use verify::data_support::UnsupportedHandle;

/// Rounds of detection and cutting.
const ROUNDS: usize = 8;

/// Apply the rule of the module docs to `out` (meshed from `input` at size `sigma` with
/// `opts`: the angle bound of the skinny edits, and their largest move, half the run's
/// resolution or of `sigma`).
pub(super) fn cut_unsupported_handles(
    out: &mut Outcome,
    input: &Input,
    sigma: f64,
    opts: &crate::MeshOptions,
) {
    let Some(data) = &input.support_data else {
        return;
    };
    let t = std::time::Instant::now();
    let support = super::unsupported::support_options(input, sigma);
    let normals = input.support_normals.as_deref();
    let before = out.mesh.vertices.clone();
    let mut changed = false;
    for _ in 0..ROUNDS {
        let handles = verify::data_support::unsupported_handles(&out.mesh, data, normals, &support);
        if handles.is_empty() {
            break;
        }
        // Around the whole ball first, else along a loop through each tunnel (measured on
        // the scan table: loops first left the genus-15 row at genus 1, with no handle the
        // rule finds; balls reach the source's genus on every row).
        let Some(decisions) = cut_round(out, &handles, input, opts, sigma, Cut::Ball)
            .or_else(|| cut_round(out, &handles, input, opts, sigma, Cut::Loop))
        else {
            break;
        };
        out.stats.topology_decisions.extend(decisions);
        changed = true;
    }
    if changed {
        super::unsupported::after_edit(out, &before);
        // The closings are judged as the repair's are: `unmet: angle` from the mesh written.
        crate::levels::repair::record_min_angle(&mut out.stats, opts.criteria.min_angle_deg);
    }
    let dt = t.elapsed().as_secs_f64();
    out.stats.time_total_s += dt;
    out.stats.time_queue_s += dt;
}

/// Where a handle is cut: the stars of the vertices of a loop through its tunnel, or of its
/// whole geodesic ball.
#[derive(Clone, Copy)]
enum Cut {
    Loop,
    Ball,
}

/// One round: cut `handles` (see the module docs); the decisions, or `None` (the mesh
/// unchanged) when the cut does not lower the genus or changes the component count.
fn cut_round(
    out: &mut Outcome,
    handles: &[UnsupportedHandle],
    input: &Input,
    opts: &crate::MeshOptions,
    sigma: f64,
    how: Cut,
) -> Option<Vec<TopologyDecision>> {
    let mut ball: Vec<u32> = match how {
        Cut::Loop => handles
            .iter()
            .flat_map(|x| x.loop_vertices.iter().copied())
            .collect(),
        Cut::Ball => {
            let loops = verify::short_loops::ShortLoops::new(&out.mesh)?;
            handles
                .iter()
                .flat_map(|x| loops.ball(x.vertex, x.radius))
                .collect()
        }
    };
    ball.sort_unstable();
    ball.dedup();
    let (genus0, comps0) = genus_and_components(&out.mesh)?;
    let mut mesh = out.mesh.clone();
    let mut balls = out.balls.clone();
    let d = crate::levels::repair::repair(&mut mesh, &mut balls, None, &ball, &[], None);
    let (genus1, comps1) = genus_and_components(&mesh)?;
    if genus1 >= genus0 || comps1 != comps0 {
        return None;
    }
    let e = crate::levels::skinny::improve(
        &mut mesh,
        &mut balls,
        input.surface(),
        opts.criteria.min_angle_deg,
        0.5 * opts.resolution.unwrap_or(sigma),
    );
    let st = &mut out.stats;
    st.skinny_flips += e.flips;
    st.skinny_collapses += e.collapses;
    st.skinny_moves += e.moves;
    out.mesh = mesh;
    out.balls = balls;
    Some(
        d.into_iter()
            .map(|mut x| {
                if let DecisionKind::Separate { loops } = x.kind {
                    let near = handles
                        .iter()
                        .min_by(|a, b| dist(a, x.center).total_cmp(&dist(b, x.center)))
                        .expect("a round has handles")
                        .clone();
                    x.kind = DecisionKind::CutUnsupportedHandle {
                        loops,
                        handle: near,
                    };
                }
                x
            })
            .collect(),
    )
}

fn dist(h: &UnsupportedHandle, c: DVec3) -> f64 {
    DVec3::from_array(h.at).distance(c)
}

/// The total genus and the component count of a closed, oriented 2-manifold (`None` if the
/// mesh is not one).
fn genus_and_components(mesh: &meshio::TriMesh) -> Option<(i64, usize)> {
    let t = verify::topology::analyze(mesh, 0);
    if !t.is_closed_oriented_manifold() {
        return None;
    }
    let g = t.genera();
    Some((g.iter().map(|x| x.unwrap_or(0)).sum(), g.len()))
}
