//! The offscreen stereo target: a 2-layer colour image (layer 0 the left eye, layer 1 the
//! right), multisampled colour and depth when MSAA is on, and the multiview render pass that
//! draws both layers in one pass (view mask 0b11) and resolves the samples.
//!
//! ## Joint or split views
//!
//! [`ViewPasses::Joint`], one pass with view mask `0b11`, is the default: every draw is recorded
//! once and the driver renders it for both eyes. Lavapipe (Mesa 22.3) gets the second view
//! wrong: a triangle that is clipped or culled in the first view is lost in the second (the
//! right eye showed holes in the stage wherever a wall tile was off-screen for the left eye).
//! On such a driver the views are split, [`ViewPasses::Split`]: two passes with view masks
//! `0b01` and `0b10` over the same attachments, the second keeping what the first wrote to
//! layer 0. The shaders are the same (`gl_ViewIndex` still picks the eye), and each eye's
//! pixels are the same as a correct joint pass gives. `ARGILE_VIEW_PASSES=joint|split`
//! overrides the choice.

use std::sync::Arc;

use ash::vk;

use super::gpu::device::Device;
use super::gpu::image::{Image, ImageDesc};
use super::RenderError;

/// The format of the images read back: 8-bit sRGB, so the shaders write linear colour.
pub(crate) const COLOUR_FORMAT: vk::Format = vk::Format::R8G8B8A8_SRGB;

/// The environment variable that overrides [`ViewPasses::for_device`].
pub const VIEW_PASSES_VARIABLE: &str = "ARGILE_VIEW_PASSES";

/// How the two eyes are drawn: in one multiview pass, or one pass per eye.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewPasses {
    /// One pass, view mask `0b11`: each draw is recorded once for both eyes.
    Joint,
    /// Two passes, view masks `0b01` then `0b10` (for drivers that get the second view of a
    /// joint pass wrong).
    Split,
}

impl ViewPasses {
    /// The choice for a device: split on lavapipe, whose second view loses triangles that
    /// are clipped in the first; joint elsewhere. `override_` (`joint` or `split`) wins.
    pub fn for_device(device_name: &str, override_: Option<&str>) -> Result<Self, String> {
        match override_.map(str::trim) {
            Some("joint") => Ok(ViewPasses::Joint),
            Some("split") => Ok(ViewPasses::Split),
            Some(other) if !other.is_empty() => {
                Err(format!("{VIEW_PASSES_VARIABLE}={other} is neither `joint` nor `split`"))
            }
            _ if device_name.contains("llvmpipe") => Ok(ViewPasses::Split),
            _ => Ok(ViewPasses::Joint),
        }
    }

    /// The view mask of each pass, in recording order.
    pub fn view_masks(self) -> &'static [u32] {
        match self {
            ViewPasses::Joint => &[0b11],
            ViewPasses::Split => &[0b01, 0b10],
        }
    }
}

/// One multiview render pass over the target's attachments.
pub(crate) struct ViewPass {
    pub(crate) render_pass: vk::RenderPass,
    pub(crate) framebuffer: vk::Framebuffer,
}

/// Both eyes' attachments and the render passes. Field order is drop order: framebuffers and
/// render passes go before the images they refer to.
pub(crate) struct StereoTarget {
    pub(crate) passes: Vec<ViewPass>,
    /// The single-sample image that is read back (the resolve target with MSAA).
    pub(crate) output: Image,
    /// Multisampled colour (MSAA only).
    pub(crate) msaa: Option<Image>,
    pub(crate) depth: Image,
    pub(crate) extent: vk::Extent2D,
    pub(crate) samples: vk::SampleCountFlags,
    device: Arc<Device>,
}

pub(crate) fn depth_format(device: &Device) -> Result<vk::Format, RenderError> {
    [vk::Format::D32_SFLOAT, vk::Format::X8_D24_UNORM_PACK32, vk::Format::D16_UNORM]
        .into_iter()
        .find(|&f| {
            // SAFETY: a plain query.
            let props =
                unsafe { device.instance.raw.get_physical_device_format_properties(device.physical, f) };
            props.optimal_tiling_features.contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT)
        })
        .ok_or_else(|| RenderError::Unsupported(format!("{} offers no depth format", device.info.name)))
}

