//! Checks against a surface (ours): geometry, the loose epsilon-sample certificate and
//! condition 2 of definition 2.2, the normal bound of lemma 3.1, theorem 4.7.

use std::sync::Arc;

use glam::DVec3;
use meshio::TriMesh;
use oracle::Surface;

use crate::distance::NormalDeviation;
use crate::{
    DmFn, DmSource, MedialAxisEstimate, MeshDistance, Options, Report, Status, bvh, certificate,
    distance, pass_fail,
};

/// Every check of [`crate::check_against`] beyond those of [`crate::check`].
pub(crate) fn against(
    r: &mut Report,
    mesh: &TriMesh,
    bvh: &bvh::TriangleBvh,
    surface: &dyn Surface,
    opts: &Options,
) {
    // Implicit functions: the grid scan's points of S join the S -> mesh samples and the
    // component seeds.
    let grid = crate::grid_scan::run(surface, opts);
    let scan = grid.as_ref().and_then(|g| g.as_ref().ok());
    // The d_M source (a Delaunay triangulation of the sample: one thread for a while) beside
    // the distances (parallel).
    opts.stage("distances");
    let scan_points = scan.map(|g| &g.surface_points[..]);
    let ((normals, hausdorff), dm) = rayon::join(
        || hausdorff_check(r, mesh, bvh, surface, opts, scan_points),
        || dm_source(mesh, surface, opts),
    );
    // Measured: every sample projected, and some facet lies where S is the data's surface.
    let measured = r.geometry.as_ref().is_some_and(|g| {
        g.projection_failures == 0 && g.trusted.as_ref().is_none_or(|t| t.facets > 0)
    });
    let dm = dm.unwrap_or_else(|e| {
        r.push("loose-epsilon", Status::Fail, e);
        None
    });
    opts.stage("certificate");
    let balls = certificate_checks(r, mesh, surface, opts, &dm, measured.then_some(hausdorff));

    normals_check(r, mesh, &normals);
    crate::hypothesis::reconcile(r, opts);

    opts.stage("components");
    let seeds = scan.map_or(&[][..], |g| &g.seeds[..]);
    components_sampled_check(r, mesh, bvh, surface, opts, &balls, seeds);
    if let Some(g) = &grid {
        crate::grid_scan::genus_check(r, mesh, g, opts);
    }
}

/// Mesh <-> S distances and the `hausdorff` check; gives the normal deviation and the
/// two-sided Hausdorff estimate.
fn hausdorff_check(
    r: &mut Report,
    mesh: &TriMesh,
    bvh: &bvh::TriangleBvh,
    surface: &dyn Surface,
    opts: &Options,
    scan_points: Option<&[DVec3]>,
) -> (NormalDeviation, f64) {
    let g = distance::geometry_labelled(
        mesh,
        bvh,
        surface,
        opts.samples_per_edge,
        opts.surface_samples.as_deref(),
        opts.surface_samples_source.as_deref(),
        scan_points,
    );
    // A point set's mesh with no facet where S is the data's surface has no figure at all.
    let nothing = g.trusted.as_ref().is_some_and(|t| t.facets == 0);
    let detail = if nothing {
        format!(
            "not measured: none of the {} facets lies where S is the surface the data shows",
            mesh.triangles.len()
        )
    } else {
        hausdorff_detail(&g)
    };
    // A sample with no point of S found has no distance: the figure would leave it out
    // silently, so it fails the check as much as a distance above the limit.
    let status = match opts.max_hausdorff {
        _ if nothing => Status::Skipped,
        _ if g.projection_failures > 0 => Status::Fail,
        Some(m) => pass_fail(g.hausdorff <= m),
        None => Status::Info,
    };
    r.push(
        "hausdorff",
        status,
        match opts.max_hausdorff {
            Some(m) => format!("{detail}; limit {m}"),
            None => detail,
        },
    );
    let normals = g.normals.clone();
    let hausdorff = g.hausdorff;
    r.geometry = Some(g);
    (normals, hausdorff)
}

