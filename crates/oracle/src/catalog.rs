//! Reference implicit surfaces by name (ours; the paper's examples of section 6.6.1 among them).
//!
//! The eight reference surfaces of the project catalog (`data/implicit_surfaces.json`, a copy of
//! the shared catalog: `sphere`, `ellipsoid`, `torus`, `double_torus`, `tanglecube`, `chair`,
//! `blobs`, `heart`) and three surfaces of the paper's section 6 experiments:
//!
//! - `trefoil`: the trefoil knot "in sausage format" of the paper's figure 5 (section 6.6.1), as a
//!   tube of constant radius 0.2 around the (2,3) torus knot
//!   `c(t) = ((1 + 0.5 cos 3t) cos 2t, (1 + 0.5 cos 3t) sin 2t, -0.5 sin 3t)`: `f(p) = dist(p, c) -
//!   0.2`, evaluated natively (nearest of 128 samples of c, then safeguarded Newton on the curve
//!   parameter: exact to rounding wherever f < 0.13; elsewhere >= 0.13, a lower bound of the
//!   distance to the curve's torus of revolution far from it) with the exact
//!   gradient `(p - c(t*)) / |p - c(t*)|`. The curve's reach is 0.416 (half its smallest
//!   doubly-critical distance, 0.832; its smallest radius of curvature is 0.715), so the tube's
//!   medial axis is the curve inside and at least 0.216 away outside: d_M = 0.2 on the whole
//!   surface (the catalog's `dm_inf`), like a torus. Genus 1. The paper builds its sausage as
//!   `f1^2 + f2^2 = delta` from two algebraic surfaces meeting along the knot, and notes that
//!   its radius is not constant; done literally (stereographic image of `w^2 = z^3` on S^3),
//!   that tube's radius varies fivefold along the knot, and so does d_M, unlike the paper's
//!   "almost constant diameter" of Table 1. This one has no closed-form expression
//!   ([`CatalogEntry::expression`] is `None`; [`surface_from_expression`] refuses it).
//! - `barth_octic`: the octic with cubic symmetry meshed in the paper's figure 7 (eight pillows at
//!   the vertices of a cube, joined by two nodes along each edge; 24 singular points):
//!   with `s = x^2+y^2+z^2`, `q = x^2 y^2 + y^2 z^2 + z^2 x^2` and the golden ratio `phi`,
//!   `phi^5 s^4 - (phi^7 + phi) s^3 + (phi^7 + phi + 7) s^2 - 32 q - 2 (phi^4 - 1) s + phi`.
//!   Not smooth.
//! - `klein_bottle`: the classic immersed Klein bottle sextic
//!   `(s + 2y - 1)((s - 2y - 1)^2 - 8z^2) + 16xz(s - 2y - 1)`. Not a manifold in R^3 (it
//!   self-intersects), not smooth.
//!
//! [`surface`] evaluates every catalog surface with a native Rust closure (the fast path, no
//! interpretation); its gradient is the exact derivative of the compiled expression.
//!
//! ```
//! use oracle::{Surface, catalog};
//! let torus = catalog::surface("torus").unwrap();
//! assert_eq!(torus.dm_inf_hint(), Some(0.3));
//! let e = catalog::entry("tanglecube").unwrap();
//! assert_eq!((e.genus, e.components), (Some(5), Some(1)));
//! assert!(catalog::names().contains(&"trefoil"));
//! assert!(catalog::surface("teapot").is_err());
//! ```

use crate::BoundingSphere;
use crate::expr::Expr;
use crate::implicit::{ImplicitError, ImplicitSurface};
use glam::DVec3;
use std::sync::{Arc, OnceLock};

/// The shared catalog, embedded.
pub const CATALOG_JSON: &str = include_str!("../data/implicit_surfaces.json");

