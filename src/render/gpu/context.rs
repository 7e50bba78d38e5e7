//! The GPU device: one adapter, one device and queue, shared by the window and the headless
//! renderer so both run exactly the same passes under the same features and limits.

use thiserror::Error;

/// What went wrong while finding a GPU.
#[derive(Debug, Error)]
pub enum ContextError {
    #[error(
        "no GPU adapter found ({0}); install Vulkan drivers, or Mesa's software Vulkan \
         (Debian: apt-get install mesa-vulkan-drivers)"
    )]
    NoAdapter(String),
    #[error("the GPU adapter {adapter} refused a device: {reason}")]
    NoDevice { adapter: String, reason: String },
}

/// Optional features we use when the adapter has them; everything works without them. On an
/// adapter that is the CPU, also mappable vertex and index buffers: there every buffer is host
/// memory, and the CPU surface extraction writes its mesh straight into the buffers it is drawn
/// from (render/surface/cpu/).
pub fn wanted_features(adapter: &wgpu::Adapter) -> wgpu::Features {
    let mut optional = wgpu::Features::TIMESTAMP_QUERY
        | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
        | wgpu::Features::FLOAT32_FILTERABLE;
    if adapter.get_info().device_type == wgpu::DeviceType::Cpu {
        optional |= wgpu::Features::MAPPABLE_PRIMARY_BUFFERS;
    }
    adapter.features() & optional
}

/// Limits we ask for: the adapter's own, so large clouds and grids fit where the hardware allows.
pub fn wanted_limits(adapter: &wgpu::Adapter) -> wgpu::Limits {
    adapter.limits()
}

/// The device descriptor used by both the window (through eframe) and the headless renderer.
pub fn device_descriptor(adapter: &wgpu::Adapter) -> wgpu::DeviceDescriptor<'static> {
    wgpu::DeviceDescriptor {
        label: Some("loudscape::device"),
        required_features: wanted_features(adapter),
        required_limits: wanted_limits(adapter),
        ..Default::default()
    }
}

/// A device for rendering without a window.
pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
}

impl GpuContext {
    /// Finds an adapter (a real GPU when there is one, otherwise a software one such as lavapipe)
    /// and opens a device on it.
    pub fn new_headless() -> Result<Self, ContextError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY);
        let instance = wgpu::Instance::new(desc);
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            ..Default::default()
        };
        let adapter = pollster::block_on(instance.request_adapter(&options))
            .map_err(|e| ContextError::NoAdapter(e.to_string()))?;
        let (device, queue) = pollster::block_on(
            adapter.request_device(&device_descriptor(&adapter)),
        )
        .map_err(|e| ContextError::NoDevice {
            adapter: adapter.get_info().name,
            reason: e.to_string(),
        })?;
        Ok(Self {
            adapter,
            device,
            queue,
        })
    }

    /// One line naming the adapter and backend, for logs and benchmarks.
    pub fn describe(&self) -> String {
        describe_adapter(&self.adapter)
    }
}

/// "llvmpipe (LLVM 15.0.6, 256 bits) on Vulkan (Cpu)".
/// The largest buffer, in bytes, that this device can both create and bind for storage: the
/// size limit of every storage buffer the passes allocate or split their data by.
pub fn storage_binding_limit(device: &wgpu::Device) -> u64 {
    let limits = device.limits();
    limits
        .max_storage_buffer_binding_size
        .min(limits.max_buffer_size)
}

pub fn describe_adapter(adapter: &wgpu::Adapter) -> String {
    let info = adapter.get_info();
    format!(
        "{} on {:?} ({:?})",
        info.name, info.backend, info.device_type
    )
}
