//! The station: wires scene, field, tools, mesher, stereo rig and renderer together.
//!
//! The only module that knows every other; the CLI in `main.rs` is a thin shell over it.

mod playback;

pub use playback::Playback;