/// One catalog surface.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CatalogEntry {
    /// The catalog name (e.g. `torus`).
    pub name: &'static str,
    /// Expression in x, y, z (syntax of [`crate::expr`]); the solid is `f < 0`. `None` for a
    /// surface with a native implementation only (`trefoil`).
    pub expression: Option<String>,
    /// A sphere holding the surface (the value is positive on it).
    pub bounding_sphere: BoundingSphere,
    /// False if the surface has singular points (mesh with a constant size bound).
    pub smooth: bool,
    /// Genus of the surface, if it is an orientable closed manifold of known genus.
    pub genus: Option<u32>,
    /// Number of connected components, if known.
    pub components: Option<u32>,
    /// Known d_M^inf (reach), if known.
    pub dm_inf: Option<f64>,
    /// True for the entries of the shared reference catalog (false for the paper's extras).
    pub reference: bool,
}

/// Errors of [`surface`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[allow(missing_docs)] // variant fields: named in the variant's docs and message
pub enum CatalogError {
    /// No catalog surface is called `name` (`known` lists the names).
    /// An expression was given where a catalog name was expected, without a bounding sphere.
    /// The surface `name` is native only (no expression to build it from).
    /// Building the implicit surface `name` failed.
    #[error("unknown catalog surface '{name}'; known: {known}")]
    UnknownName { name: String, known: String },
    #[error(
        "'{expression}' is an expression, not a catalog surface: give its bounding sphere (cx,cy,cz,r) too"
    )]
    MissingBoundingSphere { expression: String },
    #[error(
        "catalog surface '{name}' has no closed-form expression (it is evaluated natively): use catalog::surface(\"{name}\")"
    )]
    NoExpression { name: String },
    #[error("surface '{name}': {source}")]
    Implicit {
        name: String,
        #[source]
        source: Box<ImplicitError>,
    },
}

#[derive(serde::Deserialize)]
struct RawSphere {
    center: [f64; 3],
    radius: f64,
}

#[derive(serde::Deserialize)]
struct RawEntry {
    name: String,
    f: String,
    inside: String,
    bounding_sphere: RawSphere,
    smooth: bool,
    genus: u32,
    components: u32,
}

const PHI: f64 = 1.618_033_988_749_895;
/// Radius of the torus of revolution carrying the `trefoil` curve.
pub const TREFOIL_R: f64 = 1.0;
/// Radius of the tube of that torus (the curve winds 3 times around it).
pub const TREFOIL_A: f64 = 0.5;
/// Radius of the `trefoil` sausage, equal to its d_M everywhere.
pub const TREFOIL_TUBE: f64 = 0.2;
const TREFOIL_SAMPLES: usize = 128;
/// [`trefoil_nearest`] is exact where |f| < this.
const TREFOIL_EXACT: f64 = 0.13;

/// The trefoil curve c(t) and its first two derivatives.
pub fn trefoil_curve(t: f64) -> (DVec3, DVec3, DVec3) {
    let (s1, c1) = t.sin_cos();
    let (s2, c2) = (2.0 * s1 * c1, c1 * c1 - s1 * s1);
    let (s3, c3) = (s1 * (3.0 - 4.0 * s1 * s1), c1 * (4.0 * c1 * c1 - 3.0));
    let (r, a) = (TREFOIL_R, TREFOIL_A);
    let rho = r + a * c3;
    let d_rho = -3.0 * a * s3;
    let dd_rho = -9.0 * a * c3;
    (
        DVec3::new(rho * c2, rho * s2, -a * s3),
        DVec3::new(
            d_rho * c2 - 2.0 * rho * s2,
            d_rho * s2 + 2.0 * rho * c2,
            -3.0 * a * c3,
        ),
        DVec3::new(
            dd_rho * c2 - 4.0 * d_rho * s2 - 4.0 * rho * c2,
            dd_rho * s2 + 4.0 * d_rho * c2 - 4.0 * rho * s2,
            9.0 * a * s3,
        ),
    )
}

