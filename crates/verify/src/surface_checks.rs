//! Checks against a surface (ours): geometry, the loose epsilon-sample certificate and
//! condition 2 of definition 2.2, the normal bound of lemma 3.1, theorem 4.7.

use std::sync::Arc;

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
    let ml = opts.max_listed;
    let (normals, hausdorff) = hausdorff_check(r, mesh, bvh, surface, opts);

    // d_M source.
    let dm = dm_source(r, mesh, surface, opts);
    certificate_checks(r, mesh, surface, opts, ml, &dm, hausdorff);

    normals_check(r, mesh, &normals);

    components_sampled_check(r, mesh, bvh, surface, opts, hausdorff);
}

/// Mesh <-> S distances and the `hausdorff` check; gives the normal deviation and the
/// two-sided Hausdorff estimate.
fn hausdorff_check(
    r: &mut Report,
    mesh: &TriMesh,
    bvh: &bvh::TriangleBvh,
    surface: &dyn Surface,
    opts: &Options,
) -> (NormalDeviation, f64) {
    let g = distance::geometry(
        mesh,
        bvh,
        surface,
        opts.samples_per_edge,
        opts.surface_samples.as_deref(),
    );
    let detail = format!(
        "two-sided {:.3e} ({:.3e} of the bounding radius); mesh->S max {:.3e} mean {:.3e} \
         ({} samples, {} projection failures); S->mesh max {:.3e} mean {:.3e} ({})",
        g.hausdorff,
        g.hausdorff_relative,
        g.mesh_to_surface.max,
        g.mesh_to_surface.mean,
        g.mesh_to_surface.samples,
        g.projection_failures,
        g.surface_to_mesh.max,
        g.surface_to_mesh.mean,
        g.surface_samples_source
    );
    match opts.max_hausdorff {
        // A sample that could not be projected has no distance: the estimate would leave it
        // out silently, so it fails the check as much as a distance above the limit.
        Some(m) => r.push(
            "hausdorff",
            pass_fail(g.hausdorff <= m && g.projection_failures == 0),
            format!("{detail}; limit {m}"),
        ),
        None => r.push(
            "hausdorff",
            if g.projection_failures == 0 {
                Status::Info
            } else {
                Status::Fail
            },
            detail,
        ),
    }
    let normals = g.normals.clone();
    let hausdorff = g.hausdorff;
    r.geometry = Some(g);
    (normals, hausdorff)
}

/// The d_M function, its supremum and a description, from [`Options::dm`] (pushes a FAIL
/// `loose-epsilon` check when the pole estimate fails).
fn dm_source(
    r: &mut Report,
    mesh: &TriMesh,
    surface: &dyn Surface,
    opts: &Options,
) -> Option<(DmFn, f64, String)> {
    match &opts.dm {
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
            let samples = opts.surface_samples.as_deref().unwrap_or(&mesh.vertices);
            match MedialAxisEstimate::new(samples, None) {
                Ok(m) => {
                    let sup = samples.iter().map(|&p| m.dm(p)).fold(0.0, f64::max);
                    let n = m.poles.len();
                    let m = Arc::new(m);
                    let f: DmFn = Arc::new(move |x| m.dm(x));
                    Some((
                        f,
                        sup,
                        format!("Voronoi poles of {} samples ({n} poles)", samples.len()),
                    ))
                }
                Err(e) => {
                    r.push("loose-epsilon", Status::Fail, e.to_string());
                    None
                }
            }
        }
    }
}