/// On a point set with facets where S is not the data's surface ([`Surface::data_defined`]):
/// where the figure was measured and why the rest has no guarantee (appended to the theorem
/// checks' lines).
fn trusted_note(r: &Report) -> String {
    match r.geometry.as_ref().and_then(|g| g.trusted.as_ref()) {
        Some(t) if t.facets < t.of => format!(
            "; measured on the {} of {} facets where S is the surface the data shows; the \
             other {} (beyond the data: S there is an extrapolation or the far field's sign \
             boundary) have no guarantee",
            t.facets,
            t.of,
            t.of - t.facets
        ),
        _ => String::new(),
    }
}

/// The d_M function, its supremum and a description, from [`Options::dm`]; the error's text
/// when the pole estimate fails (the caller reports it as a FAILed `loose-epsilon`).
fn dm_source(
    mesh: &TriMesh,
    surface: &dyn Surface,
    opts: &Options,
) -> Result<Option<(DmFn, f64, String)>, String> {
    Ok(match &opts.dm {
        DmSource::Auto => surface.dm_inf_hint().filter(|v| *v > 0.0).map(|v| {
            let f: DmFn = Arc::new(move |_| v);
            (f, v, format!("constant d_M^inf hint {v} of the surface"))
        }),
        DmSource::Constant(v) => {
            let v = *v;
            let f: DmFn = Arc::new(move |_| v);
            Some((f, v, format!("constant {v}")))
        }
        DmSource::Function { dm, sup } => Some((dm.clone(), *sup, "given function".into())),
        DmSource::Poles => {
            // Labelled samples (input triangles, noisy points) serve the distances only.
            let samples = opts.dm_samples.as_deref().unwrap_or_else(|| {
                opts.surface_samples
                    .as_deref()
                    .filter(|_| opts.surface_samples_source.is_none())
                    .unwrap_or(&mesh.vertices)
            });
            match MedialAxisEstimate::new(samples, None) {
                Ok(m) => {
                    let sup = {
                        use rayon::prelude::*;
                        samples
                            .par_iter()
                            .map(|&p| m.dm(p))
                            .reduce(|| 0.0, f64::max)
                    };
                    let n = m.poles.len();
                    let m = Arc::new(m);
                    let f: DmFn = Arc::new(move |x| m.dm(x));
                    Some((
                        f,
                        sup,
                        format!("Voronoi poles of {} samples ({n} poles)", samples.len()),
                    ))
                }
                Err(e) => return Err(e.to_string()),
            }
        }
    })
}