/// The point of the trefoil curve nearest to `p` (exact to rounding where dist(p, c) < 0.33;
/// elsewhere a curve point at distance > 0.33).
///
/// The nearest of 128 samples (parameter step h = 2 pi / 128; consecutive samples at most 0.17
/// apart, so every curve point is within 0.085 of one, and the sample distance exceeds the
/// true distance d by less than 0.09; only those of nearby azimuth are looked at) is on the
/// right strand when d < 0.33: the other strands
/// are at least 0.832 - d away, more than d + 0.17. Its distance above 0.42 means d > 0.33: the
/// sample is returned. Otherwise the distance has a single minimum within one step of that
/// sample, found by Newton's method on g'(t) = (c(t) - p) . c'(t), safeguarded by bisection of
/// the bracket [t_k - h, t_k + h].
pub fn trefoil_nearest(p: DVec3) -> DVec3 {
    static SAMPLES: OnceLock<Vec<DVec3>> = OnceLock::new();
    let h = std::f64::consts::TAU / TREFOIL_SAMPLES as f64;
    let samples = SAMPLES.get_or_init(|| {
        (0..TREFOIL_SAMPLES)
            .map(|k| trefoil_curve(k as f64 * h).0)
            .collect()
    });
    // Only the samples whose azimuth 2t is within 1.2 rad of p's (two windows of the parameter,
    // one per pass of the knot through that half-plane): a curve point within 0.42 of p is
    // within asin(0.42 / 0.5) < 1.01 rad of p's azimuth, the curve being at least 0.5 from
    // the z axis.
    let n = TREFOIL_SAMPLES as i64;
    let t0 = p.y.atan2(p.x).rem_euclid(std::f64::consts::TAU) / 2.0;
    let k0 = (t0 / h).round() as i64;
    let (mut k, mut best) = (0, f64::INFINITY);
    for base in [k0, k0 + n / 2] {
        for i in base - 10..=base + 10 {
            let i = i.rem_euclid(n) as usize;
            let d = samples[i].distance_squared(p);
            if d < best {
                (k, best) = (i, d);
            }
        }
    }
    // Far from the curve (the true distance is > sqrt(best) - 0.09, see below): the sample.
    if best > (TREFOIL_TUBE + TREFOIL_EXACT + 0.09).powi(2) {
        return samples[k];
    }
    let tk = k as f64 * h;
    let (mut lo, mut hi, mut t) = (tk - h, tk + h, tk);
    for _ in 0..60 {
        let (c, d1, d2) = trefoil_curve(t);
        let w = c - p;
        let g1 = w.dot(d1);
        if g1 == 0.0 {
            break;
        }
        if g1 > 0.0 {
            hi = t;
        } else {
            lo = t;
        }
        let g2 = d1.length_squared() + w.dot(d2);
        let step = g1 / g2;
        // Quadratic convergence: after a step below 1e-9 the error in t is ~1e-18.
        if g2 > 0.0 && step.abs() <= 1e-9 {
            t -= step;
            break;
        }
        let next = t - step;
        t = if g2 > 0.0 && next > lo && next < hi {
            next
        } else {
            0.5 * (lo + hi)
        };
        if hi - lo <= 1e-12 {
            break;
        }
    }
    let c = trefoil_curve(t).0;
    if c.distance_squared(p) <= best {
        c
    } else {
        samples[k]
    }
}

fn trefoil_native(p: DVec3) -> f64 {
    // The curve lies on the torus of revolution (R, a): the distance to that torus is a lower
    // bound of the distance to the curve. Far from it (most points of a segment crossing the
    // bounding ball) that bound is returned: f >= 0.13 there, no root, and it is 50x cheaper.
    let rho = (p.x * p.x + p.y * p.y).sqrt() - TREFOIL_R;
    let lower = ((rho * rho + p.z * p.z).sqrt() - TREFOIL_A).abs();
    if lower > TREFOIL_TUBE + TREFOIL_EXACT {
        return lower - TREFOIL_TUBE;
    }
    p.distance(trefoil_nearest(p)) - TREFOIL_TUBE
}

