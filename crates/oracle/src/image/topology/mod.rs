//! P1 for images (section 6.6.2): components of the trilinear level set from the voxel grid, and seed points.
//!
//! Grid nodes (voxel centres) are *inside* when their value is `< 0`. The grid is padded by
//! one layer of background nodes (outside), all joined into one *exterior* node.
//!
//! **Connectivity.** Two nodes of the same sign are joined when they are 6-neighbours (the grid
//! edge between them is linear, so it never leaves their side), or when they are the diagonal
//! of an ambiguous face and the bilinear saddle of that face is on their side (the asymptotic
//! decider: the inside pair is joined if the saddle value is `< 0`, the outside pair otherwise).
//! These are exact connections of the trilinear interpolant's inside and outside regions, so
//! every component of the node sets lies in one true region. The last kind of connection is a
//! tunnel through a cell's interior between corners no face joins (marching cubes 33's
//! tunnels): [`interior`] finds those, by slicing the cell. With all three the node sets'
//! components are the regions' (up to ties: a saddle exactly at the iso value). Until
//! 2026-12-05 the tunnels were left out and the counts could be too high: 285 for 284 on
//! nibabel's `anatomical.nii` at iso 9444.5, 43 for 35 on the jittered checkerboard of the
//! image suite (marching cubes of the interpolant sampled at 1/8 voxel gives 284 and 35).
//!
//! **Surface components.** The regions of R³ \ S form a tree (each closed surface separates
//! space in two), so #surface components = #inside regions + #outside regions - 1.
//!
//! **Seeds.** Every surface component crosses a grid edge (the trilinear interpolant is
//! harmonic, so a component inside one cell would break the maximum principle; a component
//! meeting only face interiors would give a closed curve inside a face, same argument). For
//! every pair (inside component, outside component) joined by a sign-changing edge we keep the
//! first such edge in scan order; its crossing (exact: the interpolant is linear along an
//! edge) lies on the unique surface component separating the two regions, so every surface
//! component gets a seed. Up to 4096 other crossings are kept at a regular stride for extra
//! seeds.
//!
//! **Seed tetrahedra.** A component is meshed only once one of its facets is restricted,
//! i.e. a Voronoi vertex of the sample lies in the region it encloses. For the smallest
//! components the seed is replaced by four points of the component (crossings of its extreme
//! grid edges, and of rays from its deepest node) whose circumcentre lies in that region:
//! the tetrahedron's four facets are restricted from the first insertion. On the nilearn
//! fixture at iso 3 (10 components, 7 of them 1 to 13 voxels), the mesher missed 1 to 4
//! components with a single seed each (seeds 0-7), none with the tetrahedra.
//!
//! **Joins** (`necks`): the grid edges and saddle diagonals of one inside region, where a
//! mesh that splits a component has missed a neck (the mesher rings them with points of S). The scan of node signs runs in parallel (rayon); union-find and the collection are
//! sequential in index order, so the result does not depend on the thread count.

mod dsu;
mod euler;
mod interior;
mod labels;
mod necks;
mod pairs;
#[cfg(test)]
mod reference;
mod saddles;
mod scan;
mod seeds;
mod tets;
mod vanishing;