/// The loose epsilon-sample certificate and theorem 4.7 (or SKIPs without d_M).
fn certificate_checks(
    r: &mut Report,
    mesh: &TriMesh,
    surface: &dyn Surface,
    opts: &Options,
    ml: usize,
    dm: &Option<(DmFn, f64, String)>,
    hausdorff: f64,
) {
    let computed;
    let balls = match &opts.surface_balls {
        Some(b) => b.as_slice(),
        None => {
            computed = if dm.is_some() {
                certificate::surface_delaunay_balls(mesh, surface)
            } else {
                Vec::new()
            };
            &computed
        }
    };
    match dm {
        Some((f, sup, source)) => {
            let cert = certificate::loose_epsilon(
                balls,
                mesh.triangles.len(),
                f.as_ref(),
                opts.epsilon,
                source,
                ml,
            );
            r.push(
                "loose-epsilon",
                pass_fail(cert.passed()),
                format!(
                    "achieved eps {:.4} (max r/d_M(c), at facet {}){}; {} balls, {} facets \
                     without ball, d_M: {}",
                    cert.eps_achieved,
                    cert.worst_facet.map_or("-".to_string(), |f| f.to_string()),
                    match cert.requested_eps {
                        Some(e) =>
                            format!(", requested {e}: {} facets exceed", cert.exceeding_total),
                        None => String::new(),
                    },
                    cert.balls,
                    cert.facets_without_ball,
                    cert.dm_source
                ),
            );
            let hb = certificate::hausdorff_bound(cert.eps_achieved, *sup, hausdorff);
            r.push(
                "theorem-4.7",
                if hb.applicable {
                    pass_fail(hb.holds)
                } else {
                    Status::Info
                },
                format!(
                    "measured Hausdorff {:.3e} vs 4.5 eps^2 d_M^sup = {:.3e} (eps {:.4}, \
                     d_M^sup {:.4}){}",
                    hb.hausdorff,
                    hb.bound,
                    hb.eps,
                    hb.dm_sup,
                    if hb.applicable {
                        ""
                    } else {
                        "; not applicable: eps >= 0.096"
                    }
                ),
            );
            r.certificate = Some(cert);
            r.hausdorff_bound = Some(hb);
        }
        None => {
            if r.check("loose-epsilon").is_none() {
                r.push(
                    "loose-epsilon",
                    Status::Skipped,
                    "no d_M: the surface gives no dm_inf_hint; set Options::dm (command line: --dm poles or --dm VALUE)".into(),
                );
            }
            r.push(
                "theorem-4.7",
                Status::Skipped,
                "needs the certificate's eps and d_M^sup".into(),
            );
        }
    }
}

/// Normals, against lemma 3.1 when the certificate gives rho < 1/7.
fn normals_check(r: &mut Report, mesh: &TriMesh, normals: &NormalDeviation) {
    // Normals, against lemma 3.1 when the certificate gives rho = max r / d_M(c) < 1/7.
    let rho = r
        .certificate
        .as_ref()
        .map(|c| c.eps_achieved)
        .filter(|e| e.is_finite());
    let mut measured = format!(
        "facet normal vs surface gradient at vertices: max {:.3} deg (as lines {:.3} deg), \
         mean {:.3} deg, {} facets facing inward",
        normals.max_deg, normals.max_line_deg, normals.mean_deg, normals.inverted_facets
    );
    if normals.max_uncertainty_deg > 0.0 {
        measured += &format!(
            "; beyond the data's rounding (gradient direction known to {:.3} deg at worst): \
             {:.3} deg",
            normals.max_uncertainty_deg, normals.max_excess_line_deg
        );
    }
    let facets = mesh.triangles.len();
    match rho.and_then(certificate::normal_bound_deg) {
        // Whatever the sampling, a mesh whose facets mostly face inward is inside out.
        _ if facets > 0 && 2 * normals.inverted_facets > facets => r.push(
            "normals",
            Status::Fail,
            format!("{measured}: the mesh is inside out (most facets face against the gradient)"),
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
                match rho {
                    Some(e) => format!("the certificate's rho = {e:.4} is not below 1/7"),
                    None => "no certificate (no d_M)".into(),
                }
            ),
        ),
    }
}

/// Condition 2 of definition 2.2: a mesh point near every seed on S.
fn components_sampled_check(
    r: &mut Report,
    mesh: &TriMesh,
    bvh: &bvh::TriangleBvh,
    surface: &dyn Surface,
    opts: &Options,
    hausdorff: f64,
) {
    // Condition 2 of definition 2.2.
    let seeds = match &opts.component_seeds {
        Some(s) => s.clone(),
        None => surface.seed_points(opts.seed),
    };
    let radius = surface.bounding_sphere().radius;
    let tol = opts
        .seed_tolerance
        .unwrap_or((2.0 * hausdorff).max(1e-3 * radius));
    let dist = MeshDistance::new(mesh, bvh);
    let cov = certificate::component_coverage(&dist, &seeds, tol);
    r.push(
        "components-sampled",
        pass_fail(cov.uncovered == 0 && !seeds.is_empty()),
        if seeds.is_empty() {
            "no seed points on S to check against".into()
        } else {
            format!(
                "{} of {} seed points of S farther than {:.3e} from the mesh",
                cov.uncovered,
                seeds.len(),
                tol
            )
        },
    );
    r.components_sampled = Some(cov);
}
