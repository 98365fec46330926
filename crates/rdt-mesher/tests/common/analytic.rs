//! Analytic test surfaces defined only through `oracle`'s trait (no backend), and a rayon
//! pool helper, shared by the integration tests and the mesher's unit tests
//! (`src/mesher/tests.rs` includes this file).

use glam::DVec3;
use oracle::{BoundingSphere, Surface};

/// A surface given by a closure and a bounding sphere.
pub struct Analytic<F: Fn(DVec3) -> f64 + Send + Sync> {
    pub f: F,
    pub center: DVec3,
    pub radius: f64,
}
impl<F: Fn(DVec3) -> f64 + Send + Sync> Surface for Analytic<F> {
    fn bounding_sphere(&self) -> BoundingSphere {
        BoundingSphere {
            center: self.center,
            radius: self.radius,
        }
    }
    fn value(&self, p: DVec3) -> f64 {
        (self.f)(p)
    }
}

/// The ellipsoid with semi-axes `axes` centred at `(cx, -cx, 0.3 cx)`, in a ball of radius
/// 1.5 (the random ellipsoids of the property tests: axes in [0.4, 1.2], |cx| <= 0.5).
pub fn ellipsoid(axes: DVec3, cx: f64) -> Analytic<impl Fn(DVec3) -> f64 + Send + Sync> {
    let c = DVec3::new(cx, -cx, 0.3 * cx);
    Analytic {
        f: move |p: DVec3| {
            let q = p - c;
            (q.x / axes.x).powi(2) + (q.y / axes.y).powi(2) + (q.z / axes.z).powi(2) - 1.0
        },
        center: c,
        radius: 1.5,
    }
}

pub fn sphere() -> Analytic<impl Fn(DVec3) -> f64 + Send + Sync> {
    Analytic {
        f: |p: DVec3| p.length_squared() - 1.0,
        center: DVec3::ZERO,
        radius: 2.0,
    }
}

pub fn torus() -> Analytic<impl Fn(DVec3) -> f64 + Send + Sync> {
    Analytic {
        f: |p: DVec3| {
            let q = p.length_squared() + 1.0 - 0.09;
            q * q - 4.0 * (p.x * p.x + p.y * p.y)
        },
        center: DVec3::ZERO,
        radius: 2.0,
    }
}

/// Runs `f` on a rayon pool of `n` threads.
pub fn in_pool<R: Send>(n: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
        .install(f)
}
