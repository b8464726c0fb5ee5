//! The stereo renderer: uploads mesh chunk diffs, draws a [`Frame`] in one multiview pass and
//! reads both eyes back.
//!
//! One frame is in flight: `draw` waits for its frame to finish, so the host may rewrite the
//! uniforms and the chunk arena between frames without per-frame copies or deferred releases.
//! The window and XR swapchain targets, which overlap frames, will bring those.

use std::sync::Arc;

use ash::vk;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};

use super::chunks::{ArenaStorage, ChunkArena};
use super::compose::{ComposeFramebuffers, ComposedOutput, Composer, COMPOSED_FORMAT};
use super::environment::{build_radiance_cube, irradiance_sh9, reflection_lod, CubeMap};
use super::gpu::buffer::{Buffer, MemoryUse};
use super::gpu::device::Device;
use super::gpu::image::{
    read_layers, record_copy_to_buffer, transition, Image, ImageDesc, Sampler, FRAGMENT_READ, TRANSFER_WRITE,
};
use super::gpu::instance::Instance;
use super::gpu::pipeline::{DescriptorPool, Layout, Pipeline, PipelineDesc, PUSH_CONSTANT_BYTES};
use super::gpu::swapchain::{color_range, surface_extensions, Surface, SwapchainDesc};
use super::panel::PanelGpu;
use super::shapes::{centred_box, full_screen_quad, icosphere, torus_spine, unit_box, unit_cylinder};
use super::target::{begin_pass, StereoTarget, ViewPass};
pub use super::target::{ViewPasses, VIEW_PASSES_VARIABLE};
use super::window::{to_rgba, Presented, WindowHandles, WindowOutput};
use super::xr_target::{SwapchainImages, SwapchainTarget};
use super::{
    Environment, EyeMark, Frame, GlyphShape, Light, PanelPaint, RenderError, ValidationLog, MAX_LIGHTS,
};
use crate::math::Vec3;
use crate::mesh::{MeshDiff, Vertex};
use crate::stereo::display::{DisplayMode, Parity};
use crate::stereo::floating::FloatingWindow;

macro_rules! spirv {
    ($name:literal) => {
        include_bytes!(concat!(env!("OUT_DIR"), "/", $name, ".spv"))
    };
}

/// Spacing of the grid drawn on the stage walls, metres.
const STAGE_GRID_M: f32 = 0.05;
/// Tools whose crosshairs the stage shows.
const MAX_TOOLS: usize = 2;

/// What to render into.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RendererDesc {
    /// Width of each eye's image, pixels.
    pub width: u32,
    /// Height of each eye's image, pixels.
    pub height: u32,
    /// MSAA samples per pixel (1, 2, 4 or 8).
    pub samples: u32,
    /// Turn the Vulkan validation layer on.
    pub validation: bool,
    /// How the eyes are drawn; `None` lets `ARGILE_VIEW_PASSES`, then the device, decide
    /// ([`ViewPasses::for_device`]).
    pub view_passes: Option<ViewPasses>,
}

/// Both eyes' images, read back: 8-bit sRGB, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct StereoImage {
    /// Left eye (multiview layer 0).
    pub left: image::RgbaImage,
    /// Right eye (multiview layer 1).
    pub right: image::RgbaImage,
}

#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct EyeUniforms {
    view_proj: [[f32; 4]; 4],
    inv_view_proj: [[f32; 4]; 4],
    position: [f32; 4],
}

/// Mirrors `FrameUniforms` in `shaders/include/frame.glsl` (std140: only vec4 and mat4).
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct FrameUniforms {
    eyes: [EyeUniforms; 2],
    light_vector: [[f32; 4]; MAX_LIGHTS],
    light_radiance: [[f32; 4]; MAX_LIGHTS],
    sh: [[f32; 4]; 9],
    material: [f32; 4],
    background: [f32; 4],
    params: [f32; 4],
    tools: [[f32; 4]; MAX_TOOLS],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct StagePush {
    min: [f32; 4],
    max: [f32; 4],
    colour: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GlyphPush {
    model: [[f32; 4]; 4],
    colour: [f32; 4],
    /// x: the torus's tube radius (each vertex moves that far along its normal); 0 otherwise.
    shape: [f32; 4],
}

/// The floating window's strips per view: x from the left edge, y from the right edge.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct WindowMaskPush {
    strips: [[f32; 4]; 2],
}

const _: () = assert!(std::mem::size_of::<FrameUniforms>() == 640);
const _: () = assert!(std::mem::size_of::<GlyphPush>() as u32 <= PUSH_CONSTANT_BYTES);

/// The chunk arena's GPU buffers (host-visible, written in place between frames).
struct ArenaBuffers {
    vertices: Buffer,
    indices: Buffer,
    device: Arc<Device>,
}

impl ArenaStorage for ArenaBuffers {
    type Error = RenderError;

    fn reserve(&mut self, vertices: u32, indices: u32) -> Result<(), RenderError> {
        let vertex_bytes = u64::from(vertices) * std::mem::size_of::<Vertex>() as u64;
        grow(&self.device, &mut self.vertices, vertex_bytes, vk::BufferUsageFlags::VERTEX_BUFFER)?;
        grow(&self.device, &mut self.indices, u64::from(indices) * 4, vk::BufferUsageFlags::INDEX_BUFFER)
    }

    fn write_vertices(&mut self, at: u32, vertices: &[Vertex]) {
        self.vertices.write(at as usize * std::mem::size_of::<Vertex>(), vertices);
    }

    fn write_indices(&mut self, at: u32, indices: &[u32]) {
        self.indices.write(at as usize * 4, indices);
    }
}

/// Replaces `buffer` by one of at least `bytes` with the same contents at the same offsets (no
/// frame is in flight between frames, so the old one can go at once).
pub(super) fn grow(
    device: &Arc<Device>,
    buffer: &mut Buffer,
    bytes: u64,
    usage: vk::BufferUsageFlags,
) -> Result<(), RenderError> {
    if bytes > buffer.size {
        let mut grown = Buffer::new(device, bytes, usage, MemoryUse::Upload)?;
        let old = buffer.size as usize;
        grown.bytes_mut()[..old].copy_from_slice(buffer.bytes_mut());
        *buffer = grown;
    }
    Ok(())
}

/// A fixed mesh in buffers of its own, drawn whole.
struct ShapeMesh {
    vertices: Buffer,
    indices: Buffer,
    index_count: u32,
}

impl ShapeMesh {
    fn new(device: &Arc<Device>, (vertices, indices): (Vec<Vertex>, Vec<u32>)) -> Result<Self, RenderError> {
        let upload = |bytes: &[u8], usage| -> Result<Buffer, RenderError> {
            let mut buffer = Buffer::new(device, bytes.len() as u64, usage, MemoryUse::Upload)?;
            buffer.write(0, bytes);
            Ok(buffer)
        };
        Ok(Self {
            vertices: upload(bytemuck::cast_slice(&vertices), vk::BufferUsageFlags::VERTEX_BUFFER)?,
            indices: upload(bytemuck::cast_slice(&indices), vk::BufferUsageFlags::INDEX_BUFFER)?,
            index_count: indices.len() as u32,
        })
    }
}

struct Shapes {
    sphere: ShapeMesh,
    glyph_box: ShapeMesh,
    cylinder: ShapeMesh,
    torus: ShapeMesh,
    cube: ShapeMesh,
    quad: ShapeMesh,
}

/// The pipelines of one view pass (a pipeline is made for one render pass).
struct Pipelines {
    background: Pipeline,
    stage: Pipeline,
    clay: Pipeline,
    glyph: Pipeline,
    hud: Pipeline,
    /// Viewport and scissor set when recording (each batch is clipped).
    panel: Pipeline,
    /// The panel on a surface in the scene: depth-tested against the clay, drawn before the
    /// translucent glyphs (the hand's ray lies over it).
    panel_in_scene: Pipeline,
    /// The floating window's strips, over the scene and under the HUD.
    window_mask: Pipeline,
}

/// The heads-up display's quads (host-visible, rewritten when the text or the size changes).
struct HudMesh {
    vertices: Buffer,
    indices: Buffer,
    index_count: u32,
    /// What the buffers hold: the lines and marks for an image of this size.
    text: Vec<String>,
    marks: Vec<EyeMark>,
    extent: (u32, u32),
}

/// Makes the Vulkan instance and device for a renderer that does not make its own: an OpenXR
/// runtime does, through XR_KHR_vulkan_enable2, from the create infos Argile gives it (adding
/// the extensions it needs). The instance and device belong to the renderer all the same,
/// which destroys them when dropped.
pub trait VulkanMaker {
    /// Creates the instance from `info` with the loader's `get_instance_proc_addr`.
    ///
    /// # Safety
    /// `info` must be a valid create info whose pointers live across the call, and
    /// `get_instance_proc_addr` the loaded Vulkan loader's.
    unsafe fn create_instance(
        &mut self,
        get_instance_proc_addr: vk::PFN_vkGetInstanceProcAddr,
        info: &vk::InstanceCreateInfo<'_>,
    ) -> Result<vk::Instance, RenderError>;

    /// The physical device of `instance` to render on.
    fn physical_device(&mut self, instance: vk::Instance) -> Result<vk::PhysicalDevice, RenderError>;

    /// Creates the device on `physical` from `info`.
    ///
    /// # Safety
    /// As [`VulkanMaker::create_instance`]; `physical` must come from
    /// [`VulkanMaker::physical_device`].
    unsafe fn create_device(
        &mut self,
        get_instance_proc_addr: vk::PFN_vkGetInstanceProcAddr,
        physical: vk::PhysicalDevice,
        info: &vk::DeviceCreateInfo<'_>,
    ) -> Result<vk::Device, RenderError>;
}

/// The renderer's Vulkan handles, as an OpenXR session's graphics binding needs them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VulkanHandles {
    /// The instance.
    pub instance: vk::Instance,
    /// The physical device.
    pub physical_device: vk::PhysicalDevice,
    /// The device.
    pub device: vk::Device,
    /// The family of the queue the renderer submits to.
    pub queue_family: u32,
    /// The queue's index in its family.
    pub queue_index: u32,
}