fn trefoil_gradient(p: DVec3) -> DVec3 {
    let w = p - trefoil_nearest(p);
    let l = w.length();
    if l > 0.0 { w / l } else { DVec3::Z }
}

fn octic_coefficients() -> [f64; 6] {
    let p = PHI;
    [
        p.powi(5),
        p.powi(7) + p,
        p.powi(7) + p + 7.0,
        32.0,
        2.0 * (p.powi(4) - 1.0),
        p,
    ]
}

fn octic_expression() -> String {
    let [a, b, c, d, e, g] = octic_coefficients();
    format!(
        "{a}*(x^2+y^2+z^2)^4-{b}*(x^2+y^2+z^2)^3+{c}*(x^2+y^2+z^2)^2-{d}*(x^2*y^2+y^2*z^2+z^2*x^2)-{e}*(x^2+y^2+z^2)+{g}"
    )
}

fn load() -> Vec<CatalogEntry> {
    let raw: Vec<RawEntry> = serde_json::from_str(CATALOG_JSON)
        .expect("embedded data/implicit_surfaces.json is valid (tested)");
    let known_dm = |n: &str| match n {
        "sphere" => Some(1.0),
        "torus" => Some(0.3),
        "ellipsoid" => Some(0.16),
        _ => None,
    };
    let mut out: Vec<CatalogEntry> = raw
        .into_iter()
        .map(|r| {
            debug_assert_eq!(r.inside, "f < 0");
            let name: &'static str = Box::leak(r.name.into_boxed_str());
            CatalogEntry {
                name,
                expression: Some(r.f),
                bounding_sphere: BoundingSphere {
                    center: DVec3::from_array(r.bounding_sphere.center),
                    radius: r.bounding_sphere.radius,
                },
                smooth: r.smooth,
                genus: Some(r.genus),
                components: Some(r.components),
                dm_inf: known_dm(name),
                reference: true,
            }
        })
        .collect();
    let ball = BoundingSphere::at_origin;
    out.push(CatalogEntry {
        name: "trefoil",
        expression: None,
        bounding_sphere: ball(2.0),
        smooth: true,
        genus: Some(1),
        components: Some(1),
        dm_inf: Some(TREFOIL_TUBE),
        reference: false,
    });
    out.push(CatalogEntry {
        name: "barth_octic",
        expression: Some(octic_expression()),
        bounding_sphere: ball(2.0),
        smooth: false,
        genus: None,
        components: None,
        dm_inf: None,
        reference: false,
    });
    out.push(CatalogEntry {
        name: "klein_bottle",
        expression: Some(
            "(x^2+y^2+z^2+2*y-1)*((x^2+y^2+z^2-2*y-1)^2-8*z^2)+16*x*z*(x^2+y^2+z^2-2*y-1)".into(),
        ),
        bounding_sphere: ball(5.0),
        smooth: false,
        genus: None,
        components: Some(1),
        dm_inf: None,
        reference: false,
    });
    out
}

/// Every catalog entry, reference ones first (in the JSON's order), then the paper's extras.
pub fn entries() -> &'static [CatalogEntry] {
    static ENTRIES: OnceLock<Vec<CatalogEntry>> = OnceLock::new();
    ENTRIES.get_or_init(load)
}

/// Names of all catalog surfaces.
pub fn names() -> Vec<&'static str> {
    entries().iter().map(|e| e.name).collect()
}

/// The entry named `name`.
pub fn entry(name: &str) -> Option<CatalogEntry> {
    entries().iter().find(|e| e.name == name).cloned()
}

