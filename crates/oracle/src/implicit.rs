//! Implicit surfaces (section 6.6.1): the zero set of a function `f` (solid where `f < 0`)
//! inside a bounding sphere, given as a Rust closure or an expression string (compiled once,
//! see [`crate::expr`]).
//!
//! Construction checks the input and fails with an [`ImplicitError`] when:
//! - the bounding sphere has a non-finite center or a radius that is not finite and positive;
//! - `f <= 0` (or NaN) at one of ~2000 points of a Fibonacci lattice on the bounding sphere
//!   (the surface crosses or touches it);
//! - `f` is NaN at a point of the seed grid inside the ball;
//! - no point of the seed grid (default 33^3 vertices on the ball's bounding cube) has `f < 0`
//!   and no seed point was given: the surface is empty or thinner than the grid step.
//!
//! At query time the value is returned as is: the mesher turns NaN into
//! [`crate::OracleError::NaN`]; the root finders here return a point with NaN coordinates
//! when `f` is NaN at a probe (never a silently wrong point).
//!
//! ```
//! use glam::DVec3;
//! use oracle::{BoundingSphere, Surface, implicit::ImplicitSurface};
//!
//! let bs = BoundingSphere::at_origin(2.0);
//! // From a closure (solid where f < 0) ...
//! let sphere = ImplicitSurface::from_fn(|p: DVec3| p.length_squared() - 1.0, bs).unwrap();
//! // ... or from an expression, with an exact gradient.
//! let torus = ImplicitSurface::from_expr("(x^2+y^2+z^2+1-0.09)^2-4*(x^2+y^2)", bs).unwrap();
//! let p = torus.crossing(DVec3::ZERO, torus.value(DVec3::ZERO), DVec3::new(1.0, 0.0, 0.0),
//!                        torus.value(DVec3::new(1.0, 0.0, 0.0)));
//! assert!((p.x - 0.7).abs() < 1e-6);
//! assert!(sphere.seed_points(1).iter().all(|q| (q.length() - 1.0).abs() < 1e-6));
//! // Bad input is an error, not a panic.
//! assert!(ImplicitSurface::from_expr("x^2+y^2+z^2-9", bs).is_err()); // crosses the sphere
//! assert!(ImplicitSurface::from_expr("x^2+(y^2-1", bs).is_err()); // does not parse
//! ```

use crate::expr::{Expr, ExprError};
use crate::roots;
pub use crate::roots::central_difference;
use crate::{BoundingSphere, Surface};
use glam::DVec3;
use rayon::prelude::*;
use std::fmt;
use std::sync::Arc;

/// A value function: negative inside the solid, positive outside.
pub type ValueFn = dyn Fn(DVec3) -> f64 + Send + Sync;
/// A gradient function.
pub type GradientFn = dyn Fn(DVec3) -> DVec3 + Send + Sync;

/// Errors detected when building an [`ImplicitSurface`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[allow(missing_docs)] // variant fields: named in the variant's docs and message
pub enum ImplicitError {
    /// The bounding sphere has a non-finite center or a radius not finite and positive.
    /// The value is not positive at `point` of the bounding sphere.
    /// The value is NaN at `point` in the bounding ball.
    /// No sample of the seed grid is inside the solid.
    /// A builder parameter `name` is not finite and positive.
    /// A user seed point is not finite or outside the bounding sphere.
    /// The expression does not parse.
    /// A bounding sphere given as text is malformed.
    #[error(
        "invalid bounding sphere: center ({}, {}, {}) and radius {radius}; the center must be finite and the radius finite and > 0",
        center[0], center[1], center[2]
    )]
    BadBoundingSphere { center: [f64; 3], radius: f64 },
    #[error(
        "the surface crosses or touches the bounding sphere (center ({}, {}, {}), radius {radius}): f({}, {}, {}) = {value}, but f must be > 0 on the sphere; enlarge the radius or move the center",
        center[0], center[1], center[2], point[0], point[1], point[2]
    )]
    CrossesBoundary {
        point: [f64; 3],
        value: f64,
        center: [f64; 3],
        radius: f64,
    },
    #[error(
        "the surface function returned NaN at ({}, {}, {}) (in the bounding ball); fix the function or its domain",
        point[0], point[1], point[2]
    )]
    NaN { point: [f64; 3] },
    #[error(
        "no surface inside the bounding sphere: f >= 0 at all {samples} points of a {n}^3 grid (step {step}); the solid f < 0 is empty or thinner than the step: shrink the bounding sphere around the surface (the step scales with it; in the library, `ImplicitSurface::seed_grid` refines the grid)"
    )]
    NoSurfaceInside { n: usize, samples: usize, step: f64 },
    #[error("invalid {name} = {value}: it must be finite and > 0")]
    BadParameter { name: &'static str, value: f64 },
    #[error(
        "seed point ({}, {}, {}) is not finite or outside the bounding sphere",
        point[0], point[1], point[2]
    )]
    BadSeedPoint { point: [f64; 3] },
    #[error("invalid expression: {0}")]
    Expr(#[from] ExprError),
    #[error("invalid bounding sphere '{text}': {reason}; write it as cx,cy,cz,r (e.g. 0,0,0,2)")]
    BoundingSphereSyntax { text: String, reason: String },
}

