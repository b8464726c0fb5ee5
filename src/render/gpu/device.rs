//! Physical device selection and the logical device: one graphics queue, one command pool.

use std::sync::Arc;

use ash::vk;

use super::super::RenderError;
use super::instance::{version_string, Instance};
use super::swapchain::Surface;

/// The environment variable that overrides the device choice: an index or part of a name.
pub const DEVICE_VARIABLE: &str = "ARGILE_DEVICE";

/// The kind of a Vulkan device, in order of preference.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum DeviceKind {
    /// A discrete GPU.
    Discrete,
    /// A GPU sharing memory with the CPU.
    Integrated,
    /// A virtualised GPU.
    Virtual,
    /// A software rasteriser (lavapipe).
    Cpu,
    /// Anything else.
    Other,
}

impl std::fmt::Display for DeviceKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            DeviceKind::Discrete => "discrete GPU",
            DeviceKind::Integrated => "integrated GPU",
            DeviceKind::Virtual => "virtual GPU",
            DeviceKind::Cpu => "CPU (software)",
            DeviceKind::Other => "other",
        })
    }
}

/// What Argile needs to know of a physical device, as plain values.
#[derive(Clone, Debug, PartialEq)]
pub struct DeviceInfo {
    /// Name as the driver reports it.
    pub name: String,
    /// Kind.
    pub kind: DeviceKind,
    /// Highest Vulkan version it supports.
    pub api_version: u32,
    /// Whether `VK_KHR_multiview` (core in 1.1) is supported: single-pass stereo needs it.
    pub multiview: bool,
    /// Multiview views per pass (at least 2 needed).
    pub max_multiview_views: u32,
    /// A queue family that does graphics, if any.
    pub graphics_queue_family: Option<u32>,
    /// Sample counts supported by both colour and depth framebuffers.
    pub sample_counts: vk::SampleCountFlags,
}

impl DeviceInfo {
    /// Why the device cannot run Argile, if it cannot.
    pub fn unusable_because(&self) -> Option<String> {
        if self.api_version < vk::API_VERSION_1_1 {
            return Some(format!("Vulkan {} only; 1.1 is needed", version_string(self.api_version)));
        }
        if !self.multiview || self.max_multiview_views < 2 {
            return Some("no multiview (single-pass stereo)".into());
        }
        if self.graphics_queue_family.is_none() {
            return Some("no graphics queue".into());
        }
        None
    }

    /// The sample counts as a list, e.g. `1/2/4/8`.
    pub fn sample_list(&self) -> String {
        [1u32, 2, 4, 8, 16, 32, 64]
            .iter()
            .filter(|&&n| self.sample_counts.contains(vk::SampleCountFlags::from_raw(n)))
            .map(u32::to_string)
            .collect::<Vec<_>>()
            .join("/")
    }
}

/// Chooses a device: the one `override_` names (an index or part of a name, case-insensitive),
/// else the first usable device of the most preferred kind. Returns its index and why.
pub fn choose_device(devices: &[DeviceInfo], override_: Option<&str>) -> Result<(usize, String), String> {
    if devices.is_empty() {
        return Err("no Vulkan device found; install a driver (for a CPU renderer: the Debian package \
                    mesa-vulkan-drivers)"
            .into());
    }
    if let Some(wanted) = override_.map(str::trim).filter(|w| !w.is_empty()) {
        let lower = wanted.to_lowercase();
        let found = match wanted.parse::<usize>() {
            Ok(i) if i < devices.len() => Some(i),
            Ok(_) => None,
            Err(_) => devices.iter().position(|d| d.name.to_lowercase().contains(&lower)),
        };
        let Some(i) = found else {
            let names: Vec<String> =
                devices.iter().enumerate().map(|(i, d)| format!("[{i}] {}", d.name)).collect();
            return Err(format!(
                "{DEVICE_VARIABLE}={wanted} names no Vulkan device; there are {}",
                names.join(", ")
            ));
        };
        return match devices[i].unusable_because() {
            Some(why) => Err(format!(
                "{DEVICE_VARIABLE}={wanted} picks {}, which cannot be used: {why}",
                devices[i].name
            )),
            None => Ok((i, format!("{DEVICE_VARIABLE}={wanted} asks for it"))),
        };
    }
    let best = devices
        .iter()
        .enumerate()
        .filter(|(_, d)| d.unusable_because().is_none())
        .min_by_key(|(i, d)| (d.kind, *i));
    match best {
        Some((i, d)) => Ok((
            i,
            match d.kind {
                DeviceKind::Discrete => "it is the first usable discrete GPU".to_owned(),
                DeviceKind::Cpu => "no usable GPU was found, so Vulkan renders on the CPU".to_owned(),
                kind => format!("no usable discrete GPU was found; it is the first usable {kind}"),
            },
        )),
        None => Err(format!(
            "no Vulkan device can run Argile: {}",
            devices
                .iter()
                .map(|d| format!("{} ({})", d.name, d.unusable_because().unwrap_or_default()))
                .collect::<Vec<_>>()
                .join("; ")
        )),
    }
}