/// The offscreen stereo renderer.
///
/// Field order is drop order (after `Drop::drop` waits for the device): the composition's
/// destination and pass, pipelines and the descriptor pool, the target, buffers, the environment, layouts, and the device last.
pub struct Renderer {
    /// A runtime's swapchain images the stereo passes draw into, if attached.
    swapchain: Option<SwapchainTarget>,
    /// The window frames are presented in, if any.
    window: Option<WindowOutput>,
    /// The offscreen destination of the last composition, made for its mode and size.
    composed: Option<ComposedOutput>,
    /// The display-mode composition pass, reading the target's output.
    composer: Composer,
    /// One set of pipelines per view pass of the target.
    pipelines: Vec<Pipelines>,
    descriptors: DescriptorPool,
    target: StereoTarget,
    arena_buffers: ArenaBuffers,
    arena: ChunkArena,
    /// The fixed meshes: the glyph shapes, stage box, full-screen quad.
    shapes: Shapes,
    uniforms: Buffer,
    readback: Buffer,
    _radiance: Image,
    _sampler: Sampler,
    layout: Layout,
    cube_size: u32,
    sh: [Vec3; 9],
    /// Where screenshots of the window are read back (made on first use).
    screenshot: Option<Buffer>,
    hud: HudMesh,
    panel: PanelGpu,
    command_buffer: vk::CommandBuffer,
    fence: vk::Fence,
    drawn: bool,
    device: Arc<Device>,
}

impl std::fmt::Debug for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Renderer")
            .field("device", &self.device.info.name)
            .field("extent", &self.target.extent)
            .field("triangles", &self.arena.triangles())
            .finish_non_exhaustive()
    }
}

impl Renderer {
    /// Picks a Vulkan device, builds the stereo target, the environment's cube map (scaled by
    /// `environment_intensity`) and the pipelines.
    pub fn new(
        desc: &RendererDesc,
        environment: &Environment,
        environment_intensity: f32,
    ) -> Result<Self, RenderError> {
        Self::build(desc, environment, environment_intensity, None, None)
    }

    /// As [`Renderer::new`], on a Vulkan instance and device that `maker` makes from Argile's
    /// create infos (an OpenXR runtime, through XR_KHR_vulkan_enable2), on the physical device
    /// it names. Draw into its swapchains with [`Renderer::attach_swapchains`] and
    /// [`Renderer::draw_to_swapchain`].
    pub fn for_external(
        desc: &RendererDesc,
        environment: &Environment,
        environment_intensity: f32,
        maker: &mut dyn VulkanMaker,
    ) -> Result<Self, RenderError> {
        Self::build(desc, environment, environment_intensity, None, Some(maker))
    }

    /// As [`Renderer::new`], for a window of `window_size` pixels that [`Renderer::present`]
    /// shows frames in; `desc` sizes each eye. The renderer keeps `window` alive while it
    /// needs it.
    pub fn for_window(
        desc: &RendererDesc,
        environment: &Environment,
        environment_intensity: f32,
        window: Arc<dyn WindowHandles>,
        window_size: (u32, u32),
    ) -> Result<Self, RenderError> {
        Self::build(desc, environment, environment_intensity, Some((window, window_size)), None)
    }