/// Parse a bounding sphere written `cx,cy,cz,r` (as on the command line). The values are only
/// checked for syntax and finiteness here, the radius sign by [`ImplicitBuilder::build`].
///
/// ```
/// let bs = oracle::implicit::parse_bounding_sphere("1, 0, 0, 2.5").unwrap();
/// assert_eq!((bs.center.x, bs.radius), (1.0, 2.5));
/// assert!(oracle::implicit::parse_bounding_sphere("0,0,2").is_err());
/// ```
pub fn parse_bounding_sphere(text: &str) -> Result<BoundingSphere, ImplicitError> {
    let err = |reason: String| ImplicitError::BoundingSphereSyntax {
        text: text.to_string(),
        reason,
    };
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != 4 {
        return Err(err(format!("expected 4 numbers, found {}", parts.len())));
    }
    let mut v = [0.0; 4];
    for (x, p) in v.iter_mut().zip(&parts) {
        *x = p
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| err(format!("'{p}' is not a finite number")))?;
    }
    Ok(BoundingSphere {
        center: DVec3::new(v[0], v[1], v[2]),
        radius: v[3],
    })
}

/// The function `f` of an implicit surface with its exact gradient and its source expression,
/// when known (shared, cheap to clone).
#[derive(Clone)]
struct Function {
    f: Arc<ValueFn>,
    grad: Option<Arc<GradientFn>>,
    expr: Option<Arc<Expr>>,
}

/// An implicit surface `f = 0` with its bounding sphere; implements [`Surface`]. Cheap to clone
/// (shared function and precomputed grid).
#[derive(Clone)]
pub struct ImplicitSurface {
    func: Function,
    bs: BoundingSphere,
    dm_inf: Option<f64>,
    tolerance: f64,
    crossing_step: f64,
    sign_only: bool,
    grid: Arc<Grid>,
    user_seeds: Vec<DVec3>,
    max_seeds: usize,
    lines: usize,
}

impl fmt::Debug for ImplicitSurface {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ImplicitSurface")
            .field(
                "expr",
                &self.func.expr.as_ref().map(|e| e.source().to_string()),
            )
            .field("bounding_sphere", &self.bs)
            .field("dm_inf", &self.dm_inf)
            .field("tolerance", &self.tolerance)
            .field("crossing_step", &self.crossing_step)
            .field("sign_only", &self.sign_only)
            .field("grid_n", &self.grid.n)
            .finish_non_exhaustive()
    }
}

/// Options of an [`ImplicitSurface`], checked by [`ImplicitBuilder::build`].
pub struct ImplicitBuilder {
    func: Function,
    bs: BoundingSphere,
    dm_inf: Option<f64>,
    tolerance: Option<f64>,
    crossing_step: Option<f64>,
    grid_n: usize,
    user_seeds: Vec<DVec3>,
    max_seeds: usize,
    lines: usize,
    sphere_samples: usize,
}

