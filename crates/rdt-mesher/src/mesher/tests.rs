//! Unit tests of the run as a whole: the scaffold's fallback, budget stops, lazy balls, and
//! `Mesher::validate` (the incremental Del_S(E) against a full recomputation).

use super::*;
use crate::{Criteria, OracleKind, Sizing, Unmet};
use glam::DVec3;
use oracle::catalog;

fn torus_opts() -> MeshOptions {
    MeshOptions {
        criteria: Criteria {
            size: Some(Sizing::Constant(0.05)),
            min_angle_deg: 30.0,
            max_distance: None,
        },
        ..Default::default()
    }
}

/// The scaffold is used on the torus, and its fallback (the triangulation rebuilt from the
/// samples alone, refinement resumed) leaves a consistent Del_S(E) and a valid mesh.
#[test]
fn scaffold_rebuild_resumes_the_plain_algorithm() {
    let s = catalog::surface("torus").unwrap();
    let opts = torus_opts();
    let mut r = Mesher::new(&s, &opts);
    r.run(&mut |_| {}).unwrap();
    assert!(r.stats.scaffold_points > 0);
    assert!(r.scaffold.is_clear(&r.restricted, &r.tri, &r.voronoi));
    let samples = r.sample_points();
    r.drop_scaffold().unwrap();
    assert_eq!(r.tri.num_vertices(), samples);
    assert_eq!(r.scaffold.count(), 0);
    r.refine_loop(&mut |_| {}).unwrap();
    assert_eq!(r.stats.scaffold_rebuilds, 1);
    r.validate().unwrap();
    let out = r.finish().unwrap();
    assert!(out.stats.criteria_met, "{:?}", out.stats.unmet);
    assert_eq!(
        crate::topology::nonmanifold_elements(&out.mesh.triangles),
        (vec![], vec![])
    );
    let v = out.mesh.vertices.len() as i64;
    let f = out.mesh.triangles.len() as i64;
    assert_eq!(v - f / 2, 0, "Euler characteristic of a torus"); // V - E + F, E = 3F/2
    for p in &out.mesh.vertices {
        assert!(s.value(*p).abs() < 1e-5);
    }
}

/// A run stopped early by a budget, while facets at scaffold points remain, leaves them out
/// of the mesh (every output vertex is on S) and says so among the unmet criteria.
#[test]
fn budget_stop_leaves_scaffold_facets_out() {
    let s = catalog::surface("torus").unwrap();
    let mut saw_scaffold_facets = false;
    for max in [120, 200, 400, 800] {
        let out = mesh(
            &s,
            &MeshOptions {
                max_vertices: Some(max),
                ..torus_opts()
            },
        )
        .unwrap();
        assert!(out.stats.stopped_by.is_some());
        assert!(out.stats.scaffold_points > 0);
        for p in out.mesh.vertices.iter().chain(&out.sample) {
            assert!(s.value(*p).abs() < 1e-5, "{p} is not on S");
        }
        saw_scaffold_facets |= out
            .stats
            .unmet
            .iter()
            .any(|u| matches!(u, Unmet::Scaffold { .. }));
    }
    assert!(
        saw_scaffold_facets,
        "no budget stopped with facets at scaffold points"
    );
}

/// Every surface Delaunay ball of `out` is centered on S and passes through its facet's
/// vertices (a lazy facet resolved: no NaN or placeholder left).
fn assert_balls_on_s(s: &dyn Surface, out: &MeshResult) {
    assert_eq!(out.balls.len(), out.mesh.triangles.len());
    for (t, b) in out.mesh.triangles.iter().zip(&out.balls) {
        assert!(b.center.is_finite() && b.radius > 0.0, "{b:?}");
        assert!(s.value(b.center).abs() < 1e-5, "center {} off S", b.center);
        for &v in t {
            let d = out.mesh.vertices[v as usize].distance(b.center);
            assert!(
                (d - b.radius).abs() <= 1e-9 * b.radius.max(1.0),
                "{d} vs {b:?}"
            );
        }
    }
}