/// The loose epsilon-sample certificate and theorem 4.7 (or SKIPs without d_M). Both PASS
/// only where the paper's theorems hold: the certificate's eps below epsilon_1 ~ 0.096
/// (theorems 4.4 to 4.7 need eps < epsilon_1); above it they are INFO with "no guarantee".
/// `hausdorff`: the measured two-sided figure, `None` when some sample was not measured.
/// Returns the balls used (empty when none were computed).
fn certificate_checks(
    r: &mut Report,
    mesh: &TriMesh,
    surface: &dyn Surface,
    opts: &Options,
    dm: &Option<(DmFn, f64, String)>,
    hausdorff: Option<f64>,
) -> Vec<certificate::SurfaceBall> {
    let balls = match &opts.surface_balls {
        Some(b) => b.clone(),
        None if dm.is_some() => certificate::surface_delaunay_balls(mesh, surface),
        None => Vec::new(),
    };
    let Some((f, sup, source)) = dm else {
        if r.check("loose-epsilon").is_none() {
            r.push(
                "loose-epsilon",
                Status::Skipped,
                format!("no d_M: the surface gives no d_M^inf hint; {DM_HINT}"),
            );
        }
        r.push(
            "theorem-4.7",
            Status::Skipped,
            format!("needs the certificate's eps and d_M^sup; {DM_HINT}"),
        );
        return balls;
    };
    let cert = certificate::loose_epsilon(
        &balls,
        mesh.triangles.len(),
        f.as_ref(),
        opts.epsilon,
        source,
        opts.max_listed,
    );
    let (status, detail) = epsilon_verdict(&cert, opts.epsilon_derived);
    let note = trusted_note(r);
    let detail = match status {
        Status::Pass => format!(
            "{detail}{}",
            note.replacen("measured on", "they apply on", 1)
        ),
        _ => detail,
    };
    r.push("loose-epsilon", status, detail);
    let mut hb =
        certificate::hausdorff_bound(cert.eps_achieved, *sup, hausdorff.unwrap_or(f64::NAN));
    // The least the true figure can be: the exact S -> mesh side, and the mesh -> S maximum
    // less its precision (an image's branch and bound reports an upper bound).
    let least = r.geometry.as_ref().and_then(|g| {
        (g.bounded_only == 0).then(|| {
            g.surface_to_mesh
                .max
                .max(g.mesh_to_surface.max - g.mesh_to_surface_precision)
        })
    });
    hb.undecided = !hb.holds && least.is_some_and(|l| l <= hb.bound);
    let figures = format!(
        "measured Hausdorff {:.3e} vs 4.5 eps^2 d_M^sup = {:.3e} (eps {:.4}, d_M^sup {:.4}){note}",
        hb.hausdorff, hb.bound, hb.eps, hb.dm_sup
    );
    let (status, detail) = if hausdorff.is_none() {
        (
            Status::Skipped,
            format!(
                "{figures}; not measured: a Hausdorff sample has no point of S, or no facet lies \
                 where S is the surface the data shows"
            ),
        )
    } else if !cert.passed() {
        (
            Status::Info,
            format!("{figures}; no guarantee: the loose epsilon-sample certificate does not hold"),
        )
    } else if hb.applicable && hb.undecided {
        (
            Status::Info,
            format!(
                "{figures}; not decided: the measured figure is an upper bound within {:.1e} \
                 (the true one is at least {:.3e}), on both sides of the bound",
                r.geometry
                    .as_ref()
                    .map_or(0.0, |g| g.mesh_to_surface_precision),
                least.unwrap_or(f64::NAN)
            ),
        )
    } else if hb.applicable {
        (pass_fail(hb.holds), figures)
    } else {
        (
            Status::Info,
            format!(
                "{figures}; no guarantee at eps = {:.4} (theorem 4.7 needs eps < {})",
                hb.eps,
                certificate::EPSILON_1
            ),
        )
    };
    r.push("theorem-4.7", status, detail);
    r.certificate = Some(cert);
    r.hausdorff_bound = Some(hb);
    balls
}

/// Where a user gets a d_M from, per command.
const DM_HINT: &str = "give one (verify: --dm poles or --dm VALUE; mesh: --epsilon E, whose \
                       second pass is certified with d_M from Voronoi poles; library: \
                       Options::dm)";

