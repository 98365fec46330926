//! Reference implicit surfaces, by name.
//!
//! The eight reference surfaces of the project catalog (`data/implicit_surfaces.json`, a copy of
//! the shared catalog: `sphere`, `ellipsoid`, `torus`, `double_torus`, `tanglecube`, `chair`,
//! `blobs`, `heart`) and three surfaces of the paper's section 6 experiments:
//!
//! - `trefoil`: the "sausage" trefoil knot of the paper's figure 5, built as the paper describes.
//!   The trefoil is the link of the singularity `w^2 = z^3` in C^2: the curve
//!   `F(z, w) = w^2 - z^3 = 0` on the unit sphere S^3 of C^2 = R^4. Pulling `F` back to R^3 by the
//!   inverse stereographic projection `p -> (2p, |p|^2 - 1) / (|p|^2 + 1)` (pole (0,0,0,1) sent to
//!   infinity), with `z = X1 + i X2`, `w = X3 + i X4`, gives `f1 = Re F` and `f2 = Im F`, two
//!   surfaces of R^3 meeting along a trefoil; the surface is `f1^2 + f2^2 = 0.02`, a tube of
//!   varying radius (about 0.04 to 0.21; strands stay 0.73 apart) around that (2,3) torus knot, which lies on the torus
//!   of revolution of radii 1.325 and 0.869 around the z axis. Genus 1. The chirality is that
//!   of this formula (not checked against the paper's "left").
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
    pub name: &'static str,
    /// Expression in x, y, z (syntax of [`crate::expr`]); the solid is `f < 0`.
    pub expression: String,
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
pub enum CatalogError {
    #[error("unknown catalog surface '{name}'; known: {known}")]
    UnknownName { name: String, known: String },
    #[error(
        "'{expression}' is an expression, not a catalog surface: give its bounding sphere (cx,cy,cz,r) too"
    )]
    MissingBoundingSphere { expression: String },
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
/// Tube parameter of `trefoil`: the surface is `|F|^2 = TREFOIL_DELTA`.
pub const TREFOIL_DELTA: f64 = 0.02;

fn trefoil_expression() -> String {
    let r2 = "(x^2+y^2+z^2)";
    let d = format!("(1+{r2})");
    let x1 = format!("(2*x/{d})");
    let x2 = format!("(2*y/{d})");
    let x3 = format!("(2*z/{d})");
    let x4 = format!("(({r2}-1)/{d})");
    let re = format!("({x3}^2-{x4}^2-{x1}^3+3*{x1}*{x2}^2)");
    let im = format!("(2*{x3}*{x4}-3*{x1}^2*{x2}+{x2}^3)");
    format!("{re}^2+{im}^2-{TREFOIL_DELTA}")
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
                expression: r.f,
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
    let ball = |r: f64| BoundingSphere {
        center: DVec3::ZERO,
        radius: r,
    };
    out.push(CatalogEntry {
        name: "trefoil",
        expression: trefoil_expression(),
        bounding_sphere: ball(3.0),
        smooth: true,
        genus: Some(1),
        components: Some(1),
        dm_inf: None,
        reference: false,
    });
    out.push(CatalogEntry {
        name: "barth_octic",
        expression: octic_expression(),
        bounding_sphere: ball(2.0),
        smooth: false,
        genus: None,
        components: None,
        dm_inf: None,
        reference: false,
    });
    out.push(CatalogEntry {
        name: "klein_bottle",
        expression: "(x^2+y^2+z^2+2*y-1)*((x^2+y^2+z^2-2*y-1)^2-8*z^2)+16*x*z*(x^2+y^2+z^2-2*y-1)"
            .into(),
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

fn trefoil_native(p: DVec3) -> f64 {
    let r2 = p.length_squared();
    let inv = 1.0 / (1.0 + r2);
    let (x1, x2, x3, x4) = (
        2.0 * p.x * inv,
        2.0 * p.y * inv,
        2.0 * p.z * inv,
        (r2 - 1.0) * inv,
    );
    // F = w^2 - z^3 with z = x1 + i x2, w = x3 + i x4.
    let re = x3 * x3 - x4 * x4 - (x1 * x1 * x1 - 3.0 * x1 * x2 * x2);
    let im = 2.0 * x3 * x4 - (3.0 * x1 * x1 * x2 - x2 * x2 * x2);
    re * re + im * im - TREFOIL_DELTA
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
    let expr = Arc::new(Expr::parse(&e.expression).map_err(|err| wrap(err.into()))?);
    let mut b =
        ImplicitSurface::builder(f, e.bounding_sphere).gradient(move |p| expr.eval_grad(p).1);
    if let Some(d) = e.dm_inf {
        b = b.dm_inf_hint(d);
    }
    b.build().map_err(wrap)
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
    let mut b =
        ImplicitSurface::builder_from_expr(&e.expression, e.bounding_sphere).map_err(wrap)?;
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
        let expr = Arc::new(Expr::parse(&e.expression).map_err(|err| wrap(err.into()))?);
        let mut b = ImplicitSurface::builder(f, bs).gradient(move |p| expr.eval_grad(p).1);
        if let Some(d) = e.dm_inf {
            b = b.dm_inf_hint(d);
        }
        return b.build().map_err(wrap);
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