/// Delaying the crossing of facets known bad without it changes the refinement order
/// only: both runs meet the criteria with a valid Del_S(E) (`validate`) and balls on S, at
/// sizes within 5%, and the lazy run calls the crossing oracle less.
#[test]
fn lazy_balls_change_the_order_not_the_guarantees() {
    let s = catalog::surface("torus").unwrap();
    let opts = torus_opts();
    let mut runs = Vec::new();
    for lazy in [false, true] {
        let mut r = Mesher::new(&s, &opts);
        r.lazy_balls = lazy;
        r.run(&mut |_| {}).unwrap();
        if let Err(e) = r.validate() {
            panic!("lazy {lazy}: {e}");
        }
        let out = r.finish().unwrap();
        assert!(out.stats.criteria_met, "lazy {lazy}: {:?}", out.stats.unmet);
        assert_balls_on_s(&s, &out);
        runs.push((out.stats.vertices, out.stats.oracle_crossing_calls));
    }
    let (eager, lazy) = (runs[0], runs[1]);
    let ratio = lazy.0 as f64 / eager.0 as f64;
    assert!(
        (0.95..=1.05).contains(&ratio),
        "sizes {eager:?} vs {lazy:?}"
    );
    assert!(lazy.1 < eager.1, "crossing calls {eager:?} vs {lazy:?}");
}

/// A budget stop leaves lazy facets in Del_S(E): `finish` computes their balls.
#[test]
fn budget_stop_resolves_lazy_balls() {
    let s = catalog::surface("torus").unwrap();
    for max in [150, 700] {
        let opts = MeshOptions {
            max_vertices: Some(max),
            scaffold: false,
            ..torus_opts()
        };
        let mut r = Mesher::new(&s, &opts);
        r.run(&mut |_| {}).unwrap();
        let lazy = r.restricted.iter().filter(|(_, _, f)| f.lazy).count();
        assert!(lazy > 0, "max {max}: no lazy facet left to resolve");
        let out = r.finish().unwrap();
        assert!(out.stats.stopped_by.is_some());
        assert_balls_on_s(&s, &out);
    }
}

/// Scaffold or not, the output is a mesh of S: every vertex on S, the same topology, and
/// sizes within a few percent.
#[test]
fn scaffold_changes_speed_not_the_result() {
    let s = catalog::surface("torus").unwrap();
    let on = mesh(&s, &torus_opts()).unwrap();
    let off = mesh(
        &s,
        &MeshOptions {
            scaffold: false,
            ..torus_opts()
        },
    )
    .unwrap();
    assert!(on.stats.scaffold_points > 0);
    assert_eq!(off.stats.scaffold_points, 0);
    for out in [&on, &off] {
        assert!(out.stats.criteria_met);
        assert_eq!(out.stats.sample_points, out.mesh.vertices.len());
        assert_eq!(out.sample.len(), out.stats.sample_points);
        for p in out.mesh.vertices.iter().chain(&out.sample) {
            assert!(s.value(*p).abs() < 1e-5);
        }
    }
    let (a, b) = (
        on.mesh.vertices.len() as f64,
        off.mesh.vertices.len() as f64,
    );
    assert!((a / b - 1.0).abs() < 0.05, "{a} vs {b} vertices");
}

/// Analytic surfaces through `oracle`'s trait only (shared with the integration tests).
#[path = "../../tests/common/analytic.rs"]
mod analytic;
use analytic::{ellipsoid, in_pool, sphere, torus};

/// Run the refinement on `s`, then check Del(E), the Voronoi cache and Del_S(E) against a
/// recomputation from scratch.
fn run_and_validate(s: &dyn Surface, opts: &MeshOptions) -> Result<(), String> {
    opts.validate().unwrap();
    let mut r = Mesher::new(s, opts);
    r.run(&mut |_| {}).unwrap();
    r.validate()
}

