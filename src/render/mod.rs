//! Everything Vulkan.
//!
//! Owns device selection, render targets, pipelines, environment maps and the chunk buffers of
//! the clay mesh. It reads a per-frame [`Frame`] snapshot plus [`crate::mesh::MeshDiff`]s and
//! never sees the field. `unsafe` is confined to this module (and `xr`).

mod frame;

pub use frame::*;
