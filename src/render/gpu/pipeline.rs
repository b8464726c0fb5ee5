//! Graphics pipelines from plain descriptions, and the one layout they share.

use std::sync::Arc;

use ash::vk;

use super::super::RenderError;
use super::device::Device;
use crate::mesh::Vertex;

/// Bytes of push constants every pipeline may use (the guaranteed minimum is 128).
pub(crate) const PUSH_CONSTANT_BYTES: u32 = 128;

/// How a pipeline draws: a plain value.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PipelineDesc {
    /// Name for errors and logs.
    pub(crate) name: &'static str,
    /// SPIR-V of the vertex shader.
    pub(crate) vertex: &'static [u8],
    /// SPIR-V of the fragment shader.
    pub(crate) fragment: &'static [u8],
    /// How many of the [`Vertex`] attributes the vertex shader reads, in order: 0 none (no
    /// vertex buffer), 1 position, 2 and normal, 3 and colour.
    pub(crate) attributes: usize,
    pub(crate) cull: vk::CullModeFlags,
    pub(crate) depth_test: bool,
    pub(crate) depth_write: bool,
    /// Premultiplied-free alpha blending (`src·a + dst·(1−a)`).
    pub(crate) blend: bool,
    /// With `blend`, the source is premultiplied by its alpha (`src + dst·(1−a)`).
    pub(crate) premultiplied: bool,
    /// The value of the fragment shader's specialization constant 0 (`constant_id = 0`), for
    /// shaders that have one.
    pub(crate) fragment_constant: Option<u32>,
}

/// The descriptor set layouts and pipeline layout shared by every pipeline: set 0 binding 0 the
/// frame uniforms, binding 1 the radiance cube map; set 1 binding 0 a panel texture (only the
/// panel pipeline reads it); 128 bytes of push constants.
pub(crate) struct Layout {
    pub(crate) pipeline: vk::PipelineLayout,
    pub(crate) set: vk::DescriptorSetLayout,
    pub(crate) panel_set: vk::DescriptorSetLayout,
    device: Arc<Device>,
}

impl Layout {
    pub(crate) fn new(device: &Arc<Device>) -> Result<Self, RenderError> {
        let all = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        let bindings = [
            vk::DescriptorSetLayoutBinding::default()
                .binding(0)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .descriptor_count(1)
                .stage_flags(all),
            vk::DescriptorSetLayoutBinding::default()
                .binding(1)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .descriptor_count(1)
                .stage_flags(vk::ShaderStageFlags::FRAGMENT),
        ];
        let d = &device.raw;
        let set = set_layout(d, &bindings)?;
        let texture = [vk::DescriptorSetLayoutBinding::default()
            .binding(0)
            .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
            .descriptor_count(1)
            .stage_flags(vk::ShaderStageFlags::FRAGMENT)];
        let panel_set = set_layout(d, &texture)?;
        let ranges = [vk::PushConstantRange::default().stage_flags(all).offset(0).size(PUSH_CONSTANT_BYTES)];
        let sets = [*set, *panel_set];
        let info = vk::PipelineLayoutCreateInfo::default().set_layouts(&sets).push_constant_ranges(&ranges);
        // SAFETY: as above; the set layouts are live.
        let pipeline = unsafe { d.create_pipeline_layout(&info, None) }
            .map_err(RenderError::vk("vkCreatePipelineLayout"))?;
        let (set, panel_set) =
            (scopeguard::ScopeGuard::into_inner(set), scopeguard::ScopeGuard::into_inner(panel_set));
        Ok(Self { pipeline, set, panel_set, device: device.clone() })
    }
}

/// A descriptor set layout of `bindings`, destroyed again if the caller fails before it keeps it.
fn set_layout<'d>(
    d: &'d ash::Device,
    bindings: &[vk::DescriptorSetLayoutBinding<'_>],
) -> Result<
    scopeguard::ScopeGuard<vk::DescriptorSetLayout, impl FnOnce(vk::DescriptorSetLayout) + 'd>,
    RenderError,
> {
    // SAFETY: a valid create info on a live device.
    let set = unsafe {
        d.create_descriptor_set_layout(&vk::DescriptorSetLayoutCreateInfo::default().bindings(bindings), None)
    }
    .map_err(RenderError::vk("vkCreateDescriptorSetLayout"))?;
    Ok(scopeguard::guard(set, move |set| {
        // SAFETY: nothing uses the set layout yet.
        unsafe { d.destroy_descriptor_set_layout(set, None) }
    }))
}

