//! A window's Vulkan surface and its swapchain.
//!
//! [`Surface`] owns the `VkSurfaceKHR` (made from the window's raw handles with `ash-window`) and
//! holds the instance alive; [`Swapchain`] owns the swapchain, one view per image and, for
//! each image, the semaphore that its rendering signals and its presentation waits on (a
//! semaphore per image, not per frame: the presentation engine may hold an image's semaphore
//! until that image comes back). Both destroy their handles in `Drop`; the swapchain's images
//! belong to the swapchain and are never destroyed by us.

use std::sync::Arc;

use ash::vk;
use raw_window_handle::{RawDisplayHandle, RawWindowHandle};

use super::super::RenderError;
use super::device::Device;
use super::instance::Instance;

/// The instance extensions a window on this display needs (`VK_KHR_surface` and the
/// platform's).
pub(crate) fn surface_extensions(
    display: RawDisplayHandle,
) -> Result<Vec<*const std::ffi::c_char>, RenderError> {
    ash_window::enumerate_required_extensions(display).map(<[_]>::to_vec).map_err(|e| {
        RenderError::Unsupported(format!(
            "Vulkan cannot present to this kind of display ({e}); run headless (`argile render`) or \
             use an X11 or Wayland session"
        ))
    })
}

/// A window's surface.
pub(crate) struct Surface {
    pub(crate) raw: vk::SurfaceKHR,
    pub(crate) loader: ash::khr::surface::Instance,
    _instance: Arc<Instance>,
}

impl std::fmt::Debug for Surface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Surface").field("raw", &self.raw).finish_non_exhaustive()
    }
}

impl Surface {
    /// Creates the surface of the window behind `display` and `window`.
    ///
    /// # Safety
    /// The handles must be valid and the window must outlive the surface.
    pub(crate) unsafe fn new(
        instance: &Arc<Instance>,
        display: RawDisplayHandle,
        window: RawWindowHandle,
    ) -> Result<Self, RenderError> {
        // SAFETY: the caller vouches for the handles; the instance was created with the
        // extensions `surface_extensions` names for this display.
        let raw =
            unsafe { ash_window::create_surface(&instance.entry, &instance.raw, display, window, None) }
                .map_err(RenderError::vk("vkCreate*SurfaceKHR"))?;
        let loader = ash::khr::surface::Instance::new(&instance.entry, &instance.raw);
        Ok(Self { raw, loader, _instance: instance.clone() })
    }

    /// Whether queue family `family` of `physical` can present to this surface.
    pub(crate) fn supports(&self, physical: vk::PhysicalDevice, family: u32) -> bool {
        // SAFETY: a plain query on live handles of the same instance.
        unsafe { self.loader.get_physical_device_surface_support(physical, family, self.raw) }
            .unwrap_or(false)
    }
}

impl Drop for Surface {
    fn drop(&mut self) {
        // SAFETY: every swapchain of this surface holds an Arc to it, so none is left; the
        // instance is alive (held by `self.instance`).
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}

/// What a swapchain is made with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct SwapchainDesc {
    /// The window's size in pixels, used when the surface leaves the extent to us.
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// 2 for quad-buffer stereo (only when the surface offers it), else 1.
    pub(crate) layers: u32,
    /// Wait for the display's vertical blank (FIFO) rather than present at once.
    pub(crate) vsync: bool,
}

/// A swapchain, its image views and per-image semaphores.
pub(crate) struct Swapchain {
    pub(crate) raw: vk::SwapchainKHR,
    pub(crate) loader: ash::khr::swapchain::Device,
    pub(crate) images: Vec<vk::Image>,
    /// For each image, one 2D view per layer (the composition renders into each layer).
    pub(crate) layer_views: Vec<Vec<vk::ImageView>>,
    /// Signalled when image `i`'s rendering is done; presentation waits on it.
    pub(crate) rendered: Vec<vk::Semaphore>,
    pub(crate) format: vk::Format,
    pub(crate) extent: vk::Extent2D,
    pub(crate) layers: u32,
    /// Whether the images can be copied from (screenshots).
    pub(crate) readable: bool,
    _surface: Arc<Surface>,
    device: Arc<Device>,
}

impl std::fmt::Debug for Swapchain {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Swapchain")
            .field("images", &self.images.len())
            .field("format", &self.format)
            .field("extent", &self.extent)
            .field("layers", &self.layers)
            .finish_non_exhaustive()
    }
}

/// The surface format to use: 8-bit sRGB (the shaders write linear colour), BGRA or RGBA.
pub(crate) fn pick_format(formats: &[vk::SurfaceFormatKHR]) -> Option<vk::SurfaceFormatKHR> {
    let srgb = |f: &&vk::SurfaceFormatKHR| {
        matches!(f.format, vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB)
            && f.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR
    };
    formats.iter().find(srgb).copied()
}

