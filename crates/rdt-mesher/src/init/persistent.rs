//! Persistent facets (section 6.2, with section 6.4.2's bipolar variant): an initial sample.
//!
//! For every control point x (a point of S, at least one per component), a ball B_x of radius
//! rho_x < min(dist(x, other control points) / 2, d_M(x), sigma(x) / 3) is centered at x and
//! three points of S on its bounding sphere are taken. The balls are pairwise disjoint, so B_x is
//! an empty surface Delaunay ball of those three points: they form a *persistent facet*
//! (lemma 6.1: it stays in Del_S(E) until the end, because sigma is 1-Lipschitz).
//!
//! The three points are found on the great arcs of the sphere from x - rho n to x + rho n
//! (n the unit gradient at x) through the tangent directions at 0, 120 and 240 degrees, by
//! bisection on the sign of the value along the arc: they are on the sphere by construction and
//! on S within [`Surface::tolerance`].
//!
//! Bipolar variant (section 6.4.2): a persistent facet whose dual Voronoi edge crosses S more
//! than once is not seen by the bipolar oracle (an even number of crossings gives no sign
//! change). The centers of its other surface Delaunay balls (the other crossings, found with the
//! intersection oracle [`Surface::crossings`]) are added to the sample until every persistent
//! facet's dual edge crosses S exactly once; they are far from x, so the facet stays persistent.

use crate::error::MeshError;
use crate::options::MeshOptions;
use delaunay3::{Dual, Insertion, Triangulation, VertexId};
use glam::DVec3;
use oracle::Surface;

/// The initial sample of section 6.2 and its persistent facets.
#[derive(Clone, Debug)]
pub struct PersistentInit {
    /// The sample E_i: the facets' vertices first (three per facet, in facet order), then the
    /// extra points (section 6.4.2's centers and, if needed, a few random-line seeds so that the
    /// sample spans 3D).
    pub points: Vec<DVec3>,
    /// One triangle per kept control point: three points of S on the sphere around it.
    pub facets: Vec<[DVec3; 3]>,
    /// The control point and the radius rho of its ball, per facet.
    pub balls: Vec<(DVec3, f64)>,
    /// Points added by section 6.4.2 (other crossings of the facets' dual edges).
    pub bipolar_insertions: usize,
}

/// The initial sample E_i of section 6.2 built around the control points E'_i (see the module
/// docs). Control points where the gradient vanishes, or where no sign change is found on the
/// arcs even after shrinking the ball 12 times, are skipped; an error is returned if none is left.
pub fn persistent_facet_points(
    surface: &dyn Surface,
    control: &[DVec3],
    opts: &MeshOptions,
) -> Result<Vec<DVec3>, MeshError> {
    Ok(persistent_facets(surface, control, opts)?.points)
}

/// Like [`persistent_facet_points`], also returning the facets and their balls.
///
/// ```
/// use rdt_mesher::{init::persistent_facets, Criteria, MeshOptions};
/// use oracle::{BoundingSphere, Surface};
/// use glam::DVec3;
/// struct Sphere;
/// impl Surface for Sphere {
///     fn bounding_sphere(&self) -> BoundingSphere {
///         BoundingSphere { center: DVec3::ZERO, radius: 2.0 }
///     }
///     fn value(&self, p: DVec3) -> f64 { p.length_squared() - 1.0 }
/// }
/// let opts = MeshOptions { criteria: Criteria::uniform(0.3), ..Default::default() };
/// let init = persistent_facets(&Sphere, &[DVec3::X, -DVec3::X], &opts).unwrap();
/// assert_eq!(init.facets.len(), 2);
/// for (f, (x, rho)) in init.facets.iter().zip(&init.balls) {
///     assert!(*rho < 0.1); // sigma / 3
///     for p in f {
///         assert!((p.distance(*x) - rho).abs() < 1e-9 && (p.length() - 1.0).abs() < 1e-6);
///     }
/// }
/// ```
pub fn persistent_facets(
    surface: &dyn Surface,
    control: &[DVec3],
    opts: &MeshOptions,
) -> Result<PersistentInit, MeshError> {
    let bs = surface.bounding_sphere();
    let tol = surface.tolerance();
    let dm = surface.dm_inf_hint().filter(|d| *d > 0.0 && d.is_finite());
    let control: Vec<DVec3> = control.iter().copied().filter(|p| p.is_finite()).collect();
    let mut facets = Vec::new();
    let mut balls = Vec::new();
    for (i, &x) in control.iter().enumerate() {
        let half = control
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i)
            .map(|(_, q)| 0.5 * q.distance(x))
            .fold(f64::INFINITY, f64::min);
        if half <= 0.0 {
            continue; // duplicate control point: the first copy gets the facet
        }
        let sigma = opts.criteria.scale_at(x, 0.1 * bs.radius);
        if !(sigma > 0.0 && sigma.is_finite()) {
            return Err(MeshError::InvalidSizeField {
                value: sigma,
                at: x,
            });
        }
        let mut rho = 0.9 * half.min(sigma / 3.0).min(dm.unwrap_or(f64::INFINITY));
        let g = surface.gradient(x);
        let gl = g.length();
        if !(gl > 0.0 && gl.is_finite()) {
            continue;
        }
        let n = g / gl;
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let mut found = None;
        for _ in 0..12 {
            if let Some(f) = facet_on_sphere(surface, x, n, u, v, rho, tol)? {
                found = Some(f);
                break;
            }
            rho *= 0.5;
        }
        if let Some(f) = found {
            facets.push(f);
            balls.push((x, rho));
        }
    }
    if facets.is_empty() {
        return Err(MeshError::NoSeeds {
            center: bs.center,
            radius: bs.radius,
        });
    }
    let mut points: Vec<DVec3> = facets.iter().flatten().copied().collect();
    // A 3D initial sample: random-line seeds outside every ball B_x (so that the balls stay
    // empty), as the mesher would otherwise add them without that care.
    let mut seed = opts.seed;
    let mut tries = 0;
    while points.len() + opts.initial_points.len() < 8 && tries < 8 {
        seed = seed.wrapping_add(0x51ED);
        for p in oracle::roots::random_line_seeds(surface, 64, seed) {
            if points.len() + opts.initial_points.len() >= 8 {
                break;
            }
            if balls.iter().all(|(x, r)| p.distance(*x) > 2.0 * r) {
                points.push(p);
            }
        }
        tries += 1;
    }
    // Section 6.4.2: make every persistent facet bipolar.
    let mut bipolar_insertions = 0;
    for _round in 0..8 {
        let extra = non_bipolar_centers(surface, &points, &opts.initial_points, &facets, &balls)?;
        if extra.is_empty() {
            break;
        }
        bipolar_insertions += extra.len();
        points.extend(extra);
    }
    Ok(PersistentInit {
        points,
        facets,
        balls,
        bipolar_insertions,
    })
}