/// Reads a physical device's properties into a [`DeviceInfo`].
pub(crate) fn describe(instance: &ash::Instance, pd: vk::PhysicalDevice) -> DeviceInfo {
    // SAFETY: `pd` was enumerated from `instance`; these are plain queries.
    let (props, queues) = unsafe {
        (
            instance.get_physical_device_properties(pd),
            instance.get_physical_device_queue_family_properties(pd),
        )
    };
    let name = props.device_name_as_c_str().map(|c| c.to_string_lossy().into_owned()).unwrap_or_default();
    let kind = match props.device_type {
        vk::PhysicalDeviceType::DISCRETE_GPU => DeviceKind::Discrete,
        vk::PhysicalDeviceType::INTEGRATED_GPU => DeviceKind::Integrated,
        vk::PhysicalDeviceType::VIRTUAL_GPU => DeviceKind::Virtual,
        vk::PhysicalDeviceType::CPU => DeviceKind::Cpu,
        _ => DeviceKind::Other,
    };
    let (mut multiview, mut max_views) = (false, 0);
    if props.api_version >= vk::API_VERSION_1_1 {
        let mut mv = vk::PhysicalDeviceMultiviewFeatures::default();
        let mut mv_props = vk::PhysicalDeviceMultiviewProperties::default();
        // SAFETY: the instance is 1.1 and the device supports 1.1, so the *2 queries exist; the
        // chained structs live across the calls.
        unsafe {
            let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut mv);
            instance.get_physical_device_features2(pd, &mut features);
            let mut p2 = vk::PhysicalDeviceProperties2::default().push_next(&mut mv_props);
            instance.get_physical_device_properties2(pd, &mut p2);
        }
        multiview = mv.multiview == vk::TRUE;
        max_views = mv_props.max_multiview_view_count;
    }
    let graphics_queue_family =
        queues.iter().position(|q| q.queue_flags.contains(vk::QueueFlags::GRAPHICS)).map(|i| i as u32);
    let limits = props.limits;
    DeviceInfo {
        name,
        kind,
        api_version: props.api_version,
        multiview,
        max_multiview_views: max_views,
        graphics_queue_family,
        sample_counts: limits.framebuffer_color_sample_counts & limits.framebuffer_depth_sample_counts,
    }
}

/// Every physical device of `instance`, described.
pub(crate) fn enumerate(
    instance: &ash::Instance,
) -> Result<Vec<(vk::PhysicalDevice, DeviceInfo)>, RenderError> {
    // SAFETY: a plain query on a live instance.
    let pds = unsafe { instance.enumerate_physical_devices() }
        .map_err(RenderError::vk("vkEnumeratePhysicalDevices"))?;
    Ok(pds.into_iter().map(|pd| (pd, describe(instance, pd))).collect())
}

/// The logical device with its graphics queue and command pool.
///
/// Owns the device and the pool; `Drop` waits for the device to be idle, destroys the pool,
/// then the device. Every other Vulkan object holds an `Arc<Device>`, so they are gone first.
pub(crate) struct Device {
    pub(crate) raw: ash::Device,
    pub(crate) physical: vk::PhysicalDevice,
    pub(crate) info: DeviceInfo,
    pub(crate) queue: vk::Queue,
    pub(crate) pool: vk::CommandPool,
    pub(crate) memory: vk::PhysicalDeviceMemoryProperties,
    pub(crate) instance: Arc<Instance>,
}

impl std::fmt::Debug for Device {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Device").field("name", &self.info.name).finish_non_exhaustive()
    }
}