/// The swapchain extent: the surface's own when it has one, else the window's size clamped to
/// what the surface allows.
pub(crate) fn pick_extent(caps: &vk::SurfaceCapabilitiesKHR, width: u32, height: u32) -> vk::Extent2D {
    if caps.current_extent.width != u32::MAX {
        return caps.current_extent;
    }
    vk::Extent2D {
        width: width.clamp(caps.min_image_extent.width, caps.max_image_extent.width.max(1)),
        height: height.clamp(caps.min_image_extent.height, caps.max_image_extent.height.max(1)),
    }
}

/// One image more than the minimum (so acquiring never waits on the display), within the
/// maximum (0 means none).
pub(crate) fn pick_image_count(caps: &vk::SurfaceCapabilitiesKHR) -> u32 {
    let wanted = caps.min_image_count + 1;
    if caps.max_image_count == 0 {
        wanted
    } else {
        wanted.min(caps.max_image_count)
    }
}

impl Swapchain {
    /// The surface's capabilities for the device.
    pub(crate) fn capabilities(
        device: &Device,
        surface: &Surface,
    ) -> Result<vk::SurfaceCapabilitiesKHR, RenderError> {
        // SAFETY: a plain query on live handles of the same instance.
        unsafe { surface.loader.get_physical_device_surface_capabilities(device.physical, surface.raw) }
            .map_err(RenderError::vk("vkGetPhysicalDeviceSurfaceCapabilitiesKHR"))
    }

    /// Creates a swapchain on `surface`, replacing `old` (which is then destroyed) when given.
    pub(crate) fn new(
        device: &Arc<Device>,
        surface: &Arc<Surface>,
        desc: SwapchainDesc,
        old: Option<Swapchain>,
    ) -> Result<Self, RenderError> {
        let physical = device.physical;
        let caps = Self::capabilities(device, surface)?;
        // SAFETY: plain queries on live handles of the same instance.
        let (formats, modes) = unsafe {
            (
                surface
                    .loader
                    .get_physical_device_surface_formats(physical, surface.raw)
                    .map_err(RenderError::vk("vkGetPhysicalDeviceSurfaceFormatsKHR"))?,
                surface
                    .loader
                    .get_physical_device_surface_present_modes(physical, surface.raw)
                    .map_err(RenderError::vk("vkGetPhysicalDeviceSurfacePresentModesKHR"))?,
            )
        };
        let format = pick_format(&formats).ok_or_else(|| {
            RenderError::Unsupported(format!(
                "the window surface of {} offers no 8-bit sRGB format (it offers {:?})",
                device.info.name,
                formats.iter().map(|f| f.format).collect::<Vec<_>>()
            ))
        })?;
        if desc.layers > caps.max_image_array_layers {
            return Err(RenderError::Unsupported(format!(
                "the window surface of {} offers {} image layer(s); quad-buffer stereo needs {}",
                device.info.name, caps.max_image_array_layers, desc.layers
            )));
        }
        let present_mode = if desc.vsync || !modes.contains(&vk::PresentModeKHR::MAILBOX) {
            vk::PresentModeKHR::FIFO
        } else {
            vk::PresentModeKHR::MAILBOX
        };
        let readable = caps.supported_usage_flags.contains(vk::ImageUsageFlags::TRANSFER_SRC);
        let mut usage = vk::ImageUsageFlags::COLOR_ATTACHMENT;
        if readable {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        let extent = pick_extent(&caps, desc.width, desc.height);
        let composite = if caps.supported_composite_alpha.contains(vk::CompositeAlphaFlagsKHR::OPAQUE) {
            vk::CompositeAlphaFlagsKHR::OPAQUE
        } else {
            vk::CompositeAlphaFlagsKHR::INHERIT
        };
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.raw)
            .min_image_count(pick_image_count(&caps))
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(desc.layers)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(composite)
            .present_mode(present_mode)
            .clipped(true)
            .old_swapchain(old.as_ref().map_or(vk::SwapchainKHR::null(), |o| o.raw));
        let loader = ash::khr::swapchain::Device::new(&device.instance.raw, &device.raw);
        // SAFETY: `info` is valid for this surface (format, extent, count and layers checked
        // against its capabilities); the old swapchain, if any, is retired by this call.
        let raw = unsafe { loader.create_swapchain(&info, None) }
            .map_err(RenderError::vk("vkCreateSwapchainKHR"))?;
        drop(old);
        let mut swapchain = Self {
            raw,
            loader,
            images: Vec::new(),
            layer_views: Vec::new(),
            rendered: Vec::new(),
            format: format.format,
            extent,
            layers: desc.layers,
            readable,
            _surface: surface.clone(),
            device: device.clone(),
        };
        // SAFETY: `raw` is live; the images belong to it.
        swapchain.images = unsafe { swapchain.loader.get_swapchain_images(raw) }
            .map_err(RenderError::vk("vkGetSwapchainImagesKHR"))?;
        for &image in &swapchain.images {
            swapchain.layer_views.push(Vec::new());
            for layer in 0..desc.layers {
                let view_info = vk::ImageViewCreateInfo::default()
                    .image(image)
                    .view_type(vk::ImageViewType::TYPE_2D)
                    .format(format.format)
                    .subresource_range(color_range(1).base_array_layer(layer));
                // SAFETY: a view of a live swapchain image with its own format; destroyed in
                // Drop (pushed before the next fallible call, so a failure still frees it).
                let view = unsafe { device.raw.create_image_view(&view_info, None) }
                    .map_err(RenderError::vk("vkCreateImageView"))?;
                swapchain.layer_views.last_mut().expect("pushed above").push(view);
            }
            // SAFETY: a plain create on a live device; destroyed in Drop.
            let semaphore = unsafe { device.raw.create_semaphore(&vk::SemaphoreCreateInfo::default(), None) }
                .map_err(RenderError::vk("vkCreateSemaphore"))?;
            swapchain.rendered.push(semaphore);
        }
        Ok(swapchain)
    }

