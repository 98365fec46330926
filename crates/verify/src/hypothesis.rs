//! Section 4's hypothesis against its consequences (ours): theorems 4.4 to 4.7 and lemma 3.1
//! hold for a loose eps-sample with respect to the *true* d_M. When `verify` takes d_M from an
//! estimate (the surface's d_M^inf hint, [`DmSource::Auto`]: an image's distance-map estimate,
//! clamped at one voxel; a point set's; the chair's upper estimate; or the Voronoi poles of
//! the mesh, [`DmSource::Poles`]), the `loose-epsilon` certificate holds for the estimate only.
//! Where S is thinner than the estimate, the theorems' consequences can fail while the
//! certificate PASSes: nibabel's `resampled_anat_moved.nii` (its NaN voxels given 0) at iso
//! 5000 and the default size (sigma = 0.09 x the image's estimate, 4 mm) said `loose-epsilon`
//! PASS "theorems 4.4 to 4.7 apply" next to `theorem-4.7` FAIL (a tongue of S 1.2 mm long,
//! about 0.16 voxel, 1.4 mm from the mesh; bound 0.146) and `normals` FAIL at the same place.
//!
//! Rule: with an estimated d_M, when `loose-epsilon` PASSes and `theorem-4.7` or `normals`
//! (lemma 3.1's bound, not an inside-out mesh) FAILs, the failed consequence shows the
//! estimate too large somewhere, so the hypothesis is not met:
//! - eps derived from the size (`Options::epsilon_derived`, or none: nothing was asked):
//!   the three checks are INFO "no guarantee", with the evidence;
//! - eps asked for (`--epsilon`, `--certify-epsilon`): `loose-epsilon` FAILs (E is not a
//!   loose eps-sample of S for its true d_M), and the consequences keep their FAIL.
//!
//! A d_M given by the user (`--dm VALUE`, [`DmSource::Constant`], [`DmSource::Function`]) is
//! asserted, not estimated: its consequences FAIL as measured.

use crate::{DmSource, Options, Report, Status};

/// The words of a `normals` FAIL whatever the sampling (an inside-out mesh): written by
/// `surface_checks`, and that FAIL is left alone here.
pub(crate) const INSIDE_OUT: &str = "the mesh is inside out";

/// The clause of a passing `loose-epsilon` line that claims the theorems.
const APPLY: &str = "theorems 4.4 to 4.7 apply";

/// Whether `opts` takes d_M from an estimate.
fn estimated(opts: &Options) -> bool {
    matches!(opts.dm, DmSource::Auto | DmSource::Poles)
}

/// The failed consequences of the hypothesis, said for the user (empty: none failed).
fn evidence(r: &Report) -> Vec<String> {
    let mut out = Vec::new();
    if r.status("theorem-4.7") == Some(Status::Fail) {
        let b = r.hausdorff_bound.as_ref();
        let at = r
            .geometry
            .as_ref()
            .and_then(|g| g.surface_to_mesh.argmax)
            .map_or(String::new(), |p| {
                format!(
                    "; the point of S farthest from the mesh at ({:.4}, {:.4}, {:.4})",
                    p[0], p[1], p[2]
                )
            });
        out.push(format!(
            "theorem 4.7's bound is exceeded (measured Hausdorff {:.3e} > {:.3e}{at})",
            b.map_or(f64::NAN, |b| b.hausdorff),
            b.map_or(f64::NAN, |b| b.bound)
        ));
    }
    let normals = r.check("normals");
    if normals.is_some_and(|c| c.status == Status::Fail && !c.detail.contains(INSIDE_OUT)) {
        out.push("lemma 3.1's normal bound is exceeded (see `normals`)".into());
    }
    out
}

/// Apply the rule of the module docs to the checks `loose-epsilon`, `theorem-4.7` and
/// `normals` of `r`, already pushed.
pub(crate) fn reconcile(r: &mut Report, opts: &Options) {
    if !estimated(opts) || r.status("loose-epsilon") != Some(Status::Pass) {
        return;
    }
    let ev = evidence(r);
    if ev.is_empty() {
        return;
    }
    let why = format!(
        "d_M here is an estimate ({}) and the theorems' consequences fail: {}; so S is thinner \
         than the estimate somewhere (a part the size does not resolve)",
        r.certificate
            .as_ref()
            .map_or("the surface's hint", |c| c.dm_source.as_str()),
        ev.join("; ")
    );
    r.dm_estimate_contradicted = true;
    let asked = opts.epsilon.is_some() && !opts.epsilon_derived;
    for c in r.checks.iter_mut() {
        match (c.name.as_str(), c.status) {
            ("loose-epsilon", Status::Pass) => {
                let kept = c.detail.replace(APPLY, "the theorems would apply");
                if asked {
                    c.status = Status::Fail;
                    c.detail = format!(
                        "{kept}; but {why}: E is not a loose eps-sample of S for its true d_M"
                    );
                } else {
                    c.status = Status::Info;
                    c.detail =
                        format!("{kept}; no guarantee: {why}; a smaller --size resolves more of S");
                }
            }
            ("theorem-4.7" | "normals", Status::Fail) if !asked => {
                if c.name == "normals" && c.detail.contains(INSIDE_OUT) {
                    continue;
                }
                c.status = Status::Info;
                c.detail = format!(
                    "{}; no guarantee: the bound assumes the estimated d_M, which S does not \
                     have everywhere (see loose-epsilon)",
                    c.detail
                );
            }
            _ => {}
        }
    }
}
