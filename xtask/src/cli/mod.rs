//! The commands that drive one library call each (ours): parse the flags, call the library,
//! print. `input` and `points` read what the flags name; `view` turns a run into pictures
//! and the HTML viewer.

pub mod delaunay;
pub mod input;
pub mod mesh;
pub mod mesh_adaptive;
pub use rdt_mesher::pipeline::report as mesh_report;
pub mod output;
pub mod points;
pub mod verify;
pub mod view;
