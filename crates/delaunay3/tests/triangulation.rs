mod common;

use common::*;
use delaunay3::predicates::{Sign, orient3d};
use delaunay3::{Changes, DVec3, Dual, Error, Facet, Insertion, Location, Triangulation, VertexId};
use proptest::prelude::*;

fn uniform(n: usize, seed: u64) -> Vec<DVec3> {
    let mut r = Rng(seed);
    (0..n).map(|_| cube_point(&mut r)).collect()
}

#[test]
fn random_points_one_by_one_and_bulk() {
    let pts = uniform(3000, 1);
    let t = bulk_agrees_with_one_by_one(&pts);
    // Euler-type sanity for points in general position: ~6.5 tets per vertex.
    let ratio = t.num_finite_cells() as f64 / pts.len() as f64;
    assert!((5.0..8.0).contains(&ratio), "{ratio}");
}

#[test]
fn deterministic_bulk() {
    let pts = uniform(2000, 9);
    let mut a = Triangulation::new();
    let mut b = Triangulation::new();
    let ia = a.insert_bulk(&pts).unwrap();
    let ib = b.insert_bulk(&pts).unwrap();
    assert_eq!(ia, ib);
    let ca: Vec<_> = a.finite_cells().map(|c| a.cell_vertices(c)).collect();
    let cb: Vec<_> = b.finite_cells().map(|c| b.cell_vertices(c)).collect();
    assert_eq!(ca, cb);
}

#[test]
fn invalid_points_are_errors() {
    let mut t = Triangulation::new();
    for p in [
        DVec3::new(f64::NAN, 0.0, 0.0),
        DVec3::new(0.0, f64::INFINITY, 0.0),
        DVec3::new(0.0, 0.0, f64::NEG_INFINITY),
        DVec3::new(1e70, 0.0, 0.0),
        DVec3::new(0.0, 1e-50, 0.0),
    ] {
        let e = t.insert(p).unwrap_err();
        assert!(matches!(e, Error::InvalidPoint(_)));
        assert!(e.to_string().contains("2^200"), "{e}");
    }
    assert_eq!(t.num_vertices(), 0);
    let mut pts = uniform(10, 3);
    pts[7].y = f64::NAN;
    assert!(t.insert_bulk(&pts).is_err());
    assert_eq!(t.num_vertices(), 0, "bulk insertion is all or nothing");
    let pts = uniform(10, 3);
    t.insert_bulk(&pts).unwrap();
    assert!(t.insert(DVec3::new(f64::NAN, 0.5, 0.5)).is_err());
    assert!(t.locate(DVec3::new(f64::NAN, 0.5, 0.5), None).is_err());
    assert!(
        t.conflict_zone(DVec3::new(f64::NAN, 0.5, 0.5), None)
            .is_err()
    );
    assert!(t.is_valid().is_ok());
}

#[test]
fn degenerate_starts() {
    let mut t = Triangulation::new();
    assert_eq!(t.dimension(), -1);
    assert_eq!(
        t.insert(DVec3::ZERO).unwrap(),
        Insertion::New(VertexId::from_index(0))
    );
    assert_eq!(
        t.insert(DVec3::ZERO).unwrap(),
        Insertion::Duplicate(VertexId::from_index(0))
    );
    assert_eq!(
        t.insert(DVec3::new(-0.0, 0.0, 0.0)).unwrap(),
        Insertion::Duplicate(VertexId::from_index(0))
    );
    assert_eq!(t.dimension(), 0);
    for i in 1..20 {
        t.insert(DVec3::new(i as f64, 0.0, 0.0)).unwrap();
    }
    assert_eq!(t.dimension(), 1);
    for i in 0..20 {
        for j in 1..5 {
            t.insert(DVec3::new(i as f64, j as f64, 0.0)).unwrap();
        }
    }
    assert_eq!(t.dimension(), 2);
    assert_eq!(t.num_finite_cells(), 0);
    assert!(t.is_valid().is_ok());
    assert_eq!(
        t.insert(DVec3::new(3.0, 2.0, 0.0)).unwrap(),
        Insertion::Duplicate(VertexId::from_index(33))
    );
    let mut ch = Changes::default();
    let r = t
        .insert_with(DVec3::new(2.5, 1.5, 1.0), None, Some(&mut ch))
        .unwrap();
    assert_eq!(r, Insertion::New(VertexId::from_index(100)));
    assert_eq!(t.dimension(), 3);
    assert!(t.is_valid().is_ok());
    assert_eq!(ch.created.len(), t.num_cells());
    assert!(ch.removed.is_empty());
    assert_eq!(t.num_vertices(), 101);
    // A cone over 100 coplanar points: at least 100 - 2 triangles in the base.
    assert!(t.num_finite_cells() >= 98);
    assert_eq!(
        t.insert(DVec3::new(3.0, 2.0, 0.0)).unwrap(),
        Insertion::Duplicate(VertexId::from_index(33))
    );
    for v in (0..101).map(VertexId::from_index) {
        assert!(t.vertex_cell(v).is_some());
    }
}