impl Drop for Layout {
    fn drop(&mut self) {
        // SAFETY: the pipelines using these layouts are dropped first (field order in the
        // renderer) and no frame is in flight.
        unsafe {
            self.device.raw.destroy_pipeline_layout(self.pipeline, None);
            self.device.raw.destroy_descriptor_set_layout(self.set, None);
            self.device.raw.destroy_descriptor_set_layout(self.panel_set, None);
        }
    }
}

/// A graphics pipeline. `Drop` destroys it.
pub(crate) struct Pipeline {
    pub(crate) raw: vk::Pipeline,
    device: Arc<Device>,
}

struct ShaderModule<'d> {
    raw: vk::ShaderModule,
    device: &'d ash::Device,
}

impl<'d> ShaderModule<'d> {
    fn new(device: &'d ash::Device, spirv: &[u8], pipeline: &str) -> Result<Self, RenderError> {
        let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv)).map_err(|e| {
            RenderError::Unsupported(format!("the {pipeline} shader is not valid SPIR-V: {e}"))
        })?;
        // SAFETY: the code is SPIR-V compiled by glslc at build time.
        let raw =
            unsafe { device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None) }
                .map_err(RenderError::vk("vkCreateShaderModule"))?;
        Ok(Self { raw, device })
    }
}

impl Drop for ShaderModule<'_> {
    fn drop(&mut self) {
        // SAFETY: modules are only needed while their pipeline is created.
        unsafe { self.device.destroy_shader_module(self.raw, None) };
    }
}

impl Pipeline {
    /// Creates the pipeline for `render_pass` (subpass 0) with `layout`, a fixed viewport of
    /// `extent` (or, with `None`, a viewport and scissor set when recording) and `samples`
    /// rasterisation samples.
    pub(crate) fn new(
        device: &Arc<Device>,
        desc: &PipelineDesc,
        layout: vk::PipelineLayout,
        render_pass: vk::RenderPass,
        extent: Option<vk::Extent2D>,
        samples: vk::SampleCountFlags,
    ) -> Result<Self, RenderError> {
        let d = &device.raw;
        let (vs, fs) =
            (ShaderModule::new(d, desc.vertex, desc.name)?, ShaderModule::new(d, desc.fragment, desc.name)?);
        let constant = desc.fragment_constant.unwrap_or(0).to_ne_bytes();
        let entries = [vk::SpecializationMapEntry::default().constant_id(0).offset(0).size(constant.len())];
        let specialization = vk::SpecializationInfo::default().map_entries(&entries).data(&constant);
        let mut fragment_stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::FRAGMENT)
            .module(fs.raw)
            .name(c"main");
        if desc.fragment_constant.is_some() {
            fragment_stage = fragment_stage.specialization_info(&specialization);
        }
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(vs.raw)
                .name(c"main"),
            fragment_stage,
        ];
        let bindings = [vk::VertexInputBindingDescription::default()
            .binding(0)
            .stride(std::mem::size_of::<Vertex>() as u32)
            .input_rate(vk::VertexInputRate::VERTEX)];
        let attributes = [
            vk::VertexInputAttributeDescription::default()
                .location(0)
                .binding(0)
                .format(vk::Format::R32G32B32_SFLOAT)
                .offset(0),
            vk::VertexInputAttributeDescription::default()
                .location(1)
                .binding(0)
                .format(vk::Format::R32G32B32_SFLOAT)
                .offset(12),
            vk::VertexInputAttributeDescription::default()
                .location(2)
                .binding(0)
                .format(vk::Format::R32G32B32A32_SFLOAT)
                .offset(24),
        ];
        // With no attribute, the vertex shader works from gl_VertexIndex alone.
        let used = desc.attributes.min(attributes.len());
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(if used == 0 { &[] } else { &bindings })
            .vertex_attribute_descriptions(&attributes[..used]);
        let assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let fixed = extent.unwrap_or_default();
        let viewports = [full_viewport(fixed)];
        let scissors = [vk::Rect2D { offset: vk::Offset2D::default(), extent: fixed }];
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let (viewport, dynamic) = match extent {
            Some(_) => (
                vk::PipelineViewportStateCreateInfo::default().viewports(&viewports).scissors(&scissors),
                vk::PipelineDynamicStateCreateInfo::default(),
            ),
            None => (
                vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1),
                vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states),
            ),
        };
        // The projections flip y (clip y points down), so counter-clockwise triangles seen
        // from outside stay counter-clockwise on screen.
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(desc.cull)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(samples);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(desc.depth_test)
            .depth_write_enable(desc.depth_write)
            .depth_compare_op(vk::CompareOp::LESS_OR_EQUAL);
        let attachment = [if desc.blend {
            vk::PipelineColorBlendAttachmentState::default()
                .blend_enable(true)
                .src_color_blend_factor(if desc.premultiplied {
                    vk::BlendFactor::ONE
                } else {
                    vk::BlendFactor::SRC_ALPHA
                })
                .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
                .color_blend_op(vk::BlendOp::ADD)
                .src_alpha_blend_factor(vk::BlendFactor::ONE)
                .dst_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
                .alpha_blend_op(vk::BlendOp::ADD)
                .color_write_mask(vk::ColorComponentFlags::RGBA)
        } else {
            vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA)
        }];
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachment);
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .dynamic_state(&dynamic)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .layout(layout)
            .render_pass(render_pass)
            .subpass(0);
        // SAFETY: every state struct lives across the call; the layout and render pass are live.
        let raw = unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) }
            .map_err(|(_, e)| RenderError::vk("vkCreateGraphicsPipelines")(e))?[0];
        Ok(Self { raw, device: device.clone() })
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        // SAFETY: no frame using the pipeline is in flight when the renderer drops it.
        unsafe { self.device.raw.destroy_pipeline(self.raw, None) };
    }
}

