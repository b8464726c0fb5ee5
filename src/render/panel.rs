//! The panels' paint: triangle meshes laid out in an eye image's pixels, drawn over the scene in
//! every view at zero parallax, as the heads-up display is.
//!
//! The `ui` module tessellates its panels (egui) into a [`PanelPaint`], a plain value: vertices
//! in pixels with texture coordinates and a linear, premultiplied colour; batches, each clipped
//! to a pixel rectangle and sampling one texture; and the texture updates since the last paint.
//! The renderer turns the pixels into normalised device coordinates, the same for both views
//! (so each letter lands on the same pixel in the left and the right eye: the panel sits on
//! the screen plane whatever the convergence), clips each batch by a scissor, and blends
//! premultiplied colour over the scene. Textures are sRGB: sampling gives linear colour.
//!
//! A panel may instead lie on a surface in the scene ([`PanelPaint::placement`], the headset's
//! panel in the support hand): its pixels are then taken into the scene and seen by each eye
//! through its own view, depth-tested against the clay, and each batch is clipped to its
//! rectangle in the fragment shader (a scissor cannot follow a surface seen at an angle).

use std::collections::HashMap;
use std::sync::Arc;

use ash::vk;

use super::gpu::buffer::{Buffer, MemoryUse};
use super::gpu::device::Device;
use super::gpu::image::{transition, Image, ImageDesc, Sampler, FRAGMENT_READ, TRANSFER_WRITE};
use super::gpu::pipeline::{full_viewport, write_sampled};
use super::RenderError;
use crate::mesh::Vertex;

/// One vertex of a panel mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PanelVertex {
    /// Pixels of the eye image, from its top-left corner (x right, y down).
    pub position_px: [f32; 2],
    /// Texture coordinates in [0, 1].
    pub uv: [f32; 2],
    /// Linear RGBA, premultiplied by its alpha.
    pub colour: [f32; 4],
}

/// A run of indices drawn with one texture inside one clip rectangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PanelBatch {
    /// The clip rectangle, pixels: `[x0, y0, x1, y1]`, `x1`, `y1` exclusive.
    pub clip_px: [u32; 4],
    /// The first index of the run in [`PanelPaint::indices`].
    pub first_index: u32,
    /// How many indices (three a triangle).
    pub index_count: u32,
    /// Which texture (see [`PanelTexture::id`]).
    pub texture: u64,
}

/// New texels for a texture: the whole texture (made or remade at `size`) or a patch of it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PanelTexture {
    /// The texture, as batches name it.
    pub id: u64,
    /// Where the patch goes in the texture; `None`: the texels are the whole texture.
    pub offset_px: Option<[u32; 2]>,
    /// The texels' width and height.
    pub size_px: [u32; 2],
    /// sRGB-encoded RGBA, premultiplied, row by row: `size_px[0] * size_px[1] * 4` bytes.
    pub srgba: Vec<u8>,
}

/// What the panels paint in one frame: see the module docs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PanelPaint {
    /// The size of the image the pixels are laid out in: each view's.
    pub extent_px: (u32, u32),
    /// Every batch's vertices.
    pub vertices: Vec<PanelVertex>,
    /// Triangles, three indices into `vertices` each.
    pub indices: Vec<u32>,
    /// Drawn in order, later over earlier.
    pub batches: Vec<PanelBatch>,
    /// Texture updates, applied before drawing, in order.
    pub textures: Vec<PanelTexture>,
    /// Textures no longer used, freed after drawing.
    pub freed: Vec<u64>,
    /// Where the panel is: `None`, on the screen plane of every view (zero parallax);
    /// `Some(m)`, on a surface in the scene, `m` taking its pixels (x right, y down, z 0) to
    /// scene metres.
    pub placement: Option<glam::Mat4>,
}

/// What the panel pipeline's shaders read from the push constants (`shaders/panel.vert`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PanelPush {
    placement: [[f32; 4]; 4],
    clip: [f32; 4],
    placed: [f32; 4],
}

/// The largest side of a panel texture, texels: every Vulkan device can sample it.
pub const MAX_TEXTURE_SIDE: u32 = 4096;

/// The most textures the panels may hold at once.
const MAX_TEXTURES: u32 = 32;

/// A panel texture on the device and the descriptor set that samples it.
struct PanelImage {
    image: Image,
    set: vk::DescriptorSet,
}