/// Native Rust implementation of the catalog function `name` (equal to the compiled expression
/// up to rounding; tested).
pub fn native_fn(name: &str) -> Option<fn(DVec3) -> f64> {
    Some(match name {
        "sphere" => |p| p.x * p.x + p.y * p.y + p.z * p.z - 1.0,
        "ellipsoid" => |p| {
            let (y, z) = (p.y / 0.6, p.z / 0.4);
            p.x * p.x + y * y + z * z - 1.0
        },
        "torus" => |p| {
            let (x2, y2, z2) = (p.x * p.x, p.y * p.y, p.z * p.z);
            let s = x2 + y2 + z2 + 1.0 - 0.09;
            s * s - 4.0 * (x2 + y2)
        },
        "double_torus" => |p| {
            let (x, y, z) = (p.x, p.y, p.z);
            let xm = x - 1.0;
            let t = x * (xm * xm) * (x - 2.0) + y * y;
            t * t + z * z - 0.03
        },
        "tanglecube" => |p| {
            let (x2, y2, z2) = (p.x * p.x, p.y * p.y, p.z * p.z);
            x2 * x2 - 5.0 * x2 + y2 * y2 - 5.0 * y2 + z2 * z2 - 5.0 * z2 + 11.8
        },
        "chair" => |p| {
            let (x2, y2, z2) = (p.x * p.x, p.y * p.y, p.z * p.z);
            let s = x2 + y2 + z2 - 0.95 * 25.0;
            let (zm, zp) = (p.z - 5.0, p.z + 5.0);
            s * s - 0.8 * (zm * zm - 2.0 * x2) * (zp * zp - 2.0 * y2)
        },
        "blobs" => |p| {
            let (x, y, z) = (p.x, p.y, p.z);
            let (y2, z2) = (y * y, z * z);
            let (xm, xp, ym) = (x - 0.5, x + 0.5, y - 0.6);
            0.5 - (-(xm * xm + y2 + z2) / 0.2).exp()
                - (-(xp * xp + y2 + z2) / 0.2).exp()
                - (-(x * x + ym * ym + z2) / 0.1).exp()
        },
        "heart" => |p| {
            let (x2, y2, z2) = (p.x * p.x, p.y * p.y, p.z * p.z);
            let t = x2 + 2.25 * y2 + z2 - 1.0;
            let z3 = z2 * p.z;
            t * t * t - x2 * z3 - 0.1125 * y2 * z3
        },
        "trefoil" => trefoil_native,
        "barth_octic" => |p| {
            let [a, b, c, d, e, g] = octic_coefficients();
            let (x2, y2, z2) = (p.x * p.x, p.y * p.y, p.z * p.z);
            let s = x2 + y2 + z2;
            let q = x2 * y2 + y2 * z2 + z2 * x2;
            let s2 = s * s;
            a * s2 * s2 - b * s2 * s + c * s2 - d * q - e * s + g
        },
        "klein_bottle" => |p| {
            let (x, y, z) = (p.x, p.y, p.z);
            let s = x * x + y * y + z * z;
            let m = s - 2.0 * y - 1.0;
            (s + 2.0 * y - 1.0) * (m * m - 8.0 * z * z) + 16.0 * x * z * m
        },
        _ => return None,
    })
}

/// The catalog surface `name`, evaluated by its native closure, with the exact gradient of its
/// expression and its known d_M^inf as [`crate::Surface::dm_inf_hint`].
///
/// ```
/// use glam::DVec3;
/// use oracle::{Surface, catalog};
/// let s = catalog::surface("sphere").unwrap();
/// let (a, b) = (DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0));
/// let p = s.crossing(a, s.value(a), b, s.value(b));
/// assert!((p.x - 1.0).abs() <= s.tolerance());
/// ```
pub fn surface(name: &str) -> Result<ImplicitSurface, CatalogError> {
    let unknown = || CatalogError::UnknownName {
        name: name.to_string(),
        known: names().join(", "),
    };
    let e = entry(name).ok_or_else(unknown)?;
    let f = native_fn(name).ok_or_else(unknown)?;
    let wrap = |source: ImplicitError| CatalogError::Implicit {
        name: name.to_string(),
        source: Box::new(source),
    };
    native_builder(&e, f, e.bounding_sphere, &wrap)?
        .build()
        .map_err(wrap)
}

