//! The scan's joins through saddles (ours, P1 of section 6.6.2): where a region of the
//! trilinear level set passes between two grid nodes only through a saddle (the diagonal of an
//! ambiguous face, by the asymptotic decider, or a tunnel through a cell's interior). A handle
//! of S thinner than the sample is such a passage that a mesh closes (a tunnel of the outside
//! filled, a loop of the inside cut): the mesher samples S around the saddles that its mesh
//! puts on the wrong side (`rdt_mesher`'s handle reseeding).

use super::euler::mixed_cells;
use super::interior::{FACES, face_diagonal, interior_joins};
use super::necks::Join;
use crate::image::ImageSurface;
use glam::DVec3;

/// A grid node's index in the volume, or `usize::MAX` for the background layer around it.
fn node_index(s: &ImageSurface, p: [i64; 3]) -> usize {
    let [nx, ny, nz] = s.dims_isize().map(|n| n as i64);
    let [i, j, k] = p;
    if i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz {
        usize::MAX
    } else {
        (i + nx * (j + ny * k)) as usize
    }
}

impl ImageSurface {
    /// Every join of the scan through a saddle, with its side (`true`: the inside region's):
    /// the diagonal of each ambiguous face that its saddle joins (`via`: the saddle), and each
    /// join through a cell's interior (`via`: the saddle of the slice that joins). World
    /// space, in cell order (the same for any thread count); a node of the background layer
    /// around the grid has index `usize::MAX`.
    pub fn saddle_joins(&self) -> Vec<(Join, bool)> {
        let to_world = self.inv.inverse();
        mixed_cells(self, |cell, g, out| {
            let corner = |c: usize| {
                [
                    cell[0] + (c & 1) as i64,
                    cell[1] + ((c >> 1) & 1) as i64,
                    cell[2] + (c >> 2) as i64,
                ]
            };
            let at = |p: DVec3| to_world.transform_point3(DVec3::from(cell.map(|x| x as f64)) + p);
            let local =
                |c: usize| DVec3::new((c & 1) as f64, ((c >> 1) & 1) as f64, (c >> 2) as f64);
            let join = |a: usize, b: usize, via: DVec3| Join {
                a: at(local(a)),
                b: at(local(b)),
                via: at(via),
                diagonal: true,
                nodes: [node_index(self, corner(a)), node_index(self, corner(b))],
            };
            // The faces at the lowest corner (each face of the grid once).
            for &face in &FACES[..3] {
                let Some([a, b]) = face_diagonal(g, face) else {
                    continue;
                };
                let (p00, u, v) = (face.0 as usize, face.1 as usize, face.2 as usize);
                let [f00, f10, f01, f11] = [p00, p00 + u, p00 + v, p00 + u + v].map(|k| g[k]);
                let den = f00 + f11 - f10 - f01;
                let (x, y) = ((f00 - f01) / den, (f00 - f10) / den);
                let via = local(p00) + local(u) * x + local(v) * y;
                let (a, b) = (a as usize, b as usize);
                out.push((join(a, b, via), g[a] < 0.0));
            }
            for j in interior_joins(g) {
                let (a, b) = (j.a as usize, j.b as usize);
                out.push((join(a, b, DVec3::from(j.via)), g[a] < 0.0));
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use crate::image::{ImageOptions, ImageSurface, Volume, Voxels};

    /// Two bright voxels touching along an edge, at a level below the face saddle (joined
    /// through it: one inside join) and above it (apart: the outside pair is joined, one
    /// outside join); the saddle is at the face's centre and on its side.
    #[test]
    fn an_edge_contact_is_one_saddle_join_on_the_side_its_level_gives() {
        let mut data = vec![0u8; 27];
        data[1 + 3 + 9] = 1; // (1, 1, 1)
        data[2 + 3 * 2 + 9] = 1; // (2, 2, 1): an edge contact with (1, 1, 1)
        let vol = Volume::new([3, 3, 3], Voxels::U8(data), glam::DAffine3::IDENTITY).unwrap();
        for (iso, inside) in [(0.4, true), (0.6, false)] {
            let opts = ImageOptions {
                iso: Some(iso),
                ..Default::default()
            };
            let s = ImageSurface::new(vol.clone(), &opts).unwrap();
            let joins = s.saddle_joins();
            assert_eq!(joins.len(), 1, "{joins:?}");
            let (j, side) = joins[0];
            assert_eq!(side, inside);
            assert!(
                (j.via - glam::DVec3::new(1.5, 1.5, 1.0)).length() < 1e-12,
                "{j:?}"
            );
            assert_eq!(crate::Surface::value(&s, j.via) < 0.0, inside);
        }
    }
}