    fn build(
        desc: &RendererDesc,
        environment: &Environment,
        environment_intensity: f32,
        window: Option<(Arc<dyn WindowHandles>, (u32, u32))>,
        external: Option<&mut dyn VulkanMaker>,
    ) -> Result<Self, RenderError> {
        let display = match &window {
            Some((w, _)) => Some(
                w.display_handle()
                    .map_err(|e| RenderError::Unsupported(format!("the window has no display handle ({e})")))?
                    .as_raw(),
            ),
            None => None,
        };
        let extensions = match display {
            Some(display) => surface_extensions(display)?,
            None => Vec::new(),
        };
        let (instance, device_maker) = match external {
            None => (Arc::new(Instance::new(desc.validation, &extensions)?), None),
            Some(maker) => {
                let instance = Instance::create_with(desc.validation, &extensions, |entry, info| {
                    // SAFETY: `info` and what it points to live across the call; the entry's
                    // vkGetInstanceProcAddr is the loader's own.
                    unsafe { maker.create_instance(entry.static_fn().get_instance_proc_addr, info) }
                })?;
                (Arc::new(instance), Some(maker))
            }
        };
        let surface = match (&window, display) {
            (Some((w, _)), Some(display)) => {
                let handle = w
                    .window_handle()
                    .map_err(|e| RenderError::Unsupported(format!("the window has no window handle ({e})")))?
                    .as_raw();
                // SAFETY: the handles come from a live window that the renderer keeps alive
                // (in `WindowOutput`) for longer than the surface.
                Some(Arc::new(unsafe { Surface::new(&instance, display, handle)? }))
            }
            _ => None,
        };
        let device = match device_maker {
            None => Device::new(instance, surface.as_deref())?,
            Some(maker) => {
                let physical = maker.physical_device(instance.raw.handle())?;
                let get_instance_proc_addr = instance.entry.static_fn().get_instance_proc_addr;
                Device::create_with(instance, None, Some(physical), |physical, info| {
                    // SAFETY: as for the instance; `physical` is the one the maker named.
                    unsafe { maker.create_device(get_instance_proc_addr, physical, info) }
                })?
            }
        };
        let view_passes = match desc.view_passes {
            Some(v) => v,
            None => {
                let wanted = std::env::var(VIEW_PASSES_VARIABLE).ok();
                ViewPasses::for_device(&device.info.name, wanted.as_deref())
                    .map_err(RenderError::Unsupported)?
            }
        };
        tracing::debug!("stereo view passes: {view_passes:?}");
        let target = StereoTarget::new(&device, desc.width, desc.height, desc.samples, view_passes)?;
        let layout = Layout::new(&device)?;

        let cube_size = match environment {
            Environment::Studio => 256,
            Environment::Equirect { width, .. } => (width / 4).next_power_of_two().clamp(64, 1024),
        };
        let cube = build_radiance_cube(environment, environment_intensity, cube_size);
        let sh = irradiance_sh9(&cube);
        let radiance = upload_cube(&device, &cube)?;
        let sampler = Sampler::linear(&device, cube.levels.len() as f32)?;

        let uniforms = Buffer::new(
            &device,
            std::mem::size_of::<FrameUniforms>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            MemoryUse::Upload,
        )?;
        let descriptors = DescriptorPool::new(&device, &layout, uniforms.raw, radiance.view, sampler.raw)?;
        let readback = Buffer::new(
            &device,
            u64::from(desc.width) * u64::from(desc.height) * 4 * 2,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryUse::Readback,
        )?;

        let shapes = Shapes {
            sphere: ShapeMesh::new(&device, icosphere(3))?,
            glyph_box: ShapeMesh::new(&device, centred_box())?,
            cylinder: ShapeMesh::new(&device, unit_cylinder(32))?,
            torus: ShapeMesh::new(&device, torus_spine(48, 16))?,
            cube: ShapeMesh::new(&device, unit_box())?,
            quad: ShapeMesh::new(&device, full_screen_quad())?,
        };

        const INITIAL_VERTICES: u32 = 1 << 16;
        const INITIAL_INDICES: u32 = 1 << 17;
        let arena_buffers = ArenaBuffers {
            vertices: Buffer::new(
                &device,
                u64::from(INITIAL_VERTICES) * std::mem::size_of::<Vertex>() as u64,
                vk::BufferUsageFlags::VERTEX_BUFFER,
                MemoryUse::Upload,
            )?,
            indices: Buffer::new(
                &device,
                u64::from(INITIAL_INDICES) * 4,
                vk::BufferUsageFlags::INDEX_BUFFER,
                MemoryUse::Upload,
            )?,
            device: device.clone(),
        };

        let pipelines = make_pipelines(&device, &layout, &target)?;

        let composer = Composer::new(
            &device,
            target.output.view,
            COMPOSED_FORMAT,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        )?;

        let command_buffer = device.command_buffer()?;
        // SAFETY: a valid create info on a live device; destroyed in Drop.
        let fence = unsafe { device.raw.create_fence(&vk::FenceCreateInfo::default(), None) }
            .map_err(RenderError::vk("vkCreateFence"))?;

        let window = match (window, surface) {
            (Some((window, (width, height))), Some(surface)) => Some(WindowOutput::new(
                &device,
                surface,
                window,
                SwapchainDesc { width, height, layers: 1, vsync: true },
            )?),
            _ => None,
        };

        Ok(Self {
            swapchain: None,
            window,
            composed: None,
            composer,
            pipelines,
            descriptors,
            target,
            arena_buffers,
            arena: ChunkArena::new(INITIAL_VERTICES, INITIAL_INDICES),
            shapes,
            uniforms,
            readback,
            _radiance: radiance,
            _sampler: sampler,
            layout,
            cube_size,
            sh,
            screenshot: None,
            hud: HudMesh {
                vertices: Buffer::new(&device, 4096, vk::BufferUsageFlags::VERTEX_BUFFER, MemoryUse::Upload)?,
                indices: Buffer::new(&device, 1024, vk::BufferUsageFlags::INDEX_BUFFER, MemoryUse::Upload)?,
                index_count: 0,
                text: Vec::new(),
                marks: Vec::new(),
                extent: (0, 0),
            },
            panel: PanelGpu::new(&device)?,
            command_buffer,
            fence,
            drawn: false,
            device,
        })
    }

    /// The name of the Vulkan device in use.
    pub fn device_name(&self) -> &str {
        &self.device.info.name
    }

    /// Triangles of clay the renderer holds.
    pub fn triangle_count(&self) -> usize {
        self.arena.triangles()
    }

    /// Mesh chunks the renderer holds.
    pub fn chunk_count(&self) -> usize {
        self.arena.chunk_count()
    }

    /// Applies a mesh diff to the chunk buffers.
    pub fn apply(&mut self, diff: &MeshDiff) -> Result<(), RenderError> {
        self.arena.apply(diff, &mut self.arena_buffers)
    }

    /// The validation layer's log (always empty when the layer is off). Keep the handle to
    /// read what is reported while the renderer is dropped.
    pub fn validation_log(&self) -> ValidationLog {
        self.device.instance.validation_log()
    }

    /// How the eyes are drawn.
    pub fn view_passes(&self) -> ViewPasses {
        if self.target.passes.len() == 1 {
            ViewPasses::Joint
        } else {
            ViewPasses::Split
        }
    }

    /// Whether the validation layer is on.
    pub fn validation(&self) -> bool {
        self.device.instance.validation()
    }

