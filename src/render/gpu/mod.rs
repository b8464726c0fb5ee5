//! The Vulkan layer under the renderer: one file per kind of object, each object owning its
//! handles and destroying them in `Drop` (children hold an `Arc<Device>`, the device an
//! `Arc<Instance>`, so destruction runs in reverse order of creation).

pub(crate) mod buffer;
pub(crate) mod device;
pub(crate) mod image;
pub(crate) mod instance;
pub(crate) mod pipeline;
pub(crate) mod swapchain;

pub use device::{choose_device, DeviceInfo, DeviceKind, DEVICE_VARIABLE};
pub use instance::ValidationLog;
