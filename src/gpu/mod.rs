//! Ray casting on the GPU: the scene's wide BVH traversed by a wgpu compute shader
//! (`traverse.wgsl`), for `gather --backend gpu` and H at points; and the adapter choice that
//! the cube map's rasteriser shares.
//!
//! A software traversal, not hardware ray queries: wgpu's ray queries need
//! `VK_KHR_ray_query`, which datacenter GPUs without RT cores (the H100) and Debian 12's
//! lavapipe lack; a compute shader runs everywhere Vulkan, Metal or DX12 does.
//!
//! **What matches the CPU.** The random numbers, strata and the order of every sum are the
//! CPU's, and each point's rays are summed in ray order by one invocation, so an image is the
//! same on every run and however the work is split into dispatches. Hit distances agree with
//! the CPU's to within a few ulps (the GPU may fuse multiply-adds, and its sin, cos and
//! division are not correctly rounded), so images agree to f_diff of about 1e-6, not bit for
//! bit. The traversal keeps the CPU's watertightness by evaluating each shared edge with its
//! vertices in a fixed order (see `traverse.wgsl`): no ray escapes a closed room.

pub(crate) mod gather;
mod scene;

pub use scene::{DispatchSplit, GpuRay, GpuScene};

use crate::error::{DeviceErrorKind, Error, Result};

/// A wgpu device and what it is called.
pub(crate) struct Device {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// The adapter's name and backend, for the report.
    pub adapter_name: String,
    pub limits: wgpu::Limits,
    /// A software implementation (Mesa's lavapipe), with its limits.
    pub software: bool,
}

impl Device {
    /// The first Vulkan, Metal or DX12 adapter with `features`. (Not GL: wgpu's GL fallback
    /// has neither R32Float render targets nor storage buffers everywhere.) A software
    /// implementation (Mesa's lavapipe) is taken only when `allow_software`.
    pub fn open(label: &str, allow_software: bool, features: wgpu::Features) -> Result<Device> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::VULKAN | wgpu::Backends::METAL | wgpu::Backends::DX12,
            ..wgpu::InstanceDescriptor::new_without_display_handle_from_env()
        });
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            ..Default::default()
        }))
        .map_err(|e| {
            let message = format!("no Vulkan, Metal or DX12 adapter ({e})");
            Error::device(DeviceErrorKind::NoAdapter, message)
        })?;
        let info = adapter.get_info();
        if info.device_type == wgpu::DeviceType::Cpu && !allow_software {
            let message = format!("adapter '{}' is a software implementation", info.name);
            return Err(Error::device(DeviceErrorKind::NoAdapter, message));
        }
        if !adapter.features().contains(features) {
            let message = format!(
                "adapter '{}' lacks {:?}",
                info.name,
                features - adapter.features()
            );
            return Err(Error::device(DeviceErrorKind::Unsupported, message));
        }
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some(label),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| {
            let message = format!("adapter '{}' refused a device: {e}", info.name);
            Error::device(DeviceErrorKind::Failed, message)
        })?;
        Ok(Device {
            device,
            queue,
            adapter_name: format!("{} ({:?})", info.name, info.backend),
            limits,
            software: info.device_type == wgpu::DeviceType::Cpu,
        })
    }

    /// Runs `work`, catching the device's errors: see [`checked`].
    pub fn checked<T>(&self, what: &str, work: impl FnOnce() -> Result<T>) -> Result<T> {
        checked(&self.device, what, work)
    }

    /// Copies `buffer` (made with COPY_SRC) back to the host.
    pub fn read_back(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        let readback = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: buffer.size(),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &readback, 0, buffer.size());
        self.queue.submit([encoder.finish()]);
        let slice = readback.slice(..);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
        let bytes = match slice.get_mapped_range() {
            Ok(view) => view.to_vec(),
            Err(e) => {
                let message = format!("cannot read the results back: {e}");
                return Err(Error::device(DeviceErrorKind::Readback, message));
            }
        };
        readback.unmap();
        Ok(bytes)
    }

    /// A storage buffer holding `contents`.
    pub fn storage(&self, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        // wgpu refuses zero-sized bindings.
        let padded;
        let contents = if contents.is_empty() {
            padded = [0u8; 16];
            &padded[..]
        } else {
            contents
        };
        self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::STORAGE | usage,
        })
    }

    /// Waits until the queue has finished everything submitted.
    pub fn wait(&self) {
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
    }
}

/// Runs `work`, turning `device`'s out-of-memory and validation errors into ours (wgpu would
/// otherwise panic on them); `what` names the pipeline in the message.
pub(crate) fn checked<T>(device: &wgpu::Device, what: &str, work: impl FnOnce() -> Result<T>) -> Result<T> {
    let out_of_memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let result = work();
    for (scope, kind) in [
        (validation, DeviceErrorKind::Failed),
        (out_of_memory, DeviceErrorKind::OutOfMemory),
    ] {
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(Error::device(kind, format!("{what} failed: {e}")));
        }
    }
    result
}

/// Workgroups for `invocations` invocations of 64 as a 2D grid (`x · y`, x at most the
/// device limit): the shaders index `id.x + id.y · groups.x · 64`.
pub(crate) fn workgroups(invocations: u32, limit: u32) -> (u32, u32) {
    let groups = invocations.div_ceil(64).max(1);
    let x = groups.min(limit);
    (x, groups.div_ceil(x))
}

/// Whether this machine has a hardware (not software) Vulkan, Metal or DX12 adapter: what
/// `--backend auto` asks. Probed once per process.
pub(crate) fn hardware_adapter() -> bool {
    static PROBED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *PROBED.get_or_init(|| Device::open("hmdist probe", false, wgpu::Features::empty()).is_ok())
}
