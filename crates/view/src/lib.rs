//! (ours) Seeing a mesh: a [`Scene`] (a triangle mesh with per-facet measures and the facets a
//! check or a criterion flags) drawn as a shaded PNG from three fixed views with a colour bar
//! ([`picture()`]), or written as one self-contained HTML viewer ([`html()`]).
//!
//! Everything here is deterministic: the same scene gives the same bytes. Nothing needs a GPU,
//! a browser or the network; the HTML page draws with WebGL, or with a 2D canvas where WebGL is
//! missing, from data inlined in the page.
#![forbid(unsafe_code)]

pub mod camera;
mod font;
pub mod html;
pub mod palette;
pub mod picture;
pub mod raster;
pub mod scene;

pub use camera::Axis;
pub use html::html;
pub use picture::{PictureOptions, encode_png, picture};
pub use scene::{Highlight, Measure, Scene, SceneError};