/// A descriptor pool with the one set the renderer binds. `Drop` destroys the pool (and so
/// frees the set).
pub(crate) struct DescriptorPool {
    raw: vk::DescriptorPool,
    pub(crate) set: vk::DescriptorSet,
    device: Arc<Device>,
}

impl DescriptorPool {
    /// Allocates the set of `layout` and points it at `uniforms` and the cube map.
    pub(crate) fn new(
        device: &Arc<Device>,
        layout: &Layout,
        uniforms: vk::Buffer,
        cube_view: vk::ImageView,
        sampler: vk::Sampler,
    ) -> Result<Self, RenderError> {
        let d = &device.raw;
        let sizes = [
            vk::DescriptorPoolSize { ty: vk::DescriptorType::UNIFORM_BUFFER, descriptor_count: 1 },
            vk::DescriptorPoolSize { ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER, descriptor_count: 1 },
        ];
        // SAFETY: a valid create info on a live device.
        let raw = unsafe {
            d.create_descriptor_pool(
                &vk::DescriptorPoolCreateInfo::default().max_sets(1).pool_sizes(&sizes),
                None,
            )
        }
        .map_err(RenderError::vk("vkCreateDescriptorPool"))?;
        let mut pool = Self { raw, set: vk::DescriptorSet::null(), device: device.clone() };
        let layouts = [layout.set];
        // SAFETY: the pool has room for exactly this set.
        let set = unsafe {
            d.allocate_descriptor_sets(
                &vk::DescriptorSetAllocateInfo::default().descriptor_pool(raw).set_layouts(&layouts),
            )
        }
        .map_err(RenderError::vk("vkAllocateDescriptorSets"))?[0];
        let buffer_info = [vk::DescriptorBufferInfo { buffer: uniforms, offset: 0, range: vk::WHOLE_SIZE }];
        let image_info = [vk::DescriptorImageInfo {
            sampler,
            image_view: cube_view,
            image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        }];
        let writes = [
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(0)
                .descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                .buffer_info(&buffer_info),
            vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(1)
                .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                .image_info(&image_info),
        ];
        // SAFETY: the set is not in use; the buffer, view and sampler are live and outlive the
        // pool (field order in the renderer).
        unsafe { d.update_descriptor_sets(&writes, &[]) };
        pool.set = set;
        Ok(pool)
    }
}

impl Drop for DescriptorPool {
    fn drop(&mut self) {
        // SAFETY: no frame using the set is in flight when the renderer drops the pool.
        unsafe { self.device.raw.destroy_descriptor_pool(self.raw, None) };
    }
}

/// The viewport over all of `extent`, depths 0 to 1.
pub(crate) fn full_viewport(extent: vk::Extent2D) -> vk::Viewport {
    vk::Viewport {
        x: 0.0,
        y: 0.0,
        width: extent.width as f32,
        height: extent.height as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    }
}

/// Points binding `binding` of `set` at `view` (in `SHADER_READ_ONLY_OPTIMAL`) sampled by
/// `sampler`.
///
/// # Safety
/// `set` must not be in use by a pending command buffer, and `view` and `sampler` must outlive
/// its use.
pub(crate) unsafe fn write_sampled(
    device: &ash::Device,
    set: vk::DescriptorSet,
    binding: u32,
    view: vk::ImageView,
    sampler: vk::Sampler,
) {
    let image_info = [vk::DescriptorImageInfo {
        sampler,
        image_view: view,
        image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
    }];
    let write = vk::WriteDescriptorSet::default()
        .dst_set(set)
        .dst_binding(binding)
        .descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
        .image_info(&image_info);
    // SAFETY: the caller's contract.
    unsafe { device.update_descriptor_sets(&[write], &[]) };
}
