//! The runtime's Vulkan side: the instance and device it creates for the application
//! (`XR_KHR_vulkan_enable2`), the swapchain images it makes on the application's device, and the
//! readback of captured layer images with its own command pool on the session's queue family.

use ash::vk;

/// A Vulkan instance the runtime created for the application; the application owns it.
#[derive(Clone)]
pub struct Instance {
    pub instance: ash::Instance,
    /// The physical device `xrGetVulkanGraphicsDevice2KHR` answered, once asked.
    pub physical: Option<vk::PhysicalDevice>,
}

/// A Vulkan device the runtime created for the application; the application owns it.
#[derive(Clone)]
pub struct Device {
    pub instance: ash::Instance,
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
}

fn vk_error(what: &str, e: vk::Result) -> String {
    format!("{what} failed: {e}")
}

/// How an image is used at one point of a command buffer: layout, stages and accesses.
pub type Use = (vk::ImageLayout, vk::PipelineStageFlags, vk::AccessFlags);

/// Records a layout transition of `range` of `image` from one use to another.
///
/// # Safety
/// `cmd` must be recording on `device`, and `image` be that device's.
pub unsafe fn transition(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    range: vk::ImageSubresourceRange,
    from: Use,
    to: Use,
) {
    let barrier = vk::ImageMemoryBarrier::default()
        .old_layout(from.0)
        .new_layout(to.0)
        .src_access_mask(from.2)
        .dst_access_mask(to.2)
        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
        .image(image)
        .subresource_range(range);
    device.cmd_pipeline_barrier(cmd, from.1, to.1, vk::DependencyFlags::empty(), &[], &[], &[barrier]);
}

/// `vkCreateInstance` through the application's `vkGetInstanceProcAddr`.
///
/// # Safety
/// `gipa` must be a Vulkan loader's `vkGetInstanceProcAddr`; `info` and `allocator` valid
/// Vulkan structures (or `allocator` null).
pub unsafe fn create_instance(
    gipa: vk::PFN_vkGetInstanceProcAddr,
    info: *const vk::InstanceCreateInfo<'_>,
    allocator: *const vk::AllocationCallbacks<'_>,
) -> Result<Instance, vk::Result> {
    let entry = ash::Entry::from_static_fn(ash::StaticFn { get_instance_proc_addr: gipa });
    let instance = entry.create_instance(&*info, allocator.as_ref())?;
    Ok(Instance { instance, physical: None })
}

/// The physical device the simulated headset is "plugged into": the first one.
pub fn physical_device(instance: &ash::Instance) -> Result<vk::PhysicalDevice, String> {
    // SAFETY: the instance is live (the application owns it and passed it to us).
    let devices = unsafe { instance.enumerate_physical_devices() }
        .map_err(|e| vk_error("vkEnumeratePhysicalDevices", e))?;
    devices.first().copied().ok_or_else(|| "the Vulkan instance has no physical device".to_string())
}

/// `vkCreateDevice` for the application.
///
/// # Safety
/// `info` and `allocator` must be valid Vulkan structures (or `allocator` null).
pub unsafe fn create_device(
    instance: &Instance,
    physical: vk::PhysicalDevice,
    info: *const vk::DeviceCreateInfo<'_>,
    allocator: *const vk::AllocationCallbacks<'_>,
) -> Result<Device, vk::Result> {
    let device = instance.instance.create_device(physical, &*info, allocator.as_ref())?;
    Ok(Device { instance: instance.instance.clone(), physical, device })
}

/// What a session needs of the application's device.
pub struct Gpu {
    pub device: ash::Device,
    queue: vk::Queue,
    pool: vk::CommandPool,
    memory: vk::PhysicalDeviceMemoryProperties,
}

