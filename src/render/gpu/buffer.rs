//! Buffers with their own memory, persistently mapped when host-visible.

use std::sync::Arc;

use ash::vk;

use super::super::RenderError;
use super::device::Device;

/// A buffer and its memory. `Drop` destroys the buffer, then frees the memory.
pub(crate) struct Buffer {
    pub(crate) raw: vk::Buffer,
    memory: vk::DeviceMemory,
    /// Start of the mapping (host-visible buffers only).
    mapped: Option<std::ptr::NonNull<u8>>,
    /// Size in bytes.
    pub(crate) size: vk::DeviceSize,
    /// Whether the mapping needs explicit invalidation before the host reads it.
    coherent: bool,
    device: Arc<Device>,
}

impl std::fmt::Debug for Buffer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Buffer").field("size", &self.size).finish_non_exhaustive()
    }
}

/// Where a buffer's memory lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MemoryUse {
    /// Written by the host, read by the GPU (uploads, uniforms, the chunk arena).
    Upload,
    /// Written by the GPU, read by the host (readback): cached when possible.
    Readback,
}

impl Buffer {
    /// A host-visible, mapped buffer of `size` bytes.
    pub(crate) fn new(
        device: &Arc<Device>,
        size: vk::DeviceSize,
        usage: vk::BufferUsageFlags,
        memory_use: MemoryUse,
    ) -> Result<Self, RenderError> {
        let size = size.max(4);
        let info =
            vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        let d = &device.raw;
        // SAFETY: a valid create info on a live device.
        let raw = unsafe { d.create_buffer(&info, None) }.map_err(RenderError::vk("vkCreateBuffer"))?;
        // Destroys the buffer if a later step fails.
        let guard = scopeguard::guard(raw, |raw| {
            // SAFETY: the buffer is not bound or used yet.
            unsafe { d.destroy_buffer(raw, None) }
        });
        // SAFETY: `raw` is a live buffer of this device.
        let req = unsafe { d.get_buffer_memory_requirements(raw) };
        let required = vk::MemoryPropertyFlags::HOST_VISIBLE;
        let preferred = match memory_use {
            MemoryUse::Upload => vk::MemoryPropertyFlags::HOST_COHERENT,
            MemoryUse::Readback => vk::MemoryPropertyFlags::HOST_CACHED,
        };
        let (memory, flags) = device.allocate(req, required, preferred)?;
        // SAFETY: the memory was allocated for this buffer's requirements; mapping the whole
        // of a host-visible allocation once is allowed.
        let mapped = unsafe {
            d.bind_buffer_memory(raw, memory, 0)
                .and_then(|()| d.map_memory(memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty()))
        };
        let mapped = match mapped {
            Ok(p) => p,
            Err(e) => {
                // SAFETY: the memory is not mapped and its buffer is destroyed by the guard.
                unsafe { d.free_memory(memory, None) };
                return Err(RenderError::vk("vkMapMemory")(e));
            }
        };
        let raw = scopeguard::ScopeGuard::into_inner(guard);
        Ok(Self {
            raw,
            memory,
            mapped: std::ptr::NonNull::new(mapped.cast()),
            size,
            coherent: flags.contains(vk::MemoryPropertyFlags::HOST_COHERENT),
            device: device.clone(),
        })
    }

    /// The mapped bytes.
    pub(crate) fn bytes_mut(&mut self) -> &mut [u8] {
        let ptr = self.mapped.expect("buffers are created mapped");
        // SAFETY: the mapping covers `size` bytes for the buffer's whole life; `&mut self`
        // makes this the only view of it, and the GPU is not using the buffer while the host
        // writes (each frame is waited for before the next host update).
        unsafe { std::slice::from_raw_parts_mut(ptr.as_ptr(), self.size as usize) }
    }

    /// Writes `data` at byte `offset`.
    pub(crate) fn write<T: bytemuck::Pod>(&mut self, offset: usize, data: &[T]) {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        self.bytes_mut()[offset..offset + bytes.len()].copy_from_slice(bytes);
        // Host-coherent upload memory needs no flush; non-coherent memory is flushed here.
        if !self.coherent {
            self.flush_or_invalidate(false);
        }
    }

    /// The mapped bytes, after making the GPU's writes visible to the host.
    pub(crate) fn read(&mut self) -> &[u8] {
        if !self.coherent {
            self.flush_or_invalidate(true);
        }
        self.bytes_mut()
    }

    fn flush_or_invalidate(&self, invalidate: bool) {
        // The whole mapping: WHOLE_SIZE needs no rounding to the non-coherent atom size.
        let range = [vk::MappedMemoryRange::default().memory(self.memory).offset(0).size(vk::WHOLE_SIZE)];
        // SAFETY: the range is this buffer's own memory, mapped whole.
        let result = unsafe {
            if invalidate {
                self.device.raw.invalidate_mapped_memory_ranges(&range)
            } else {
                self.device.raw.flush_mapped_memory_ranges(&range)
            }
        };
        if let Err(e) = result {
            tracing::error!("cannot flush or invalidate mapped memory: {e}");
        }
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: the renderer waits for each frame before releasing or replacing buffers, so
        // the GPU no longer uses this one; unmapping happens implicitly when freeing.
        unsafe {
            self.device.raw.destroy_buffer(self.raw, None);
            self.device.raw.free_memory(self.memory, None);
        }
    }
}
