//! The default size of a mesh or a point set, checked against the data (ours; section 6.5's
//! sigma needs d_M^inf, which a mesh with thin parts or a scan does not give): the input's
//! suggested size (its bounding-box diagonal / 50, or the scan's spacing) does not look at
//! thin parts, and a part thinner than the size can have no mesh at all. Measured
//! (2026-12-06): `pymeshlab`'s `cow.obj` at its suggested size 0.043 had no mesh on three
//! lower legs, about 0.07 across, nor on the ears and horn tips (`data-support` FAILed:
//! eight data regions lost, up to 4.4 median edges from the mesh); at 0.02, none lost.
//!
//! Rule: without `--size`, when the output loses a region of the data (what FAILs
//! `data-support`: `verify::data_support::lost_regions`), the size is halved and the input
//! meshed again, at most [`HALVINGS`] times, each forecasting at most the default size's
//! 100k vertices and within the budgets (else it is not made, and a note says why); each
//! halving is a note. A requested size is kept as asked: its lost
//! regions FAIL the check and say to try a smaller `--size`.
//!
//! Cost: with `verify` on, the lost regions are the report's (nothing measured twice; each
//! halving verifies its mesh once more); with `--no-verify`, the data-support measure alone:
//! fertility at its default size (95k samples) took 0.40-0.47 s and now 0.69-0.74 s.
//!
//! Budgets: `--time-limit` bounds the whole run, every halving included (each gets the time
//! left); a mesh stopped by a budget is not halved (its missing parts are the budget's), and
//! when the run at the halved size is stopped by one, the previous mesh is kept.
//!
//! Invariant: deterministic (the same meshes at the same sizes, the check's order).

use meshio::TriMesh;
use verify::data_support::UncoveredRegion;

use super::request::{Request, SizeRequest};
use super::{Input, InputKind};

/// Halvings of the default size at most (the vertex count grows up to 4^HALVINGS times).
pub(crate) const HALVINGS: usize = 2;

/// Without a requested size, on a mesh or a point set (the inputs with data to check).
pub(crate) fn applies(input: &Input, request: &Request) -> bool {
    matches!(request.size, SizeRequest::Auto)
        && matches!(input.kind, InputKind::Polyhedron | InputKind::PointSet)
        && input.support_data.is_some()
}

/// A halved size's forecast within the default size's limit
/// ([`super::AUTO_MAX_VERTICES`]) and the mesher's vertex cap `cap`; without a forecast, yes
/// (the budgets are checked while meshing).
pub(crate) fn affordable(forecast: Option<&super::Forecast>, cap: usize) -> bool {
    forecast.is_none_or(|f| f.vertices <= super::AUTO_MAX_VERTICES.min(cap as u64))
}

/// The first lost data region of a verified mesh's report, if any.
pub(crate) fn reported_lost(report: &verify::Report) -> Option<UncoveredRegion> {
    let ds = report.data_support.as_ref()?;
    ds.uncovered_regions.first().filter(|r| r.lost()).cloned()
}

/// The first data region `mesh` (meshed at `sigma`) loses, if any.
pub(crate) fn first_lost(input: &Input, mesh: &TriMesh, sigma: f64) -> Option<UncoveredRegion> {
    let data = input.support_data.as_deref()?;
    let opts = super::unsupported::support_options(input, sigma);
    verify::data_support::lost_regions(mesh, data, &opts)
        .into_iter()
        .next()
}

/// The note of a halving from `sigma`.
pub(crate) fn halving(sigma: f64, lost: &UncoveredRegion) -> String {
    format!(
        "size {sigma:.5} lost a part of the data ({}): meshing again at {:.5}",
        located(lost),
        0.5 * sigma
    )
}

/// The budget that stopped a run (`--max-vertices`, `--time-limit`, an interrupt), if any:
/// its missing parts are the budget's, and a finer size would stop sooner. A stalled
/// manifold patch is not a budget (a finer size can mend it).
pub(crate) fn budget_stop(stats: &crate::Stats) -> Option<&crate::StopReason> {
    stats.stopped_by.as_ref().filter(|r| r.is_budget())
}

/// The note when the mesh at `sigma` was stopped by the budget `why`: the size stays.
pub(crate) fn stopped(sigma: f64, why: &crate::StopReason) -> String {
    format!(
        "size {sigma:.5}: the run stopped at {why} before the criteria were met, so the size is \
         not halved (a finer size would stop sooner)"
    )
}

/// The note when no time is left of `--time-limit` (`limit` seconds) to mesh again at half
/// `sigma`: the mesh at `sigma` is kept.
pub(crate) fn no_time_left(sigma: f64, lost: &UncoveredRegion, limit: f64) -> String {
    format!(
        "size {sigma:.5} lost a part of the data ({}); no time is left of --time-limit \
         ({limit:.3} s) to mesh again at {:.5}, so the mesh at {sigma:.5} is kept",
        located(lost),
        0.5 * sigma
    )
}

/// The note when the run at half `sigma` was stopped by the budget `why` and the mesh at
/// `sigma` is kept.
pub(crate) fn halving_stopped(
    sigma: f64,
    lost: &UncoveredRegion,
    why: &crate::StopReason,
) -> String {
    format!(
        "size {sigma:.5} lost a part of the data ({}); meshing again at {:.5} stopped at {why} \
         before the criteria were met, so the mesh at {sigma:.5} is kept",
        located(lost),
        0.5 * sigma
    )
}

/// The time left of `limit` since `start` (`None` without a limit; zero when spent).
pub(crate) fn time_left(
    start: std::time::Instant,
    limit: Option<std::time::Duration>,
) -> Option<std::time::Duration> {
    limit.map(|t| t.saturating_sub(start.elapsed()))
}

/// The note when the budgets refuse the halving from `sigma`.
pub(crate) fn over_budget(sigma: f64, lost: &UncoveredRegion) -> String {
    format!(
        "size {sigma:.5} lost a part of the data ({}); {:.5} forecasts more than the default \
         size's limit of 100k vertices or the budgets (--max-vertices, --max-memory), so the \
         size stays: request a --size to go finer",
        located(lost),
        0.5 * sigma
    )
}

fn located(r: &UncoveredRegion) -> String {
    format!(
        "{} points, {:.3e} across, at ({:.4}, {:.4}, {:.4}), {:.1} median edges from the mesh",
        r.points, r.extent, r.centroid[0], r.centroid[1], r.centroid[2], r.distance_in_edges
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The time left of `--time-limit` after some of it is spent, and none once it is.
    #[test]
    fn a_halving_gets_the_time_left() {
        use std::time::{Duration, Instant};
        let start = Instant::now() - Duration::from_secs(3);
        let left = time_left(start, Some(Duration::from_secs(10))).unwrap();
        assert!(
            left <= Duration::from_secs(7) && left > Duration::from_secs(5),
            "{left:?}"
        );
        assert_eq!(
            time_left(start, Some(Duration::from_secs(2))),
            Some(Duration::ZERO)
        );
        assert_eq!(time_left(start, None), None);
    }
}
