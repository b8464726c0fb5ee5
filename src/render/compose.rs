//! The composition pass: the last pass of a frame, turning the 2-layer stereo image into what
//! a display mode shows (see [`crate::stereo::display`] for the modes and their layouts).
//!
//! One full-screen triangle, one fragment shader (`shaders/compose.frag`) with the mode as a
//! specialization constant (a pipeline per mode, made when the mode is first used: on lavapipe
//! a mode chosen at run time made the pass 5 to 14 times slower, see `BENCHMARKS.md`) and the
//! interlace parity and the anaglyph matrices in push constants. The destination is any colour image view with its
//! format and final layout given by the caller: the offscreen [`ComposedOutput`] here, and a
//! window's swapchain images (final layout `PRESENT_SRC_KHR`) alike. Colour arithmetic is done
//! on linear values: the stereo image is read through its sRGB view, and the shader encodes
//! sRGB itself when the destination format is UNORM (as many swapchains are).
//!
//! ```text
//!  stereo image (2 layers, SHADER_READ_ONLY) ──texelFetch──► compose.frag ──► destination
//!                                                              (one pass per destination layer:
//!                                                               2 for quad-buffer, else 1)
//! ```

use std::sync::Arc;

use ash::vk;

use super::gpu::buffer::{Buffer, MemoryUse};
use super::gpu::device::Device;
use super::gpu::image::{read_layers, Image, ImageDesc, Sampler};
use super::gpu::pipeline::{Pipeline, PipelineDesc};
use super::RenderError;
use crate::stereo::display::{DisplayMode, Matrix3, Parity, DUBOIS_RED_CYAN_LEFT, DUBOIS_RED_CYAN_RIGHT};

/// Mirrors the push constant block of `shaders/compose.frag`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ComposePush {
    /// The left eye's anaglyph matrix, one column per vec4.
    left: [[f32; 4]; 3],
    /// The right eye's.
    right: [[f32; 4]; 3],
    /// Parity offset, encode sRGB, destination layer, unused.
    params: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<ComposePush>() == 112);

/// How many modes `shaders/compose.frag` has (the anaglyphs share one).
const SHADER_MODES: usize = 10;

/// The mode numbers of `shaders/compose.frag` (its specialization constant `MODE`).
fn shader_mode(mode: DisplayMode) -> u32 {
    match mode {
        DisplayMode::QuadBuffer => 0,
        DisplayMode::SideBySide => 1,
        DisplayMode::SideBySideHalf => 2,
        DisplayMode::TopBottom => 3,
        DisplayMode::TopBottomHalf => 4,
        DisplayMode::RowInterlaced => 5,
        DisplayMode::ColumnInterlaced => 6,
        DisplayMode::Anaglyph | DisplayMode::AnaglyphGreenMagenta | DisplayMode::AnaglyphAmberBlue => 7,
        DisplayMode::Mono => 8,
        DisplayMode::FrameSequential => 9,
    }
}

/// A row-major 3×3 matrix as three GLSL columns.
fn columns(m: &Matrix3) -> [[f32; 4]; 3] {
    [0, 1, 2].map(|k| [m[0][k], m[1][k], m[2][k], 0.0])
}

/// Whether a colour format stores sRGB-encoded values (the hardware encodes on write).
fn is_srgb(format: vk::Format) -> bool {
    matches!(
        format,
        vk::Format::R8G8B8A8_SRGB
            | vk::Format::B8G8R8A8_SRGB
            | vk::Format::A8B8G8R8_SRGB_PACK32
            | vk::Format::R8G8B8_SRGB
            | vk::Format::B8G8R8_SRGB
    )
}

/// The handles a [`Composer`] owns besides its pipelines; `Drop` destroys them (after the
/// pipelines, which are declared before this in the composer).
struct ComposerHandles {
    render_pass: vk::RenderPass,
    pipeline_layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pool: vk::DescriptorPool,
    device: Arc<Device>,
}

