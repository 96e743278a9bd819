//! Headless device setup. Finds any adapter wgpu can use (a real GPU, or Mesa's llvmpipe through
//! Vulkan or GL); `WGPU_BACKEND=gl|vulkan` picks a backend.

use thiserror::Error;

/// Why no device could be created.
#[derive(Debug, Error)]
pub enum GpuError {
    /// No adapter at all (no GPU driver and no software rasterizer).
    #[error(
        "no GPU adapter available ({0}); install Mesa (e.g. mesa-vulkan-drivers or libegl-mesa0) or run on a machine with a GPU"
    )]
    NoAdapter(String),
    /// The adapter refused to create a device.
    #[error("the GPU adapter could not create a device: {0}")]
    Device(String),
}

/// A device and queue with a description of the adapter.
#[derive(Debug)]
pub struct GpuContext {
    /// The device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Adapter information (name, backend, device type).
    pub info: wgpu::AdapterInfo,
}

impl GpuContext {
    /// Create a headless device on the best adapter available.
    pub fn new_headless() -> Result<Self, GpuError> {
        pollster::block_on(Self::new_async())
    }

    async fn new_async() -> Result<Self, GpuError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: None,
                apply_limit_buckets: false,
            })
            .await
            .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        let info = adapter.get_info();
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("lodestone"),
                required_limits: adapter.limits(),
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::Device(e.to_string()))?;
        Ok(Self {
            device,
            queue,
            info,
        })
    }

    /// Whether the adapter is a software rasterizer (Mesa's llvmpipe or lavapipe, WARP, …).
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// "name (backend, device type)".
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.info.name, self.info.backend, self.info.device_type
        )
    }
}