/// The panels' device side: their vertex and index buffers (host-visible, rewritten each frame
/// they change), textures, sampler and descriptor pool.
pub(crate) struct PanelGpu {
    pub(crate) vertices: Buffer,
    pub(crate) indices: Buffer,
    /// The batches the buffers hold, and the extent they were laid out for.
    pub(crate) batches: Vec<PanelBatch>,
    extent: vk::Extent2D,
    /// Where the panel written last lies (see [`PanelPaint::placement`]).
    pub(crate) placement: Option<glam::Mat4>,
    textures: HashMap<u64, PanelImage>,
    pool: vk::DescriptorPool,
    sampler: Sampler,
    device: Arc<Device>,
}

impl PanelGpu {
    pub(crate) fn new(device: &Arc<Device>) -> Result<Self, RenderError> {
        let sizes = [vk::DescriptorPoolSize {
            ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            descriptor_count: MAX_TEXTURES,
        }];
        let info = vk::DescriptorPoolCreateInfo::default()
            .flags(vk::DescriptorPoolCreateFlags::FREE_DESCRIPTOR_SET)
            .max_sets(MAX_TEXTURES)
            .pool_sizes(&sizes);
        // SAFETY: a valid create info on a live device.
        let pool = unsafe { device.raw.create_descriptor_pool(&info, None) }
            .map_err(RenderError::vk("vkCreateDescriptorPool"))?;
        let pool_guard = scopeguard::guard(pool, |pool| {
            // SAFETY: nothing was allocated from the pool yet.
            unsafe { device.raw.destroy_descriptor_pool(pool, None) }
        });
        let buffer = |usage| Buffer::new(device, 4096, usage, MemoryUse::Upload);
        let vertices = buffer(vk::BufferUsageFlags::VERTEX_BUFFER)?;
        let indices = buffer(vk::BufferUsageFlags::INDEX_BUFFER)?;
        let sampler = Sampler::linear(device, 0.0)?;
        Ok(Self {
            vertices,
            indices,
            batches: Vec::new(),
            extent: vk::Extent2D::default(),
            placement: None,
            textures: HashMap::new(),
            pool: scopeguard::ScopeGuard::into_inner(pool_guard),
            sampler,
            device: device.clone(),
        })
    }

    /// Applies `paint`'s texture updates (waiting for the device: no frame is in flight
    /// then) and writes its meshes for a view of `extent`. A batch whose texture was never
    /// given, or whose indices fall outside the mesh, is left out.
    pub(crate) fn write(
        &mut self,
        paint: &PanelPaint,
        extent: vk::Extent2D,
        set_layout: vk::DescriptorSetLayout,
    ) -> Result<(), RenderError> {
        for update in &paint.textures {
            self.update_texture(update, set_layout)?;
        }
        self.extent = extent;
        self.placement = paint.placement.filter(|m| m.is_finite());
        let (w, h) = (paint.extent_px.0.max(1) as f32, paint.extent_px.1.max(1) as f32);
        // On the screen plane, normalised device coordinates; on a surface, the pixels (the
        // vertex shader places them).
        let position = |[x, y]: [f32; 2]| match self.placement {
            None => [2.0 * x / w - 1.0, 2.0 * y / h - 1.0, 0.0],
            Some(_) => [x, y, 0.0],
        };
        let vertices: Vec<Vertex> = paint
            .vertices
            .iter()
            .map(|v| Vertex {
                position: position(v.position_px),
                normal: [v.uv[0], v.uv[1], 0.0],
                colour: v.colour,
            })
            .collect();
        let count = vertices.len() as u32;
        let fits = |b: &PanelBatch| {
            let end = u64::from(b.first_index) + u64::from(b.index_count);
            end <= paint.indices.len() as u64
                && paint.indices[b.first_index as usize..end as usize].iter().all(|&i| i < count)
                && self.textures.contains_key(&b.texture)
        };
        self.batches = paint.batches.iter().copied().filter(|b| b.index_count > 0 && fits(b)).collect();
        super::renderer::grow(
            &self.device,
            &mut self.vertices,
            std::mem::size_of_val(vertices.as_slice()) as u64,
            vk::BufferUsageFlags::VERTEX_BUFFER,
        )?;
        super::renderer::grow(
            &self.device,
            &mut self.indices,
            paint.indices.len() as u64 * 4,
            vk::BufferUsageFlags::INDEX_BUFFER,
        )?;
        self.vertices.write(0, &vertices);
        self.indices.write(0, &paint.indices);
        for id in &paint.freed {
            self.free(*id);
        }
        Ok(())
    }

