//! Golden fingerprints (ours): the exact cell slots, neighbors, vertex ids and change lists
//! that the kernel produced before its speed work (issue 21). Performance changes must keep
//! them: the mesher's output depends on cell ids and on the order of created cells, not
//! only on the (unique) set of Delaunay cells. A mismatch means an optimisation changed the
//! numbering, not necessarily the triangulation (the other tests check that). The bulk
//! insertion's numbering changed once, on purpose, with its order (2026-12-06; the mesher
//! does not use it): `bulk_cells_are_unchanged` holds its cells to the earlier order's.

mod common;

use common::*;
use delaunay3::{CellId, Changes, DVec3, Triangulation, VertexId};

/// FNV-1a over `u32` words.
struct Fnv(u64);

impl Fnv {
    fn word(&mut self, x: u32) {
        for b in x.to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x100_0000_01b3);
        }
    }
}

/// Every live slot with its vertices and neighbors, in slot order.
fn hash_cells(t: &Triangulation, h: &mut Fnv) {
    for c in t.live_cells() {
        h.word(c.to_u32());
        for v in t.cell_vertices(c) {
            h.word(v.to_u32());
        }
        for i in 0..4 {
            h.word(t.neighbor(c, i).to_u32());
        }
    }
}

fn hash_ids(ids: &[CellId], h: &mut Fnv) {
    h.word(ids.len() as u32);
    for c in ids {
        h.word(c.to_u32());
    }
}

/// Bulk insertion: the returned vertex ids and the cells.
fn bulk(pts: &[DVec3]) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    let mut t = Triangulation::new();
    for v in t.insert_bulk(pts).unwrap() {
        h.word(v.to_u32());
    }
    hash_cells(&t, &mut h);
    h.0
}

/// Bulk insertion's cells as sets of input indices (the infinite vertex as `u32::MAX`),
/// sorted: the triangulation whatever the insertion order and numbering.
fn bulk_cells(pts: &[DVec3]) -> u64 {
    let mut t = Triangulation::new();
    let ids = t.insert_bulk(pts).unwrap();
    let mut input = vec![0u32; t.num_vertices()];
    for (i, v) in ids.iter().enumerate() {
        input[v.to_u32() as usize] = i as u32;
    }
    let mut cells: Vec<[u32; 4]> = t
        .live_cells()
        .map(|c| {
            let mut q = t.cell_vertices(c).map(|v| {
                if v == VertexId::INFINITE {
                    u32::MAX
                } else {
                    input[v.to_u32() as usize]
                }
            });
            q.sort_unstable();
            q
        })
        .collect();
    cells.sort_unstable();
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    for q in cells {
        q.into_iter().for_each(|x| h.word(x));
    }
    h.0
}

/// One-by-one insertion with [`Changes`], then batched cavities (find / insert).
fn incremental(pts: &[DVec3]) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    let mut t = Triangulation::new();
    let mut ch = Changes::default();
    let half = pts.len() / 2;
    for &p in &pts[..half] {
        let r = t.insert_with(p, None, Some(&mut ch)).unwrap();
        h.word(r.vertex().to_u32());
        hash_ids(&ch.created, &mut h);
        hash_ids(&ch.removed_cells, &mut h);
    }
    let mut cavs: Vec<delaunay3::Cavity> = (0..4).map(|_| Default::default()).collect();
    for chunk in pts[half..].chunks(4) {
        for (i, &p) in chunk.iter().enumerate() {
            t.find_cavity(p, None, i as u64, &mut cavs[i]).unwrap();
        }
        let mut touched = std::collections::HashSet::new();
        for cav in &cavs[..chunk.len()] {
            if cav.touched_cells().any(|c| touched.contains(&c)) {
                let r = t.insert_with(cav.point(), None, Some(&mut ch)).unwrap();
                h.word(r.vertex().to_u32());
            } else {
                touched.extend(cav.cells().iter().copied());
                let r = t.insert_cavity(cav, Some(&mut ch));
                h.word(r.vertex().to_u32());
            }
            hash_ids(&ch.created, &mut h);
            hash_ids(&ch.removed_cells, &mut h);
        }
    }
    hash_cells(&t, &mut h);
    h.0
}

/// Uniform points, grid points (ties everywhere: the sort's tie handling and the
/// perturbation), rounded sphere points, and points sharing a few x values.
fn inputs() -> Vec<Vec<DVec3>> {
    let mut r = Rng(42);
    let cube: Vec<DVec3> = (0..20_000).map(|_| cube_point(&mut r)).collect();
    let mut grid = Vec::new();
    for x in 0..13 {
        for y in 0..11 {
            for z in 0..9 {
                grid.push(DVec3::new(x as f64, y as f64 * 0.5, z as f64 * 0.25));
            }
        }
    }
    for i in (1..grid.len()).rev() {
        let j = (r.next_u64() % (i as u64 + 1)) as usize;
        grid.swap(i, j);
    }
    let sphere: Vec<DVec3> = (0..5000).map(|_| r.unit_vector() * 3.0).collect();
    let slabs: Vec<DVec3> = (0..5000)
        .map(|_| DVec3::new((r.next_u64() % 7) as f64, r.next_f64(), r.next_f64()))
        .collect();
    vec![cube, grid, sphere, slabs]
}

#[test]
fn numbering_is_unchanged() {
    let got: Vec<(u64, u64)> = inputs()
        .iter()
        .map(|p| (bulk(p), incremental(&p[..p.len().min(4000)])))
        .collect();
    let want: [(u64, u64); 4] = [
        (0x8006ca05b3812ba4, 0x87b0a8dd799d684b),
        (0x9f4c3a4ff207919d, 0xa4c4075b6f3728db),
        (0xb49ad4a149cc9116, 0x263f2995b6fe3944),
        (0xfb599c7680e92f68, 0x9ab2e2d919fe276f),
    ];
    assert_eq!(got, want, "{got:#x?}");
}

/// The bulk insertion's order changed (2026-12-06: Hilbert keys instead of median splits),
/// and with it the numbering above; the cells, as sets of input points, are those the
/// median order gave (these fingerprints were taken with it).
#[test]
fn bulk_cells_are_unchanged() {
    let got: Vec<u64> = inputs().iter().map(|p| bulk_cells(p)).collect();
    let want: [u64; 4] = [
        0xb0ec88a7ba06d46d,
        0x15c5a0609afc9ee5,
        0xb41221a61a3aaa4d,
        0x3ec606bafe4ee7c9,
    ];
    assert_eq!(got, want, "{got:#x?}");
}