#[test]
fn changes_match_conflict_zone_and_star() {
    let pts = uniform(500, 4);
    let mut t = Triangulation::new();
    t.insert_bulk(&pts[..400]).unwrap();
    let mut ch = Changes::default();
    let mut r = Rng(77);
    // Inside, outside the hull, and on existing vertices.
    let mut queries: Vec<DVec3> = pts[400..].to_vec();
    queries.extend((0..50).map(|_| cube_point(&mut r) * 3.0 - DVec3::ONE));
    queries.extend_from_slice(&pts[..20]);
    for p in queries {
        let (zone, boundary) = t.conflict_zone(p, None).unwrap();
        let mut before: Vec<[VertexId; 4]> = zone.iter().map(|&c| t.cell_vertices(c)).collect();
        let res = t.insert_with(p, None, Some(&mut ch)).unwrap();
        match res {
            Insertion::Duplicate(_) => {
                assert!(zone.is_empty() && ch.removed.is_empty() && ch.created.is_empty());
            }
            Insertion::New(v) => {
                let mut removed = ch.removed.clone();
                before.sort_unstable();
                removed.sort_unstable();
                assert_eq!(before, removed);
                assert_eq!(boundary.len(), ch.created.len());
                let mut star = t.incident_cells(v);
                star.sort_unstable();
                let mut created = ch.created.clone();
                created.sort_unstable();
                assert_eq!(star, created);
                for &c in &created {
                    assert!(t.cell_vertices(c).contains(&v));
                }
            }
        }
    }
    assert!(t.is_valid().is_ok());
}

#[test]
fn facet_orientation_and_duals() {
    let pts = uniform(300, 5);
    let mut t = Triangulation::new();
    t.insert_bulk(&pts).unwrap();
    let (mut segs, mut rays, mut nones) = (0, 0, 0);
    for c in t.live_cells().collect::<Vec<_>>() {
        for i in 0..4u8 {
            let f = Facet { cell: c, index: i };
            let m = t.mirror_facet(f);
            assert_eq!(t.mirror_facet(m), f);
            let fv = t.facet_vertices(f);
            // Same facet, opposite orientation from the other side.
            let mv = t.facet_vertices(m);
            let mut a = fv;
            let mut b = mv;
            a.sort_unstable();
            b.sort_unstable();
            assert_eq!(a, b);
            let opp = t.cell_vertices(c)[i as usize];
            if !fv.contains(&VertexId::INFINITE) {
                let [p, q, r] = fv.map(|v| t.point(v));
                // The normal points away from the opposite vertex (or from infinity).
                if opp != VertexId::INFINITE {
                    assert_eq!(orient3d(p, q, r, t.point(opp)), Sign::Positive);
                }
                let w = t.cell_vertices(m.cell)[m.index as usize];
                if w != VertexId::INFINITE {
                    assert_eq!(orient3d(p, q, r, t.point(w)), Sign::Negative);
                }
            }
            match t.dual(f) {
                None => {
                    nones += 1;
                    assert!(fv.contains(&VertexId::INFINITE));
                }
                Some(Dual::Segment(a, b)) => {
                    segs += 1;
                    assert_eq!(a, t.circumcenter(c));
                    assert_eq!(b, t.circumcenter(m.cell));
                }
                Some(Dual::Ray { origin, direction }) => {
                    rays += 1;
                    let fin = if t.is_infinite(c) { m } else { f };
                    assert_eq!(origin, t.circumcenter(fin.cell));
                    // Points away from the hull: against every point, not just the cell.
                    let [p, _, _] = t.facet_vertices(fin).map(|v| t.point(v));
                    for &q in &pts {
                        assert!(direction.dot(q - p) <= 1e-12 * direction.length());
                    }
                }
            }
        }
    }
    assert!(segs > 0 && rays > 0 && nones > 0);
    // Each facet with a dual appears twice in the loop above, once in finite_facets().
    let ff: Vec<Facet> = t.finite_facets().collect();
    assert_eq!(2 * ff.len(), segs + rays);
    for f in ff {
        assert!(t.dual(f).is_some());
    }
}

