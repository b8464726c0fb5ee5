//! Device-local images with their memory and one view; samplers.

use std::sync::Arc;

use ash::vk;

use super::super::RenderError;
use super::device::Device;

/// What an image is: a plain value, so images are described before they are made.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) struct ImageDesc {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// Array layers (2 for a stereo target, 6 for a cube map).
    pub(crate) layers: u32,
    pub(crate) mip_levels: u32,
    pub(crate) format: vk::Format,
    pub(crate) samples: vk::SampleCountFlags,
    pub(crate) usage: vk::ImageUsageFlags,
    /// A cube map (6 layers, viewed as a cube) rather than a 2D array.
    pub(crate) cube: bool,
}

impl ImageDesc {
    fn aspect(&self) -> vk::ImageAspectFlags {
        match self.format {
            vk::Format::D32_SFLOAT | vk::Format::D16_UNORM | vk::Format::X8_D24_UNORM_PACK32 => {
                vk::ImageAspectFlags::DEPTH
            }
            vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT => {
                vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
            }
            _ => vk::ImageAspectFlags::COLOR,
        }
    }

    /// Every layer and level.
    pub(crate) fn whole(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default()
            .aspect_mask(self.aspect())
            .base_mip_level(0)
            .level_count(self.mip_levels)
            .base_array_layer(0)
            .layer_count(self.layers)
    }
}

/// An image, its memory and a view of all its layers and levels. `Drop` destroys the view,
/// the image, then frees the memory.
pub(crate) struct Image {
    pub(crate) view: vk::ImageView,
    pub(crate) raw: vk::Image,
    memory: vk::DeviceMemory,
    pub(crate) desc: ImageDesc,
    device: Arc<Device>,
}

impl std::fmt::Debug for Image {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Image").field("desc", &self.desc).finish_non_exhaustive()
    }
}

impl Image {
    /// Creates the image in device-local memory, with a 2D-array (or cube) view.
    pub(crate) fn new(device: &Arc<Device>, desc: ImageDesc) -> Result<Self, RenderError> {
        let d = &device.raw;
        let info = vk::ImageCreateInfo::default()
            .flags(if desc.cube {
                vk::ImageCreateFlags::CUBE_COMPATIBLE
            } else {
                vk::ImageCreateFlags::empty()
            })
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D { width: desc.width, height: desc.height, depth: 1 })
            .mip_levels(desc.mip_levels)
            .array_layers(desc.layers)
            .samples(desc.samples)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: a valid create info on a live device; formats and usages were checked by
        // the caller against the device's format properties.
        let raw = unsafe { d.create_image(&info, None) }.map_err(RenderError::vk("vkCreateImage"))?;
        let image_guard = scopeguard::guard(raw, |raw| {
            // SAFETY: the image is not in use yet.
            unsafe { d.destroy_image(raw, None) }
        });
        // SAFETY: a live image of this device.
        let req = unsafe { d.get_image_memory_requirements(raw) };
        let (memory, _) =
            device.allocate(req, vk::MemoryPropertyFlags::empty(), vk::MemoryPropertyFlags::DEVICE_LOCAL)?;
        let memory_guard = scopeguard::guard(memory, |memory| {
            // SAFETY: the memory is not in use yet (its image is destroyed after this guard).
            unsafe { d.free_memory(memory, None) }
        });
        // SAFETY: the memory satisfies the image's requirements and is bound once.
        unsafe { d.bind_image_memory(raw, memory, 0) }.map_err(RenderError::vk("vkBindImageMemory"))?;
        let view_type = match (desc.cube, desc.layers) {
            (true, _) => vk::ImageViewType::CUBE,
            (false, 1) => vk::ImageViewType::TYPE_2D,
            (false, _) => vk::ImageViewType::TYPE_2D_ARRAY,
        };
        let view_info = vk::ImageViewCreateInfo::default()
            .image(raw)
            .view_type(view_type)
            .format(desc.format)
            .subresource_range(desc.whole());
        // SAFETY: the view describes a subresource range of this bound image.
        let view =
            unsafe { d.create_image_view(&view_info, None) }.map_err(RenderError::vk("vkCreateImageView"))?;
        let memory = scopeguard::ScopeGuard::into_inner(memory_guard);
        let raw = scopeguard::ScopeGuard::into_inner(image_guard);
        Ok(Self { view, raw, memory, desc, device: device.clone() })
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: the renderer waits for its frames before dropping images, so none is in use;
        // the view goes before the image, the image before its memory.
        unsafe {
            self.device.raw.destroy_image_view(self.view, None);
            self.device.raw.destroy_image(self.raw, None);
            self.device.raw.free_memory(self.memory, None);
        }
    }
}

/// A trilinear, edge-clamped sampler. `Drop` destroys it.
pub(crate) struct Sampler {
    pub(crate) raw: vk::Sampler,
    device: Arc<Device>,
}