    fn free(&mut self, id: u64) {
        if let Some(old) = self.textures.remove(&id) {
            // SAFETY: no frame is in flight between frames (the renderer waits for each); the
            // set came from this pool, made with FREE_DESCRIPTOR_SET.
            unsafe {
                let _ = self.device.raw.device_wait_idle();
                let _ = self.device.raw.free_descriptor_sets(self.pool, &[old.set]);
            }
        }
    }

    fn update_texture(
        &mut self,
        update: &PanelTexture,
        set_layout: vk::DescriptorSetLayout,
    ) -> Result<(), RenderError> {
        let [w, h] = update.size_px;
        if w == 0 || h == 0 || update.srgba.len() as u64 != u64::from(w) * u64::from(h) * 4 {
            return Ok(());
        }
        let fresh = match update.offset_px {
            None => true,
            Some(_) => !self.textures.contains_key(&update.id),
        };
        if fresh {
            if update.offset_px.is_some() {
                // A patch of a texture never made: nothing to put it in.
                return Ok(());
            }
            self.free(update.id);
            // Vulkan guarantees 4096 texels a side; the panels ask for no larger.
            if w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE {
                return Err(RenderError::Unsupported(format!(
                    "a panel texture of {w} × {h} texels is larger than {MAX_TEXTURE_SIDE} a side"
                )));
            }
            if self.textures.len() as u32 >= MAX_TEXTURES {
                return Err(RenderError::Unsupported(format!(
                    "the panels hold more than {MAX_TEXTURES} textures"
                )));
            }
            let desc = ImageDesc {
                width: w,
                height: h,
                layers: 1,
                mip_levels: 1,
                format: vk::Format::R8G8B8A8_SRGB,
                samples: vk::SampleCountFlags::TYPE_1,
                usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
                cube: false,
            };
            let image = Image::new(&self.device, desc)?;
            let layouts = [set_layout];
            let info =
                vk::DescriptorSetAllocateInfo::default().descriptor_pool(self.pool).set_layouts(&layouts);
            // SAFETY: the pool has room (counted above) and the layout is live.
            let set = unsafe { self.device.raw.allocate_descriptor_sets(&info) }
                .map_err(RenderError::vk("vkAllocateDescriptorSets"))?[0];
            // SAFETY: the set is new and unused; the view and sampler outlive it.
            unsafe { write_sampled(&self.device.raw, set, 0, image.view, self.sampler.raw) };
            self.textures.insert(update.id, PanelImage { image, set });
        }
        let target = &self.textures[&update.id];
        let [x, y] = update.offset_px.unwrap_or([0, 0]);
        let (tw, th) = (target.image.desc.width, target.image.desc.height);
        if u64::from(x) + u64::from(w) > u64::from(tw) || u64::from(y) + u64::from(h) > u64::from(th) {
            return Ok(());
        }
        let mut staging = Buffer::new(
            &self.device,
            update.srgba.len() as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryUse::Upload,
        )?;
        staging.write(0, &update.srgba);
        let range = target.image.desc.whole();
        let raw = target.image.raw;
        let d = &self.device.raw;
        let old = if fresh { vk::ImageLayout::UNDEFINED } else { vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL };
        self.device.submit_and_wait(|cb| {
            transition(
                d,
                cb,
                raw,
                range,
                (old, vk::PipelineStageFlags::FRAGMENT_SHADER, vk::AccessFlags::empty()),
                TRANSFER_WRITE,
            );
            let region = vk::BufferImageCopy::default()
                .image_subresource(
                    vk::ImageSubresourceLayers::default()
                        .aspect_mask(vk::ImageAspectFlags::COLOR)
                        .layer_count(1),
                )
                .image_offset(vk::Offset3D { x: x as i32, y: y as i32, z: 0 })
                .image_extent(vk::Extent3D { width: w, height: h, depth: 1 });
            // SAFETY: the image is in TRANSFER_DST_OPTIMAL and the region lies inside the
            // staging buffer and the image (checked above).
            unsafe {
                d.cmd_copy_buffer_to_image(
                    cb,
                    staging.raw,
                    raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                )
            };
            transition(d, cb, raw, range, TRANSFER_WRITE, FRAGMENT_READ);
        })
    }