/// The `loose-epsilon` line: FAIL when the certificate fails (a facet over the requested
/// eps, a facet without ball, d_M undefined) and an eps was requested or derived (INFO "no
/// guarantee" when none was: nothing promised fails), PASS when it holds with eps < epsilon_1 (the
/// range of theorems 4.4 to 4.7), INFO "no guarantee" when it holds only above. A facet over
/// a `derived` eps (sigma / d_M^inf, not asked for) at or above epsilon_1 is INFO too: no
/// theorem applies at that eps, so nothing promised fails (the facets are still counted;
/// the mesher's own `unmet: size` line says the same).
fn epsilon_verdict(cert: &certificate::EpsilonCertificate, derived: bool) -> (Status, String) {
    let figures = format!(
        "achieved eps {:.4} (max r/d_M(c), at facet {}){}; {} balls, {} facets without ball, \
         d_M: {}",
        cert.eps_achieved,
        cert.worst_facet.map_or("-".to_string(), |f| f.to_string()),
        match cert.requested_eps {
            Some(e) => format!(", requested {e}: {} facets exceed", cert.exceeding_total),
            None => String::new(),
        },
        cert.balls,
        cert.facets_without_ball,
        cert.dm_source
    );
    let e1 = certificate::EPSILON_1;
    let only_over_derived = derived
        && cert.facets_without_ball == 0
        && cert.undefined_dm == 0
        && cert.requested_eps.is_some_and(|e| e >= e1);
    // Nothing asked (no eps, derived or given): a facet without a ball or a ball without
    // d_M means the certificate does not hold, and no theorem speaks of this mesh; that is
    // no guarantee, not a failure of anything promised (a marching-cubes mesh, the
    // triangles of a topological decision). `--epsilon E` asks, and then it FAILs.
    if !cert.passed() && cert.requested_eps.is_none() {
        let mut why = Vec::new();
        if cert.facets_without_ball > 0 {
            why.push(format!(
                "{} facets have no surface Delaunay ball (no crossing of S on the line through \
                 their circumcentre orthogonal to them: they are not facets of the restricted \
                 Delaunay triangulation of the mesh's vertices)",
                cert.facets_without_ball
            ));
        }
        if cert.undefined_dm > 0 {
            why.push(format!(
                "d_M is not positive and finite at {} ball centres",
                cert.undefined_dm
            ));
        }
        return (
            Status::Info,
            format!(
                "{figures}; no guarantee: the certificate does not hold ({}), so no theorem \
                 speaks of this mesh; nothing was asked (--epsilon E asks, and FAILs on it)",
                why.join("; ")
            ),
        );
    }
    if !cert.passed() && only_over_derived {
        (
            Status::Info,
            format!(
                "{figures}; no guarantee at eps = {:.4} (the theorems need eps < {e1}; the \
                 requested eps is sigma / d_M^inf, not asked for: --certify-epsilon E asks)",
                cert.eps_achieved
            ),
        )
    } else if !cert.passed() {
        (Status::Fail, figures)
    } else if cert.eps_achieved < e1 {
        (
            Status::Pass,
            format!("{figures}; a loose eps-sample with eps < {e1}: theorems 4.4 to 4.7 apply"),
        )
    } else {
        (
            Status::Info,
            format!(
                "{figures}; no guarantee at eps = {:.4} (the theorems need eps < {e1})",
                cert.eps_achieved
            ),
        )
    }
}

/// Normals, against lemma 3.1 when the certificate gives rho < 1/7.
fn normals_check(r: &mut Report, mesh: &TriMesh, normals: &NormalDeviation) {
    if r.geometry
        .as_ref()
        .and_then(|g| g.trusted.as_ref())
        .is_some_and(|t| t.facets == 0)
    {
        r.push(
            "normals",
            Status::Skipped,
            "not measured: no facet lies where S is the surface the data shows".into(),
        );
        return;
    }
    // Normals, against lemma 3.1 when the certificate gives rho = max r / d_M(c) < 1/7:
    // only when every facet has its ball and d_M (else rho is a max over part of the mesh,
    // 0 over none, and bounds nothing).
    let rho = r
        .certificate
        .as_ref()
        .filter(|c| c.balls > 0 && c.facets_without_ball == 0 && c.undefined_dm == 0)
        .map(|c| c.eps_achieved)
        .filter(|e| e.is_finite());
    let mut measured = format!(
        "facet normal vs surface gradient at vertices: max {:.3} deg (as lines {:.3} deg), \
         mean {:.3} deg, {} facets facing inward{}",
        normals.max_deg,
        normals.max_line_deg,
        normals.mean_deg,
        normals.inverted_facets,
        trusted_note(r)
    );
    if normals.max_uncertainty_deg > 0.0 {
        measured += &format!(
            "; beyond the data's rounding (gradient direction known to {:.3} deg at worst): \
             {:.3} deg",
            normals.max_uncertainty_deg, normals.max_excess_line_deg
        );
    }
    let facets = r
        .geometry
        .as_ref()
        .and_then(|g| g.trusted.as_ref())
        .map_or(mesh.triangles.len(), |t| t.facets);
    match rho.and_then(certificate::normal_bound_deg) {
        // Whatever the sampling, a mesh whose facets mostly face inward is inside out.
        _ if facets > 0 && 2 * normals.inverted_facets > facets => r.push(
            "normals",
            Status::Fail,
            format!(
                "{measured}: {} (most facets face against the gradient)",
                crate::hypothesis::INSIDE_OUT
            ),
        ),
        Some(bound) => r.push(
            "normals",
            pass_fail(normals.inverted_facets == 0 && normals.max_excess_line_deg <= bound),
            format!(
                "{measured}; lemma 3.1 bound {bound:.3} deg at rho = {:.4}",
                rho.unwrap_or(f64::NAN)
            ),
        ),
        None => r.push(
            "normals",
            Status::Info,
            format!(
                "{measured}; no guarantee: {}",
                match (rho, &r.certificate) {
                    (Some(e), _) => format!("the certificate's rho = {e:.4} is not below 1/7"),
                    (None, Some(_)) => "the certificate does not hold (see loose-epsilon)".into(),
                    (None, None) => "no certificate (no d_M)".into(),
                }
            ),
        ),
    }
}