pub(crate) use euler::inside_euler;
pub use necks::{Join, Node};
#[cfg(test)]
pub(crate) use reference::compute_reference;
pub(crate) use scan::compute;
pub use seeds::Topology;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::{ImageOptions, ImageSurface, Volume, Voxels};
    use crate::roots::SplitMix64;
    use glam::{DAffine3, DVec3};

    fn check(dims: [usize; 3], data: Vec<f32>, iso: f64) -> usize {
        let vol = Volume::new(dims, Voxels::F32(data), DAffine3::IDENTITY).unwrap();
        let Ok(s) = ImageSurface::new(
            vol,
            &ImageOptions {
                iso: Some(iso),
                ..Default::default()
            },
        ) else {
            return 0;
        };
        let (a, b) = (compute(&s, &s.inside_bits_rows()), compute_reference(&s));
        assert_eq!(
            (a.inside_components, a.outside_components, a.crossing_edges),
            (b.inside_components, b.outside_components, b.crossing_edges),
            "dims {dims:?}"
        );
        assert_eq!(a.component_seeds.len(), b.component_seeds.len());
        assert_eq!(
            (
                a.vanishing_components,
                &a.component_vanishing,
                a.surface_components
            ),
            (
                b.vanishing_components,
                &b.component_vanishing,
                b.surface_components
            ),
            "dims {dims:?}"
        );
        for p in a.component_seeds.iter().chain(&a.extra_seeds) {
            assert!(crate::Surface::value(&s, *p).abs() < 1e-9);
        }
        a.surface_components
    }

    #[test]
    fn every_seed_is_labelled_with_its_own_component() {
        // Five balls, one of them hollow (a cavity: two components), on 40 x 24 x 24 voxels.
        let dims = [40, 24, 24];
        let centres = [
            (6.0, 6.0),
            (6.0, 17.0),
            (17.0, 6.0),
            (17.0, 17.0),
            (30.0, 12.0),
        ];
        let mut data = Vec::new();
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let p = glam::DVec3::new(i as f64, j as f64, k as f64);
                    let v = centres
                        .iter()
                        .map(|&(x, y)| {
                            let r = p.distance(glam::DVec3::new(x, y, 12.0));
                            if x > 25.0 {
                                1.0 - (r - 6.0).abs() / 3.0
                            } else {
                                1.0 - r / 4.0
                            }
                        })
                        .fold(f64::MIN, f64::max);
                    data.push(v as f32);
                }
            }
        }
        let vol = Volume::new(dims, Voxels::F32(data), DAffine3::IDENTITY).unwrap();
        let opts = ImageOptions {
            iso: Some(0.0),
            ..Default::default()
        };
        let s = ImageSurface::new(vol, &opts).unwrap();
        let t = s.topology();
        assert_eq!(t.surface_components, 6);
        let labels: Vec<Option<usize>> = t
            .component_seeds
            .iter()
            .map(|p| s.component_of(*p))
            .collect();
        assert_eq!(labels, (0..6).map(Some).collect::<Vec<_>>());
        // Far from S: no component.
        assert_eq!(s.component_of(glam::DVec3::new(12.0, 12.0, 12.0)), None);
    }

    /// A block of 6^3 voxels at 2 (inside at iso 1) in a background of 0, with the voxels
    /// `ones` set to 1 (the iso value: outside by the convention, a puncture).
    fn block_with_ties(ones: &[[usize; 3]]) -> ImageSurface {
        block_with(ones, &[])
    }

    /// [`block_with_ties`], and the voxels `zeros` set to 0 (truly outside).
    fn block_with(ones: &[[usize; 3]], zeros: &[[usize; 3]]) -> ImageSurface {
        let n = 10;
        let mut v = vec![0f32; n * n * n];
        for k in 2..8 {
            for j in 2..8 {
                for i in 2..8 {
                    v[i + n * (j + n * k)] = 2.0;
                }
            }
        }
        for &[i, j, k] in ones {
            v[i + n * (j + n * k)] = 1.0;
        }
        for &[i, j, k] in zeros {
            v[i + n * (j + n * k)] = 0.0;
        }
        let vol = Volume::new([n; 3], Voxels::F32(v), DAffine3::IDENTITY).unwrap();
        let opts = ImageOptions {
            iso: Some(1.0),
            ..Default::default()
        };
        ImageSurface::new(vol, &opts).unwrap()
    }

    #[test]
    fn a_crossing_at_a_tied_node_has_its_component() {
        // The block's corner voxel at the iso value: a point of S (an inside neighbour below,
        // the background above) whose own cell, above it, has no inside corner; the cells
        // below it name its component.
        let s = block_with_ties(&[[7, 7, 7]]);
        let t = s.topology();
        assert_eq!(t.surface_components, 1);
        let face = s.component_of(DVec3::new(1.5, 4.0, 4.0));
        assert_eq!(face, Some(0));
        assert_eq!(s.component_of(DVec3::splat(7.0)), face);
    }

    #[test]
    fn voxels_at_the_iso_value_inside_the_solid_vanish() {
        // One voxel, and a line of three, at the iso value: punctures, no surface.
        for ones in [vec![[4, 4, 4]], vec![[3, 4, 4], [4, 4, 4], [5, 4, 4]]] {
            let s = block_with_ties(&ones);
            let t = s.topology();
            assert_eq!((t.outside_components, t.vanishing_components), (2, 1));
            assert_eq!(t.surface_components, 1, "only the block's boundary");
            assert_eq!(t.component_vanishing.iter().filter(|&&v| v).count(), 1);
            // No seed there, and the interpolant is <= 0 (inside or on S) all around.
            let p = DVec3::new(4.0, 4.0, 4.0);
            assert!(
                crate::Surface::seed_points(&s, 0)
                    .iter()
                    .all(|q| q.distance(p) > 1.0)
            );
            let mut rng = SplitMix64(5);
            for _ in 0..2000 {
                let q = p + DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 2.0
                    - DVec3::ONE;
                assert!(crate::Surface::value(&s, q) <= 0.0, "{q}");
            }
        }
        // A whole cell of ties encloses volume under the convention: a cavity, not vanishing.
        let cube: Vec<[usize; 3]> = (0..8)
            .map(|c| [4 + (c & 1), 4 + ((c >> 1) & 1), 4 + (c >> 2)])
            .collect();
        let t = block_with_ties(&cube).topology().clone();
        assert_eq!((t.vanishing_components, t.surface_components), (0, 2));
        // A tie beside a voxel truly outside (0) is part of a real cavity.
        let s = block_with(&[[4, 4, 4]], &[[5, 4, 4]]);
        let t = s.topology();
        assert_eq!((t.vanishing_components, t.surface_components), (0, 2));
    }

    #[test]
    fn run_based_matches_node_based_with_ties() {
        // Small integers at an integer iso value: many nodes exactly at it.
        let mut rng = SplitMix64(78);
        let mut vanishing = 0;
        for _ in 0..200 {
            let dims = [
                1 + (rng.next_u64() % 40) as usize,
                1 + (rng.next_u64() % 6) as usize,
                1 + (rng.next_u64() % 6) as usize,
            ];
            let n = dims[0] * dims[1] * dims[2];
            let data: Vec<f32> = (0..n).map(|_| (rng.next_u64() % 4) as f32).collect();
            check(dims, data.clone(), 1.0);
            let vol = Volume::new(dims, Voxels::F32(data), DAffine3::IDENTITY).unwrap();
            if let Ok(s) = ImageSurface::new(
                vol,
                &ImageOptions {
                    iso: Some(1.0),
                    ..Default::default()
                },
            ) {
                vanishing += s.topology().vanishing_components;
            }
        }
        assert!(vanishing > 10, "too few vanishing components: {vanishing}");
    }

    #[test]
    fn run_based_matches_node_based() {
        let mut rng = SplitMix64(77);
        let mut many = 0;
        for case in 0..300 {
            let dims = [
                1 + (rng.next_u64() % 70) as usize,
                1 + (rng.next_u64() % 6) as usize,
                1 + (rng.next_u64() % 6) as usize,
            ];
            let n = dims[0] * dims[1] * dims[2];
            // Sparse or dense random binary-ish data with random values (ambiguous faces).
            let density = [0.1, 0.3, 0.5, 0.8][case % 4];
            let data: Vec<f32> = (0..n)
                .map(|_| {
                    if rng.next_f64() < density {
                        0.5 + rng.next_f64() as f32
                    } else {
                        rng.next_f64() as f32 * 0.5
                    }
                })
                .collect();
            many += (check(dims, data, 0.5) > 3) as usize;
        }
        assert!(many > 100, "too few cases with several components: {many}");
    }
}