impl Device {
    /// Picks a device (see [`choose_device`]) and creates it with multiview enabled; with a
    /// `surface`, its graphics queue must present to it and the swapchain extension is on.
    pub(crate) fn new(instance: Arc<Instance>, surface: Option<&Surface>) -> Result<Arc<Self>, RenderError> {
        let raw_instance = instance.raw.clone();
        Self::create_with(instance, surface, None, |physical, create| {
            // SAFETY: `physical` belongs to the instance; `create` and what it points to
            // outlive the call.
            unsafe { raw_instance.create_device(physical, create, None) }
                .map(|d| d.handle())
                .map_err(RenderError::vk("vkCreateDevice"))
        })
    }

    /// As [`Device::new`], on `physical` when given (an OpenXR runtime names the device its
    /// headset is on), with the device made by `create_device` from Argile's create info (a
    /// runtime makes it through `xrCreateVulkanDeviceKHR`). The device belongs to this value
    /// all the same: `Drop` destroys it.
    pub(crate) fn create_with(
        instance: Arc<Instance>,
        surface: Option<&Surface>,
        physical: Option<vk::PhysicalDevice>,
        create_device: impl FnOnce(
            vk::PhysicalDevice,
            &vk::DeviceCreateInfo<'_>,
        ) -> Result<vk::Device, RenderError>,
    ) -> Result<Arc<Self>, RenderError> {
        let devices = enumerate(&instance.raw)?;
        let (physical, info, why) = match physical {
            Some(wanted) => {
                let Some((pd, info)) = devices.iter().find(|(pd, _)| *pd == wanted).cloned() else {
                    return Err(RenderError::NoDevice(
                        "the OpenXR runtime named a Vulkan device this instance does not list".into(),
                    ));
                };
                if let Some(why) = info.unusable_because() {
                    return Err(RenderError::NoDevice(format!(
                        "the headset's Vulkan device {} cannot run Argile: {why}",
                        info.name
                    )));
                }
                (pd, info, "the OpenXR runtime renders the headset on it".to_owned())
            }
            None => {
                let infos: Vec<DeviceInfo> = devices.iter().map(|(_, i)| i.clone()).collect();
                let wanted = std::env::var(DEVICE_VARIABLE).ok();
                let (index, why) = choose_device(&infos, wanted.as_deref()).map_err(RenderError::NoDevice)?;
                let (pd, info) = devices[index].clone();
                (pd, info, why)
            }
        };
        tracing::info!(
            "Vulkan device: {} ({}, Vulkan {}), chosen because {why}",
            info.name,
            info.kind,
            version_string(info.api_version)
        );
        let family = info.graphics_queue_family.expect("usable devices have a graphics queue");
        let priorities = [1.0f32];
        let queue_info =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
        let mut extensions = Vec::new();
        if let Some(surface) = surface {
            if !surface.supports(physical, family) {
                return Err(RenderError::Unsupported(format!(
                    "{} cannot present to this window (its graphics queue has no presentation \
                     support); pick another device with {DEVICE_VARIABLE} or run headless",
                    info.name
                )));
            }
            extensions.push(ash::khr::swapchain::NAME.as_ptr());
        }
        let mut multiview = vk::PhysicalDeviceMultiviewFeatures::default().multiview(true);
        let create = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_extension_names(&extensions)
            .push_next(&mut multiview);
        let handle = create_device(physical, &create)?;
        // SAFETY: `handle` is a live device just created on `physical` of this instance.
        let raw = unsafe { ash::Device::load(instance.raw.fp_v1_0(), handle) };
        // SAFETY: the queue family and index were requested above.
        let queue = unsafe { raw.get_device_queue(family, 0) };
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: a valid create info on a live device.
        let pool = match unsafe { raw.create_command_pool(&pool_info, None) } {
            Ok(p) => p,
            Err(e) => {
                // SAFETY: nothing else was created from the device.
                unsafe { raw.destroy_device(None) };
                return Err(RenderError::vk("vkCreateCommandPool")(e));
            }
        };
        // SAFETY: a plain query.
        let memory = unsafe { instance.raw.get_physical_device_memory_properties(physical) };
        Ok(Arc::new(Self { raw, physical, info, queue, pool, memory, instance }))
    }