impl Sampler {
    /// A sampler with linear filtering between texels and mip levels.
    pub(crate) fn linear(device: &Arc<Device>, max_lod: f32) -> Result<Self, RenderError> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .min_lod(0.0)
            .max_lod(max_lod);
        // SAFETY: a valid create info on a live device.
        let raw =
            unsafe { device.raw.create_sampler(&info, None) }.map_err(RenderError::vk("vkCreateSampler"))?;
        Ok(Self { raw, device: device.clone() })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: no frame using the sampler is in flight when the renderer drops it.
        unsafe { self.device.raw.destroy_sampler(self.raw, None) };
    }
}

/// An image's use on one side of a [`transition`]: layout, stage and access.
pub(crate) type ImageUse = (vk::ImageLayout, vk::PipelineStageFlags, vk::AccessFlags);

/// Being written by a copy.
pub(crate) const TRANSFER_WRITE: ImageUse = (
    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
    vk::PipelineStageFlags::TRANSFER,
    vk::AccessFlags::TRANSFER_WRITE,
);

/// Being sampled by fragment shaders.
pub(crate) const FRAGMENT_READ: ImageUse = (
    vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
    vk::PipelineStageFlags::FRAGMENT_SHADER,
    vk::AccessFlags::SHADER_READ,
);

/// A pipeline barrier that moves `image` (all of `range`) between layouts.
pub(crate) fn transition(
    device: &ash::Device,
    cb: vk::CommandBuffer,
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    (old, src_stage, src_access): (vk::ImageLayout, vk::PipelineStageFlags, vk::AccessFlags),
    (new, dst_stage, dst_access): (vk::ImageLayout, vk::PipelineStageFlags, vk::AccessFlags),
) {
    let barrier = vk::ImageMemoryBarrier::default()
        .old_layout(old)
        .new_layout(new)
        .src_access_mask(src_access)
        .dst_access_mask(dst_access)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(range);
    // SAFETY: `cb` is recording and `image` belongs to `device`.
    unsafe {
        device.cmd_pipeline_barrier(
            cb,
            src_stage,
            dst_stage,
            vk::DependencyFlags::empty(),
            &[],
            &[],
            std::slice::from_ref(&barrier),
        )
    };
}

/// Records a copy of every layer of `image` (8-bit RGBA, `width` × `height` × `layers`, in
/// `TRANSFER_SRC_OPTIMAL`, its writes made available to transfers) into `buffer`, made visible
/// to the host for when the submission has finished.
pub(crate) fn record_copy_to_buffer(
    d: &ash::Device,
    cb: vk::CommandBuffer,
    image: vk::Image,
    (width, height, layers): (u32, u32, u32),
    buffer: vk::Buffer,
) {
    let region = vk::BufferImageCopy::default()
        .image_subresource(
            vk::ImageSubresourceLayers::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .mip_level(0)
                .base_array_layer(0)
                .layer_count(layers),
        )
        .image_extent(vk::Extent3D { width, height, depth: 1 });
    let to_host = vk::BufferMemoryBarrier::default()
        .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
        .dst_access_mask(vk::AccessFlags::HOST_READ)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .buffer(buffer)
        .offset(0)
        .size(vk::WHOLE_SIZE);
    // SAFETY: `cb` is recording; the image is in TRANSFER_SRC_OPTIMAL (the caller's contract)
    // and the buffer holds every layer.
    unsafe {
        d.cmd_copy_image_to_buffer(cb, image, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buffer, &[region]);
        d.cmd_pipeline_barrier(
            cb,
            vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::HOST,
            vk::DependencyFlags::empty(),
            &[],
            &[to_host],
            &[],
        );
    }
}

/// Copies every layer of `source` (8-bit RGBA, in `TRANSFER_SRC_OPTIMAL`, its writes made
/// available to transfers) into `buffer` and returns the layers as images, top row first.
pub(crate) fn read_layers(
    device: &Device,
    source: &Image,
    buffer: &mut super::buffer::Buffer,
) -> Result<Vec<image::RgbaImage>, RenderError> {
    let ImageDesc { width, height, layers, .. } = source.desc;
    let layer_bytes = width as usize * height as usize * 4;
    debug_assert!(buffer.size as usize >= layer_bytes * layers as usize, "the readback buffer is too small");
    let d = &device.raw;
    let (image, raw_buffer) = (source.raw, buffer.raw);
    device.submit_and_wait(|cb| record_copy_to_buffer(d, cb, image, (width, height, layers), raw_buffer))?;
    let bytes = buffer.read();
    Ok((0..layers as usize)
        .map(|i| {
            image::RgbaImage::from_raw(width, height, bytes[i * layer_bytes..(i + 1) * layer_bytes].to_vec())
                .expect("the readback buffer holds whole layers")
        })
        .collect())
}
