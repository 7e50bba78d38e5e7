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
    #[error("the GPU adapter {adapter} is too small for loudscape: {reason}")]
    TooSmall { adapter: String, reason: String },
}

/// Storage buffers the busiest compute pass binds in its one stage: marching tetrahedra's
/// extraction (bindings 1-9 of shaders/surface/extraction.wgsl and its edge table,
/// render/surface/extraction.rs). Above WebGPU's guaranteed 8: wgpu offers 29 on Metal, 16 on
/// DX12 binding tiers 1-2 and more on tier 3, and Vulkan drivers (lavapipe included) more still;
/// docs/ARCHITECTURE.md has the review.
pub const STORAGE_BUFFERS_PER_STAGE: u32 = 10;

/// The limits the passes cannot do without, checked before any pipeline is built, so that a
/// GPU that lacks them is refused with one line instead of failing at the first pipeline. Buffer
/// sizes need no check: the passes split their data by [`storage_binding_limit`].
pub fn check_limits(limits: &wgpu::Limits) -> Result<(), String> {
    let storage = limits.max_storage_buffers_per_shader_stage;
    if storage < STORAGE_BUFFERS_PER_STAGE {
        return Err(format!(
            "it binds {storage} storage buffers per shader stage, the surface passes need \
             {STORAGE_BUFFERS_PER_STAGE}"
        ));
    }
    let invocations = limits.max_compute_invocations_per_workgroup;
    if invocations < 256 || limits.max_compute_workgroup_size_x < 256 {
        return Err(format!(
            "its compute workgroups hold {invocations} invocations, the passes use 256"
        ));
    }
    Ok(())
}

/// Optional features we use when the adapter has them; everything works without them
/// (timings fall back to wall time). On an adapter that is the CPU, also mappable vertex and
/// index buffers: there every buffer is host memory, and the CPU surface extraction writes its
/// mesh straight into the buffers it is drawn from (render/surface/cpu/; elsewhere it copies).
/// No optional texture feature either: the volume's density and gradient are an rgba16float
/// texture, filterable in every WebGPU implementation (render/volume_grids.rs).
pub fn wanted_features(adapter: &wgpu::Adapter) -> wgpu::Features {
    let mut optional =
        wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
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
        Self::new_headless_narrowed(|_, _| {})
    }

    /// As [`Self::new_headless`], on a device whose limits and features `narrow` lowers from
    /// those asked of the adapter (tests: a device no bigger than a smaller GPU offers, which
    /// wgpu then enforces).
    pub fn new_headless_narrowed(
        narrow: impl FnOnce(&mut wgpu::Limits, &mut wgpu::Features),
    ) -> Result<Self, ContextError> {
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
        let mut descriptor = device_descriptor(&adapter);
        narrow(
            &mut descriptor.required_limits,
            &mut descriptor.required_features,
        );
        check_limits(&descriptor.required_limits).map_err(|reason| ContextError::TooSmall {
            adapter: adapter.get_info().name,
            reason,
        })?;
        let (device, queue) =
            pollster::block_on(adapter.request_device(&descriptor)).map_err(|e| {
                ContextError::NoDevice {
                    adapter: adapter.get_info().name,
                    reason: e.to_string(),
                }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn webgpu_minimum_limits_are_refused_with_the_reason() {
        let reason = check_limits(&wgpu::Limits::default()).unwrap_err();
        assert!(reason.contains("8 storage buffers"), "{reason}");
        assert!(
            reason.contains(&STORAGE_BUFFERS_PER_STAGE.to_string()),
            "{reason}"
        );
        assert!(check_limits(&wgpu::Limits::downlevel_defaults()).is_err());
    }

    #[test]
    fn metal_and_dx12_limits_as_wgpu_reports_them_are_enough() {
        // wgpu-hal 30: Metal 31 buffer slots less 2 internal; DX12 tiers 1-2: 64 UAVs / 2 / 2;
        // both 1024 invocations per workgroup.
        for storage in [29, 16] {
            let limits = wgpu::Limits {
                max_storage_buffers_per_shader_stage: storage,
                max_compute_invocations_per_workgroup: 1024,
                max_compute_workgroup_size_x: 1024,
                ..wgpu::Limits::default()
            };
            assert_eq!(check_limits(&limits), Ok(()), "{storage} storage buffers");
        }
    }
}