impl Gpu {
    /// Takes the binding's queue and makes the runtime's own command pool on its family.
    pub fn new(d: &Device, family: u32, index: u32) -> Result<Gpu, String> {
        // SAFETY: the device is live and the family/index were given by the application's
        // graphics binding, which the caller checked against the device's queue families.
        unsafe {
            let queue = d.device.get_device_queue(family, index);
            let pool = d
                .device
                .create_command_pool(
                    &vk::CommandPoolCreateInfo::default()
                        .queue_family_index(family)
                        .flags(vk::CommandPoolCreateFlags::TRANSIENT),
                    None,
                )
                .map_err(|e| vk_error("vkCreateCommandPool", e))?;
            let memory = d.instance.get_physical_device_memory_properties(d.physical);
            Ok(Gpu { device: d.device.clone(), queue, pool, memory })
        }
    }

    /// Destroys the runtime's command pool (the device stays: it is the application's).
    pub fn destroy(&self) {
        // SAFETY: every command buffer from the pool was waited for in `submit`.
        unsafe { self.device.destroy_command_pool(self.pool, None) };
    }

    fn memory_type(&self, bits: u32, flags: vk::MemoryPropertyFlags) -> Option<u32> {
        (0..self.memory.memory_type_count).find(|&i| {
            bits & (1 << i) != 0 && self.memory.memory_types[i as usize].property_flags.contains(flags)
        })
    }

    fn allocate(
        &self,
        req: vk::MemoryRequirements,
        flags: vk::MemoryPropertyFlags,
    ) -> Result<vk::DeviceMemory, String> {
        let ty = self
            .memory_type(req.memory_type_bits, flags)
            .ok_or_else(|| format!("no Vulkan memory type with {flags:?}"))?;
        // SAFETY: the device is live; the allocation is freed by the caller.
        unsafe {
            self.device
                .allocate_memory(
                    &vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(ty),
                    None,
                )
                .map_err(|e| vk_error("vkAllocateMemory", e))
        }
    }

    /// Records commands into a one-time command buffer, submits it on the session's queue and
    /// waits for it.
    fn submit(&self, record: impl FnOnce(vk::CommandBuffer)) -> Result<(), String> {
        // SAFETY: the pool belongs to this device; the buffer and fence are waited for and
        // freed before returning.
        unsafe {
            let cmd = self
                .device
                .allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(self.pool)
                        .level(vk::CommandBufferLevel::PRIMARY)
                        .command_buffer_count(1),
                )
                .map_err(|e| vk_error("vkAllocateCommandBuffers", e))?[0];
            let fence = self
                .device
                .create_fence(&vk::FenceCreateInfo::default(), None)
                .map_err(|e| vk_error("vkCreateFence", e))?;
            let result = (|| {
                self.device
                    .begin_command_buffer(
                        cmd,
                        &vk::CommandBufferBeginInfo::default()
                            .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
                    )
                    .map_err(|e| vk_error("vkBeginCommandBuffer", e))?;
                record(cmd);
                self.device.end_command_buffer(cmd).map_err(|e| vk_error("vkEndCommandBuffer", e))?;
                let cmds = [cmd];
                self.device
                    .queue_submit(self.queue, &[vk::SubmitInfo::default().command_buffers(&cmds)], fence)
                    .map_err(|e| vk_error("vkQueueSubmit", e))?;
                self.device
                    .wait_for_fences(&[fence], true, u64::MAX)
                    .map_err(|e| vk_error("vkWaitForFences", e))
            })();
            self.device.destroy_fence(fence, None);
            self.device.free_command_buffers(self.pool, &[cmd]);
            result
        }
    }
}

/// What a swapchain's images are.
#[derive(Clone, Copy, Debug)]
pub struct ImageDesc {
    pub format: vk::Format,
    pub width: u32,
    pub height: u32,
    pub layers: u32,
    pub mips: u32,
    pub samples: vk::SampleCountFlags,
    pub usage: vk::ImageUsageFlags,
    pub mutable: bool,
}

impl ImageDesc {
    fn aspect(&self) -> vk::ImageAspectFlags {
        if self.format == vk::Format::D32_SFLOAT {
            vk::ImageAspectFlags::DEPTH
        } else {
            vk::ImageAspectFlags::COLOR
        }
    }