impl ImplicitBuilder {
    /// An analytic gradient (else: central differences, or the exact one of an expression).
    pub fn gradient(mut self, g: impl Fn(DVec3) -> DVec3 + Send + Sync + 'static) -> Self {
        self.func.grad = Some(Arc::new(g));
        self
    }
    /// A known lower bound of d_M^inf (reach), returned by [`Surface::dm_inf_hint`].
    pub fn dm_inf_hint(mut self, d: f64) -> Self {
        self.dm_inf = Some(d);
        self
    }
    /// Crossing precision (absolute). Default 1e-7 of the bounding radius.
    pub fn tolerance(mut self, t: f64) -> Self {
        self.tolerance = Some(t);
        self
    }
    /// Sampling step of the intersection oracle. Default 1e-3 of the bounding radius.
    pub fn crossing_step(mut self, s: f64) -> Self {
        self.crossing_step = Some(s);
        self
    }
    /// Cells per axis of the seed grid on the ball's bounding cube (default 32, clamped to
    /// 2..=256).
    pub fn seed_grid(mut self, n: usize) -> Self {
        self.grid_n = n.clamp(2, 256);
        self
    }
    /// Points known to be on (or near) S: returned first by [`Surface::seed_points`]. They must
    /// be finite and inside the bounding sphere.
    pub fn seed_points(mut self, pts: Vec<DVec3>) -> Self {
        self.user_seeds = pts;
        self
    }
    /// Cap of the seed list (default 200; user seed points are always kept).
    pub fn max_seeds(mut self, n: usize) -> Self {
        self.max_seeds = n.max(1);
        self
    }
    /// Random lines shot by [`Surface::seed_points`] in addition to the grid (default 64).
    pub fn random_lines(mut self, n: usize) -> Self {
        self.lines = n;
        self
    }

    /// Check everything (see the module doc) and precompute the seed grid.
    pub fn build(self) -> Result<ImplicitSurface, ImplicitError> {
        let bs = self.bs;
        if !(bs.center.is_finite() && bs.radius.is_finite() && bs.radius > 0.0) {
            return Err(ImplicitError::BadBoundingSphere {
                center: bs.center.to_array(),
                radius: bs.radius,
            });
        }
        let positive = |name: &'static str, v: Option<f64>| match v {
            Some(v) if !(v.is_finite() && v > 0.0) => {
                Err(ImplicitError::BadParameter { name, value: v })
            }
            _ => Ok(()),
        };
        positive("dm_inf_hint", self.dm_inf)?;
        positive("tolerance", self.tolerance)?;
        positive("crossing_step", self.crossing_step)?;
        for p in &self.user_seeds {
            if !p.is_finite() || !bs.contains(*p) {
                return Err(ImplicitError::BadSeedPoint {
                    point: p.to_array(),
                });
            }
        }
        let f = &*self.func.f;
        // 1. f > 0 on the bounding sphere.
        let lattice = fibonacci_sphere(self.sphere_samples);
        let on_sphere: Vec<(DVec3, f64)> = lattice
            .par_iter()
            .map(|u| {
                let p = bs.center + *u * bs.radius;
                (p, f(p))
            })
            .collect();
        let mut all_sign = true;
        for &(p, v) in &on_sphere {
            if v.is_nan() {
                return Err(ImplicitError::NaN {
                    point: p.to_array(),
                });
            }
            if v <= 0.0 {
                return Err(ImplicitError::CrossesBoundary {
                    point: p.to_array(),
                    value: v,
                    center: bs.center.to_array(),
                    radius: bs.radius,
                });
            }
            all_sign &= roots::is_sign_value(v);
        }
        // 2. The grid: NaN check, inside check, sign-only detection.
        let grid = Grid::sample(f, bs, self.grid_n);
        if let Some(p) = grid.first_nan() {
            return Err(ImplicitError::NaN {
                point: p.to_array(),
            });
        }
        let (has_neg, grid_sign) = grid.summary();
        all_sign &= grid_sign;
        if !has_neg && self.user_seeds.is_empty() {
            return Err(ImplicitError::NoSurfaceInside {
                n: grid.n,
                samples: grid.inside_count(),
                step: grid.step,
            });
        }
        Ok(ImplicitSurface {
            func: self.func,
            bs,
            dm_inf: self.dm_inf,
            tolerance: self.tolerance.unwrap_or(1e-7 * bs.radius),
            crossing_step: self.crossing_step.unwrap_or(1e-3 * bs.radius),
            sign_only: all_sign,
            grid: Arc::new(grid),
            user_seeds: self.user_seeds,
            max_seeds: self.max_seeds,
            lines: self.lines,
        })
    }
}

