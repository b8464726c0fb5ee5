//! Argile: an immersive stereo/VR sculpting station.
#![deny(unsafe_op_in_unsafe_fn)]
#![warn(missing_docs, clippy::undocumented_unsafe_blocks)]

pub mod app;
pub mod field;
pub mod input;
pub mod math;
pub mod mesh;
pub mod render;
pub mod scene;
pub mod stereo;
pub mod tool;
pub mod xr;
