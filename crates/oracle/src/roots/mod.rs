//! Root finding for the bipolar and intersection oracles (section 6.4.2), shared by every
//! backend. (It also re-exports the surface-generic helpers behind [`Surface`]'s provided
//! methods, random-line seeds and projection, and the [`SplitMix64`] generator.)
//!
//! # Vocabulary (every root finder here speaks it)
//! - **Side**: a value `f` is *inside* when `f < 0` and *outside* when `f >= 0` (zero
//!   included), the bipolar convention of [`crate::Surface::crossing`].
//! - **Bracket**: two ends `a`, `b` (or two parameters `t0 < t1` along a segment) whose values
//!   are on opposite sides; every finder takes it as [`Ends`] (ends and their values). Every step keeps this invariant: a probe replaces the end on its
//!   side, so a sign change stays between the ends.
//! - **Tolerance** `tol`: an absolute length in space; `ttol = tol / |b − a|` is the same in
//!   parameter units.
//! - **Illinois step**: after a probe replaces one end, the value kept at the other end is
//!   halved if the same end moved on the previous step too (the `bracket` file).
//! - **Safeguard**: a bisection step when the bracket did not shrink fast enough (each finder
//!   states its rule), so the cost stays within a small factor of bisection.
//! - **Termination**: the bracket is shorter than the tolerance (the answer is then its
//!   midpoint, within `tol / 2` of a sign change), or the probes are adjacent floats, or
//!   (distance-like functions only) `|f| < tol` at a probe or a Newton step is below
//!   `tol / 2`, or an iteration cap.
//!
//! # The finders
//! - [`bisect`] / [`try_bisect`]: bisection; the only one valid for sign-only functions.
//! - [`try_find_root`]: Illinois in parameter units with probes kept `tol` inside the
//!   bracket, bisection for sign-only values (implicit surfaces).
//! - `illinois`: Illinois in space, bisection every third step if the bracket did not halve,
//!   `|f| < tol` accepted (the smoothed polyhedron).
//! - `newton_bracketed`: Newton steps kept inside the bracket, `illinois` otherwise (point
//!   sets, whose IMLS value has an exact gradient).
//! - `ParamBracket::solve`: Illinois on a function of the parameter with probes `ttol / 4`
//!   inside the bracket (the image backend's per-cell trilinear polynomial).
//!
//! Each backend keeps its own finder: changing one would change the meshes (the iterates are
//! part of the output).

pub(crate) mod bisect;
mod bracket;
mod illinois;
mod newton;
pub(crate) mod rng;
pub(crate) mod scan;
#[cfg(test)]
mod tests;

pub use crate::surface::{
    nearest_crossing_on_rays, project_newton, project_robust, random_line_seeds,
};
pub use bisect::{bisect, try_bisect};
pub(crate) use bracket::ParamBracket;
pub use bracket::{Ends, is_sign_value};
pub(crate) use illinois::illinois;
pub use illinois::try_find_root;
pub(crate) use newton::newton_bracketed;
pub use rng::SplitMix64;
pub(crate) use scan::sample_crossings;
pub use scan::{all_crossings, try_all_crossings};

#[cfg(doc)]
use crate::Surface;

use glam::DVec3;

/// Central-difference gradient of `f` at `p` with step `h` (one evaluation on each side of
/// `p` along each axis).
pub fn central_difference(f: impl Fn(DVec3) -> f64, p: DVec3, h: f64) -> DVec3 {
    let d = |e: DVec3| f(p + e * h) - f(p - e * h);
    DVec3::new(d(DVec3::X), d(DVec3::Y), d(DVec3::Z)) / (2.0 * h)
}