/// Condition 2 of definition 2.2: a mesh point near every seed on S.
///
/// The threshold is the mesh's own scale at the seed: twice the radius of the surface
/// Delaunay ball of the facet nearest to the seed (its circumradius when no ball is known).
/// Why: by theorem 4.14 the surface Delaunay balls cover S (for eps <= epsilon_0), and a ball
/// B(c, r) has its facet's vertices on its sphere, so every point of a sampled component is
/// within 2r of a facet; and a component without vertices is at least 2 d_M^inf from the
/// others (the midpoint of a closest pair is on the medial axis), which exceeds 2r when
/// r < d_M^inf (any eps < 1). A fixed multiple of the bounding radius or of the Hausdorff
/// estimate has no such meaning (a false alarm in the estimate would let a missed component
/// pass).
fn components_sampled_check(
    r: &mut Report,
    mesh: &TriMesh,
    bvh: &bvh::TriangleBvh,
    surface: &dyn Surface,
    opts: &Options,
    balls: &[certificate::SurfaceBall],
    grid_seeds: &[DVec3],
) {
    let mut seeds = match &opts.component_seeds {
        Some(s) => s.clone(),
        None => surface.seed_points(opts.seed),
    };
    seeds.extend_from_slice(grid_seeds);
    let mut radius: Vec<f64> = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            certificate::circumcircle(a, b, c).map_or(0.0, |x| x.1)
        })
        .collect();
    for b in balls {
        if let Some(x) = radius.get_mut(b.facet) {
            *x = b.radius;
        }
    }
    let slack = 10.0 * surface.tolerance();
    let tol = |facet: usize| match opts.seed_tolerance {
        Some(t) => t,
        None => 2.0 * radius.get(facet).copied().unwrap_or(0.0) + slack,
    };
    let dist = MeshDistance::new(mesh, bvh);
    let mut cov = certificate::component_coverage(&dist, &seeds, &tol);
    let threshold = match opts.seed_tolerance {
        Some(t) => format!("{t:.3e} (given)"),
        None => "twice the surface Delaunay ball radius of their nearest facet".into(),
    };
    let far = format!(
        "{} of {} seed points of S farther from the mesh than {threshold} (largest threshold \
         {:.3e}, farthest seed {:.3e}){}",
        cov.uncovered,
        seeds.len(),
        cov.tolerance,
        cov.seeds.iter().map(|s| s.distance).fold(0.0, f64::max),
        worst_uncovered(&cov),
    );
    let (status, detail) = if let Some(img) = surface.as_image() {
        // Images: the voxel scan names each seed's component, so a far seed is a missed
        // component only when no mesh vertex lies on its component.
        let mut acc =
            crate::scan_components::account(mesh, img, &opts.dropped_points, &opts.sliver_points);
        if let Some(t) = &r.topology {
            acc = acc.with_mesh_genus(t);
        }
        let far_seeds = cov.uncovered;
        for s in cov.seeds.iter_mut().filter(|s| !s.covered) {
            let c = img.component_of(DVec3::from_array(s.seed));
            s.covered = c.is_some_and(|c| acc.has_piece(c) || acc.excused(c));
        }
        cov.uncovered = cov.seeds.iter().filter(|s| !s.covered).count();
        let worst = acc
            .components
            .iter()
            .find(|c| c.fate == crate::scan_components::Fate::Missed)
            .map(|c| {
                format!(
                    "; largest missed: {} voxel edges crossed, at ({:.4}, {:.4}, {:.4})",
                    c.crossing_edges, c.seed[0], c.seed[1], c.seed[2]
                )
            })
            .unwrap_or_default();
        let detail = format!(
            "components: {}{worst}; {far}, {} of them on meshed components",
            acc.summary(),
            far_seeds - cov.uncovered
        );
        let status = pass_fail(acc.missed == 0 && cov.uncovered == 0);
        crate::scan_components::scan_topology_check(r, &acc);
        r.scan_components = Some(acc);
        (status, detail)
    } else if seeds.is_empty() {
        (Status::Fail, "no seed points on S to check against".into())
    } else if opts.dropped_triangles.is_empty() || cov.uncovered == 0 {
        (pass_fail(cov.uncovered == 0), far)
    } else {
        // A far seed on a component dropped as unsupported by the data is accounted for (by
        // `data-support`'s list of dropped components), not missed.
        let far_seeds = cov.uncovered;
        for s in cov.seeds.iter_mut().filter(|s| !s.covered) {
            let p = DVec3::from_array(s.seed);
            let d = opts
                .dropped_triangles
                .iter()
                .map(|&[a, b, c]| p.distance(geom::closest::closest_point_triangle(p, a, b, c)))
                .fold(f64::INFINITY, f64::min);
            s.covered = d <= s.tolerance;
        }
        cov.uncovered = cov.seeds.iter().filter(|s| !s.covered).count();
        let detail = format!(
            "{far}, {} of them on components dropped as unsupported by the data (see data-support)",
            far_seeds - cov.uncovered
        );
        (pass_fail(cov.uncovered == 0), detail)
    };
    r.push("components-sampled", status, detail);
    r.components_sampled = Some(cov);
}

