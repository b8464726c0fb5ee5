//! Argile: an immersive stereo/VR sculpting station.
//!
//! A designer shapes virtual clay with two hands, in a headset or in front of a stereo display.
//! The clay is a sparse density field; its iso-surface is meshed incrementally and drawn by a
//! Vulkan renderer in single-pass stereo. The same renderer runs offscreen, so stereo images
//! are regression-tested on machines without a GPU.
//!
//! ## Data flow
//!
//! ```text
//!  devices ──► input ──► tool pose per hand ──► tool ──► field ──► dirty bricks
//!  (XR hands, SpaceMouse,    (filtered,          (band-limited   (sparse     │
//!   gamepad, mouse,           clutched,           stamps,        bricks)     ▼
//!   scripted timeline)        mapped)             strokes)                  mesh (per brick,
//!                                                                            chunk diffs)
//!  views ◄── stereo rig (interaxial, convergence,                                │
//!    │       off-axis frusta)  or  xr session                                    ▼
//!    └────────────────────────────────────────────────────────────────► render: chunk buffers,
//!                                                                        multiview pass (MSAA,
//!                                                                        env-mapped clay, tools,
//!                                                                        stage) ──► target
//!                                                        (offscreen PNG pair / window / XR swapchain)
//! ```
//!
//! Each stage owns its data and hands the next a small plain value (poses, dirty brick keys,
//! [`mesh::MeshDiff`], [`render::StereoViews`]); no stage reaches back up the flow. [`app`] is the
//! only module that knows them all; [`bench`] runs the `argile bench` workloads over them as a
//! user of the library would, and no module names it. `tests/architecture.rs` checks the
//! dependency rules.
//!
//! Conventions: world space in metres, right-handed, +Y up; density in [0, 1] with the surface
//! at the iso-level (0.5); colours linear RGBA.

// Lint policy. Unsafe code is confined to `render` and `xr`; each block says why it is sound.
#![deny(unsafe_op_in_unsafe_fn)]
#![warn(
    missing_docs,
    missing_debug_implementations,
    clippy::undocumented_unsafe_blocks,
    clippy::missing_safety_doc,
    rust_2018_idioms
)]

pub mod app;
pub mod bench;
pub mod clay;
pub mod config;
pub mod field;
pub mod input;
pub mod io;
pub mod lattice;
pub mod math;
pub mod mesh;
pub mod parts;
pub mod render;
pub mod scene;
pub mod spline;
pub mod stereo;
pub mod tool;
pub mod ui;
pub mod xr;
