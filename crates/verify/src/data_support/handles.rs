//! Handles the data does not show (ours; issue 16: a point set has no genus to compare with,
//! so a wrong genus passed every other check): a handle of the output whose tunnel is
//! smaller than the data's band, or whose neighbourhood faces against the data.
//!
//! The candidates are the short handles of [`crate::short_loops`]: seeds whose geodesic ball
//! of radius at most [`SEARCH_BANDS`] times the band (at the seed's nearest data point)
//! holds a handle, the smallest ball first, one per place (a seed within [`SAME_PLACE_BANDS`]
//! bands of a kept one is the same handle). A candidate of radius `r` at band `b` is
//! unsupported when
//! - `r <= BELOW_BAND * b`: its tunnel's loop (about `2 r` long) is shorter than the band, the
//!   scale below which the data (spacing and noise) shows nothing; or
//! - with data normals, the ball's orientation agreement (area-weighted mean of the facet
//!   normal against the nearest data point's normal, as for components) is below the
//!   check's `min_agreement`: a tube between two sheets (facing sideways) or a pocket.
//!
//! Measured on the scan table's saved meshes (`cargo xtask scans --save DIR`): the 19
//! spurious handles of its 5 rows of wrong genus are at 0.02-0.81 bands with agreements
//! -0.46 to 0.84 (each row has one at most 0.53 bands, or one below agreement 0.5); the
//! genuine handles of fertility (genus 4) at 1.20 bands and more, agreements 0.70-0.99.

use meshio::TriMesh;
use serde::Serialize;

use glam::DVec3;

use crate::short_loops::{ShortHandle, ShortLoops};

/// The search's reach, in bands.
pub const SEARCH_BANDS: f64 = 1.5;
/// A handle within this many bands is below the data's resolution.
pub const BELOW_BAND: f64 = 0.5;
/// Seeds within this many bands of a kept candidate are the same handle.
const SAME_PLACE_BANDS: f64 = 3.0;
/// Candidates measured at most (smallest first).
const MAX_CANDIDATES: usize = 64;

/// A handle of the mesh that the data does not show.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct UnsupportedHandle {
    /// A vertex of the tunnel (the seed of the smallest ball holding it) and its position.
    pub vertex: u32,
    pub at: [f64; 3],
    /// That ball's geodesic radius: the tunnel's loop is about twice as long.
    pub radius: f64,
    /// The data's band there.
    pub band: f64,
    /// Orientation agreement of the ball's triangles with the data normals (with normals).
    pub agreement: Option<f64>,
    /// `below_band` or `faces_against_data`.
    pub reason: &'static str,
    /// A loop through the tunnel (`crate::short_loops::ShortHandle::loop_vertices`): where
    /// the mesher cuts it. Not in the report.
    #[serde(skip)]
    pub loop_vertices: Vec<u32>,
}

impl UnsupportedHandle {
    /// The check's detail for the smallest of `total` such handles.
    pub fn describe(&self, total: usize) -> String {
        format!(
            "{total} handles the data does not show (smallest: a tunnel at ({:.4}, {:.4}, {:.4}) within a geodesic ball of radius {:.3e}, {})",
            self.at[0],
            self.at[1],
            self.at[2],
            self.radius,
            self.why()
        )
    }

    /// Its size in bands and why it is unsupported, e.g. `0.41 bands, below the data's
    /// band, agreement 0.27`.
    pub fn why(&self) -> String {
        format!(
            "{:.2} bands, {}{}",
            self.radius / self.band,
            if self.reason == "below_band" {
                "below the data's band"
            } else {
                "facing against the data"
            },
            self.agreement
                .map_or(String::new(), |a| format!(", agreement {a:.2}"))
        )
    }
}

/// The unsupported handles of the closed mesh `mesh` (its search `loops`), smallest first;
/// `band_at`: the data's band at the data point nearest a point; `agree`: each triangle's
/// area-weighted agreement (`area * n_t . n_i`), with data normals.
pub(super) fn unsupported_handles(
    mesh: &TriMesh,
    loops: &ShortLoops,
    band_at: &(dyn Fn(DVec3) -> f64 + Sync),
    agree: Option<&[f64]>,
    min_agreement: f64,
) -> Vec<UnsupportedHandle> {
    if !loops.has_handles() {
        return Vec::new();
    }
    let band_of = |v: u32| band_at(mesh.vertices[v as usize]);
    let mut found: Vec<(f64, ShortHandle)> = loops
        .handles(&|v| SEARCH_BANDS * band_of(v))
        .into_iter()
        .map(|h| (h.radius / band_of(h.seed), h))
        .collect();
    found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.seed.cmp(&b.1.seed)));
    let mut kept: Vec<(f64, ShortHandle)> = Vec::new();
    for f in found {
        let p = mesh.vertices[f.1.seed as usize];
        let b = band_of(f.1.seed);
        if kept
            .iter()
            .all(|k| mesh.vertices[k.1.seed as usize].distance(p) > SAME_PLACE_BANDS * b)
        {
            kept.push(f);
            if kept.len() == MAX_CANDIDATES {
                break;
            }
        }
    }
    kept.into_iter()
        .filter_map(|(ratio, h)| {
            let (seed, radius) = (h.seed, h.radius);
            let agreement = agree.map(|a| ball_agreement(mesh, loops, a, seed, radius));
            let reason = if ratio <= BELOW_BAND {
                "below_band"
            } else if agreement.is_some_and(|x| x < min_agreement) {
                "faces_against_data"
            } else {
                return None;
            };
            Some(UnsupportedHandle {
                vertex: seed,
                at: mesh.vertices[seed as usize].to_array(),
                radius,
                band: band_of(seed),
                agreement,
                reason,
                loop_vertices: h.loop_vertices,
            })
        })
        .collect()
}

/// The area-weighted agreement of the triangles inside the geodesic ball (all three
/// corners in it); 1 when it holds none.
fn ball_agreement(
    mesh: &TriMesh,
    loops: &ShortLoops,
    agree: &[f64],
    seed: u32,
    radius: f64,
) -> f64 {
    let (mut sum, mut area) = (0.0, 0.0);
    for t in loops.ball_triangles(seed, radius) {
        let [a, b, c] = mesh.triangles[t as usize].map(|i| mesh.vertices[i as usize]);
        sum += agree[t as usize];
        area += 0.5 * (b - a).cross(c - a).length();
    }
    if area > 0.0 { sum / area } else { 1.0 }
}
