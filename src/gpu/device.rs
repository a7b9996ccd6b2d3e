//! The adapter and the device: which GPU the backends take ([`open_for`], with
//! `select.rs`'s assignment rules), opening it, and the checks every GPU job makes (buffer
//! limits, errors caught, dispatch shapes, shader constants).

use super::select::AdapterListing;
use crate::backend::Backend;
use crate::error::{DeviceErrorKind, Error, Result};

/// The graphics APIs hmdist runs on. (Not GL: wgpu's GL fallback has neither R32Float render
/// targets nor storage buffers everywhere.)
const BACKENDS: wgpu::Backends = wgpu::Backends::VULKAN
    .union(wgpu::Backends::METAL)
    .union(wgpu::Backends::DX12);

fn instance() -> wgpu::Instance {
    wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: BACKENDS,
        ..wgpu::InstanceDescriptor::new_without_display_handle_from_env()
    })
}

/// `instance`'s adapters, in the order `--gpu N` counts them, with their listings.
fn enumerate(instance: &wgpu::Instance) -> (Vec<wgpu::Adapter>, Vec<AdapterListing>) {
    let adapters = pollster::block_on(instance.enumerate_adapters(BACKENDS));
    let listed = adapters
        .iter()
        .enumerate()
        .map(|(i, a)| super::select::AdapterListing::of(i, &a.get_info()))
        .collect();
    (adapters, listed)
}

/// The adapter that `--gpu`, `HMDIST_GPU`, `CUDA_VISIBLE_DEVICES` or `SLURM_LOCALID` assign
/// (see `select.rs`), or `None` where none applies and wgpu chooses.
fn assigned(instance: &wgpu::Instance) -> Result<Option<wgpu::Adapter>> {
    let assignment = super::select::Assignment::from_process();
    if assignment.is_empty() {
        return Ok(None);
    }
    let (mut adapters, listed) = enumerate(instance);
    Ok(super::select::choose(&listed, &assignment)?.map(|i| adapters.swap_remove(i)))
}

/// The adapter the GPU backends open: the assigned one, else wgpu's high-performance choice.
fn pick(instance: &wgpu::Instance) -> Result<wgpu::Adapter> {
    match assigned(instance)? {
        Some(adapter) => Ok(adapter),
        None => wgpus_choice(instance),
    }
}

/// wgpu's high-performance adapter.
fn wgpus_choice(instance: &wgpu::Instance) -> Result<wgpu::Adapter> {
    pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: None,
        ..Default::default()
    }))
    .map_err(|e| {
        let message = format!("no Vulkan, Metal or DX12 adapter ({e})");
        Error::device(DeviceErrorKind::NoAdapter, message)
    })
}

/// Every Vulkan, Metal or DX12 adapter of this machine, in the order `--gpu N` counts them,
/// and the one the GPU backends take here: `hmdist gpu list`.
pub fn adapters() -> Result<(Vec<AdapterListing>, Option<AdapterListing>)> {
    let instance = instance();
    let (_, listed) = enumerate(&instance);
    let assignment = super::select::Assignment::from_process();
    let taken = if assignment.is_empty() {
        wgpus_choice(&instance).ok().and_then(|a| {
            let info = super::select::AdapterListing::of(0, &a.get_info());
            listed
                .iter()
                .find(|l| (&l.name, &l.pci_bus, &l.backend) == (&info.name, &info.pci_bus, &info.backend))
                .cloned()
        })
    } else {
        super::select::choose(&listed, &assignment)?.map(|i| listed[i].clone())
    };
    Ok((listed, taken))
}

/// Set to 1 to let `--backend gpu` (and `auto`) run on a software implementation (Mesa's
/// lavapipe), as `--backend gpu-software` does.
pub const SOFTWARE_GPU: &str = "HMDIST_GPU_SOFTWARE";

/// Whether [`SOFTWARE_GPU`] allows software adapters.
fn software_allowed() -> bool {
    std::env::var(SOFTWARE_GPU).is_ok_and(|v| !v.is_empty() && v != "0")
}

/// The GPU `backend` runs on, opened by `open(allow_software)`, or `None` for the CPU: the one
/// place the backend choice is made, for gather, H at points and the cube map.
/// - `cpu`: none.
/// - `gpu`: a hardware adapter ([`SOFTWARE_GPU`] allows software); any failure is the error.
/// - `gpu-software`: any adapter.
/// - `auto`: the CPU where there is no hardware adapter (or, with [`SOFTWARE_GPU`], no adapter
///   at all); where there is one, the GPU, and its failures (out of memory, a rejected
///   shader) are errors, not a quiet CPU render.
pub(crate) fn open_for<T>(backend: Backend, open: impl FnOnce(bool) -> Result<T>) -> Result<Option<T>> {
    choose(backend, software_allowed(), adapter_for_auto, open)
}

/// [`open_for`]'s rule, with the environment (`software`: [`SOFTWARE_GPU`] is set) and the
/// probe for `auto` (`adapter(software)`: is there an adapter it may use) given.
fn choose<T>(
    backend: Backend,
    software: bool,
    adapter: impl FnOnce(bool) -> bool,
    open: impl FnOnce(bool) -> Result<T>,
) -> Result<Option<T>> {
    match backend {
        Backend::Cpu => Ok(None),
        Backend::Gpu => open(software).map(Some),
        Backend::GpuSoftware => open(true).map(Some),
        Backend::Auto if adapter(software) => open(software).map(Some),
        Backend::Auto => Ok(None),
    }
}

/// Whether `--backend auto` runs on the GPU here.
pub(crate) fn auto_uses_gpu() -> bool {
    adapter_for_auto(software_allowed())
}