impl ImplicitSurface {
    /// Builder for a closure `f` (solid where `f < 0`) with bounding sphere `bs`.
    pub fn builder(
        f: impl Fn(DVec3) -> f64 + Send + Sync + 'static,
        bs: BoundingSphere,
    ) -> ImplicitBuilder {
        ImplicitBuilder {
            func: Function {
                f: Arc::new(f),
                grad: None,
                expr: None,
            },
            bs,
            dm_inf: None,
            tolerance: None,
            crossing_step: None,
            grid_n: 32,
            user_seeds: Vec::new(),
            max_seeds: 200,
            lines: 64,
            sphere_samples: 2000,
        }
    }

    /// Builder for an expression in `x`, `y`, `z` (see [`crate::expr`]); the gradient is exact.
    pub fn builder_from_expr(
        src: &str,
        bs: BoundingSphere,
    ) -> Result<ImplicitBuilder, ImplicitError> {
        let e = Arc::new(Expr::parse(src)?);
        Ok(Self::builder_from_compiled(e, bs))
    }

    /// Builder for an already compiled expression.
    pub fn builder_from_compiled(e: Arc<Expr>, bs: BoundingSphere) -> ImplicitBuilder {
        let (ev, eg) = (e.clone(), e.clone());
        let mut b = Self::builder(move |p| ev.eval(p), bs).gradient(move |p| eg.eval_grad(p).1);
        b.func.expr = Some(e);
        b
    }

    /// A closure surface with default options.
    pub fn from_fn(
        f: impl Fn(DVec3) -> f64 + Send + Sync + 'static,
        bs: BoundingSphere,
    ) -> Result<Self, ImplicitError> {
        Self::builder(f, bs).build()
    }

    /// An expression surface with default options.
    pub fn from_expr(src: &str, bs: BoundingSphere) -> Result<Self, ImplicitError> {
        Self::builder_from_expr(src, bs)?.build()
    }

    /// The compiled expression, if built from one.
    pub fn expr(&self) -> Option<&Expr> {
        self.func.expr.as_deref()
    }

    /// True if every value sampled at construction was -1, 0 or 1: crossings then use plain
    /// bisection.
    pub fn is_sign_only(&self) -> bool {
        self.sign_only
    }

    /// Seed points from the construction grid only (no random lines): one crossing per grid cell
    /// with a sign change, in cell order, with the index of its cluster of face-adjacent
    /// sign-change cells.
    fn grid_crossings(&self) -> (Vec<DVec3>, Vec<usize>) {
        let g = &*self.grid;
        let cells = g.sign_change_cells();
        let f = |p: DVec3| (self.func.f)(p);
        let tol = self.tolerance;
        let pts: Vec<Option<DVec3>> = cells
            .par_iter()
            .map(|&c| {
                let (mut a, mut fa, mut b, mut fb) = g.first_crossing_edge(c)?;
                // A vertex outside the ball holds +inf (never evaluated): move it to where the
                // edge leaves the ball, so that the root is searched inside the ball only.
                if fa == f64::INFINITY {
                    (a, fa, b, fb) = (b, fb, a, fa);
                }
                if fb == f64::INFINITY {
                    let (_, exit) = self.bs.clip_segment(a, b)?;
                    b = exit;
                    fb = f(b);
                    if fb.is_nan() || (fb < 0.0) == (fa < 0.0) {
                        return None;
                    }
                }
                roots::try_find_root(f, roots::Ends::new(a, fa, b, fb), tol).ok()
            })
            .collect();
        let comp = g.clusters(&cells);
        let mut out = Vec::with_capacity(cells.len());
        let mut ids = Vec::with_capacity(cells.len());
        for (p, c) in pts.into_iter().zip(comp) {
            if let Some(p) = p {
                out.push(p);
                ids.push(c);
            }
        }
        (out, ids)
    }
}