    /// Lays out the HUD text and the eyes' marks again when they or the image size changed.
    fn write_hud(&mut self, lines: &[String], marks: &[EyeMark]) -> Result<(), RenderError> {
        let extent = (self.target.extent.width, self.target.extent.height);
        let hud = &mut self.hud;
        if hud.text == lines && hud.marks == marks && hud.extent == extent {
            return Ok(());
        }
        let (vertices, indices) = super::hud::layout(lines, marks, extent.0, extent.1);
        let vertex_bytes = std::mem::size_of_val(vertices.as_slice()) as u64;
        grow(&self.device, &mut hud.vertices, vertex_bytes, vk::BufferUsageFlags::VERTEX_BUFFER)?;
        grow(&self.device, &mut hud.indices, indices.len() as u64 * 4, vk::BufferUsageFlags::INDEX_BUFFER)?;
        hud.vertices.write(0, &vertices);
        hud.indices.write(0, &indices);
        hud.index_count = indices.len() as u32;
        hud.text = lines.to_vec();
        hud.marks = marks.to_vec();
        hud.extent = extent;
        Ok(())
    }

    /// Applies the panels' texture updates and writes their meshes (none: nothing drawn).
    fn write_panel(&mut self, paint: Option<&PanelPaint>) -> Result<(), RenderError> {
        match paint {
            Some(paint) => self.panel.write(paint, self.target.extent, self.layout.panel_set),
            None => {
                self.panel.batches.clear();
                Ok(())
            }
        }
    }

    fn write_uniforms(&mut self, frame: &Frame) {
        let mut u = FrameUniforms::default();
        for (eye, view) in u.eyes.iter_mut().zip(&frame.views.eyes) {
            let view_proj = view.projection * view.view;
            eye.view_proj = view_proj.to_cols_array_2d();
            eye.inv_view_proj = view_proj.inverse().to_cols_array_2d();
            eye.position = view.position_m.extend(1.0).to_array();
        }
        let lights = &frame.lights[..frame.lights.len().min(MAX_LIGHTS)];
        for (i, light) in lights.iter().enumerate() {
            let (vector, radiance) = match *light {
                Light::Directional { direction, radiance } => (direction.extend(0.0), radiance),
                Light::Point { position_m, radiance } => (position_m.extend(1.0), radiance),
            };
            u.light_vector[i] = vector.to_array();
            u.light_radiance[i] = radiance.extend(0.0).to_array();
        }
        for (dst, c) in u.sh.iter_mut().zip(&self.sh) {
            *dst = c.extend(0.0).to_array();
        }
        let m = &frame.material;
        u.material = [m.shininess, m.specular, m.reflectivity, m.ambient];
        u.background = frame.background.extend(if frame.show_environment { 1.0 } else { 0.0 }).to_array();
        let tools = &frame.tools[..frame.tools.len().min(MAX_TOOLS)];
        for (dst, t) in u.tools.iter_mut().zip(tools) {
            *dst = t.model.w_axis.truncate().extend(t.model.x_axis.truncate().length()).to_array();
        }
        let stage_tools = if frame.stage.is_some() { tools.len() } else { 0 };
        u.params = [
            lights.len() as f32,
            reflection_lod(m.shininess, self.cube_size),
            stage_tools as f32,
            STAGE_GRID_M,
        ];
        self.uniforms.write(0, std::slice::from_ref(&u));
    }

    /// Draws one stereo frame (both eyes in one multiview pass) and waits for it to finish.
    pub fn draw(&mut self, frame: &Frame) -> Result<(), RenderError> {
        self.write_uniforms(frame);
        self.write_hud(&frame.hud, &frame.eye_marks)?;
        self.write_panel(frame.panel.as_ref())?;
        self.submit(|cb| self.record_stereo(cb, frame), None, None)?;
        self.finish()?;
        self.drawn = true;
        Ok(())
    }

    /// Records the stereo view passes of `frame` (the uniforms already written).
    fn record_stereo(&self, cb: vk::CommandBuffer, frame: &Frame) {
        for (pass, pipelines) in self.target.passes.iter().zip(&self.pipelines) {
            self.target.begin(cb, pass, frame.background.extend(1.0).to_array());
            self.record_pass(cb, pipelines, frame);
            // SAFETY: `cb` is inside the render pass begun above.
            unsafe { self.device.raw.cmd_end_render_pass(cb) };
        }
    }

    /// Records the frame's command buffer with `record` and submits it, waiting on `wait`
    /// (at the colour-output and transfer stages) and signalling `signal`. [`Self::finish`]
    /// waits for it.
    fn submit(
        &self,
        record: impl FnOnce(vk::CommandBuffer),
        wait: Option<vk::Semaphore>,
        signal: Option<vk::Semaphore>,
    ) -> Result<(), RenderError> {
        let d = &self.device.raw;
        let cb = self.command_buffer;
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: the previous submission of `cb` finished (`finish` waited for it), so it can
        // be re-recorded; every handle recorded is owned by `self` and outlives the submission.
        unsafe {
            d.begin_command_buffer(cb, &begin).map_err(RenderError::vk("vkBeginCommandBuffer"))?;
            record(cb);
            d.end_command_buffer(cb).map_err(RenderError::vk("vkEndCommandBuffer"))?;
            let cbs = [cb];
            let waits: Vec<vk::Semaphore> = wait.into_iter().collect();
            let stages = [vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT | vk::PipelineStageFlags::TRANSFER];
            let signals: Vec<vk::Semaphore> = signal.into_iter().collect();
            let submit = [vk::SubmitInfo::default()
                .command_buffers(&cbs)
                .wait_semaphores(&waits)
                .wait_dst_stage_mask(&stages[..waits.len()])
                .signal_semaphores(&signals)];
            d.queue_submit(self.device.queue, &submit, self.fence).map_err(RenderError::vk("vkQueueSubmit"))
        }
    }

    /// Waits for the submitted frame to finish.
    fn finish(&self) -> Result<(), RenderError> {
        let d = &self.device.raw;
        // SAFETY: the fence belongs to this device and was passed to the last submission.
        unsafe {
            d.wait_for_fences(&[self.fence], true, u64::MAX).map_err(RenderError::vk("vkWaitForFences"))?;
            d.reset_fences(&[self.fence]).map_err(RenderError::vk("vkResetFences"))
        }
    }

    /// Tells the renderer the window now has `width` × `height` pixels; the swapchain is remade
    /// before the next frame.
    pub fn resize_window(&mut self, width: u32, height: u32) {
        if let Some(w) = &mut self.window {
            if (w.desc.width, w.desc.height) != (width, height) {
                w.desc.width = width;
                w.desc.height = height;
                w.stale = true;
            }
        }
    }

    /// The most image layers the window's surface offers (quad-buffer stereo needs 2); `None`
    /// without a window.
    pub fn window_max_layers(&self) -> Result<Option<u32>, RenderError> {
        self.window.as_ref().map(WindowOutput::max_layers).transpose()
    }