/// Where the uncovered seed farthest past its threshold is (empty when every seed is covered).
fn worst_uncovered(cov: &certificate::ComponentCoverage) -> String {
    cov.seeds
        .iter()
        .filter(|s| !s.covered)
        .max_by(|a, b| (a.distance / a.tolerance).total_cmp(&(b.distance / b.tolerance)))
        .map_or(String::new(), |s| {
            format!(
                "; the farthest past its threshold at ({:.4}, {:.4}, {:.4}): {:.3e} from the mesh, \
                 threshold {:.3e}",
                s.seed[0], s.seed[1], s.seed[2], s.distance, s.tolerance
            )
        })
}

/// The `hausdorff` line: each side's figure, what it is and how it was measured.
fn hausdorff_detail(g: &distance::Geometry) -> String {
    let mut s = format!(
        "two-sided {:.3e} ({:.3e} of the bounding radius); mesh->S max {:.3e} mean {:.3e} \
         ({} samples, {}",
        g.hausdorff,
        g.hausdorff_relative,
        g.mesh_to_surface.max,
        g.mesh_to_surface.mean,
        g.mesh_to_surface.samples,
        g.mesh_to_surface_method,
    );
    if g.projection_failures > 0 {
        s += &format!(
            "; NOT MEASURED at {} samples: no point of S found",
            g.projection_failures
        );
    }
    if g.corrected_projections > 0 {
        s += &format!(
            "; {} projections replaced by a nearer point of S found by rays",
            g.corrected_projections
        );
    }
    if g.bounded_only > 0 {
        s += &format!(
            "; {} samples only bounded above (search budget)",
            g.bounded_only
        );
    }
    s += &format!(
        "); S->mesh max {:.3e} mean {:.3e} ({})",
        g.surface_to_mesh.max, g.surface_to_mesh.mean, g.surface_samples_source
    );
    if let Some(t) = g.trusted.as_ref().filter(|t| t.facets < t.of) {
        s += &format!(
            "; on the {} of {} facets where S is the surface the data shows: the other {} \
             (beyond the data: S there is an extrapolation or the far field's sign boundary) \
             are not measured",
            t.facets,
            t.of,
            t.of - t.facets
        );
    }
    s
}