/// Three points of S on the sphere S(x, rho), on the great arcs from x - rho n to x + rho n
/// through the tangent directions at 0, 120, 240 degrees; `None` if some arc has no sign change.
fn facet_on_sphere(
    s: &dyn Surface,
    x: DVec3,
    n: DVec3,
    u: DVec3,
    v: DVec3,
    rho: f64,
    tol: f64,
) -> Result<Option<[DVec3; 3]>, MeshError> {
    let val = |p: DVec3| -> Result<f64, MeshError> {
        let f = s.value(p);
        if f.is_nan() {
            return Err(oracle::OracleError::NaN(p.x, p.y, p.z).into());
        }
        Ok(f)
    };
    let mut out = [DVec3::ZERO; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let th = k as f64 * std::f64::consts::TAU / 3.0;
        let t = th.cos() * u + th.sin() * v;
        let at = |phi: f64| x + rho * (phi.cos() * t + phi.sin() * n);
        let (mut a, mut b) = (-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2);
        let (fa, fb) = (val(at(a))?, val(at(b))?);
        if fa == 0.0 {
            *o = at(a);
            continue;
        }
        if fb == 0.0 {
            *o = at(b);
            continue;
        }
        if (fa < 0.0) == (fb < 0.0) {
            return Ok(None);
        }
        // Bisection on the angle until the arc length is below the tolerance.
        while rho * (b - a) > tol {
            let m = 0.5 * (a + b);
            if m <= a || m >= b {
                break;
            }
            let fm = val(at(m))?;
            if fm == 0.0 {
                a = m;
                b = m;
                break;
            }
            if (fm < 0.0) == (fa < 0.0) {
                a = m;
            } else {
                b = m;
            }
        }
        *o = at(0.5 * (a + b));
    }
    Ok(Some(out))
}

/// Crossings of S with the dual Voronoi edge of every persistent facet of Del(points), other
/// than the one nearest to the facet's control point x (whose ball is the persistent one).
fn non_bipolar_centers(
    s: &dyn Surface,
    points: &[DVec3],
    initial: &[DVec3],
    facets: &[[DVec3; 3]],
    balls: &[(DVec3, f64)],
) -> Result<Vec<DVec3>, MeshError> {
    let mut tri = Triangulation::new();
    let mut ids: Vec<VertexId> = Vec::with_capacity(points.len());
    for p in points.iter().chain(initial) {
        ids.push(match tri.insert(*p)? {
            Insertion::New(v) | Insertion::Duplicate(v) => v,
        });
    }
    if tri.dimension() < 3 {
        return Ok(Vec::new());
    }
    let bs = s.bounding_sphere();
    let mut out = Vec::new();
    let mut xs = Vec::new();
    for (k, (_, &(x, rho))) in facets.iter().zip(balls).enumerate() {
        let key = sorted([ids[3 * k], ids[3 * k + 1], ids[3 * k + 2]]);
        let Some(f) = tri
            .incident_facets(key[0])
            .into_iter()
            .find(|f| sorted(tri.facet_vertices(*f)) == key)
        else {
            continue; // not a Delaunay facet (another point in B_x): nothing to do here
        };
        let (a, b) = match tri.dual(f) {
            Some(Dual::Segment(a, b)) => (a, b),
            Some(Dual::Ray { origin, direction }) => {
                let d = direction.normalize_or_zero();
                let far = 2.0 * ((origin - bs.center).length() + bs.radius);
                (origin, origin + d * far)
            }
            None => continue,
        };
        let Some((a, b)) = bs.clip_segment(a, b) else {
            continue;
        };
        xs.clear();
        s.crossings(a, b, &mut xs);
        for &c in &xs {
            // The persistent ball's center x is on the edge; keep every other crossing.
            if c.distance(x) > rho {
                out.push(c);
            }
        }
    }
    Ok(out)
}

fn sorted(mut v: [VertexId; 3]) -> [VertexId; 3] {
    v.sort_unstable();
    v
}
