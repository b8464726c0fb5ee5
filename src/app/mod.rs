//! The station: wires scene, field, tools, mesher, stereo rig and renderer together.
//!
//! The only module that knows every other; the CLI in `main.rs` is a thin shell over it.

pub mod bench;
mod capture;
mod environment;
mod frame;
mod playback;

pub use capture::{render_scene, renderer_for, save_png_atomically, RenderOptions, WrittenCapture};
pub use environment::{load_environment, EnvironmentError};
pub use frame::{build_frame, world_lights};
pub use playback::Playback;
