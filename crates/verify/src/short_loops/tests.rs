use super::*;
use glam::DVec3;

/// A torus of radii `big` and `small` around z, `nu` x `nv` quads, outward.
fn torus(big: f64, small: f64, nu: usize, nv: usize) -> TriMesh {
    let mut vertices = Vec::new();
    for i in 0..nu {
        let u = i as f64 / nu as f64 * std::f64::consts::TAU;
        for j in 0..nv {
            let v = j as f64 / nv as f64 * std::f64::consts::TAU;
            let r = big + small * v.cos();
            vertices.push(DVec3::new(r * u.cos(), r * u.sin(), small * v.sin()));
        }
    }
    let id = |i: usize, j: usize| ((i % nu) * nv + j % nv) as u32;
    let mut triangles = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriMesh {
        vertices,
        triangles,
    }
}

/// A closed tube of radius `r` and length `len` along x (a capsule with flat caps: each
/// cap a fan around a centre vertex), `nr` around, `nl` along.
fn capsule(r: f64, len: f64, nr: usize, nl: usize) -> TriMesh {
    let mut vertices = Vec::new();
    for i in 0..=nl {
        let x = len * i as f64 / nl as f64;
        for j in 0..nr {
            let a = j as f64 / nr as f64 * std::f64::consts::TAU;
            vertices.push(DVec3::new(x, r * a.cos(), r * a.sin()));
        }
    }
    let id = |i: usize, j: usize| (i * nr + j % nr) as u32;
    let mut triangles = Vec::new();
    for i in 0..nl {
        for j in 0..nr {
            triangles.push([id(i, j), id(i, j + 1), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i + 1, j)]);
        }
    }
    let (c0, c1) = (vertices.len() as u32, vertices.len() as u32 + 1);
    vertices.push(DVec3::ZERO);
    vertices.push(DVec3::new(len, 0.0, 0.0));
    for j in 0..nr {
        triangles.push([c0, id(0, j + 1), id(0, j)]);
        triangles.push([c1, id(nl, j), id(nl, j + 1)]);
    }
    TriMesh {
        vertices,
        triangles,
    }
}

#[test]
fn a_thin_torus_has_a_short_handle_found_from_every_seed_within_reach() {
    // Meridian 2 pi 0.1 = 0.63: the front meets itself at about half of it (0.31).
    let m = torus(1.0, 0.1, 96, 12);
    let found = ShortLoops::new(&m).unwrap().handles(&|_| 0.45);
    assert_eq!(found.len(), m.vertices.len(), "every seed finds the tunnel");
    for h in &found {
        assert!(h.radius > 0.25 && h.radius < 0.45, "{h:?}");
    }
    // Below half the meridian no ball wraps the tube.
    assert!(ShortLoops::new(&m).unwrap().handles(&|_| 0.2).is_empty());
}

#[test]
fn a_sphere_like_component_is_not_searched_and_a_fat_torus_is_beyond_a_small_limit() {
    // Genus 0: no seed at all, whatever the limit.
    let c = capsule(0.1, 2.0, 12, 40);
    assert!(ShortLoops::new(&c).unwrap().handles(&|_| 10.0).is_empty());
    // A fat torus: its shortest loop (the meridian, 2 pi 0.5) is beyond 0.9.
    let t = torus(1.0, 0.5, 64, 32);
    assert!(ShortLoops::new(&t).unwrap().handles(&|_| 0.9).is_empty());
    assert!(!ShortLoops::new(&t).unwrap().handles(&|_| 2.0).is_empty());
}

#[test]
fn a_ball_around_a_thin_tube_separates_and_is_not_a_handle() {
    // Called on the genus-0 capsule directly: balls wrap the tube (chi drops) but the loop
    // where the front met separates the two ends, so no handle radius within any limit.
    let c = capsule(0.1, 2.0, 12, 40);
    let g = Graph::new(&c).unwrap();
    let mut sc = Scratch::new(c.vertices.len());
    for s in [0u32, 100, 250] {
        assert_eq!(g.handle_radius(s, 10.0, &mut sc), None, "seed {s}");
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let m = torus(1.0, 0.12, 64, 10);
    let lim = |v: u32| 0.3 + 0.2 * f64::from(v % 7) / 7.0;
    let all = ShortLoops::new(&m).unwrap().handles(&lim);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| ShortLoops::new(&m).unwrap().handles(&lim));
    assert_eq!(all, one);
    assert!(!all.is_empty());
}

#[test]
fn an_open_mesh_is_refused() {
    let mut m = torus(1.0, 0.1, 32, 8);
    m.triangles.pop();
    assert!(ShortLoops::new(&m).is_none());
}

#[test]
fn a_handle_s_loop_goes_once_around_the_tube_and_does_not_separate() {
    let m = torus(1.0, 0.1, 96, 12);
    let found = ShortLoops::new(&m).unwrap().handles(&|_| 0.45);
    let adjacent = |a: u32, b: u32| {
        m.triangles
            .iter()
            .any(|t| t.contains(&a) && t.contains(&b) && a != b)
    };
    for h in found.iter().step_by(97) {
        let lp = &h.loop_vertices;
        assert!(lp.len() >= 3, "{h:?}");
        let mut sorted = lp.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), lp.len(), "a simple loop: {lp:?}");
        let mut length = 0.0;
        for k in 0..lp.len() {
            let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
            assert!(adjacent(a, b), "{a} {b} not joined in {lp:?}");
            length += m.vertices[a as usize].distance(m.vertices[b as usize]);
        }
        // About the meridian (2 pi 0.1 = 0.63): once around the tube.
        assert!(length > 0.55 && length < 1.0, "length {length} of {lp:?}");
        // Without the triangles at the loop, the torus is still connected: the loop does not
        // separate it (a handle's loop, not a thin finger's).
        let kept: Vec<[u32; 3]> = m
            .triangles
            .iter()
            .filter(|t| !t.iter().any(|v| lp.contains(v)))
            .copied()
            .collect();
        let mut dsu = crate::topology::Dsu::new(m.vertices.len());
        for t in &kept {
            dsu.union(t[0], t[1]);
            dsu.union(t[0], t[2]);
        }
        let roots: std::collections::BTreeSet<u32> = kept.iter().map(|t| dsu.find(t[0])).collect();
        assert_eq!(roots.len(), 1, "{lp:?}");
    }
}
