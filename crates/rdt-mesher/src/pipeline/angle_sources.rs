//! Where the triangles below the angle bound are (not in the paper: section 6.1's refinement
//! meets the bound on every restricted facet it keeps; the triangles the topological
//! decisions add after it, at necks, cuts and bridges, need not): the `angles` check's
//! detail gains how many of the triangles below the bound lie within the box of a
//! topological decision, by kind, and how many elsewhere.
//!
//! A triangle is counted at a decision when one of its corners is within half the decision's
//! box diagonal (`TopologyDecision::size`) of the box's center: the triangles a decision
//! adds lie in that box, and the skinny edits after the decisions (flips, collapses, moves)
//! change them and the triangles sharing their corners. It is a statement of place, not of
//! cause.
//! Invariant: the check's status and figures are unchanged; only its detail grows.

use crate::TopologyDecision;
use glam::DVec3;
use meshio::TriMesh;

/// Append to the `angles` check of `report`, when it FAILed, where its triangles below the
/// bound `min_deg` (the check's, `None`: no bound asked) lie relative to `decisions`. The
/// triangles are those the check counts (the same angle measure and bound).
pub(super) fn annotate(
    report: &mut verify::Report,
    mesh: &TriMesh,
    decisions: &[TopologyDecision],
    min_deg: Option<f64>,
) {
    let Some(min_deg) = min_deg else { return };
    let Some(check) = report
        .checks
        .iter_mut()
        .find(|c| c.name == "angles" && c.status == verify::Status::Fail)
    else {
        return;
    };
    let (mut at_kinds, mut elsewhere) = (Vec::<(String, usize)>::new(), 0usize);
    for t in &mesh.triangles {
        let p = t.map(|i| mesh.vertices[i as usize]);
        if verify::quality::smallest_angle_deg(p[0], p[1], p[2]) >= min_deg {
            continue;
        }
        match decisions.iter().find(|d| p.iter().any(|&c| within(d, c))) {
            Some(d) => {
                let kind = kind_name(d);
                match at_kinds.iter_mut().find(|(k, _)| *k == kind) {
                    Some(e) => e.1 += 1,
                    None => at_kinds.push((kind, 1)),
                }
            }
            None => elsewhere += 1,
        }
    }
    let at: usize = at_kinds.iter().map(|e| e.1).sum();
    if at == 0 {
        check.detail += "; none of them at a topological decision";
        return;
    }
    let kinds: Vec<String> = at_kinds.iter().map(|(k, n)| format!("{k} {n}")).collect();
    check.detail += &format!(
        "; {at} of them at topological decisions ({}; see topology_decisions), {elsewhere} elsewhere",
        kinds.join(", ")
    );
}

/// Whether `c` lies within the box of decision `d` (the ball of its half diagonal).
fn within(d: &TopologyDecision, c: DVec3) -> bool {
    c.distance(d.center) <= 0.5 * d.size * (1.0 + 1e-9)
}

/// The decision's kind as the report names it (`bridge`, `join_neck`, ...).
fn kind_name(d: &TopologyDecision) -> String {
    serde_json::to_value(&d.kind)
        .ok()
        .and_then(|v| v.get("kind").and_then(|k| k.as_str()).map(str::to_owned))
        .unwrap_or_else(|| "decision".into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::DecisionKind;

    /// A skinny triangle at `x` (smallest angle about 1.1 degrees) or an equilateral one.
    fn triangle(m: &mut TriMesh, x: f64, skinny: bool) {
        let n = m.vertices.len() as u32;
        let h = if skinny { 0.01 } else { 0.75f64.sqrt() };
        m.vertices.extend([
            DVec3::new(x, 0.0, 0.0),
            DVec3::new(x + 1.0, 0.0, 0.0),
            DVec3::new(x + 0.5, h, 0.0),
        ]);
        m.triangles.push([n, n + 1, n + 2]);
    }

    fn angles_detail(m: &TriMesh, decisions: &[TopologyDecision]) -> (verify::Status, String) {
        let opts = verify::Options {
            min_angle_deg: Some(30.0),
            ..Default::default()
        };
        let mut r = verify::check(m, &opts);
        annotate(&mut r, m, decisions, opts.min_angle_deg);
        let c = r.check("angles").expect("the angles check ran");
        (c.status, c.detail.clone())
    }

    #[test]
    fn the_triangles_below_the_bound_are_placed_at_decisions_or_elsewhere() {
        let mut m = TriMesh::default();
        triangle(&mut m, 0.0, true);
        triangle(&mut m, 10.0, true);
        triangle(&mut m, 20.0, false);
        let bridge = TopologyDecision {
            kind: DecisionKind::Bridge,
            center: DVec3::new(0.5, 0.0, 0.0),
            size: 2.0,
            facets_removed: 2,
            facets_added: 6,
        };
        let (status, detail) = angles_detail(&m, std::slice::from_ref(&bridge));
        assert_eq!(status, verify::Status::Fail);
        assert!(detail.contains("2 of 3 triangles below"), "{detail}");
        assert!(
            detail.ends_with(
                "; 1 of them at topological decisions (bridge 1; see topology_decisions), 1 elsewhere"
            ),
            "{detail}"
        );
        // No decision near either: said so; a check that passed is left as it was.
        let far = TopologyDecision {
            center: DVec3::new(30.0, 0.0, 0.0),
            ..bridge
        };
        let (_, detail) = angles_detail(&m, std::slice::from_ref(&far));
        assert!(
            detail.ends_with("; none of them at a topological decision"),
            "{detail}"
        );
        let mut good = TriMesh::default();
        triangle(&mut good, 0.0, false);
        let (status, detail) = angles_detail(&good, &[far]);
        assert_eq!(status, verify::Status::Pass);
        assert!(!detail.contains("topological"), "{detail}");
    }
}