impl StereoTarget {
    /// A target of `width`×`height` per eye with `samples` samples per pixel, drawn in the
    /// view passes of `mode`.
    pub(crate) fn new(
        device: &Arc<Device>,
        width: u32,
        height: u32,
        samples: u32,
        mode: ViewPasses,
    ) -> Result<Self, RenderError> {
        let sample_flags = vk::SampleCountFlags::from_raw(samples);
        if !samples.is_power_of_two() || !device.info.sample_counts.contains(sample_flags) {
            return Err(RenderError::Unsupported(format!(
                "{} cannot render with {samples} samples per pixel (it offers {})",
                device.info.name,
                device.info.sample_list()
            )));
        }
        let msaa = samples > 1;
        let depth_format = depth_format(device)?;
        let base = ImageDesc {
            width,
            height,
            layers: 2,
            mip_levels: 1,
            format: COLOUR_FORMAT,
            samples: vk::SampleCountFlags::TYPE_1,
            usage: vk::ImageUsageFlags::COLOR_ATTACHMENT
                | vk::ImageUsageFlags::TRANSFER_SRC
                | vk::ImageUsageFlags::SAMPLED,
            cube: false,
        };
        let output = Image::new(device, base)?;
        let msaa_image = if msaa {
            Some(Image::new(
                device,
                ImageDesc { samples: sample_flags, usage: vk::ImageUsageFlags::COLOR_ATTACHMENT, ..base },
            )?)
        } else {
            None
        };
        let depth = Image::new(
            device,
            ImageDesc {
                format: depth_format,
                samples: sample_flags,
                usage: vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
                ..base
            },
        )?;

        let mut views = vec![msaa_image.as_ref().map_or(output.view, |m| m.view), depth.view];
        if msaa {
            views.push(output.view);
        }
        let extent = vk::Extent2D { width, height };
        let mut passes: Vec<ViewPass> = Vec::new();
        for (i, &mask) in mode.view_masks().iter().enumerate() {
            let formats = (depth_format, sample_flags);
            let made = create_render_pass(device, mask, i > 0, formats, OutputUse::Readback).and_then(
                |render_pass| match create_framebuffer(device, render_pass, &views, extent) {
                    Ok(framebuffer) => Ok(ViewPass { render_pass, framebuffer }),
                    Err(e) => {
                        // SAFETY: nothing uses the render pass yet.
                        unsafe { device.raw.destroy_render_pass(render_pass, None) };
                        Err(e)
                    }
                },
            );
            match made {
                Ok(p) => passes.push(p),
                Err(e) => {
                    for p in passes {
                        // SAFETY: nothing has used these passes yet.
                        unsafe {
                            device.raw.destroy_framebuffer(p.framebuffer, None);
                            device.raw.destroy_render_pass(p.render_pass, None);
                        }
                    }
                    return Err(e);
                }
            }
        }
        Ok(Self {
            passes,
            output,
            msaa: msaa_image,
            depth,
            extent,
            samples: sample_flags,
            device: device.clone(),
        })
    }

    /// Begins pass `pass`, clearing its views' colour to `clear` (linear RGBA) and depth to 1.
    pub(crate) fn begin(&self, cb: vk::CommandBuffer, pass: &ViewPass, clear: [f32; 4]) {
        begin_pass(&self.device, cb, pass, self.extent, clear);
    }
}

/// Begins `pass` over `extent`, clearing its views' colour to `clear` (linear RGBA) and depth
/// to 1.
pub(crate) fn begin_pass(
    device: &Device,
    cb: vk::CommandBuffer,
    pass: &ViewPass,
    extent: vk::Extent2D,
    clear: [f32; 4],
) {
    let clear_values = [
        vk::ClearValue { color: vk::ClearColorValue { float32: clear } },
        vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } },
        vk::ClearValue { color: vk::ClearColorValue { float32: clear } },
    ];
    let info = vk::RenderPassBeginInfo::default()
        .render_pass(pass.render_pass)
        .framebuffer(pass.framebuffer)
        .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
        .clear_values(&clear_values);
    // SAFETY: `cb` is recording outside a render pass; the framebuffer matches the pass.
    unsafe { device.raw.cmd_begin_render_pass(cb, &info, vk::SubpassContents::INLINE) };
}