    /// The layout images are handed to the application in and must be given back in
    /// (XR_KHR_vulkan_enable2).
    pub fn layout(&self) -> vk::ImageLayout {
        if self.usage.contains(vk::ImageUsageFlags::COLOR_ATTACHMENT) {
            vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL
        } else if self.usage.contains(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT) {
            vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL
        } else if self.usage.contains(vk::ImageUsageFlags::STORAGE) {
            vk::ImageLayout::GENERAL
        } else if self.usage.contains(vk::ImageUsageFlags::SAMPLED) {
            vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL
        } else {
            vk::ImageLayout::GENERAL
        }
    }

    fn range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default()
            .aspect_mask(self.aspect())
            .level_count(self.mips)
            .layer_count(self.layers)
    }
}

/// A swapchain's images and their memory.
pub struct Images {
    pub desc: ImageDesc,
    pub images: Vec<vk::Image>,
    memory: Vec<vk::DeviceMemory>,
}

impl Images {
    /// Makes `count` images on the application's device, in the layout the application
    /// receives them in. Colour images also get transfer-source usage, for captures.
    pub fn new(gpu: &Gpu, desc: ImageDesc, count: u32) -> Result<Images, String> {
        let mut made = Images { desc, images: Vec::new(), memory: Vec::new() };
        let mut usage = desc.usage;
        if desc.aspect() == vk::ImageAspectFlags::COLOR {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        let info = vk::ImageCreateInfo::default()
            .flags(if desc.mutable {
                vk::ImageCreateFlags::MUTABLE_FORMAT
            } else {
                vk::ImageCreateFlags::empty()
            })
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D { width: desc.width, height: desc.height, depth: 1 })
            .mip_levels(desc.mips)
            .array_layers(desc.layers)
            .samples(desc.samples)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        for _ in 0..count {
            // SAFETY: the device is live; what is made is recorded in `made` and destroyed
            // by `destroy` (also on failure below).
            let r = unsafe {
                gpu.device.create_image(&info, None).map_err(|e| vk_error("vkCreateImage", e)).and_then(
                    |image| {
                        made.images.push(image);
                        let memory = gpu.allocate(
                            gpu.device.get_image_memory_requirements(image),
                            vk::MemoryPropertyFlags::DEVICE_LOCAL,
                        )?;
                        made.memory.push(memory);
                        gpu.device
                            .bind_image_memory(image, memory, 0)
                            .map_err(|e| vk_error("vkBindImageMemory", e))
                    },
                )
            };
            if let Err(e) = r {
                made.destroy(gpu);
                return Err(e);
            }
        }
        let barriers: Vec<_> = made
            .images
            .iter()
            .map(|&image| {
                vk::ImageMemoryBarrier::default()
                    .old_layout(vk::ImageLayout::UNDEFINED)
                    .new_layout(desc.layout())
                    .dst_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE)
                    .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                    .image(image)
                    .subresource_range(desc.range())
            })
            .collect();
        let r = gpu.submit(|cmd| unsafe {
            // SAFETY: `cmd` is recording; the images are this device's.
            gpu.device.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::TOP_OF_PIPE,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::DependencyFlags::empty(),
                &[],
                &[],
                &barriers,
            )
        });
        if let Err(e) = r {
            made.destroy(gpu);
            return Err(e);
        }
        Ok(made)
    }

    /// Destroys the images and frees their memory, after the device is idle.
    pub fn destroy(&self, gpu: &Gpu) {
        // SAFETY: waiting for the device first means no submitted work still uses them.
        unsafe {
            let _ = gpu.device.device_wait_idle();
            for &i in &self.images {
                gpu.device.destroy_image(i, None);
            }
            for &m in &self.memory {
                gpu.device.free_memory(m, None);
            }
        }
    }

    /// Copies a rectangle of one array layer of image `index` (mip 0) to host memory, tightly
    /// packed 4 bytes a pixel, and gives the image back in its layout.
    pub fn read(
        &self,
        gpu: &Gpu,
        index: usize,
        layer: u32,
        offset: [i32; 2],
        extent: [u32; 2],
    ) -> Result<Vec<u8>, String> {
        let d = &self.desc;
        if !matches!(d.format, vk::Format::R8G8B8A8_SRGB | vk::Format::B8G8R8A8_SRGB) {
            return Err(format!("captures read 8-bit colour images, not {:?}", d.format));
        }
        if d.samples != vk::SampleCountFlags::TYPE_1 {
            return Err("captures cannot read multisampled images".to_string());
        }
        let size = u64::from(extent[0]) * u64::from(extent[1]) * 4;
        let image = self.images[index];
        // SAFETY: a host-visible buffer made, used for one copy that is waited for, then freed.
        unsafe {
            let buffer = gpu
                .device
                .create_buffer(
                    &vk::BufferCreateInfo::default().size(size).usage(vk::BufferUsageFlags::TRANSFER_DST),
                    None,
                )
                .map_err(|e| vk_error("vkCreateBuffer", e))?;
            let memory = match gpu.allocate(
                gpu.device.get_buffer_memory_requirements(buffer),
                vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT,
            ) {
                Ok(m) => m,
                Err(e) => {
                    gpu.device.destroy_buffer(buffer, None);
                    return Err(e);
                }
            };
            let result = (|| {
                gpu.device
                    .bind_buffer_memory(buffer, memory, 0)
                    .map_err(|e| vk_error("vkBindBufferMemory", e))?;
                let range = vk::ImageSubresourceRange::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .base_array_layer(layer)
                    .layer_count(1)
                    .level_count(1);
                let held = (d.layout(), vk::PipelineStageFlags::ALL_COMMANDS, vk::AccessFlags::MEMORY_WRITE);
                let copying = (
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    vk::PipelineStageFlags::TRANSFER,
                    vk::AccessFlags::TRANSFER_READ,
                );
                gpu.submit(|cmd| {
                    let dev = &gpu.device;
                    transition(dev, cmd, image, range, held, copying);
                    let region = vk::BufferImageCopy::default()
                        .image_subresource(
                            vk::ImageSubresourceLayers::default()
                                .aspect_mask(vk::ImageAspectFlags::COLOR)
                                .base_array_layer(layer)
                                .layer_count(1),
                        )
                        .image_offset(vk::Offset3D { x: offset[0], y: offset[1], z: 0 })
                        .image_extent(vk::Extent3D { width: extent[0], height: extent[1], depth: 1 });
                    dev.cmd_copy_image_to_buffer(
                        cmd,
                        image,
                        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                        buffer,
                        &[region],
                    );
                    let to_host = vk::BufferMemoryBarrier::default()
                        .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
                        .dst_access_mask(vk::AccessFlags::HOST_READ)
                        .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                        .buffer(buffer)
                        .size(vk::WHOLE_SIZE);
                    dev.cmd_pipeline_barrier(
                        cmd,
                        vk::PipelineStageFlags::TRANSFER,
                        vk::PipelineStageFlags::HOST,
                        vk::DependencyFlags::empty(),
                        &[],
                        &[to_host],
                        &[],
                    );
                    let back = (
                        d.layout(),
                        vk::PipelineStageFlags::ALL_COMMANDS,
                        vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE,
                    );
                    transition(dev, cmd, image, range, copying, back);
                })?;
                let ptr = gpu
                    .device
                    .map_memory(memory, 0, size, vk::MemoryMapFlags::empty())
                    .map_err(|e| vk_error("vkMapMemory", e))?;
                let mut bytes = std::slice::from_raw_parts(ptr as *const u8, size as usize).to_vec();
                gpu.device.unmap_memory(memory);
                if d.format == vk::Format::B8G8R8A8_SRGB {
                    for px in bytes.chunks_exact_mut(4) {
                        px.swap(0, 2);
                    }
                }
                Ok(bytes)
            })();
            gpu.device.destroy_buffer(buffer, None);
            gpu.device.free_memory(memory, None);
            result
        }
    }
}
