//! Everything Vulkan.
//!
//! Owns device selection, the stereo target, pipelines, the environment cube map and the chunk
//! buffers of the clay mesh. It reads a per-frame [`Frame`] snapshot plus
//! [`crate::mesh::MeshDiff`]s and never sees the field. `unsafe` is confined to this module
//! (and `xr`), each block with the reason it is sound.
//!
//! ```text
//!  MeshDiff ──► chunk arena (one vertex + one index buffer, one draw) ─┐
//!  Frame ─────► uniforms (both eyes, lights, SH irradiance) ───────────┤
//!                                                                       ▼
//!      multiview pass, view mask 0b11: background ▸ stage ▸ clay ▸ tool glyphs
//!      into 2-layer MSAA colour + depth ──resolve──► 2-layer sRGB image ──► read back
//!                                                          │
//!      composition pass (display mode: side-by-side, interlaced, anaglyph, …) ◄─┘
//!      into an offscreen image (read back) or a window's swapchain image
//! ```
//!
//! - `gpu/`: the Vulkan layer (instance, device, buffers, images, pipelines), each handle
//!   owned by one value that destroys it in `Drop`.
//! - `target`: the stereo render target and render pass.
//! - `compose`: the display-mode composition pass, from the stereo image to what a display
//!   shows (offscreen, or a window's swapchain image).
//! - `chunks`: where mesh chunks live on the GPU.
//! - `environment`: cube map and irradiance from the scene's environment (CPU).
//! - `xr_target`: an OpenXR runtime's swapchain images as the stereo passes' output (never
//!   destroyed here: the runtime owns them).
//! - `renderer`: [`Renderer`], which ties them together.

mod chunks;
mod compose;
mod environment;
mod frame;
mod gpu;
mod hud;
mod panel;
mod renderer;
mod shapes;
mod target;
mod window;
mod xr_target;

pub use frame::*;
pub use gpu::{choose_device, DeviceInfo, DeviceKind, ValidationLog, DEVICE_VARIABLE};
pub use hud::{EyeMark, BOTH_VIEWS, LEFT_VIEW, RIGHT_VIEW};
pub use panel::{PanelBatch, PanelPaint, PanelTexture, PanelVertex, MAX_TEXTURE_SIDE};
pub use renderer::{
    probe_devices, DeviceProbe, Renderer, RendererDesc, StereoImage, ViewPasses, VulkanHandles, VulkanMaker,
    VIEW_PASSES_VARIABLE,
};
pub use window::{Presented, WindowHandles};
pub use xr_target::SwapchainImages;

use ash::vk;

/// Why rendering failed; every message says what to do.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The Vulkan loader library could not be loaded.
    #[error(
        "cannot load the Vulkan loader ({0}); install the Debian packages libvulkan1 and a driver \
         (mesa-vulkan-drivers gives the CPU renderer lavapipe)"
    )]
    NoLoader(String),
    /// No device can be used (or the one asked for cannot).
    #[error("{0}")]
    NoDevice(String),
    /// The device or loader lacks something Argile needs.
    #[error("{0}")]
    Unsupported(String),
    /// An allocation failed.
    #[error(
        "out of memory allocating {bytes} bytes on {device}; render smaller images (--size) or fewer \
         samples"
    )]
    OutOfMemory {
        /// Bytes asked for.
        bytes: u64,
        /// The device.
        device: String,
    },
    /// The device was lost (a driver crash or a reset).
    #[error("the Vulkan device was lost during {call}; the driver crashed or the GPU was reset")]
    DeviceLost {
        /// The call that reported it.
        call: &'static str,
    },
    /// Any other failing Vulkan call.
    #[error("the Vulkan call {call} failed: {result}")]
    Vulkan {
        /// The call.
        call: &'static str,
        /// What it returned.
        result: vk::Result,
    },
    /// A read-back was asked for before any frame was drawn.
    #[error("nothing has been drawn yet: draw a frame before reading it back")]
    NothingDrawn,
}

impl RenderError {
    /// Maps a failing call's result to an error naming the call.
    pub(crate) fn vk(call: &'static str) -> impl Fn(vk::Result) -> RenderError {
        move |result| match result {
            vk::Result::ERROR_DEVICE_LOST => RenderError::DeviceLost { call },
            result => RenderError::Vulkan { call, result },
        }
    }
}