#[test]
fn incremental_update_equals_full_recomputation() {
    // The invariant of `crate::restricted`: after every insertion only changed Voronoi edges
    // are re-tested, and the result equals a from-scratch recomputation of Del_S(E).
    for (sigma, oracle) in [
        (0.03, OracleKind::Bipolar),
        (0.08, OracleKind::Intersection),
    ] {
        let opts = MeshOptions {
            criteria: Criteria::uniform(sigma),
            oracle,
            ..Default::default()
        };
        run_and_validate(&sphere(), &opts).unwrap();
        run_and_validate(&torus(), &opts).unwrap();
    }
}

/// Batched refinement on 4 threads (full batches at ~9k vertices, both oracles; see
/// `tests/refine.rs` for the same mesh on 1 and 4 threads) keeps Del(E) and Del_S(E) exact.
#[test]
fn batched_refinement_keeps_del_s_exact() {
    for oracle in [OracleKind::Bipolar, OracleKind::Intersection] {
        let opts = MeshOptions {
            criteria: Criteria::uniform(0.03),
            oracle,
            ..Default::default()
        };
        in_pool(4, || run_and_validate(&torus(), &opts)).unwrap();
    }
}

mod props {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 12, .. ProptestConfig::default() })]

        /// Random ellipsoids (axes in [0.4, 1.2], random center and seed; as in
        /// `tests/refine.rs`): the incremental restricted complex equals a recomputation
        /// from scratch.
        #[test]
        fn random_ellipsoids_keep_del_s_exact(ax in 0.4f64..1.2, ay in 0.4f64..1.2,
                                              az in 0.4f64..1.2, cx in -0.5f64..0.5,
                                              seed in 0u64..1000) {
            let s = ellipsoid(DVec3::new(ax, ay, az), cx);
            let opts = MeshOptions {
                criteria: Criteria::uniform(0.12),
                seed,
                ..Default::default()
            };
            prop_assert_eq!(run_and_validate(&s, &opts), Ok(()));
        }
    }
}

/// The spatial queue order from the start (`spatial_order_from: 0`): a closed manifold of
/// the torus's genus meeting every criterion, a Del_S(E) equal to a full recomputation, the
/// same mesh on one thread and on four, and a mesh different from the worst-first order's
/// (the option is not a no-op).
#[test]
fn spatial_order_keeps_the_criteria_and_is_deterministic() {
    let s = catalog::surface("torus").unwrap();
    let opts = MeshOptions {
        spatial_order_from: 0,
        ..torus_opts()
    };
    let run = |threads: usize, opts: &MeshOptions| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut r = Mesher::new(&s, opts);
            r.run(&mut |_| {}).unwrap();
            assert_eq!(r.queue.is_spatial(), opts.spatial_order_from == 0);
            r.validate().unwrap();
            r.finish().unwrap()
        })
    };
    let one = run(1, &opts);
    let four = run(4, &opts);
    assert_eq!(one.mesh.vertices, four.mesh.vertices);
    assert_eq!(one.mesh.triangles, four.mesh.triangles);
    assert!(one.stats.criteria_met, "{:?}", one.stats.unmet);
    assert!(one.stats.max_r_over_sigma.unwrap() <= 1.0);
    assert!(one.stats.min_angle_deg >= 30.0);
    assert_eq!(
        crate::topology::nonmanifold_elements(&one.mesh.triangles),
        (vec![], vec![])
    );
    let (v, f) = (
        one.mesh.vertices.len() as i64,
        one.mesh.triangles.len() as i64,
    );
    assert_eq!(v - f / 2, 0, "Euler characteristic of a torus (E = 3F/2)");
    let worst_first = run(
        2,
        &MeshOptions {
            spatial_order_from: usize::MAX,
            ..torus_opts()
        },
    );
    assert_ne!(one.mesh.triangles, worst_first.mesh.triangles);
}