impl Surface for ImplicitSurface {
    fn bounding_sphere(&self) -> BoundingSphere {
        self.bs
    }
    #[inline]
    fn value(&self, p: DVec3) -> f64 {
        (self.func.f)(p)
    }
    fn tolerance(&self) -> f64 {
        self.tolerance
    }
    fn crossing(&self, a: DVec3, fa: f64, b: DVec3, fb: f64) -> DVec3 {
        let f = |p: DVec3| (self.func.f)(p);
        let r = if self.sign_only {
            roots::try_bisect(f, roots::Ends::new(a, fa, b, fb), self.tolerance)
        } else {
            roots::try_find_root(f, roots::Ends::new(a, fa, b, fb), self.tolerance)
        };
        r.unwrap_or(DVec3::NAN)
    }
    fn crossing_step(&self) -> f64 {
        self.crossing_step
    }
    /// User seed points, then one point per cluster of sign-change cells of the seed grid and
    /// one per cell holding a random-line crossing that the grid missed, then points chosen by
    /// farthest-point sampling among all grid and random-line crossings, up to the cap (200 by
    /// default). Deterministic for a given seed, whatever the thread count.
    fn seed_points(&self, seed: u64) -> Vec<DVec3> {
        let (grid_pts, cluster) = self.grid_crossings();
        let mut line_pts = roots::random_line_seeds(self, self.lines, seed);
        line_pts.retain(|p| p.is_finite());
        let g = &*self.grid;
        // Mandatory points.
        // One point per cluster of sign-change cells, and one per cell holding a random-line
        // crossing that the grid missed (a component thinner than the grid step).
        let mut reps: Vec<DVec3> = Vec::new();
        let mut seen_cluster = vec![false; cluster.iter().map(|c| c + 1).max().unwrap_or(0)];
        for (p, &c) in grid_pts.iter().zip(&cluster) {
            if !seen_cluster[c] {
                seen_cluster[c] = true;
                reps.push(*p);
            }
        }
        let mut orphan_cells = std::collections::BTreeSet::new();
        for p in &line_pts {
            let c = g.cell_of(*p);
            if !g.is_sign_change_cell(c) && orphan_cells.insert(c) {
                reps.push(*p);
            }
        }
        let min_sep = 1e-6 * self.bs.radius;
        let mut out: Vec<DVec3> = self.user_seeds.clone();
        let room = self.max_seeds.saturating_sub(out.len());
        if reps.len() >= room {
            let chosen = farthest_points(&out, &reps, room, min_sep);
            out.extend(chosen);
            return out;
        }
        let chosen = farthest_points(&out, &reps, reps.len(), min_sep);
        out.extend(chosen);
        let pool: Vec<DVec3> = grid_pts.into_iter().chain(line_pts).collect();
        let room = self.max_seeds.saturating_sub(out.len());
        let extra = farthest_points(&out, &pool, room, min_sep);
        out.extend(extra);
        out
    }
    fn gradient(&self, p: DVec3) -> DVec3 {
        match &self.func.grad {
            Some(g) => g(p),
            None => central_difference(&*self.func.f, p, 1e-6 * self.bs.radius),
        }
    }
    fn dm_inf_hint(&self) -> Option<f64> {
        self.dm_inf
    }
}

/// `n` points of the Fibonacci lattice on the unit sphere (deterministic, near-uniform).
pub fn fibonacci_sphere(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let t = golden * i as f64;
            DVec3::new(r * t.cos(), r * t.sin(), z)
        })
        .collect()
}

/// Greedy farthest-point selection of up to `k` points of `pool`, away from `fixed` and from each
/// other, stopping when the next point would be closer than `min_sep` (duplicates). Ties go to
/// the lowest index: deterministic ([`geom::farthest::farthest_points`]).
fn farthest_points(fixed: &[DVec3], pool: &[DVec3], k: usize, min_sep: f64) -> Vec<DVec3> {
    geom::farthest::farthest_points(fixed, pool, k, Some(min_sep))
        .into_iter()
        .map(|i| pool[i])
        .collect()
}

/// Values of `f` on a regular grid of `(n+1)^3` vertices over the ball's bounding cube;
/// vertices outside the ball hold +inf (outside, never evaluated).
struct Grid {
    n: usize,
    origin: DVec3,
    step: f64,
    values: Vec<f64>,
}