    /// Draws `frame` and shows it in the window composed as `mode` (interlaced modes with
    /// `parity`, in window pixels); with `screenshot`, also reads back what was shown (the
    /// first layer). Each eye is rendered at the size the mode needs to fill the window. Waits
    /// for the frame to finish (one frame in flight).
    pub fn present(
        &mut self,
        frame: &Frame,
        (mode, parity): (DisplayMode, Parity),
        screenshot: bool,
    ) -> Result<Presented, RenderError> {
        let Some(window) = self.window.as_mut() else {
            return Err(RenderError::Unsupported("this renderer draws offscreen; it has no window".into()));
        };
        if window.desc.layers != mode.layers() {
            window.desc.layers = mode.layers();
            window.stale = true;
        }
        window.refresh()?;
        let Some(extent) = window.swapchain.as_ref().map(|s| s.extent) else {
            return Ok(Presented::Skipped);
        };
        let (eye_w, eye_h) = mode.eye_size_for_output((extent.width, extent.height));
        if (eye_w.max(1), eye_h.max(1)) != (self.target.extent.width, self.target.extent.height) {
            self.resize_eyes(eye_w.max(1), eye_h.max(1))?;
        }
        let source = self.target.output.view;
        let window = self.window.as_mut().expect("checked above");
        window.ensure_composer(source)?;
        let composer = window.composer.as_mut().expect("made with the swapchain");
        composer.prepare(mode)?;
        let swapchain = window.swapchain.as_ref().expect("checked above");
        let Some((index, suboptimal)) = swapchain.acquire(window.acquired)? else {
            window.stale = true;
            return Ok(Presented::Skipped);
        };
        let (image, format, layers) = (swapchain.images[index as usize], swapchain.format, swapchain.layers);
        let rendered = swapchain.rendered[index as usize];
        let acquired = window.acquired;
        let screenshot = screenshot && swapchain.readable;
        let shot_bytes = u64::from(extent.width) * u64::from(extent.height) * 4 * u64::from(layers);
        if screenshot && self.screenshot.as_ref().is_none_or(|b| b.size < shot_bytes) {
            self.screenshot = Some(Buffer::new(
                &self.device,
                shot_bytes,
                vk::BufferUsageFlags::TRANSFER_DST,
                MemoryUse::Readback,
            )?);
        }
        self.write_uniforms(frame);
        self.write_hud(&frame.hud, &frame.eye_marks)?;
        self.write_panel(frame.panel.as_ref())?;
        let shot_buffer = self.screenshot.as_ref().filter(|_| screenshot).map(|b| b.raw);
        let window = self.window.as_ref().expect("checked above");
        let composer = window.composer.as_ref().expect("made above");
        let framebuffers = &window.framebuffers[index as usize];
        self.submit(
            |cb| {
                self.record_stereo(cb, frame);
                self.record_composition(cb, composer, framebuffers, (mode, parity));
                if let Some(buffer) = shot_buffer {
                    // The composition left the image ready to present; copy it on the way.
                    let d = &self.device.raw;
                    let present = (
                        vk::ImageLayout::PRESENT_SRC_KHR,
                        vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                        vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
                    );
                    let copy = (
                        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                        vk::PipelineStageFlags::TRANSFER,
                        vk::AccessFlags::TRANSFER_READ,
                    );
                    transition(d, cb, image, color_range(layers), present, copy);
                    record_copy_to_buffer(d, cb, image, (extent.width, extent.height, layers), buffer);
                    let back = (
                        vk::ImageLayout::PRESENT_SRC_KHR,
                        vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                        vk::AccessFlags::empty(),
                    );
                    transition(d, cb, image, color_range(layers), copy, back);
                }
            },
            Some(acquired),
            Some(rendered),
        )?;
        let fits = window.swapchain.as_ref().expect("checked above").present(index)?;
        self.finish()?;
        self.drawn = true;
        if !fits || suboptimal {
            self.window.as_mut().expect("checked above").stale = true;
        }
        let shot = match shot_buffer {
            Some(_) => {
                let buffer = self.screenshot.as_mut().expect("made above");
                let bytes = buffer.read()[..(shot_bytes / u64::from(layers)) as usize].to_vec();
                Some(to_rgba(format, extent.width, extent.height, bytes))
            }
            None => None,
        };
        Ok(Presented::Shown(shot))
    }

    /// Remakes the stereo target (and what reads it) for eyes of `width` × `height` pixels.
    /// No frame is in flight between frames, so the old one can go at once.
    fn resize_eyes(&mut self, width: u32, height: u32) -> Result<(), RenderError> {
        let samples = self.target.samples.as_raw();
        let passes = self.view_passes();
        self.composed = None;
        if let Some(w) = &mut self.window {
            w.framebuffers.clear();
            w.composer = None;
        }
        let target = StereoTarget::new(&self.device, width, height, samples, passes)?;
        self.pipelines = make_pipelines(&self.device, &self.layout, &target)?;
        self.composer = Composer::new(
            &self.device,
            target.output.view,
            COMPOSED_FORMAT,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        )?;
        self.target = target;
        self.readback = Buffer::new(
            &self.device,
            u64::from(width) * u64::from(height) * 4 * 2,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryUse::Readback,
        )?;
        self.drawn = false;
        Ok(())
    }

    /// Records one view pass's draws: stage, clay, background (where nothing else is), the
    /// translucent tool glyphs, the floating window's strips, then the HUD and the panels.
    fn record_pass(&self, cb: vk::CommandBuffer, pipelines: &Pipelines, frame: &Frame) {
        let d = &self.device.raw;
        // SAFETY: `cb` is recording inside a render pass these pipelines were made for; every
        // buffer and set bound is owned by `self` and outlives the submission.
        unsafe {
            d.cmd_bind_descriptor_sets(
                cb,
                vk::PipelineBindPoint::GRAPHICS,
                self.layout.pipeline,
                0,
                &[self.descriptors.set],
                &[],
            );
            if let Some(stage) = &frame.stage {
                let push = StagePush {
                    min: stage.min_m.extend(0.0).to_array(),
                    max: stage.max_m.extend(0.0).to_array(),
                    colour: stage.colour.extend(1.0).to_array(),
                };
                d.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, pipelines.stage.raw);
                self.push(cb, &push);
                self.draw_shape(cb, &self.shapes.cube);
            }
            if self.arena.draw_count() > 0 {
                d.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, pipelines.clay.raw);
                d.cmd_bind_vertex_buffers(cb, 0, &[self.arena_buffers.vertices.raw], &[0]);
                d.cmd_bind_index_buffer(cb, self.arena_buffers.indices.raw, 0, vk::IndexType::UINT32);
                d.cmd_draw_indexed(cb, self.arena.draw_count(), 1, 0, 0, 0);
            }
            d.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, pipelines.background.raw);
            self.draw_shape(cb, &self.shapes.quad);
        }
        let panel_pipelines = (pipelines.panel.raw, pipelines.panel_in_scene.raw);
        if self.panel.placement.is_some() {
            self.panel.record(cb, self.layout.pipeline, panel_pipelines);
        }
        // SAFETY: as above.
        unsafe {
            if !(frame.tools.is_empty() && frame.controllers.is_empty()) {
                d.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, pipelines.glyph.raw);
                for glyph in frame.tools.iter().chain(&frame.controllers) {
                    let (mesh, tube) = match glyph.shape {
                        GlyphShape::Sphere => (&self.shapes.sphere, 0.0),
                        GlyphShape::Box => (&self.shapes.glyph_box, 0.0),
                        GlyphShape::Cylinder => (&self.shapes.cylinder, 0.0),
                        GlyphShape::Torus { tube } => (&self.shapes.torus, tube),
                    };
                    let push = GlyphPush {
                        model: glyph.model.to_cols_array_2d(),
                        colour: glyph.colour.to_array(),
                        shape: [tube, 0.0, 0.0, 0.0],
                    };
                    self.push(cb, &push);
                    self.draw_shape(cb, mesh);
                }
            }
            if frame.floating_window != FloatingWindow::NONE {
                let strips = frame.floating_window.strips.map(|s| [s.left, s.right, 0.0, 0.0]);
                d.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, pipelines.window_mask.raw);
                self.push(cb, &WindowMaskPush { strips });
                self.draw_shape(cb, &self.shapes.quad);
            }
            if self.hud.index_count > 0 {
                d.cmd_bind_pipeline(cb, vk::PipelineBindPoint::GRAPHICS, pipelines.hud.raw);
                d.cmd_bind_vertex_buffers(cb, 0, &[self.hud.vertices.raw], &[0]);
                d.cmd_bind_index_buffer(cb, self.hud.indices.raw, 0, vk::IndexType::UINT32);
                d.cmd_draw_indexed(cb, self.hud.index_count, 1, 0, 0, 0);
            }
        }
        if self.panel.placement.is_none() {
            self.panel.record(cb, self.layout.pipeline, panel_pipelines);
        }
    }

    fn draw_shape(&self, cb: vk::CommandBuffer, shape: &ShapeMesh) {
        // SAFETY: `cb` is recording inside the render pass; the buffers are live.
        unsafe {
            let d = &self.device.raw;
            d.cmd_bind_vertex_buffers(cb, 0, &[shape.vertices.raw], &[0]);
            d.cmd_bind_index_buffer(cb, shape.indices.raw, 0, vk::IndexType::UINT32);
            d.cmd_draw_indexed(cb, shape.index_count, 1, 0, 0, 0);
        }
    }

    fn push<T: bytemuck::Pod>(&self, cb: vk::CommandBuffer, value: &T) {
        // SAFETY: `cb` is recording; the value fits the layout's push constant range.
        unsafe {
            self.device.raw.cmd_push_constants(
                cb,
                self.layout.pipeline,
                vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                0,
                bytemuck::bytes_of(value),
            )
        };
    }

    /// Copies the last frame's two eyes to the host.
    pub fn read_back(&mut self) -> Result<StereoImage, RenderError> {
        if !self.drawn {
            return Err(RenderError::NothingDrawn);
        }
        let mut layers = read_layers(&self.device, &self.target.output, &mut self.readback)?.into_iter();
        match (layers.next(), layers.next()) {
            (Some(left), Some(right)) => Ok(StereoImage { left, right }),
            _ => unreachable!("the stereo target has two layers"),
        }
    }
}

