//! Presenting to a window: the surface, its swapchain (recreated when the window changes), the
//! semaphores of a frame, and screenshots of what was presented.
//!
//! One frame is in flight, as for the offscreen target: a frame acquires an image, renders the
//! stereo pass and composes it into that image in one submission, presents, and waits for the
//! submission before the next frame writes the uniforms and chunk buffers again.

use std::sync::Arc;

use ash::vk;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};

use super::compose::{ComposeFramebuffers, Composer};
use super::gpu::device::Device;
use super::gpu::swapchain::{Surface, Swapchain, SwapchainDesc};
use super::RenderError;

/// What a window gives the renderer: its raw handles. The renderer keeps the window alive for
/// as long as its surface.
pub trait WindowHandles: HasWindowHandle + HasDisplayHandle + Send + Sync {}
impl<T: HasWindowHandle + HasDisplayHandle + Send + Sync> WindowHandles for T {}

/// What became of a frame sent to the window.
#[derive(Clone, Debug, PartialEq)]
pub enum Presented {
    /// The frame is on its way to the screen; with the screenshot when one was asked for.
    Shown(Option<image::RgbaImage>),
    /// Nothing was shown: the window is minimised, or the swapchain no longer fitted it and was
    /// remade for the next frame.
    Skipped,
}

/// The window side of a renderer. Field order is drop order: the composition's framebuffers
/// and pass, the swapchain, then the surface, then the window the surface was made from.
pub(crate) struct WindowOutput {
    /// One framebuffer set per swapchain image (made with `composer`).
    pub(crate) framebuffers: Vec<ComposeFramebuffers>,
    /// The composition into this swapchain's format, reading the renderer's stereo image;
    /// remade with the swapchain or the stereo image.
    pub(crate) composer: Option<Composer>,
    pub(crate) swapchain: Option<Swapchain>,
    /// Signalled when the acquired image may be written.
    pub(crate) acquired: vk::Semaphore,
    pub(crate) surface: Arc<Surface>,
    _window: Arc<dyn WindowHandles>,
    pub(crate) desc: SwapchainDesc,
    /// The swapchain must be remade before the next frame (resize, out of date).
    pub(crate) stale: bool,
    device: Arc<Device>,
}

impl WindowOutput {
    /// Wraps `surface` (made from `window` on `device`'s instance) with a first swapchain of
    /// `desc`.
    pub(crate) fn new(
        device: &Arc<Device>,
        surface: Arc<Surface>,
        window: Arc<dyn WindowHandles>,
        desc: SwapchainDesc,
    ) -> Result<Self, RenderError> {
        // SAFETY: a plain create on a live device; destroyed in Drop.
        let acquired = unsafe { device.raw.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
            .map_err(RenderError::vk("vkCreateSemaphore"))?;
        let mut output = Self {
            framebuffers: Vec::new(),
            composer: None,
            swapchain: None,
            acquired,
            surface,
            _window: window,
            desc,
            stale: true,
            device: device.clone(),
        };
        output.refresh()?;
        Ok(output)
    }

    /// Remakes the swapchain if it is stale; leaves none while the window has no area.
    pub(crate) fn refresh(&mut self) -> Result<(), RenderError> {
        if !self.stale {
            return Ok(());
        }
        let caps = Swapchain::capabilities(&self.device, &self.surface)?;
        let zero = |e: vk::Extent2D| e.width == 0 || e.height == 0;
        if zero(caps.current_extent)
            || zero(caps.max_image_extent)
            || self.desc.width == 0
            || self.desc.height == 0
        {
            // Minimised: keep nothing, try again on the next frame.
            self.swapchain = None;
            return Ok(());
        }
        self.framebuffers.clear();
        self.composer = None;
        let old = self.swapchain.take();
        self.swapchain = Some(Swapchain::new(&self.device, &self.surface, self.desc, old)?);
        self.stale = false;
        Ok(())
    }

    /// Makes the composition pass into the swapchain, reading `source` (the stereo image's
    /// view), and its framebuffers, unless they are made.
    pub(crate) fn ensure_composer(&mut self, source: vk::ImageView) -> Result<(), RenderError> {
        let Some(swapchain) = &self.swapchain else { return Ok(()) };
        if self.composer.is_none() {
            self.framebuffers.clear();
            let composer =
                Composer::new(&self.device, source, swapchain.format, vk::ImageLayout::PRESENT_SRC_KHR)?;
            for views in &swapchain.layer_views {
                self.framebuffers.push(composer.framebuffers(views, swapchain.extent)?);
            }
            self.composer = Some(composer);
        }
        Ok(())
    }

    /// The most image layers the surface offers (2 or more allows quad-buffer stereo).
    pub(crate) fn max_layers(&self) -> Result<u32, RenderError> {
        Ok(Swapchain::capabilities(&self.device, &self.surface)?.max_image_array_layers)
    }
}

impl Drop for WindowOutput {
    fn drop(&mut self) {
        // SAFETY: waiting for idle ends every use of the semaphore; the swapchain (dropped
        // after this) waits again before destroying its own handles.
        unsafe {
            let _ = self.device.raw.device_wait_idle();
            self.device.raw.destroy_semaphore(self.acquired, None);
        }
    }
}

/// Converts a screenshot read from a swapchain image of `format` to RGBA.
pub(crate) fn to_rgba(format: vk::Format, width: u32, height: u32, mut bytes: Vec<u8>) -> image::RgbaImage {
    if format == vk::Format::B8G8R8A8_SRGB {
        for px in bytes.chunks_exact_mut(4) {
            px.swap(0, 2);
        }
    }
    image::RgbaImage::from_raw(width, height, bytes).expect("the screenshot holds width × height pixels")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bgra_screenshots_are_swizzled_and_rgba_ones_kept() {
        let bgra = to_rgba(vk::Format::B8G8R8A8_SRGB, 1, 1, vec![1, 2, 3, 4]);
        assert_eq!(bgra.get_pixel(0, 0).0, [3, 2, 1, 4]);
        let rgba = to_rgba(vk::Format::R8G8B8A8_SRGB, 1, 1, vec![1, 2, 3, 4]);
        assert_eq!(rgba.get_pixel(0, 0).0, [1, 2, 3, 4]);
    }
}