impl Drop for ComposerHandles {
    fn drop(&mut self) {
        // SAFETY: no submission using these is in flight when the composer drops (its owner
        // waits for the device first); null handles of a half-built composer are ignored.
        unsafe {
            let d = &self.device.raw;
            d.destroy_descriptor_pool(self.pool, None);
            d.destroy_pipeline_layout(self.pipeline_layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
            d.destroy_render_pass(self.render_pass, None);
        }
    }
}

/// The composition pass for destinations of one format and final layout, reading one stereo
/// image. Field order is drop order: the pipelines before the layouts and render pass.
pub(crate) struct Composer {
    /// One pipeline per display mode (indexed by [`shader_mode`]), made when first needed.
    pipelines: [Option<Pipeline>; SHADER_MODES],
    handles: ComposerHandles,
    set: vk::DescriptorSet,
    _sampler: Sampler,
    encode_srgb: bool,
}

impl Composer {
    /// A composer reading `source` (the 2-layer stereo image's sRGB array view, to be in
    /// `SHADER_READ_ONLY_OPTIMAL` when recorded) into destinations of `format`, which the pass
    /// leaves in `final_layout` (`TRANSFER_SRC_OPTIMAL` to read back, `PRESENT_SRC_KHR` to
    /// present).
    pub(crate) fn new(
        device: &Arc<Device>,
        source: vk::ImageView,
        format: vk::Format,
        final_layout: vk::ImageLayout,
    ) -> Result<Self, RenderError> {
        let d = &device.raw;
        let mut handles = ComposerHandles {
            render_pass: vk::RenderPass::null(),
            pipeline_layout: vk::PipelineLayout::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            pool: vk::DescriptorPool::null(),
            device: device.clone(),
        };
        let bindings = [vk::DescriptorSetLayoutBinding::default()
            .binding(0)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .descriptor_count(1)
            .stage_flags(vk::ShaderStageFlags::FRAGMENT)];
        // Each handle is stored in `handles` at once, whose Drop destroys it on a later failure.
        // SAFETY: a valid create info on a live device.
        handles.set_layout = unsafe {
            d.create_descriptor_set_layout(
                &vk::DescriptorSetLayoutCreateInfo::default().bindings(&bindings),
                None,
            )
        }
        .map_err(RenderError::vk("vkCreateDescriptorSetLayout"))?;
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::FRAGMENT)
            .offset(0)
            .size(std::mem::size_of::<ComposePush>() as u32)];
        let set_layouts = [handles.set_layout];
        // SAFETY: a valid create info; the set layout is live.
        handles.pipeline_layout = unsafe {
            d.create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default()
                    .set_layouts(&set_layouts)
                    .push_constant_ranges(&ranges),
                None,
            )
        }
        .map_err(RenderError::vk("vkCreatePipelineLayout"))?;
        handles.render_pass = create_render_pass(d, format, final_layout)?;
        let sizes =
            [vk::DescriptorPoolSize { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, descriptor_count: 1 }];
        // SAFETY: a valid create info on a live device.
        handles.pool = unsafe {
            d.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes),
                None,
            )
        }
        .map_err(RenderError::vk("vkCreateDescriptorPool"))?;
        // SAFETY: the pool has room for exactly this set.
        let set = unsafe {
            d.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default()
                    .descriptor_pool(handles.pool)
                    .set_layouts(&set_layouts),
            )
        }
        .map_err(RenderError::vk("vkAllocateDescriptorSets"))?[0];
        // texelFetch ignores filtering; the sampler only completes the descriptor.
        let sampler = Sampler::linear(device, 0.0)?;
        // SAFETY: the set is not in use; the view and sampler outlive the composer (the view
        // is the caller's contract, the sampler is a field).
        unsafe { super::gpu::pipeline::write_sampled(d, set, 0, source, sampler.raw) };
        Ok(Self {
            pipelines: Default::default(),
            handles,
            set,
            _sampler: sampler,
            encode_srgb: !is_srgb(format),
        })
    }

    /// Makes `mode`'s pipeline, if it is not made yet (each mode is a specialization of the
    /// one shader); [`record`](Self::record) needs it.
    pub(crate) fn prepare(&mut self, mode: DisplayMode) -> Result<(), RenderError> {
        let slot = &mut self.pipelines[shader_mode(mode) as usize];
        if slot.is_none() {
            let desc = PipelineDesc {
                name: "compose",
                vertex: include_bytes!(concat!(env!("OUT_DIR"), "/compose.vert.spv")),
                fragment: include_bytes!(concat!(env!("OUT_DIR"), "/compose.frag.spv")),
                attributes: 0,
                cull: vk::CullModeFlags::NONE,
                depth_test: false,
                depth_write: false,
                blend: false,
                premultiplied: false,
                fragment_constant: Some(shader_mode(mode)),
            };
            *slot = Some(Pipeline::new(
                &self.handles.device,
                &desc,
                self.handles.pipeline_layout,
                self.handles.render_pass,
                None,
                vk::SampleCountFlags::TYPE_1,
            )?);
        }
        Ok(())
    }

    /// Framebuffers over a destination: one view per layer (two for quad-buffer output, one
    /// otherwise), each `extent` large.
    pub(crate) fn framebuffers(
        &self,
        layer_views: &[vk::ImageView],
        extent: vk::Extent2D,
    ) -> Result<ComposeFramebuffers, RenderError> {
        let device = &self.handles.device;
        let mut out = ComposeFramebuffers { raw: Vec::new(), extent, device: device.clone() };
        for view in layer_views {
            let views = [*view];
            let info = vk::FramebufferCreateInfo::default()
                .render_pass(self.handles.render_pass)
                .attachments(&views)
                .width(extent.width)
                .height(extent.height)
                .layers(1);
            // SAFETY: the view is a live single-layer colour view of the composer's format;
            // `out` destroys what was made if a later one fails.
            let fb = unsafe { device.raw.create_framebuffer(&info, None) }
                .map_err(RenderError::vk("vkCreateFramebuffer"))?;
            out.raw.push(fb);
        }
        Ok(out)
    }

    /// Records the composition of `mode` (interlaced modes with `parity`) into `target`: the
    /// output covers the top-left `mode.output_size(eye)` pixels of each of the mode's layers,
    /// the rest is cleared to black. The source must be in `SHADER_READ_ONLY_OPTIMAL` with its
    /// writes visible to fragment shaders, and `mode` [prepared](Self::prepare).
    pub(crate) fn record(
        &self,
        cb: vk::CommandBuffer,
        target: &ComposeFramebuffers,
        (mode, parity): (DisplayMode, Parity),
        eye: (u32, u32),
    ) {
        debug_assert!(target.raw.len() >= mode.layers() as usize, "{mode} needs {} layers", mode.layers());
        let pipeline = self.pipelines[shader_mode(mode) as usize]
            .as_ref()
            .unwrap_or_else(|| panic!("the composer was not prepared for {mode}"));
        let (w, h) = mode.output_size(eye);
        let (w, h) = (w.min(target.extent.width), h.min(target.extent.height));
        let d = &self.handles.device.raw;
        let clear = [vk::ClearValue { color: vk::ClearColorValue { float32: [0.0, 0.0, 0.0, 1.0] } }];
        for (layer, &framebuffer) in target.raw.iter().take(mode.layers() as usize).enumerate() {
            let begin = vk::RenderPassBeginInfo::default()
                .render_pass(self.handles.render_pass)
                .framebuffer(framebuffer)
                .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent: target.extent })
                .clear_values(&clear);
            // Modes other than the anaglyphs ignore the matrices.
            let (left, right) =
                mode.anaglyph_matrices().unwrap_or((&DUBOIS_RED_CYAN_LEFT, &DUBOIS_RED_CYAN_RIGHT));
            let push = ComposePush {
                left: columns(left),
                right: columns(right),
                params: [parity.offset(), u32::from(self.encode_srgb), layer as u32, 0],
            };
            let viewport = vk::Viewport {
                x: 0.0,
                y: 0.0,
                width: w as f32,
                height: h as f32,
                min_depth: 0.0,
                max_depth: 1.0,
            };
            let scissor =
                vk::Rect2D { offset: vk::Offset2D::default(), extent: vk::Extent2D { width: w, height: h } };
            // SAFETY: `cb` is recording outside a render pass; every handle is owned by the
            // composer or the target and outlives the submission (the caller's contract).
            unsafe {
                d.cmd_begin_render_pass(cb, &begin, vk::SubpassContents::INLINE);
                d.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, pipeline.raw);
                d.cmd_bind_descriptor_sets(
                    cb,
                    vk::PipelineBindPoint::GRAPHICS,
                    self.handles.pipeline_layout,
                    0,
                    &[self.set],
                    &[],
                );
                d.cmd_push_constants(
                    cb,
                    self.handles.pipeline_layout,
                    vk::ShaderStageFlags::FRAGMENT,
                    0,
                    bytemuck::bytes_of(&push),
                );
                d.cmd_set_viewport(cb, 0, &[viewport]);
                d.cmd_set_scissor(cb, 0, &[scissor]);
                d.cmd_draw(cb, 3, 1, 0, 0);
                d.cmd_end_render_pass(cb);
            }
        }
    }
}