impl Renderer {
    /// The Vulkan handles an OpenXR session is created on.
    pub fn vulkan_handles(&self) -> VulkanHandles {
        VulkanHandles {
            instance: self.device.instance.raw.handle(),
            physical_device: self.device.physical,
            device: self.device.raw.handle(),
            queue_family: self
                .device
                .info
                .graphics_queue_family
                .expect("usable devices have a graphics queue"),
            queue_index: 0,
        }
    }

    /// The depth format the renderer draws with (a depth swapchain of this format can be
    /// drawn into directly).
    pub fn depth_format(&self) -> vk::Format {
        self.target.depth.desc.format
    }

    /// The colour format of the stereo images (a colour swapchain must have it).
    pub fn colour_format(&self) -> vk::Format {
        self.target.output.desc.format
    }

    /// Draws from now on into a runtime's swapchains of `width` × `height` pixels per eye and
    /// two array layers: `colour`, and `depth` where it can be the depth attachment (one
    /// sample per pixel, the renderer's depth format). Returns whether the depth is drawn
    /// into `depth` (and may be submitted). The images stay the runtime's.
    pub fn attach_swapchains(
        &mut self,
        (width, height): (u32, u32),
        colour: &SwapchainImages,
        depth: Option<&SwapchainImages>,
    ) -> Result<bool, RenderError> {
        self.swapchain = None;
        if (width, height) != (self.target.extent.width, self.target.extent.height) {
            self.resize_eyes(width, height)?;
        }
        let masks = self.view_passes().view_masks();
        let target = SwapchainTarget::new(&self.device, &self.target, masks, colour, depth)?;
        let stored = target.depth_stored;
        self.swapchain = Some(target);
        Ok(stored)
    }

    /// Draws `frame` into colour swapchain image `colour` (and depth image `depth`, when the
    /// depth is drawn into the swapchain) and waits for it, leaving the images in the layouts
    /// the runtime handed them over in.
    pub fn draw_to_swapchain(
        &mut self,
        frame: &Frame,
        colour: u32,
        depth: Option<u32>,
    ) -> Result<(), RenderError> {
        let Some(swapchain) = self.swapchain.as_mut() else {
            return Err(RenderError::Unsupported("no swapchain is attached to this renderer".into()));
        };
        let passes = swapchain.passes(&self.target, colour, depth)?;
        self.write_uniforms(frame);
        self.write_hud(&frame.hud, &frame.eye_marks)?;
        self.write_panel(frame.panel.as_ref())?;
        self.submit(
            |cb| {
                for (pass, pipelines) in passes.iter().zip(&self.pipelines) {
                    begin_pass(
                        &self.device,
                        cb,
                        pass,
                        self.target.extent,
                        frame.background.extend(1.0).to_array(),
                    );
                    self.record_pass(cb, pipelines, frame);
                    // SAFETY: `cb` is inside the render pass begun above.
                    unsafe { self.device.raw.cmd_end_render_pass(cb) };
                }
            },
            None,
            None,
        )?;
        self.finish()
    }

    /// Forgets the runtime's swapchain images (before their swapchain is destroyed).
    pub fn detach_swapchains(&mut self) {
        // SAFETY: waiting for idle makes every submission that used the images finish.
        unsafe {
            let _ = self.device.raw.device_wait_idle();
        }
        self.swapchain = None;
    }
}

impl Renderer {
    /// Composes the last frame's stereo pair as `mode` shows it (interlaced modes with
    /// `parity`) into an offscreen image, with the same pass a window uses, and waits for it.
    /// Read it with [`read_back_composed`](Self::read_back_composed).
    pub fn compose(&mut self, mode: DisplayMode, parity: Parity) -> Result<(), RenderError> {
        if !self.drawn {
            return Err(RenderError::NothingDrawn);
        }
        let extent = self.target.extent;
        let eye = (extent.width, extent.height);
        if self.composed.as_ref().map(|c| c.key) != Some((mode, eye)) {
            self.composed = None;
            let output = ComposedOutput::new(&self.device, &self.composer, mode, eye, COMPOSED_FORMAT)?;
            self.composed = Some(output);
        }
        self.composer.prepare(mode)?;
        let Some(output) = &self.composed else { unreachable!("made just above") };
        self.compose_into(&self.composer, output, (mode, parity))
    }

    /// Records and runs `composer` (prepared for the mode) from the stereo image into
    /// `output`, and waits for it.
    fn compose_into(
        &self,
        composer: &Composer,
        output: &ComposedOutput,
        (mode, parity): (DisplayMode, Parity),
    ) -> Result<(), RenderError> {
        self.device.submit_and_wait(|cb| {
            self.record_composition(cb, composer, output.framebuffers(), (mode, parity))
        })
    }