impl Drop for StereoTarget {
    fn drop(&mut self) {
        // SAFETY: the renderer waits for its frames before dropping the target; the images are
        // dropped after this (field order).
        unsafe {
            for pass in &self.passes {
                self.device.raw.destroy_framebuffer(pass.framebuffer, None);
                self.device.raw.destroy_render_pass(pass.render_pass, None);
            }
        }
    }
}

/// The dependency that makes a pass's colour writes visible to a transfer (the readback copy)
/// after it.
pub(crate) fn colour_to_transfer() -> vk::SubpassDependency {
    vk::SubpassDependency::default()
        .src_subpass(0)
        .dst_subpass(vk::SUBPASS_EXTERNAL)
        .src_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
        .dst_stage_mask(vk::PipelineStageFlags::TRANSFER)
        .src_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
        .dst_access_mask(vk::AccessFlags::TRANSFER_READ)
}

/// What the output image of the passes is for, which sets its layouts around them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum OutputUse {
    /// Read back or composed: the passes leave it in `TRANSFER_SRC_OPTIMAL`.
    Readback,
    /// A runtime's swapchain image: handed over and left in `COLOR_ATTACHMENT_OPTIMAL`
    /// (XR_KHR_vulkan_enable2's rule). With `depth_stored`, the depth attachment is a depth
    /// swapchain image whose values the runtime reads, so they are kept.
    Swapchain {
        /// The depth attachment's values are stored for the runtime.
        depth_stored: bool,
    },
}

/// A render pass drawing the views in `view_mask` into (drawn colour, depth, and with MSAA
/// the resolve target). A pass that `follows` another keeps the output image's other layer:
/// its output starts in the layout the previous pass left it in.
pub(crate) fn create_render_pass(
    device: &Device,
    view_mask: u32,
    follows: bool,
    (depth_format, sample_flags): (vk::Format, vk::SampleCountFlags),
    output: OutputUse,
) -> Result<vk::RenderPass, RenderError> {
    let msaa = sample_flags != vk::SampleCountFlags::TYPE_1;
    let output_final = match output {
        OutputUse::Readback => vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        OutputUse::Swapchain { .. } => vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
    };
    let depth_stored = matches!(output, OutputUse::Swapchain { depth_stored: true });
    let output_initial = if follows { output_final } else { vk::ImageLayout::UNDEFINED };
    let depth_initial = if follows && depth_stored {
        vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL
    } else {
        vk::ImageLayout::UNDEFINED
    };
    // Attachment 0: what the pass draws into (MSAA colour, or the output itself);
    // attachment 1: depth; attachment 2 (MSAA only): the resolve into the output.
    // The output ends in TRANSFER_SRC_OPTIMAL, ready to be read back. Load and store ops
    // apply to this pass's views only, so a following pass leaves the other layer alone.
    let drawn = vk::AttachmentDescription::default()
        .format(COLOUR_FORMAT)
        .samples(sample_flags)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(if msaa { vk::AttachmentStoreOp::DONT_CARE } else { vk::AttachmentStoreOp::STORE })
        .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
        .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
        .initial_layout(if msaa { vk::ImageLayout::UNDEFINED } else { output_initial })
        .final_layout(if msaa { vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL } else { output_final });
    let depth_attachment = vk::AttachmentDescription::default()
        .format(depth_format)
        .samples(sample_flags)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(if depth_stored { vk::AttachmentStoreOp::STORE } else { vk::AttachmentStoreOp::DONT_CARE })
        .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
        .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
        .initial_layout(depth_initial)
        .final_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL);
    let resolve = vk::AttachmentDescription::default()
        .format(COLOUR_FORMAT)
        .samples(vk::SampleCountFlags::TYPE_1)
        .load_op(vk::AttachmentLoadOp::DONT_CARE)
        .store_op(vk::AttachmentStoreOp::STORE)
        .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
        .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
        .initial_layout(output_initial)
        .final_layout(output_final);
    let mut attachments = vec![drawn, depth_attachment];
    if msaa {
        attachments.push(resolve);
    }
    let colour_ref =
        [vk::AttachmentReference { attachment: 0, layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL }];
    let depth_ref =
        vk::AttachmentReference { attachment: 1, layout: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL };
    let resolve_ref =
        [vk::AttachmentReference { attachment: 2, layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL }];
    let mut subpass = vk::SubpassDescription::default()
        .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
        .color_attachments(&colour_ref)
        .depth_stencil_attachment(&depth_ref);
    if msaa {
        subpass = subpass.resolve_attachments(&resolve_ref);
    }
    let dependencies = [
        // The previous frame's readback copy finishes before this frame writes the output.
        vk::SubpassDependency::default()
            .src_subpass(vk::SUBPASS_EXTERNAL)
            .dst_subpass(0)
            .src_stage_mask(vk::PipelineStageFlags::TRANSFER | vk::PipelineStageFlags::LATE_FRAGMENT_TESTS)
            .dst_stage_mask(
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT
                    | vk::PipelineStageFlags::EARLY_FRAGMENT_TESTS,
            )
            .src_access_mask(vk::AccessFlags::TRANSFER_READ | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE)
            .dst_access_mask(
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE | vk::AccessFlags::DEPTH_STENCIL_ATTACHMENT_WRITE,
            ),
        // The readback copy sees this frame's (resolved) colour.
        colour_to_transfer(),
    ];
    // Every draw is rendered for each view in the mask, view i into layer i.
    let view_masks = [view_mask];
    let correlation_masks = [view_mask];
    let mut multiview = vk::RenderPassMultiviewCreateInfo::default()
        .view_masks(&view_masks)
        .correlation_masks(&correlation_masks);
    let subpasses = [subpass];
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachments)
        .subpasses(&subpasses)
        .dependencies(&dependencies)
        .push_next(&mut multiview);
    // SAFETY: every array the create info points to lives across the call.
    unsafe { device.raw.create_render_pass(&info, None) }.map_err(RenderError::vk("vkCreateRenderPass"))
}