/// Whether `auto` runs on the GPU: there is a hardware adapter, or any where `software`.
/// Probed once per process for each.
fn adapter_for_auto(software: bool) -> bool {
    static PROBED: [std::sync::OnceLock<bool>; 2] = [std::sync::OnceLock::new(), std::sync::OnceLock::new()];
    *PROBED[software as usize]
        .get_or_init(|| Device::open("hmdist probe", software, wgpu::Features::empty()).is_ok())
}

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
        let adapter = pick(&instance())?;
        let info = adapter.get_info();
        if info.device_type == wgpu::DeviceType::Cpu && !allow_software {
            let message = format!(
                "the adapter, '{}', is a software implementation (hundreds of times slower than \
                 a GPU, and slower than the CPU backend): no hardware GPU was found or chosen \
                 (is its Vulkan driver visible?); --backend gpu-software (or {SOFTWARE_GPU}=1) \
                 runs on it anyway",
                info.name
            );
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

/// Refuses buffers (name, bytes) larger than `device` binds or allocates, before any is made:
/// an error naming the buffer, its size and the adapter's limit (wgpu would fail later, less
/// clearly, or the driver would).
pub(crate) fn check_buffers(device: &Device, what: &str, buffers: &[(&str, usize)]) -> Result<()> {
    check_buffers_within(&device.limits, &device.adapter_name, what, buffers)
}

/// [`check_buffers`] against `limits` of the adapter called `adapter_name`.
pub(crate) fn check_buffers_within(
    limits: &wgpu::Limits,
    adapter_name: &str,
    what: &str,
    buffers: &[(&str, usize)],
) -> Result<()> {
    let binding = limits.max_storage_buffer_binding_size;
    let buffer = limits.max_buffer_size;
    for &(name, bytes) in buffers {
        let limit = binding.min(buffer);
        if bytes as u64 > limit {
            let message = format!(
                "{what} needs a {:.1} MB '{name}' buffer; adapter '{}' allows at most {:.1} MB",
                bytes as f64 / 1e6,
                adapter_name,
                limit as f64 / 1e6
            );
            return Err(Error::device(DeviceErrorKind::Unsupported, message));
        }
    }
    Ok(())
}

/// Workgroups for `invocations` invocations of 64 as a 2D grid (`x · y`, x at most the
/// device limit): the shaders index `id.x + id.y · groups.x · 64`.
pub(crate) fn workgroups(invocations: u32, limit: u32) -> (u32, u32) {
    let groups = invocations.div_ceil(64).max(1);
    let x = groups.min(limit);
    (x, groups.div_ceil(x))
}

/// `source` (WGSL) with the value of each `const NAME: u32 = …;` line of `constants` replaced:
/// how the host puts its own layout constants into a shader. A constant the source lacks is a
/// bug of hmdist's (tests build every shader this way), so it panics.
pub(crate) fn inject_constants(source: &str, constants: &[(&str, String)]) -> String {
    let mut lines: Vec<String> = source.lines().map(String::from).collect();
    for (name, value) in constants {
        let declaration = format!("const {name}: u32 = ");
        let line = lines
            .iter_mut()
            .find(|l| l.starts_with(&declaration))
            .unwrap_or_else(|| panic!("the shader declares no `{declaration}…;` to replace"));
        *line = format!("{declaration}{value};");
    }
    lines.join("\n") + "\n"
}

/// The members (name, byte offset) and size of struct `name` in the WGSL `source`, as naga
/// lays them out: what a `#[repr(C)]` twin on the host must match.

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[should_panic(expected = "declares no `const MISSING: u32 = …;`")]
    fn a_constant_the_shader_lacks_is_caught() {
        inject_constants("const THERE: u32 = 1u;", &[("MISSING", "2u".into())]);
    }

    /// What `choose` did: opened with software allowed or not, or not at all, and its answer.
    fn chosen(
        backend: Backend,
        software: bool,
        adapter: bool,
        fails: bool,
    ) -> (Option<bool>, Result<Option<()>>) {
        let mut opened = None;
        let result = choose(
            backend,
            software,
            |_| adapter,
            |allow| {
                opened = Some(allow);
                if fails {
                    Err(Error::device(DeviceErrorKind::OutOfMemory, "out of memory"))
                } else {
                    Ok(())
                }
            },
        );
        (opened, result)
    }

    #[test]
    fn auto_reports_a_failing_gpu_and_only_gpu_software_takes_a_software_adapter() {
        // auto with an adapter whose work fails: the failure, not a quiet CPU render.
        let (opened, result) = chosen(Backend::Auto, false, true, true);
        assert_eq!(opened, Some(false));
        assert!(matches!(
            result,
            Err(Error::Device {
                kind: DeviceErrorKind::OutOfMemory,
                ..
            })
        ));
        // auto without one: the CPU, nothing opened.
        let (opened, result) = chosen(Backend::Auto, false, false, true);
        assert!(opened.is_none() && matches!(result, Ok(None)));
        // gpu asks for hardware unless HMDIST_GPU_SOFTWARE; gpu-software takes any adapter.
        assert_eq!(chosen(Backend::Gpu, false, true, false).0, Some(false));
        assert_eq!(chosen(Backend::Gpu, true, true, false).0, Some(true));
        assert_eq!(chosen(Backend::GpuSoftware, false, true, false).0, Some(true));
        assert_eq!(chosen(Backend::Auto, true, true, false).0, Some(true));
        assert!(chosen(Backend::Cpu, true, true, false).0.is_none());
    }
}