    /// Acquires the next image; `Ok(None)` when the swapchain no longer fits the surface and
    /// must be recreated. `acquired` is signalled when the image may be written.
    pub(crate) fn acquire(&self, acquired: vk::Semaphore) -> Result<Option<(u32, bool)>, RenderError> {
        // SAFETY: `acquired` is unsignalled with no pending wait (one frame in flight).
        match unsafe { self.loader.acquire_next_image(self.raw, u64::MAX, acquired, vk::Fence::null()) } {
            Ok((index, suboptimal)) => Ok(Some((index, suboptimal))),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(None),
            Err(e) => Err(RenderError::vk("vkAcquireNextImageKHR")(e)),
        }
    }

    /// Presents image `index` once its rendering is done; `Ok(false)` when the swapchain must
    /// be recreated.
    pub(crate) fn present(&self, index: u32) -> Result<bool, RenderError> {
        let waits = [self.rendered[index as usize]];
        let swapchains = [self.raw];
        let indices = [index];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(&swapchains)
            .image_indices(&indices);
        // SAFETY: `index` was acquired from this swapchain and its semaphore is signalled by the
        // submission that rendered it.
        match unsafe { self.loader.queue_present(self.device.queue, &info) } {
            Ok(false) => Ok(true),
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(false),
            Err(e) => Err(RenderError::vk("vkQueuePresentKHR")(e)),
        }
    }
}

/// Every colour layer of a single-level image.
pub(crate) fn color_range(layers: u32) -> vk::ImageSubresourceRange {
    vk::ImageSubresourceRange::default()
        .aspect_mask(vk::ImageAspectFlags::COLOR)
        .base_mip_level(0)
        .level_count(1)
        .base_array_layer(0)
        .layer_count(layers)
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        // SAFETY: the device is idle (nothing of ours may still use the views, semaphores or
        // images); the images belong to the swapchain and go with it.
        unsafe {
            let _ = self.device.raw.device_wait_idle();
            for &s in &self.rendered {
                self.device.raw.destroy_semaphore(s, None);
            }
            for &v in self.layer_views.iter().flatten() {
                self.device.raw.destroy_image_view(v, None);
            }
            self.loader.destroy_swapchain(self.raw, None);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn caps(current: (u32, u32), min_count: u32, max_count: u32) -> vk::SurfaceCapabilitiesKHR {
        vk::SurfaceCapabilitiesKHR {
            min_image_count: min_count,
            max_image_count: max_count,
            current_extent: vk::Extent2D { width: current.0, height: current.1 },
            min_image_extent: vk::Extent2D { width: 1, height: 1 },
            max_image_extent: vk::Extent2D { width: 4096, height: 2048 },
            max_image_array_layers: 1,
            ..Default::default()
        }
    }

    #[test]
    fn the_surface_extent_wins_unless_it_leaves_the_choice_to_us() {
        assert_eq!(pick_extent(&caps((800, 600), 2, 3), 10, 10), vk::Extent2D { width: 800, height: 600 });
        let free = caps((u32::MAX, u32::MAX), 2, 3);
        assert_eq!(pick_extent(&free, 1280, 720), vk::Extent2D { width: 1280, height: 720 });
        assert_eq!(pick_extent(&free, 9000, 0), vk::Extent2D { width: 4096, height: 1 });
    }

    #[test]
    fn one_image_more_than_the_minimum_within_the_maximum() {
        assert_eq!(pick_image_count(&caps((1, 1), 2, 0)), 3);
        assert_eq!(pick_image_count(&caps((1, 1), 2, 8)), 3);
        assert_eq!(pick_image_count(&caps((1, 1), 3, 3)), 3);
    }

    #[test]
    fn only_srgb_eight_bit_formats_are_taken() {
        let f = |format| vk::SurfaceFormatKHR { format, color_space: vk::ColorSpaceKHR::SRGB_NONLINEAR };
        assert_eq!(pick_format(&[f(vk::Format::B8G8R8A8_UNORM)]), None);
        assert_eq!(
            pick_format(&[f(vk::Format::B8G8R8A8_UNORM), f(vk::Format::B8G8R8A8_SRGB)]),
            Some(f(vk::Format::B8G8R8A8_SRGB))
        );
    }
}
