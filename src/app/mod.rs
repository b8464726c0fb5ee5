//! The station: wires scene, field, tools, mesher, stereo rig and renderer together.
//!
//! The only module that knows every other; the CLI in `main.rs` is a thin shell over it.

mod environment;
mod frame;
mod playback;

pub use environment::{load_environment, EnvironmentError};
pub use frame::{build_frame, world_lights};
pub use playback::Playback;
