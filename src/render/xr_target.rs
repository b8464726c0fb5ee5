//! An OpenXR runtime's swapchain images as the output of the stereo passes.
//!
//! The runtime owns the images (it made them on our device and destroys them with its
//! swapchain); this target owns only what it made over them: a 2-layer view of each image, the
//! render passes and the framebuffers. Nothing here ever destroys a swapchain image.
//!
//! ```text
//!  colour swapchain image i (2 layers: 0 = left eye, 1 = right eye)
//!      ▲ drawn directly (1 sample), or resolved into from the target's MSAA colour
//!  depth swapchain image j (2 layers), the depth attachment itself when submitted (1 sample),
//!      else the stereo target's own depth
//! ```
//!
//! The runtime hands an image over in `COLOR_ATTACHMENT_OPTIMAL` (depth:
//! `DEPTH_STENCIL_ATTACHMENT_OPTIMAL`) and expects it back in that layout at release; the
//! passes start from `UNDEFINED` (everything is cleared) and end in those layouts. The render
//! passes are compatible with the stereo target's (same formats, samples and view masks), so
//! the renderer's pipelines draw into both.

use std::collections::HashMap;
use std::sync::Arc;

use ash::vk;

use super::gpu::device::Device;
use super::target::{create_framebuffer, create_render_pass, OutputUse, StereoTarget, ViewPass};
use super::RenderError;

/// The runtime's images of one swapchain, as plain handles.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SwapchainImages {
    /// The images, in the runtime's order (the index `xrAcquireSwapchainImage` returns).
    pub images: Vec<vk::Image>,
    /// Their format.
    pub format: vk::Format,
}

/// The stereo passes drawing into a runtime's swapchain images.
///
/// Field order is drop order: framebuffers, then render passes, then the views; the images
/// are the runtime's and are left alone.
pub(crate) struct SwapchainTarget {
    /// Per (colour image, depth image) pair used so far: one framebuffer per view pass.
    framebuffers: HashMap<(u32, Option<u32>), Vec<vk::Framebuffer>>,
    render_passes: Vec<vk::RenderPass>,
    colour_views: Vec<vk::ImageView>,
    depth_views: Vec<vk::ImageView>,
    /// Whether the depth swapchain's images are the depth attachment (and hold the depth the
    /// runtime reads).
    pub(crate) depth_stored: bool,
    device: Arc<Device>,
}

impl std::fmt::Debug for SwapchainTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SwapchainTarget")
            .field("images", &self.colour_views.len())
            .field("depth_stored", &self.depth_stored)
            .finish_non_exhaustive()
    }
}

/// A 2-layer view of a runtime's image.
fn array_view(
    device: &Device,
    image: vk::Image,
    format: vk::Format,
    aspect: vk::ImageAspectFlags,
) -> Result<vk::ImageView, RenderError> {
    let info = vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(vk::ImageViewType::TYPE_2D_ARRAY)
        .format(format)
        .subresource_range(
            vk::ImageSubresourceRange::default()
                .aspect_mask(aspect)
                .base_mip_level(0)
                .level_count(1)
                .base_array_layer(0)
                .layer_count(2),
        );
    // SAFETY: the runtime made `image` on this device with 2 layers and this format (the
    // caller checked the format against the target's).
    unsafe { device.raw.create_image_view(&info, None) }.map_err(RenderError::vk("vkCreateImageView"))
}

impl SwapchainTarget {
    /// Views over the runtime's `colour` images (and `depth` images, used as the depth
    /// attachment when the target draws with one sample) and render passes compatible with
    /// `target`'s.
    pub(crate) fn new(
        device: &Arc<Device>,
        target: &StereoTarget,
        view_masks: &[u32],
        colour: &SwapchainImages,
        depth: Option<&SwapchainImages>,
    ) -> Result<Self, RenderError> {
        if colour.format != target.output.desc.format {
            return Err(RenderError::Unsupported(format!(
                "the headset's swapchain is {:?}; Argile draws {:?}",
                colour.format, target.output.desc.format
            )));
        }
        let single_sample = target.samples == vk::SampleCountFlags::TYPE_1;
        let depth = depth.filter(|d| single_sample && d.format == target.depth.desc.format);
        let mut this = Self {
            framebuffers: HashMap::new(),
            render_passes: Vec::new(),
            colour_views: Vec::new(),
            depth_views: Vec::new(),
            depth_stored: depth.is_some(),
            device: device.clone(),
        };
        for &image in &colour.images {
            this.colour_views.push(array_view(device, image, colour.format, vk::ImageAspectFlags::COLOR)?);
        }
        for &image in depth.map_or(&[][..], |d| &d.images) {
            let format = target.depth.desc.format;
            this.depth_views.push(array_view(device, image, format, vk::ImageAspectFlags::DEPTH)?);
        }
        let output = OutputUse::Swapchain { depth_stored: this.depth_stored };
        for (i, &mask) in view_masks.iter().enumerate() {
            let formats = (target.depth.desc.format, target.samples);
            this.render_passes.push(create_render_pass(device, mask, i > 0, formats, output)?);
        }
        Ok(this)
    }

    /// The view passes drawing into colour image `colour` (and depth image `depth` when the
    /// depth is stored), in recording order.
    pub(crate) fn passes(
        &mut self,
        target: &StereoTarget,
        colour: u32,
        depth: Option<u32>,
    ) -> Result<Vec<ViewPass>, RenderError> {
        let depth = depth.filter(|_| self.depth_stored);
        let colour_view = *self.colour_views.get(colour as usize).ok_or_else(|| {
            RenderError::Unsupported(format!(
                "the runtime acquired swapchain image {colour}, which it never listed"
            ))
        })?;
        let depth_view = match depth {
            Some(j) => *self.depth_views.get(j as usize).ok_or_else(|| {
                RenderError::Unsupported(format!(
                    "the runtime acquired depth image {j}, which it never listed"
                ))
            })?,
            None if self.depth_stored => {
                return Err(RenderError::Unsupported("no depth swapchain image was acquired".into()))
            }
            None => target.depth.view,
        };
        let key = (colour, depth);
        if !self.framebuffers.contains_key(&key) {
            let views = match &target.msaa {
                Some(msaa) => vec![msaa.view, depth_view, colour_view],
                None => vec![colour_view, depth_view],
            };
            let mut made = Vec::new();
            for &render_pass in &self.render_passes {
                match create_framebuffer(&self.device, render_pass, &views, target.extent) {
                    Ok(f) => made.push(f),
                    Err(e) => {
                        for f in made {
                            // SAFETY: never used.
                            unsafe { self.device.raw.destroy_framebuffer(f, None) };
                        }
                        return Err(e);
                    }
                }
            }
            self.framebuffers.insert(key, made);
        }
        Ok(self.framebuffers[&key]
            .iter()
            .zip(&self.render_passes)
            .map(|(&framebuffer, &render_pass)| ViewPass { render_pass, framebuffer })
            .collect())
    }
}

impl Drop for SwapchainTarget {
    fn drop(&mut self) {
        // SAFETY: the renderer waits for its frame before dropping this; everything destroyed
        // here was made by this value. The runtime's images are not destroyed.
        unsafe {
            let d = &self.device.raw;
            for framebuffers in self.framebuffers.values() {
                for &f in framebuffers {
                    d.destroy_framebuffer(f, None);
                }
            }
            for &p in &self.render_passes {
                d.destroy_render_pass(p, None);
            }
            for &v in self.colour_views.iter().chain(&self.depth_views) {
                d.destroy_image_view(v, None);
            }
        }
    }
}