/// The framebuffer of `render_pass` over `views` (drawn colour, depth, and with MSAA the
/// resolve target).
pub(crate) fn create_framebuffer(
    device: &Device,
    render_pass: vk::RenderPass,
    views: &[vk::ImageView],
    extent: vk::Extent2D,
) -> Result<vk::Framebuffer, RenderError> {
    // With multiview the framebuffer has one layer; the views address both layers.
    let fb_info = vk::FramebufferCreateInfo::default()
        .render_pass(render_pass)
        .attachments(views)
        .width(extent.width)
        .height(extent.height)
        .layers(1);
    // SAFETY: the views are live 2-layer views matching the render pass's attachments.
    unsafe { device.raw.create_framebuffer(&fb_info, None) }.map_err(RenderError::vk("vkCreateFramebuffer"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lavapipe_splits_the_views_and_the_override_wins() {
        let lavapipe = "llvmpipe (LLVM 15.0.6, 256 bits)";
        assert_eq!(ViewPasses::for_device(lavapipe, None), Ok(ViewPasses::Split));
        assert_eq!(ViewPasses::for_device("NVIDIA H100 80GB HBM3", None), Ok(ViewPasses::Joint));
        assert_eq!(ViewPasses::for_device(lavapipe, Some("joint")), Ok(ViewPasses::Joint));
        assert_eq!(ViewPasses::for_device("NVIDIA H100", Some(" split ")), Ok(ViewPasses::Split));
        assert_eq!(ViewPasses::for_device("NVIDIA H100", Some("")), Ok(ViewPasses::Joint));
        let e = ViewPasses::for_device(lavapipe, Some("both")).unwrap_err();
        assert!(e.contains("ARGILE_VIEW_PASSES=both"), "{e}");
        // Every view is drawn exactly once, view i into layer i.
        for mode in [ViewPasses::Joint, ViewPasses::Split] {
            assert_eq!(mode.view_masks().iter().fold(0, |all, m| all | m), 0b11);
            assert_eq!(mode.view_masks().iter().map(|m| m.count_ones()).sum::<u32>(), 2);
        }
    }
}