#[test]
fn circumcenters_are_equidistant() {
    let pts = uniform(500, 6);
    let mut t = Triangulation::new();
    t.insert_bulk(&pts).unwrap();
    for c in t.finite_cells() {
        let cc = t.circumcenter(c);
        let d = t.cell_vertices(c).map(|v| t.point(v).distance(cc));
        for k in 1..4 {
            assert!((d[k] - d[0]).abs() <= 1e-9 * d[0], "{d:?}");
        }
    }
    // A sliver: nearly flat, circumcenter far from the points but still equidistant.
    let e = 1e-9;
    let q = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 1.0, e),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 2.0 * e),
    ];
    let cc = delaunay3::circumcenter(q[0], q[1], q[2], q[3]);
    let d = q.map(|p| p.distance(cc));
    for k in 1..4 {
        assert!((d[k] - d[0]).abs() <= 1e-6 * d[0], "{d:?}");
    }
}

#[test]
fn nearest_vertex_matches_brute_force() {
    let pts = uniform(800, 8);
    let mut t = Triangulation::new();
    t.insert_bulk(&pts).unwrap();
    let mut r = Rng(3);
    for _ in 0..300 {
        let q = cube_point(&mut r) * 1.4 - DVec3::splat(0.2);
        let v = t.nearest_vertex(q, None).unwrap();
        let best = pts
            .iter()
            .map(|p| p.distance_squared(q))
            .fold(f64::INFINITY, f64::min);
        assert_eq!(t.point(v).distance_squared(q), best);
    }
    match t.locate(pts[5], None).unwrap() {
        Location::Vertex(v) => assert_eq!(t.point(v), pts[5]),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        t.locate(DVec3::splat(7.0), None).unwrap(),
        Location::Outside(_)
    ));
}

#[test]
fn exact_sphere_points() {
    // 3^2 * 11 = 99 has many representations; all points exactly cospherical.
    for (r2, s, o) in [
        (99, 1.0, DVec3::ZERO),
        (81, 0.125, DVec3::new(3.0, -5.0, 1.0)),
        (2 * 25 * 9, 1.0, DVec3::new(0.5, 0.25, 0.0)),
    ] {
        let pts = sphere_points(r2, s, o);
        assert!(pts.len() > 20);
        let t = build_checked(&pts);
        let mut b = Triangulation::new();
        b.insert_bulk(&pts).unwrap();
        assert!(b.is_valid().is_ok());
        assert_eq!(
            tets_by_points(&t),
            tets_by_points(&b),
            "perturbation is order-free"
        );
        // Plus the center: the cells are then all incident to it.
        let mut c = b.clone();
        let Insertion::New(v) = c.insert(o).unwrap() else {
            panic!()
        };
        assert!(c.is_valid().is_ok());
        // Every tetrahedron had the sphere as circumsphere: all now join the center.
        assert_eq!(c.incident_cells(v).len(), c.num_finite_cells());
    }
}

#[test]
fn grid_points_all_orders() {
    let pts = grid(6);
    let a = build_checked(&pts);
    let mut rev = pts.clone();
    rev.reverse();
    let b = build_checked(&rev);
    let mut c = Triangulation::new();
    c.insert_bulk(&pts).unwrap();
    assert!(c.is_valid().is_ok());
    assert_eq!(tets_by_points(&a), tets_by_points(&b));
    assert_eq!(tets_by_points(&a), tets_by_points(&c));
    // Volume of the tetrahedra equals the volume of the cube: a proper tessellation.
    let vol: f64 = a
        .finite_cells()
        .map(|cl| {
            let q = a.cell_vertices(cl).map(|v| a.point(v));
            (q[1] - q[0]).dot((q[2] - q[0]).cross(q[3] - q[0])).abs() / 6.0
        })
        .sum();
    assert!((vol - 125.0).abs() < 1e-9, "{vol}");
}