    /// Records the batches (inside a view pass): a full viewport, then per batch its texture's
    /// set and its clip, as the scissor on the screen plane or in the push constants on a
    /// surface. `pipelines` are the screen plane's and the surface's.
    pub(crate) fn record(
        &self,
        cb: vk::CommandBuffer,
        pipeline_layout: vk::PipelineLayout,
        (on_screen, on_surface): (vk::Pipeline, vk::Pipeline),
    ) {
        if self.batches.is_empty() {
            return;
        }
        let d = &self.device.raw;
        let extent = self.extent;
        let viewport = full_viewport(extent);
        let pipeline = if self.placement.is_some() { on_surface } else { on_screen };
        let everything = [f32::MIN, f32::MIN, f32::MAX, f32::MAX];
        let push = |clip: [f32; 4]| PanelPush {
            placement: self.placement.unwrap_or(glam::Mat4::IDENTITY).to_cols_array_2d(),
            clip,
            placed: [0.0, 0.0, 0.0, if self.placement.is_some() { 1.0 } else { 0.0 }],
        };
        // SAFETY: `cb` is recording inside a view pass; the pipeline was made with dynamic
        // viewport and scissor; buffers and sets are live until the frame finishes.
        unsafe {
            d.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, pipeline);
            d.cmd_set_viewport(cb, 0, &[viewport]);
            d.cmd_bind_vertex_buffers(cb, 0, &[self.vertices.raw], &[0]);
            d.cmd_bind_index_buffer(cb, self.indices.raw, 0, vk::IndexType::UINT32);
            let whole = vk::Rect2D { offset: vk::Offset2D::default(), extent };
            for b in &self.batches {
                let [x0, y0, x1, y1] = b.clip_px;
                let (x1, y1) = (x1.max(x0), y1.max(y0));
                if self.placement.is_some() {
                    // The rectangle is in the panel's own pixels, wherever the surface is seen.
                    if x1 == x0 || y1 == y0 {
                        continue;
                    }
                    d.cmd_set_scissor(cb, 0, &[whole]);
                    let clip = [x0 as f32, y0 as f32, x1 as f32, y1 as f32];
                    push_panel(d, cb, pipeline_layout, &push(clip));
                } else {
                    let x0 = x0.min(extent.width);
                    let y0 = y0.min(extent.height);
                    let x1 = x1.clamp(x0, extent.width);
                    let y1 = y1.clamp(y0, extent.height);
                    if x1 == x0 || y1 == y0 {
                        continue;
                    }
                    let scissor = vk::Rect2D {
                        offset: vk::Offset2D { x: x0 as i32, y: y0 as i32 },
                        extent: vk::Extent2D { width: x1 - x0, height: y1 - y0 },
                    };
                    d.cmd_set_scissor(cb, 0, &[scissor]);
                    push_panel(d, cb, pipeline_layout, &push(everything));
                }
                let set = self.textures[&b.texture].set;
                d.cmd_bind_descriptor_sets(
                    cb,
                    vk::PipelineBindPoint::GRAPHICS,
                    pipeline_layout,
                    1,
                    &[set],
                    &[],
                );
                d.cmd_draw_indexed(cb, b.index_count, 1, b.first_index, 0, 0);
            }
        }
    }
}

/// Writes the panel's push constants.
///
/// # Safety
/// `cb` is recording, with a pipeline of `layout` bound.
unsafe fn push_panel(d: &ash::Device, cb: vk::CommandBuffer, layout: vk::PipelineLayout, push: &PanelPush) {
    // SAFETY: the caller's; the struct fits the layout's push constant range (96 of 128 bytes).
    unsafe {
        d.cmd_push_constants(
            cb,
            layout,
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            0,
            bytemuck::bytes_of(push),
        )
    }
}

impl Drop for PanelGpu {
    fn drop(&mut self) {
        self.textures.clear();
        // SAFETY: the renderer waits for the device before dropping; destroying the pool frees
        // its sets.
        unsafe { self.device.raw.destroy_descriptor_pool(self.pool, None) };
    }
}
