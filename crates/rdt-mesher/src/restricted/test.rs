//! The restricted-facet test of section 6.1: a facet of Del(E) is in Del_S(E) when its dual
//! Voronoi edge (clipped to the bounding ball) meets S, as the oracle of section 6.4.2 says
//! (bipolar: a sign change; intersection: any crossing). Its surface Delaunay ball is
//! centered at the crossing (the farthest from its vertices, with several).
//!
//! A test runs in three halves: `prepare_facet` (geometry only, cheap rejections), the
//! oracle (`resolve_facet`, pure, in parallel when it pays) and `register_facet`.

use crate::error::MeshError;
use crate::options::OracleKind;
use crate::queue::QEntry;
use crate::restricted::{RFacet, sorted3};
use crate::schedule::Calls;
use crate::state::Mesher;
use delaunay3::{Facet, VertexId};
use glam::DVec3;
use oracle::OracleError;
use std::time::Instant;

/// A facet whose badness is known to exceed this without its ball is registered lazily
/// (`RFacet::lazy`): the margin above 1 covers the rounding of r >= circumradius.
const LAZY_MIN: f64 = 1.0 + 1e-9;

/// Inside S (value < 0).
#[inline]
pub(super) fn inside(f: f64) -> bool {
    f < 0.0
}

/// A facet test between its geometric and its oracle half (see `Mesher::test_facets`).
#[derive(Clone, Copy, Debug)]
pub(super) struct PendingFacet {
    pub f: Facet,
    pub m: Facet,
    pub verts: [VertexId; 3],
    /// The clipped dual from `f.cell`'s side, with the values at its ends.
    pub p: DVec3,
    pub fp: f64,
    pub q: DVec3,
    pub fq: f64,
    /// A lower bound of the facet's badness known without its ball, and the facet's
    /// circumcenter (see `Mesher::known_badness`).
    pub lb: f64,
    pub cc: DVec3,
    /// Bad anyway (`lb > LAZY_MIN`, bipolar oracle): its crossing is delayed.
    pub lazy: bool,
}