    /// Index of a memory type allowed by `type_bits` with all of `required` (and, when one
    /// exists, all of `preferred` too).
    pub(crate) fn memory_type(
        &self,
        type_bits: u32,
        required: vk::MemoryPropertyFlags,
        preferred: vk::MemoryPropertyFlags,
    ) -> Result<u32, RenderError> {
        find_memory_type(&self.memory, type_bits, required | preferred)
            .or_else(|| find_memory_type(&self.memory, type_bits, required))
            .ok_or_else(|| {
                RenderError::Unsupported(format!("{} has no memory type with {required:?}", self.info.name))
            })
    }

    /// Allocates memory for `req` of a type with `required` (and `preferred` when possible);
    /// returns it with the chosen type's flags.
    pub(crate) fn allocate(
        &self,
        req: vk::MemoryRequirements,
        required: vk::MemoryPropertyFlags,
        preferred: vk::MemoryPropertyFlags,
    ) -> Result<(vk::DeviceMemory, vk::MemoryPropertyFlags), RenderError> {
        let type_index = self.memory_type(req.memory_type_bits, required, preferred)?;
        let alloc = vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(type_index);
        // SAFETY: the allocation info names a memory type of this device.
        let memory = unsafe { self.raw.allocate_memory(&alloc, None) }.map_err(|e| match e {
            vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
                RenderError::OutOfMemory { bytes: req.size, device: self.info.name.clone() }
            }
            e => RenderError::vk("vkAllocateMemory")(e),
        })?;
        Ok((memory, self.memory.memory_types[type_index as usize].property_flags))
    }

    /// A primary command buffer from the device's pool (freed with the pool).
    pub(crate) fn command_buffer(&self) -> Result<vk::CommandBuffer, RenderError> {
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(self.pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: the pool belongs to this device and is used from one thread only (the
        // renderer owns its device and is not Sync).
        let buffers = unsafe { self.raw.allocate_command_buffers(&alloc) }
            .map_err(RenderError::vk("vkAllocateCommandBuffers"))?;
        Ok(buffers[0])
    }

    /// Records commands with `record`, submits them and waits for them to finish.
    pub(crate) fn submit_and_wait(&self, record: impl FnOnce(vk::CommandBuffer)) -> Result<(), RenderError> {
        let cb = self.command_buffer()?;
        let result = (|| {
            let begin =
                vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            // SAFETY: a fresh command buffer in the initial state.
            unsafe { self.raw.begin_command_buffer(cb, &begin) }
                .map_err(RenderError::vk("vkBeginCommandBuffer"))?;
            record(cb);
            // SAFETY: recording was begun above.
            unsafe { self.raw.end_command_buffer(cb) }.map_err(RenderError::vk("vkEndCommandBuffer"))?;
            let fence = Fence::new(self)?;
            let cbs = [cb];
            let submit = [vk::SubmitInfo::default().command_buffers(&cbs)];
            // SAFETY: the command buffer is executable; the fence is unsignalled and unused.
            unsafe { self.raw.queue_submit(self.queue, &submit, fence.raw) }
                .map_err(RenderError::vk("vkQueueSubmit"))?;
            fence.wait()
        })();
        // SAFETY: the submission finished (or never started), so the buffer is not in use.
        unsafe { self.raw.free_command_buffers(self.pool, &[cb]) };
        result
    }
}

/// Index of a memory type allowed by `type_bits` that has all of `flags`.
pub(crate) fn find_memory_type(
    memory: &vk::PhysicalDeviceMemoryProperties,
    type_bits: u32,
    flags: vk::MemoryPropertyFlags,
) -> Option<u32> {
    memory.memory_types_as_slice().iter().enumerate().find_map(|(i, t)| {
        (type_bits & (1 << i) != 0 && t.property_flags.contains(flags)).then_some(i as u32)
    })
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: every object created from this device holds an Arc to it and is gone; the
        // device is idle after the wait, so the pool and the device can be destroyed.
        unsafe {
            let _ = self.raw.device_wait_idle();
            self.raw.destroy_command_pool(self.pool, None);
            self.raw.destroy_device(None);
        }
    }
}

/// A fence, destroyed on drop.
pub(crate) struct Fence<'d> {
    device: &'d Device,
    pub(crate) raw: vk::Fence,
}