/// The render pass of one colour attachment of `format`: cleared, stored, left in
/// `final_layout`.
fn create_render_pass(
    d: &ash::Device,
    format: vk::Format,
    final_layout: vk::ImageLayout,
) -> Result<vk::RenderPass, RenderError> {
    let attachments = [vk::AttachmentDescription::default()
        .format(format)
        .samples(vk::SampleCountFlags::TYPE_1)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::STORE)
        .stencil_load_op(vk::AttachmentLoadOp::DONT_CARE)
        .stencil_store_op(vk::AttachmentStoreOp::DONT_CARE)
        .initial_layout(vk::ImageLayout::UNDEFINED)
        .final_layout(final_layout)];
    let colour_ref =
        [vk::AttachmentReference { attachment: 0, layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL }];
    let subpasses = [vk::SubpassDescription::default()
        .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
        .color_attachments(&colour_ref)];
    let dependencies = [
        // The previous readback (or presentation) of the destination ends before it is
        // written again.
        vk::SubpassDependency::default()
            .src_subpass(vk::SUBPASS_EXTERNAL)
            .dst_subpass(0)
            .src_stage_mask(
                vk::PipelineStageFlags::TRANSFER | vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
            )
            .dst_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
            .src_access_mask(vk::AccessFlags::TRANSFER_READ)
            .dst_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE),
        // The readback copy sees the composed colour.
        super::target::colour_to_transfer(),
    ];
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachments)
        .subpasses(&subpasses)
        .dependencies(&dependencies);
    // SAFETY: every array the create info points to lives across the call.
    unsafe { d.create_render_pass(&info, None) }.map_err(RenderError::vk("vkCreateRenderPass"))
}