impl Mesher<'_> {
    /// The dual of facet `f` as a segment oriented from `f.cell`'s side to the mirror side,
    /// clipped to the bounding ball, with the values at its ends (+inf = on the ball's
    /// boundary or beyond, where the value is positive by the oracle's contract).
    pub(super) fn clipped_dual(
        &self,
        f: Facet,
        m: Facet,
        verts: [VertexId; 3],
    ) -> Option<(DVec3, f64, DVec3, f64)> {
        let ci = self.tri.is_infinite(f.cell);
        let mi = self.tri.is_infinite(m.cell);
        let (p, fp, q, fq) = match (ci, mi) {
            (false, false) => {
                let a = self.voronoi.get(f.cell);
                let b = self.voronoi.get(m.cell);
                (a.cc, a.f, b.cc, b.f)
            }
            (false, true) | (true, false) => {
                let [a, b, c] = verts.map(|v| self.tri.point(v));
                // Normal out of f.cell.
                let n = (b - a).cross(c - a);
                let nl = n.length();
                if nl.is_nan() || nl <= 0.0 {
                    return None;
                }
                let n = n / nl;
                let fin = if ci { m.cell } else { f.cell };
                let info = self.voronoi.get(fin);
                let far_len = 2.0 * ((info.cc - self.ball.center).length() + self.ball.radius);
                if ci {
                    // Outward of the hull is out of the finite mirror cell, i.e. -n.
                    (info.cc - n * far_len, f64::INFINITY, info.cc, info.f)
                } else {
                    (info.cc, info.f, info.cc + n * far_len, f64::INFINITY)
                }
            }
            (true, true) => return None,
        };
        if !(p.is_finite() && q.is_finite()) {
            return None;
        }
        let (pc, qc) = self.ball.clip_segment(p, q)?;
        // An end moved by the clipping lies on the ball's boundary, where the value is
        // positive by the oracle's contract. (`clip_segment` returns unclipped ends exactly,
        // so both sides of a facet see the same values.)
        let fp = if pc == p { fp } else { f64::INFINITY };
        let fq = if qc == q { fq } else { f64::INFINITY };
        Some((pc, fp, qc, fq))
    }

    /// First half of a facet test: orient `(f, m)` from a finite cell, reject it from the
    /// cached signs (bipolar oracle), and clip its dual. `None` = not restricted.
    pub(super) fn prepare_facet(&self, f: Facet, m: Facet) -> Option<PendingFacet> {
        // Always look from a finite cell: only finite cells' facet orientation is used.
        let (f, m) = if self.tri.is_infinite(f.cell) {
            (m, f)
        } else {
            (f, m)
        };
        let bipolar = self.opts.oracle == OracleKind::Bipolar;
        // Cheap rejection from the cached signs (infinite cells have f = +inf, so a facet of
        // two infinite cells, which has the infinite vertex, is rejected here). An end outside
        // the bounding ball (or a hull facet's ray, which ends outside it) counts as outside,
        // exactly as its clipped end on the ball's boundary would.
        if bipolar && inside(self.voronoi.get(f.cell).f) == inside(self.voronoi.get(m.cell).f) {
            return None;
        }
        let verts = self.tri.facet_vertices(f);
        if verts.contains(&VertexId::INFINITE) {
            return None;
        }
        let (p, fp, q, fq) = self.clipped_dual(f, m, verts)?;
        if bipolar && inside(fp) == inside(fq) {
            return None;
        }
        let (lb, cc) = self.known_badness(verts);
        // Only with the bipolar oracle: its facet orientation is known without the crossing.
        let lazy = self.lazy_balls && bipolar && lb > LAZY_MIN;
        Some(PendingFacet {
            f,
            m,
            verts,
            p,
            fp,
            q,
            fq,
            lb,
            cc,
            lazy,
        })
    }

    /// The oracle half of a facet test (pure: may run on any thread): the surface Delaunay
    /// ball's center and whether the dual leaves `f.cell` outward (from inside S to outside).
    /// A lazy facet (`pf.lazy`) gets a NaN center: its crossing is delayed.
    pub(super) fn resolve_facet(
        &self,
        pf: &PendingFacet,
        buf: &mut Vec<DVec3>,
    ) -> Option<(DVec3, bool)> {
        let PendingFacet { p, fp, q, fq, .. } = *pf;
        if pf.lazy {
            return Some((DVec3::NAN, inside(fp)));
        }
        match self.opts.oracle {
            OracleKind::Bipolar => {
                // Values on the ball boundary are positive by contract; pass a finite one.
                let fpv = if fp.is_finite() { fp } else { 1.0 };
                let fqv = if fq.is_finite() { fq } else { 1.0 };
                Some((self.s.crossing(p, fpv, q, fqv), inside(fp)))
            }
            OracleKind::Intersection => {
                buf.clear();
                self.s.crossings(p, q, buf);
                let pts = pf.verts.map(|v| self.tri.point(v));
                let mut best: Option<(DVec3, bool, f64)> = None;
                for (k, c) in buf.iter().enumerate() {
                    let r = pts.iter().map(|v| v.distance(*c)).fold(0.0, f64::max);
                    // Inside before crossing k: parity of the crossings before it.
                    let before_inside = inside(fp) != (k % 2 == 1);
                    if best.is_none_or(|b| r > b.2) {
                        best = Some((*c, before_inside, r));
                    }
                }
                best.map(|(c, o, _)| (c, o))
            }
        }
    }

    /// Test the facets `pairs` (each with its mirror facet) and insert an entry for each
    /// restricted one, in the order given. The caller has removed any previous entry of these
    /// facets (all facets of destroyed cells are removed first). The oracle calls of one
    /// batch run in parallel when they are expensive enough to pay for it; the result does
    /// not depend on it (each call is a pure function of its segment).
    pub(crate) fn test_facets(&mut self, pairs: &[(Facet, Facet)]) -> Result<(), MeshError> {
        let this = &*self;
        let prepared = self
            .policy
            .cells(pairs.len())
            .map(pairs, |&(f, m)| this.prepare_facet(f, m));
        let pending: Vec<PendingFacet> = prepared.into_iter().flatten().collect();
        if pending.is_empty() {
            return Ok(());
        }
        let eager = pending.iter().filter(|pf| !pf.lazy).count();
        self.crossing_calls += eager as u64;
        let t = Instant::now();
        let exec = self.policy.oracle(eager, Calls::Crossings);
        let this = &*self;
        let hits = exec.map_init(&pending, Vec::new, |buf, pf| this.resolve_facet(pf, buf));
        let dt = t.elapsed();
        self.t_oracle += dt;
        self.policy.observe(Calls::Crossings, dt, eager);
        // A size field (not a constant) is evaluated here, in parallel when it pays: it is a
        // pure function of the ball center, so the values are those `register_facet` would
        // compute (or a lower bound that decides the same, see `vertex_sizes`).
        let field = self
            .opts
            .criteria
            .size
            .as_ref()
            .is_some_and(|s| s.is_field());
        let sigmas: Vec<Option<f64>> = if field {
            // sigma at the vertices first: most tests are then decided by the Lipschitz bound
            // (`vertex_sizes`), with the same outcome.
            self.fill_vertex_sizes(
                pending
                    .iter()
                    .zip(&hits)
                    .filter(|(pf, hit)| !pf.lazy && hit.is_some())
                    .flat_map(|(pf, _)| pf.verts),
            );
            let this = &*self;
            let jobs: Vec<(&PendingFacet, Option<(DVec3, bool)>)> =
                pending.iter().zip(hits.iter().copied()).collect();
            self.policy
                .field(jobs.len())
                .map(&jobs, |&(pf, hit)| match hit {
                    Some((c, _)) if !pf.lazy && c.is_finite() => {
                        this.sigma_for_test(pf.verts, (pf.lb, pf.cc), c)
                    }
                    _ => None,
                })
        } else {
            vec![None; pending.len()]
        };
        for ((pf, hit), sigma) in pending.iter().zip(&hits).zip(sigmas) {
            if let Some(hit) = *hit {
                self.register_facet(pf, hit, sigma)?;
            }
        }
        Ok(())
    }

    /// Last half of a facet test: register a restricted facet and queue it if bad.
    /// `sigma`: the size field at the ball center when already evaluated.
    fn register_facet(
        &mut self,
        pf: &PendingFacet,
        (center, outward_from_cell): (DVec3, bool),
        sigma: Option<f64>,
    ) -> Result<(), MeshError> {
        let PendingFacet { f, m, verts, .. } = *pf;
        let key = sorted3(verts);
        let lazy = pf.lazy;
        let (center, radius, bad) = if lazy {
            // Never read before `resolve_lazy`.
            (DVec3::NAN, 0.0, pf.lb)
        } else {
            if !center.is_finite() {
                return Err(OracleError::NaN(center.x, center.y, center.z).into());
            }
            let (radius, bad) = match sigma {
                Some(s) => self.ball_badness_with(verts, (pf.lb, pf.cc), center, Some(s))?,
                None => self.ball_badness(verts, (pf.lb, pf.cc), center)?,
            };
            (center, radius, bad)
        };
        let oriented = if outward_from_cell {
            verts
        } else {
            [verts[0], verts[2], verts[1]]
        };
        let rf = RFacet {
            cell: f.cell,
            index: f.index,
            oriented,
            center,
            radius,
            bad,
            version: 0, // assigned by `register`
            lazy,
        };
        let (idx, rf) = self.restricted.register(key, rf, m);
        if bad > 1.0 {
            self.queue.push(QEntry {
                bad,
                idx,
                version: rf.version,
                forced: false,
                at: self.tri.point(oriented[0]),
            });
        }
        Ok(())
    }
}