    /// Records the composition of the stereo image into `framebuffers` with `composer`
    /// (prepared for `mode`). The stereo passes leave the image ready for readback; the
    /// composition samples it, then hands it back in that layout (which the next frame's
    /// passes expect).
    fn record_composition(
        &self,
        cb: vk::CommandBuffer,
        composer: &Composer,
        framebuffers: &ComposeFramebuffers,
        (mode, parity): (DisplayMode, Parity),
    ) {
        let extent = self.target.extent;
        let d = &self.device.raw;
        let source = self.target.output.raw;
        let range = self.target.output.desc.whole();
        transition(
            d,
            cb,
            source,
            range,
            (
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT,
                vk::AccessFlags::COLOR_ATTACHMENT_WRITE,
            ),
            FRAGMENT_READ,
        );
        composer.record(cb, framebuffers, (mode, parity), (extent.width, extent.height));
        transition(
            d,
            cb,
            source,
            range,
            (
                vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                vk::PipelineStageFlags::FRAGMENT_SHADER,
                vk::AccessFlags::empty(),
            ),
            (
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                vk::PipelineStageFlags::TRANSFER,
                vk::AccessFlags::TRANSFER_READ,
            ),
        );
    }

    /// Copies the last composition to the host: one image of the mode's output size, or two
    /// (left, right) for quad-buffer.
    pub fn read_back_composed(&mut self) -> Result<Vec<image::RgbaImage>, RenderError> {
        match &mut self.composed {
            Some(output) => output.read_back(&self.device),
            None => Err(RenderError::NothingDrawn),
        }
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        // SAFETY: waiting for idle makes every submission finish; the fence was created from
        // this device and is unused afterwards. The fields then drop in declaration order.
        unsafe {
            let _ = self.device.raw.device_wait_idle();
            self.device.raw.destroy_fence(self.fence, None);
        }
    }
}

/// The pipelines of each view pass of `target`.
fn make_pipelines(
    device: &Arc<Device>,
    layout: &Layout,
    target: &StereoTarget,
) -> Result<Vec<Pipelines>, RenderError> {
    // The background is drawn after the opaque geometry, at depth 1 with the depth test on,
    // so only pixels nothing else covers are shaded.
    let base = PipelineDesc {
        name: "background",
        vertex: spirv!("background.vert"),
        fragment: spirv!("background.frag"),
        attributes: 1,
        cull: vk::CullModeFlags::NONE,
        depth_test: true,
        depth_write: false,
        blend: false,
        premultiplied: false,
        fragment_constant: None,
    };
    let panel = PipelineDesc {
        name: "panel",
        vertex: spirv!("panel.vert"),
        fragment: spirv!("panel.frag"),
        attributes: 3,
        cull: vk::CullModeFlags::NONE,
        depth_test: false,
        depth_write: false,
        blend: true,
        premultiplied: true,
        ..base
    };
    let pipelines_for = |pass: &ViewPass| -> Result<Pipelines, RenderError> {
        let make = |desc: PipelineDesc| {
            Pipeline::new(
                device,
                &desc,
                layout.pipeline,
                pass.render_pass,
                Some(target.extent),
                target.samples,
            )
        };
        Ok(Pipelines {
            background: make(base)?,
            stage: make(PipelineDesc {
                name: "stage",
                vertex: spirv!("stage.vert"),
                fragment: spirv!("stage.frag"),
                attributes: 2,
                cull: vk::CullModeFlags::FRONT,
                depth_test: true,
                depth_write: true,
                ..base
            })?,
            clay: make(PipelineDesc {
                name: "clay",
                vertex: spirv!("clay.vert"),
                fragment: spirv!("clay.frag"),
                attributes: 3,
                cull: vk::CullModeFlags::BACK,
                depth_test: true,
                depth_write: true,
                ..base
            })?,
            glyph: make(PipelineDesc {
                name: "tool glyph",
                vertex: spirv!("glyph.vert"),
                fragment: spirv!("glyph.frag"),
                attributes: 2,
                cull: vk::CullModeFlags::BACK,
                depth_test: true,
                depth_write: false,
                blend: true,
                ..base
            })?,
            window_mask: make(PipelineDesc {
                name: "floating window",
                vertex: spirv!("window_mask.vert"),
                fragment: spirv!("window_mask.frag"),
                attributes: 1,
                cull: vk::CullModeFlags::NONE,
                depth_test: false,
                depth_write: false,
                ..base
            })?,
            hud: make(PipelineDesc {
                name: "heads-up display",
                vertex: spirv!("hud.vert"),
                fragment: spirv!("hud.frag"),
                attributes: 3,
                cull: vk::CullModeFlags::NONE,
                depth_test: false,
                depth_write: false,
                blend: true,
                ..base
            })?,
            panel: Pipeline::new(device, &panel, layout.pipeline, pass.render_pass, None, target.samples)?,
            panel_in_scene: Pipeline::new(
                device,
                &PipelineDesc { name: "panel in the scene", depth_test: true, ..panel },
                layout.pipeline,
                pass.render_pass,
                None,
                target.samples,
            )?,
        })
    };
    target.passes.iter().map(pipelines_for).collect()
}

/// Uploads a cube map (all faces and levels) as a sampled RGBA16F cube image.
fn upload_cube(device: &Arc<Device>, cube: &CubeMap) -> Result<Image, RenderError> {
    let levels = cube.levels.len() as u32;
    let desc = ImageDesc {
        width: cube.size,
        height: cube.size,
        layers: 6,
        mip_levels: levels,
        format: vk::Format::R16G16B16A16_SFLOAT,
        samples: vk::SampleCountFlags::TYPE_1,
        usage: vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
        cube: true,
    };
    let image = Image::new(device, desc)?;
    let texels: usize = cube.levels.iter().map(|faces| faces.iter().map(Vec::len).sum::<usize>()).sum();
    let mut staging =
        Buffer::new(device, texels as u64 * 8, vk::BufferUsageFlags::TRANSFER_SRC, MemoryUse::Upload)?;
    let mut regions = Vec::with_capacity(cube.levels.len());
    let mut half: Vec<half::f16> = Vec::with_capacity(texels * 4);
    for (level, faces) in cube.levels.iter().enumerate() {
        let side = cube.level_size(level);
        regions.push(
            vk::BufferImageCopy::default()
                .buffer_offset(half.len() as u64 * 2)
                .image_subresource(
                    vk::ImageSubresourceLayers::default()
                        .aspect_mask(vk::ImageAspectFlags::COLOR)
                        .mip_level(level as u32)
                        .base_array_layer(0)
                        .layer_count(6),
                )
                .image_extent(vk::Extent3D { width: side, height: side, depth: 1 }),
        );
        for face in faces {
            half.extend(face.iter().flatten().map(|&v| half::f16::from_f32(v)));
        }
    }
    staging.write(0, &half);
    let range = desc.whole();
    let d = &device.raw;
    device.submit_and_wait(|cb| {
        transition(
            d,
            cb,
            image.raw,
            range,
            (vk::ImageLayout::UNDEFINED, vk::PipelineStageFlags::TOP_OF_PIPE, vk::AccessFlags::empty()),
            TRANSFER_WRITE,
        );
        // SAFETY: the image is in TRANSFER_DST_OPTIMAL and the regions lie inside the staging
        // buffer and the image.
        unsafe {
            d.cmd_copy_buffer_to_image(
                cb,
                staging.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &regions,
            )
        };
        transition(d, cb, image.raw, range, TRANSFER_WRITE, FRAGMENT_READ);
    })?;
    Ok(image)
}