/// A destination's framebuffers (one per layer). `Drop` destroys them; the views they refer
/// to belong to the caller and must outlive them.
pub(crate) struct ComposeFramebuffers {
    raw: Vec<vk::Framebuffer>,
    extent: vk::Extent2D,
    device: Arc<Device>,
}

impl Drop for ComposeFramebuffers {
    fn drop(&mut self) {
        // SAFETY: the owner waits for its submissions before dropping the framebuffers.
        unsafe {
            for &fb in &self.raw {
                self.device.raw.destroy_framebuffer(fb, None);
            }
        }
    }
}

/// An offscreen destination for one display mode: an 8-bit sRGB image of the mode's output
/// size and layers, its per-layer views and framebuffers, and a buffer to read it back.
/// Field order is drop order: framebuffers, views, then the image.
pub(crate) struct ComposedOutput {
    framebuffers: ComposeFramebuffers,
    layer_views: Vec<vk::ImageView>,
    image: Image,
    readback: Buffer,
    /// The mode and the per-eye size it was made for.
    pub(crate) key: (DisplayMode, (u32, u32)),
}

/// The format of offscreen composed images (the same as the stereo image's).
pub(crate) const COMPOSED_FORMAT: vk::Format = super::target::COLOUR_FORMAT;

impl ComposedOutput {
    /// The destination for `mode` with eyes of `eye` pixels, of 8-bit RGBA `format`
    /// ([`COMPOSED_FORMAT`] or its UNORM twin), for `composer` (made for `format` and
    /// `TRANSFER_SRC_OPTIMAL`).
    pub(crate) fn new(
        device: &Arc<Device>,
        composer: &Composer,
        mode: DisplayMode,
        eye: (u32, u32),
        format: vk::Format,
    ) -> Result<Self, RenderError> {
        let (width, height) = mode.output_size(eye);
        let layers = mode.layers();
        let image = Image::new(
            device,
            ImageDesc {
                width,
                height,
                layers,
                mip_levels: 1,
                format,
                samples: vk::SampleCountFlags::TYPE_1,
                usage: vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
                cube: false,
            },
        )?;
        let readback = Buffer::new(
            device,
            u64::from(width) * u64::from(height) * 4 * u64::from(layers),
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryUse::Readback,
        )?;
        let mut layer_views = Vec::new();
        let mut views = scopeguard::guard(&mut layer_views, |views| {
            for v in views.drain(..) {
                // SAFETY: nothing uses the view yet.
                unsafe { device.raw.destroy_image_view(v, None) };
            }
        });
        for layer in 0..layers {
            let info = vk::ImageViewCreateInfo::default()
                .image(image.raw)
                .view_type(vk::ImageViewType::TYPE_2D)
                .format(format)
                .subresource_range(
                    vk::ImageSubresourceRange::default()
                        .aspect_mask(vk::ImageAspectFlags::COLOR)
                        .base_mip_level(0)
                        .level_count(1)
                        .base_array_layer(layer)
                        .layer_count(1),
                );
            // SAFETY: a view of one layer of this live image.
            let view = unsafe { device.raw.create_image_view(&info, None) }
                .map_err(RenderError::vk("vkCreateImageView"))?;
            views.push(view);
        }
        let framebuffers = composer.framebuffers(&views[..], vk::Extent2D { width, height })?;
        let layer_views = std::mem::take(scopeguard::ScopeGuard::into_inner(views));
        Ok(Self { framebuffers, layer_views, image, readback, key: (mode, eye) })
    }