impl<'d> Fence<'d> {
    /// An unsignalled fence.
    pub(crate) fn new(device: &'d Device) -> Result<Self, RenderError> {
        // SAFETY: a valid create info on a live device.
        let raw = unsafe { device.raw.create_fence(&vk::FenceCreateInfo::default(), None) }
            .map_err(RenderError::vk("vkCreateFence"))?;
        Ok(Self { device, raw })
    }

    /// Waits until the fence signals (a lost device is an error, not a hang).
    pub(crate) fn wait(&self) -> Result<(), RenderError> {
        // SAFETY: the fence belongs to this device.
        unsafe { self.device.raw.wait_for_fences(&[self.raw], true, u64::MAX) }
            .map_err(RenderError::vk("vkWaitForFences"))
    }
}

impl Drop for Fence<'_> {
    fn drop(&mut self) {
        // SAFETY: the fence is not in use: callers wait on it before it goes out of scope, and
        // a failed submission never used it.
        unsafe { self.device.raw.destroy_fence(self.raw, None) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn device(name: &str, kind: DeviceKind) -> DeviceInfo {
        DeviceInfo {
            name: name.into(),
            kind,
            api_version: vk::API_VERSION_1_3,
            multiview: true,
            max_multiview_views: 6,
            graphics_queue_family: Some(0),
            sample_counts: vk::SampleCountFlags::TYPE_1 | vk::SampleCountFlags::TYPE_4,
        }
    }

    #[test]
    fn discrete_beats_integrated_beats_software() {
        let devices = [
            device("llvmpipe", DeviceKind::Cpu),
            device("Intel UHD", DeviceKind::Integrated),
            device("NVIDIA H100", DeviceKind::Discrete),
        ];
        assert_eq!(choose_device(&devices, None).unwrap().0, 2);
        assert_eq!(choose_device(&devices[..2], None).unwrap().0, 1);
        assert_eq!(choose_device(&devices[..1], None).unwrap().0, 0);
    }

    #[test]
    fn unusable_devices_are_skipped_and_explained() {
        let mut old = device("old GPU", DeviceKind::Discrete);
        old.multiview = false;
        let devices = [old.clone(), device("llvmpipe", DeviceKind::Cpu)];
        assert_eq!(choose_device(&devices, None).unwrap().0, 1);
        let e = choose_device(&devices[..1], None).unwrap_err();
        assert!(e.contains("old GPU (no multiview"), "{e}");
        assert!(choose_device(&[], None).unwrap_err().contains("mesa-vulkan-drivers"));
    }

    #[test]
    fn the_override_picks_by_index_or_name() {
        let devices = [device("NVIDIA H100", DeviceKind::Discrete), device("llvmpipe", DeviceKind::Cpu)];
        assert_eq!(choose_device(&devices, Some("1")).unwrap().0, 1);
        assert_eq!(choose_device(&devices, Some("LLVM")).unwrap().0, 1);
        assert_eq!(choose_device(&devices, Some("")).unwrap().0, 0);
        let e = choose_device(&devices, Some("radeon")).unwrap_err();
        assert!(
            e.contains("ARGILE_DEVICE=radeon names no Vulkan device") && e.contains("[1] llvmpipe"),
            "{e}"
        );
        assert!(choose_device(&devices, Some("7")).is_err());
    }

    #[test]
    fn memory_types_honour_the_allowed_bits_and_flags() {
        let mut memory = vk::PhysicalDeviceMemoryProperties { memory_type_count: 3, ..Default::default() };
        memory.memory_types[0].property_flags = vk::MemoryPropertyFlags::DEVICE_LOCAL;
        memory.memory_types[1].property_flags =
            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
        memory.memory_types[2].property_flags = vk::MemoryPropertyFlags::HOST_VISIBLE
            | vk::MemoryPropertyFlags::HOST_COHERENT
            | vk::MemoryPropertyFlags::HOST_CACHED;
        let host = vk::MemoryPropertyFlags::HOST_VISIBLE;
        assert_eq!(find_memory_type(&memory, 0b111, host), Some(1));
        assert_eq!(find_memory_type(&memory, 0b101, host), Some(2));
        assert_eq!(find_memory_type(&memory, 0b001, host), None);
        assert_eq!(find_memory_type(&memory, 0b111, vk::MemoryPropertyFlags::HOST_CACHED), Some(2));
    }
}