impl Grid {
    fn sample(f: &ValueFn, bs: BoundingSphere, n: usize) -> Grid {
        let m = n + 1;
        let step = 2.0 * bs.radius / n as f64;
        let origin = bs.center - DVec3::splat(bs.radius);
        let values: Vec<f64> = (0..m * m * m)
            .into_par_iter()
            .with_min_len(256)
            .map(|idx| {
                let (i, j, k) = (idx % m, (idx / m) % m, idx / (m * m));
                let p = origin + DVec3::new(i as f64, j as f64, k as f64) * step;
                if bs.contains(p) { f(p) } else { f64::INFINITY }
            })
            .collect();
        Grid {
            n,
            origin,
            step,
            values,
        }
    }
    fn m(&self) -> usize {
        self.n + 1
    }
    fn point(&self, idx: usize) -> DVec3 {
        let m = self.m();
        let (i, j, k) = (idx % m, (idx / m) % m, idx / (m * m));
        self.origin + DVec3::new(i as f64, j as f64, k as f64) * self.step
    }
    fn first_nan(&self) -> Option<DVec3> {
        self.values
            .iter()
            .position(|v| v.is_nan())
            .map(|i| self.point(i))
    }
    /// (some value < 0, every evaluated value is -1, 0 or 1)
    fn summary(&self) -> (bool, bool) {
        let neg = self.values.iter().any(|&v| v < 0.0);
        let sign = self
            .values
            .iter()
            .all(|&v| v == f64::INFINITY || roots::is_sign_value(v));
        (neg, sign)
    }
    fn inside_count(&self) -> usize {
        self.values.iter().filter(|v| v.is_finite()).count()
    }
    fn vertex(&self, i: usize, j: usize, k: usize) -> usize {
        let m = self.m();
        i + m * (j + m * k)
    }
    fn cell_index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.n * (j + self.n * k)
    }
    fn cell_of(&self, p: DVec3) -> usize {
        let q = ((p - self.origin) / self.step).floor();
        let c = |v: f64| (v.max(0.0) as usize).min(self.n - 1);
        self.cell_index(c(q.x), c(q.y), c(q.z))
    }
    fn corners(&self, c: usize) -> [usize; 8] {
        let n = self.n;
        let (i, j, k) = (c % n, (c / n) % n, c / (n * n));
        let mut out = [0; 8];
        for (b, o) in out.iter_mut().enumerate() {
            *o = self.vertex(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        }
        out
    }
    fn is_sign_change_cell(&self, c: usize) -> bool {
        let cs = self.corners(c);
        let neg = self.values[cs[0]] < 0.0;
        cs.iter().any(|&v| (self.values[v] < 0.0) != neg)
    }
    fn sign_change_cells(&self) -> Vec<usize> {
        (0..self.n * self.n * self.n)
            .filter(|&c| self.is_sign_change_cell(c))
            .collect()
    }
    /// The first of the 12 edges of cell `c` (fixed order) whose ends differ in sign.
    fn first_crossing_edge(&self, c: usize) -> Option<(DVec3, f64, DVec3, f64)> {
        let cs = self.corners(c);
        for a in 0..8 {
            for bit in [1, 2, 4] {
                if a & bit == 0 {
                    let (va, vb) = (cs[a], cs[a | bit]);
                    let (fa, fb) = (self.values[va], self.values[vb]);
                    if (fa < 0.0) != (fb < 0.0) {
                        return Some((self.point(va), fa, self.point(vb), fb));
                    }
                }
            }
        }
        None
    }
    /// Cluster id (0-based, in order of first appearance) of each of `cells` (sorted), by
    /// face adjacency.
    fn clusters(&self, cells: &[usize]) -> Vec<usize> {
        let n = self.n;
        let pos = |c: usize| cells.binary_search(&c).ok();
        let mut parent: Vec<usize> = (0..cells.len()).collect();
        fn find(parent: &mut [usize], mut x: usize) -> usize {
            while parent[x] != x {
                parent[x] = parent[parent[x]];
                x = parent[x];
            }
            x
        }
        for (a, &c) in cells.iter().enumerate() {
            let (i, j, k) = (c % n, (c / n) % n, c / (n * n));
            let nbrs = [
                (i + 1 < n).then(|| c + 1),
                (j + 1 < n).then(|| c + n),
                (k + 1 < n).then(|| c + n * n),
            ];
            for nb in nbrs.into_iter().flatten() {
                if let Some(b) = pos(nb) {
                    let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                    if ra != rb {
                        parent[ra.max(rb)] = ra.min(rb);
                    }
                }
            }
        }
        let mut label = vec![usize::MAX; cells.len()];
        let mut next = 0;
        (0..cells.len())
            .map(|a| {
                let r = find(&mut parent, a);
                if label[r] == usize::MAX {
                    label[r] = next;
                    next += 1;
                }
                label[r]
            })
            .collect()
    }
}