#[test]
fn coplanar_then_off_plane_and_slivers() {
    let mut r = Rng(11);
    let mut pts: Vec<DVec3> = (0..300)
        .map(|_| DVec3::new(r.next_f64(), r.next_f64(), 0.0))
        .collect();
    pts.push(DVec3::new(0.3, 0.3, 1.0));
    let t = build_checked(&pts);
    assert_eq!(t.dimension(), 3);
    // Nearly coplanar: tiny heights.
    let slivers: Vec<DVec3> = (0..400)
        .map(|_| DVec3::new(r.next_f64(), r.next_f64(), (r.next_f64() - 0.5) * 1e-13))
        .collect();
    build_checked(&slivers);
    // Two parallel planes of grid points (very many coplanar hull facets).
    let mut two = Vec::new();
    for x in 0..10 {
        for y in 0..10 {
            two.push(DVec3::new(x as f64, y as f64, 0.0));
            two.push(DVec3::new(x as f64 + 0.5, y as f64, 1.0));
        }
    }
    build_checked(&two);
}

#[test]
fn hull_points_on_hull_planes() {
    // Points inserted later exactly on the planes of hull facets, inside and outside them.
    let mut pts = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(4.0, 0.0, 0.0),
        DVec3::new(0.0, 4.0, 0.0),
        DVec3::new(0.0, 0.0, 4.0),
    ];
    for x in -2..7 {
        for y in -2..7 {
            pts.push(DVec3::new(x as f64, y as f64, 0.0));
            pts.push(DVec3::new(x as f64, 0.0, y as f64));
        }
    }
    let t = build_checked(&pts);
    let mut rev = pts.clone();
    rev.reverse();
    assert_eq!(tets_by_points(&t), tets_by_points(&build_checked(&rev)));
}

#[test]
fn larger_degenerate_inputs() {
    // A shuffled 12^3 grid, then exactly cospherical points around a grid point, then the
    // grid again (all duplicates): valid at the end, order-independent.
    let mut pts = grid(12);
    let mut r = Rng(5);
    for i in (1..pts.len()).rev() {
        pts.swap(i, (r.next_u64() % (i as u64 + 1)) as usize);
    }
    let sphere = sphere_points(2500, 1.0 / 8.0, DVec3::new(5.0, 5.0, 5.0));
    assert!(sphere.len() >= 150, "{}", sphere.len());
    let mut all = pts.clone();
    all.extend_from_slice(&sphere);
    all.extend_from_slice(&pts);
    let t = build_checked(&all);
    let mut b = Triangulation::new();
    b.insert_bulk(&all).unwrap();
    assert!(b.is_valid().is_ok());
    assert_eq!(tets_by_points(&t), tets_by_points(&b));
}

/// Inserts `rest` into `t` in batches of `k` through `find_cavity` (all zones searched on the
/// same state first) and `insert_cavity`, inserting a zone only when its touched cells are
/// disjoint from those of the zones inserted before it in the batch (the others are retried
/// in the next batch), as the mesher does.
fn insert_in_batches(t: &mut Triangulation, rest: &[DVec3], k: usize, seed: u64) -> usize {
    use std::collections::HashSet;
    let mut pending: Vec<DVec3> = rest.to_vec();
    let mut deferred_total = 0;
    let mut cavs: Vec<delaunay3::Cavity> = (0..k).map(|_| Default::default()).collect();
    while !pending.is_empty() {
        let n = pending.len().min(k);
        let batch: Vec<DVec3> = pending.drain(..n).collect();
        for (i, p) in batch.iter().enumerate() {
            t.find_cavity(*p, None, seed ^ i as u64, &mut cavs[i])
                .unwrap();
        }
        let mut touched = HashSet::new();
        let mut deferred = Vec::new();
        for (i, p) in batch.iter().enumerate() {
            let cav = &cavs[i];
            assert_eq!(cav.point(), *p);
            if cav.duplicate().is_some() {
                assert!(matches!(
                    t.insert_cavity(cav, None),
                    Insertion::Duplicate(_)
                ));
                continue;
            }
            if cav.touched_cells().any(|c| touched.contains(&c)) {
                deferred.push(*p);
                continue;
            }
            touched.extend(cav.cells().iter().copied());
            let mut ch = Changes::default();
            assert!(matches!(
                t.insert_cavity(cav, Some(&mut ch)),
                Insertion::New(_)
            ));
            let mut removed = ch.removed_cells.clone();
            removed.sort_unstable();
            let mut zone = cav.cells().to_vec();
            zone.sort_unstable();
            assert_eq!(removed, zone);
        }
        deferred_total += deferred.len();
        pending.splice(0..0, deferred);
    }
    deferred_total
}