    /// The framebuffers to record the composition into.
    pub(crate) fn framebuffers(&self) -> &ComposeFramebuffers {
        &self.framebuffers
    }

    /// Copies the composed layers to the host (the composition must have been submitted and
    /// have finished).
    pub(crate) fn read_back(&mut self, device: &Device) -> Result<Vec<image::RgbaImage>, RenderError> {
        read_layers(device, &self.image, &mut self.readback)
    }
}

impl Drop for ComposedOutput {
    fn drop(&mut self) {
        // SAFETY: the owner waits for its submissions first. `drop` runs before the fields
        // drop, so the framebuffers go here, before the views they use; the image follows.
        unsafe {
            for &fb in &self.framebuffers.raw {
                self.framebuffers.device.raw.destroy_framebuffer(fb, None);
            }
            self.framebuffers.raw.clear();
            for &v in &self.layer_views {
                self.framebuffers.device.raw.destroy_image_view(v, None);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_push_constants_fit_and_every_mode_has_its_own_number() {
        assert!(std::mem::size_of::<ComposePush>() <= 128, "128 bytes are guaranteed");
        let mut numbers: Vec<u32> = DisplayMode::ALL.map(shader_mode).to_vec();
        numbers.sort_unstable();
        numbers.dedup();
        assert_eq!(numbers, (0..SHADER_MODES as u32).collect::<Vec<_>>(), "the anaglyphs share one");
        // The matrices reach the shader as columns.
        let c = columns(&DUBOIS_RED_CYAN_LEFT);
        assert_eq!(c[1][0], DUBOIS_RED_CYAN_LEFT[0][1]);
        assert_eq!(c[0][2], DUBOIS_RED_CYAN_LEFT[2][0]);
        assert!(is_srgb(vk::Format::B8G8R8A8_SRGB) && !is_srgb(vk::Format::B8G8R8A8_UNORM));
    }
}