/// Builder of a catalog surface's native closure with its exact gradient (of the expression, or
/// native for `trefoil`) and its d_M^inf hint.
fn native_builder(
    e: &CatalogEntry,
    f: fn(DVec3) -> f64,
    bs: BoundingSphere,
    wrap: &dyn Fn(ImplicitError) -> CatalogError,
) -> Result<crate::implicit::ImplicitBuilder, CatalogError> {
    let mut b = ImplicitSurface::builder(f, bs);
    b = match &e.expression {
        Some(x) => {
            let expr = Arc::new(Expr::parse(x).map_err(|err| wrap(err.into()))?);
            b.gradient(move |p| expr.eval_grad(p).1)
        }
        None => b.gradient(trefoil_gradient),
    };
    if let Some(d) = e.dm_inf {
        b = b.dm_inf_hint(d);
    }
    Ok(b)
}

/// The catalog surface `name` evaluated through its compiled expression (the slow path that a
/// user expression takes; for comparisons and benches).
pub fn surface_from_expression(name: &str) -> Result<ImplicitSurface, CatalogError> {
    let e = entry(name).ok_or_else(|| CatalogError::UnknownName {
        name: name.to_string(),
        known: names().join(", "),
    })?;
    let wrap = |source: ImplicitError| CatalogError::Implicit {
        name: name.to_string(),
        source: Box::new(source),
    };
    let Some(x) = &e.expression else {
        return Err(CatalogError::NoExpression {
            name: name.to_string(),
        });
    };
    let mut b = ImplicitSurface::builder_from_expr(x, e.bounding_sphere).map_err(wrap)?;
    if let Some(d) = e.dm_inf {
        b = b.dm_inf_hint(d);
    }
    b.build().map_err(wrap)
}

/// Resolve a command-line surface spec: a catalog name (optionally with another bounding
/// sphere) or an expression in x, y, z (which needs a bounding sphere). A bare word that is
/// neither a catalog name nor a valid expression is reported as an unknown catalog name.
///
/// ```
/// use oracle::{BoundingSphere, Surface, catalog};
/// let t = catalog::resolve("torus", None).unwrap();
/// assert_eq!(t.bounding_sphere().radius, 2.0);
/// let bs = BoundingSphere { center: glam::DVec3::ZERO, radius: 3.0 };
/// let e = catalog::resolve("x^2+y^2+z^2-4", Some(bs)).unwrap();
/// assert!(e.value(glam::DVec3::ZERO) < 0.0);
/// assert!(catalog::resolve("x^2+y^2+z^2-4", None).is_err()); // needs a bounding sphere
/// assert!(catalog::resolve("teapot", Some(bs)).is_err()); // unknown name
/// ```
pub fn resolve(spec: &str, bs: Option<BoundingSphere>) -> Result<ImplicitSurface, CatalogError> {
    let spec = spec.trim();
    let wrap = |source: ImplicitError| CatalogError::Implicit {
        name: spec.to_string(),
        source: Box::new(source),
    };
    if let (Some(e), Some(f)) = (entry(spec), native_fn(spec)) {
        let Some(bs) = bs else {
            return surface(spec);
        };
        return native_builder(&e, f, bs, &wrap)?.build().map_err(wrap);
    }
    let is_word = !spec.is_empty() && spec.chars().all(|c| c.is_alphanumeric() || c == '_');
    let expr = match Expr::parse(spec) {
        Ok(x) => x,
        Err(_) if is_word => {
            return Err(CatalogError::UnknownName {
                name: spec.to_string(),
                known: names().join(", "),
            });
        }
        Err(err) => return Err(wrap(err.into())),
    };
    let Some(bs) = bs else {
        return Err(CatalogError::MissingBoundingSphere {
            expression: spec.to_string(),
        });
    };
    ImplicitSurface::builder_from_compiled(Arc::new(expr), bs)
        .build()
        .map_err(wrap)
}