#[test]
fn batched_cavities_equal_one_by_one_insertion() {
    // Random points, points on a sphere (cospherical ties) and a grid (coplanar ties): the
    // batched insertion gives the same triangulation as inserting one point at a time.
    let mut r = Rng(5);
    let random: Vec<DVec3> = (0..2000).map(|_| cube_point(&mut r)).collect();
    let sphere = sphere_points(129, 1.0, DVec3::new(1.0, 2.0, 3.0));
    let mut grid = Vec::new();
    for x in 0..7 {
        for y in 0..7 {
            for z in 0..5 {
                grid.push(DVec3::new(x as f64, y as f64, z as f64));
            }
        }
    }
    for pts in [random, sphere, grid] {
        let reference = build_checked(&pts);
        for k in [2, 8, 32] {
            let mut t = Triangulation::new();
            let mut head = 0;
            while t.dimension() < 3 {
                t.insert(pts[head]).unwrap();
                head += 1;
            }
            let deferred = insert_in_batches(&mut t, &pts[head..], k, 17);
            eprintln!("{} points, batch {k}: {deferred} deferred", pts.len());
            assert!(t.is_valid().is_ok(), "{:?}", t.is_valid());
            assert_eq!(tets_by_points(&t), tets_by_points(&reference), "batch {k}");
        }
    }
}

fn coord() -> impl Strategy<Value = f64> {
    (-1000i32..1000).prop_map(|i| i as f64 / 64.0)
}

fn point() -> impl Strategy<Value = DVec3> {
    (coord(), coord(), coord()).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn prop_random_points(pts in prop::collection::vec(point(), 0..150)) {
        build_checked(&pts);
    }

    #[test]
    fn prop_many_duplicates(base in prop::collection::vec(point(), 1..20),
                            picks in prop::collection::vec(0usize..1000, 0..200)) {
        let pts: Vec<DVec3> = picks.iter().map(|&i| base[i % base.len()]).collect();
        bulk_agrees_with_one_by_one(&pts);
    }

    #[test]
    fn prop_grid_points(pts in prop::collection::vec((0i32..5, 0i32..5, 0i32..4), 0..120),
                        scale in 0i32..4) {
        let s = [1.0, 0.5, 3.0, 1e-3][scale as usize];
        let pts: Vec<DVec3> = pts.iter()
            .map(|&(x, y, z)| DVec3::new(x as f64, y as f64, z as f64) * s).collect();
        let a = build_checked(&pts);
        let mut rev = pts.clone();
        rev.reverse();
        let b = build_checked(&rev);
        prop_assert_eq!(tets_by_points(&a), tets_by_points(&b));
    }

    #[test]
    fn prop_sphere_subsets(mask in prop::collection::vec(any::<bool>(), 150),
                           k in 0usize..3) {
        let r2 = [81, 99, 129][k];
        let all = sphere_points(r2, 1.0, DVec3::new(1.0, 2.0, 3.0));
        let pts: Vec<DVec3> = all.iter().zip(mask.iter().cycle()).filter(|(_, m)| **m)
            .map(|(p, _)| *p).collect();
        let a = build_checked(&pts);
        let mut rev = pts.clone();
        rev.reverse();
        prop_assert_eq!(tets_by_points(&a), tets_by_points(&build_checked(&rev)));
    }

    #[test]
    fn prop_batched_cavities(pts in prop::collection::vec(point(), 8..120), k in 2usize..12,
                             seed in any::<u64>()) {
        let reference = build_checked(&pts);
        let mut t = Triangulation::new();
        let mut i = 0;
        while i < pts.len() && t.dimension() < 3 {
            t.insert(pts[i]).unwrap();
            i += 1;
        }
        if t.dimension() == 3 {
            insert_in_batches(&mut t, &pts[i..], k, seed);
        }
        prop_assert!(t.is_valid().is_ok());
        prop_assert_eq!(tets_by_points(&t), tets_by_points(&reference));
    }

    #[test]
    fn prop_small_inputs_match_brute_force(seed in any::<u64>(), n in 4usize..13) {
        let mut r = Rng(seed);
        let pts: Vec<DVec3> = (0..n).map(|_| cube_point(&mut r)).collect();
        let t = build_checked(&pts);
        prop_assert_eq!(tets_by_points(&t), brute_force(&pts));
    }

    #[test]
    fn prop_slivers(pts in prop::collection::vec((coord(), coord(), -3i32..3), 4..150)) {
        let pts: Vec<DVec3> = pts.iter()
            .map(|&(x, y, z)| DVec3::new(x, y, z as f64 * 1e-12)).collect();
        build_checked(&pts);
    }
}