/// What `argile info` shows of Vulkan: every device, and the one Argile would use and why.
#[derive(Clone, Debug)]
pub struct DeviceProbe {
    /// Every physical device.
    pub devices: Vec<super::DeviceInfo>,
    /// The device chosen (index and why), or why none can be.
    pub choice: Result<(usize, String), String>,
}

impl std::fmt::Display for DeviceProbe {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, d) in self.devices.iter().enumerate() {
            writeln!(
                f,
                "  [{i}] {} ({}, Vulkan {}): multiview {} ({} views), MSAA samples {}{}",
                d.name,
                d.kind,
                super::gpu::instance::version_string(d.api_version),
                if d.multiview { "yes" } else { "no" },
                d.max_multiview_views,
                d.sample_list(),
                d.unusable_because().map(|w| format!(" — unusable: {w}")).unwrap_or_default()
            )?;
        }
        match &self.choice {
            Ok((i, why)) => {
                let name = &self.devices[*i].name;
                writeln!(f, "  would use [{i}] {name}: {why}")?;
                let wanted = std::env::var(VIEW_PASSES_VARIABLE).ok();
                match ViewPasses::for_device(name, wanted.as_deref()) {
                    Ok(ViewPasses::Joint) => writeln!(f, "  stereo: both eyes in one multiview pass"),
                    Ok(ViewPasses::Split) => writeln!(
                        f,
                        "  stereo: one multiview pass per eye (this driver loses clipped triangles in the \
                         second view of a joint pass)"
                    ),
                    Err(e) => writeln!(f, "  {e}"),
                }
            }
            Err(e) => writeln!(f, "  {e}"),
        }
    }
}

/// Lists the Vulkan devices and says which one a renderer would use (honouring
/// `ARGILE_DEVICE`), without creating a device.
pub fn probe_devices() -> Result<DeviceProbe, RenderError> {
    let instance = Instance::new(false, &[])?;
    let devices: Vec<super::DeviceInfo> =
        super::gpu::device::enumerate(&instance.raw)?.into_iter().map(|(_, info)| info).collect();
    let wanted = std::env::var(super::DEVICE_VARIABLE).ok();
    let choice = super::choose_device(&devices, wanted.as_deref());
    Ok(DeviceProbe { devices, choice })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Environment;

    /// The log really receives what the layer says: an invalid call (a buffer of size 0) is
    /// reported. Needs Vulkan and the validation layer; fails without them.
    #[test]
    fn validation_errors_reach_the_log() {
        let instance =
            Arc::new(Instance::new(true, &[]).expect("a Vulkan instance with the validation layer"));
        let log = instance.validation_log();
        let device = Device::new(instance, None).expect("a Vulkan device");
        let info = vk::BufferCreateInfo::default().size(0).usage(vk::BufferUsageFlags::VERTEX_BUFFER);
        // SAFETY: deliberately invalid (size 0) to provoke the layer; the buffer, if the driver
        // made one, is destroyed at once and never used.
        unsafe {
            if let Ok(b) = device.raw.create_buffer(&info, None) {
                device.raw.destroy_buffer(b, None);
            }
        }
        let messages = log.take();
        assert!(messages.iter().any(|m| m.contains("size")), "the layer reported {messages:?}");
        drop(device);
        assert!(log.take().is_empty(), "a clean teardown reports nothing");
    }

    /// A window's swapchain may be UNORM: the composition then encodes sRGB in the shader, and
    /// must give what an sRGB destination stores (within the rounding of the two encoders).
    #[test]
    fn a_unorm_destination_gets_the_same_srgb_values_as_an_srgb_one() {
        let desc = RendererDesc { width: 40, height: 24, samples: 1, validation: true, view_passes: None };
        let mut renderer = Renderer::new(&desc, &Environment::Studio, 1.0).expect("a Vulkan device");
        let log = renderer.validation_log();
        let rig = crate::stereo::StereoRig {
            eye_m: Vec3::new(0.0, 0.2, 0.6),
            target_m: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 60.0,
            interaxial_m: 0.063,
            convergence_m: 0.6,
            near_m: 0.05,
            far_m: 10.0,
        };
        let frame = Frame {
            views: rig.views(40.0 / 24.0),
            lights: Vec::new(),
            material: Default::default(),
            tools: Vec::new(),
            controllers: Vec::new(),
            stage: None,
            show_environment: true,
            background: Vec3::ZERO,
            hud: Vec::new(),
            panel: None,
            floating_window: FloatingWindow::NONE,
            eye_marks: Vec::new(),
        };
        renderer.draw(&frame).unwrap();
        let format = vk::Format::R8G8B8A8_UNORM;
        let mut unorm = Composer::new(
            &renderer.device,
            renderer.target.output.view,
            format,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        )
        .unwrap();
        for mode in [DisplayMode::Anaglyph, DisplayMode::SideBySideHalf, DisplayMode::Mono] {
            renderer.compose(mode, Parity::LeftEven).unwrap();
            let srgb = renderer.read_back_composed().unwrap().remove(0);
            let mut output = ComposedOutput::new(&renderer.device, &unorm, mode, (40, 24), format).unwrap();
            unorm.prepare(mode).unwrap();
            renderer.compose_into(&unorm, &output, (mode, Parity::LeftEven)).unwrap();
            let encoded = output.read_back(&renderer.device).unwrap().remove(0);
            let distinct: std::collections::HashSet<_> = srgb.pixels().collect();
            assert!(distinct.len() > 20, "{mode}: the studio gives many colours ({})", distinct.len());
            for (a, b) in srgb.pixels().zip(encoded.pixels()) {
                assert!(
                    (0..4).all(|c| a[c].abs_diff(b[c]) <= 2),
                    "{mode}: {a:?} (sRGB) against {b:?} (UNORM)"
                );
            }
        }
        drop(unorm);
        drop(renderer);
        let messages = log.take();
        assert!(messages.is_empty(), "the validation layer reported {messages:#?}");
    }

    #[test]
    fn the_uniform_block_matches_std140() {
        // Offsets in shaders/include/frame.glsl under std140 (vec4 and mat4 members only).
        let u = FrameUniforms::default();
        let base = std::ptr::from_ref(&u) as usize;
        let offset = |p: *const u8| p as usize - base;
        assert_eq!(offset(std::ptr::from_ref(&u.light_vector).cast()), 288);
        assert_eq!(offset(std::ptr::from_ref(&u.sh).cast()), 416);
        assert_eq!(offset(std::ptr::from_ref(&u.params).cast()), 592);
        assert_eq!(offset(std::ptr::from_ref(&u.tools).cast()), 608);
    }
}
