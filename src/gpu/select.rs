//! Which adapter a GPU backend opens, on a machine with several (issue #24, item 3).
//!
//! Vulkan ignores `CUDA_VISIBLE_DEVICES`: left to itself, every task of a Slurm array on a
//! multi-GPU node would open the same adapter. In this order, the first that applies:
//! 1. `--gpu SEL` (the CLI) or `HMDIST_GPU=SEL`: an index of `hmdist gpu list`, or a
//!    case-insensitive part of an adapter's name or PCI bus id (`H200`, `0000:19:00.0`).
//! 2. `CUDA_VISIBLE_DEVICES` (set by Slurm's `--gres=gpu:N` and by container runtimes): its
//!    first entry, a CUDA index or a `GPU-…` UUID, mapped to a PCI bus id by `nvidia-smi` and so
//!    to the Vulkan adapter on that bus; without `nvidia-smi`, a CUDA index counts NVIDIA's
//!    hardware adapters in PCI bus order (CUDA's order under `CUDA_DEVICE_ORDER=PCI_BUS_ID`).
//! 3. `SLURM_LOCALID`, where several hardware adapters are visible: the tasks of one node
//!    take them in turn, in PCI bus order.
//! 4. Otherwise wgpu's choice (a high-performance adapter).

use std::sync::OnceLock;

use crate::error::{DeviceErrorKind, Error, Result};

/// The environment variable that names the adapter (as `--gpu` does).
pub const SELECT_GPU: &str = "HMDIST_GPU";

/// One adapter, as `hmdist gpu list` prints it.
#[derive(Clone, Debug, PartialEq)]
pub struct AdapterListing {
    /// Its index in the list (what `--gpu N` names).
    pub index: usize,
    /// The adapter's name, as its driver gives it.
    pub name: String,
    /// `discrete`, `integrated`, `virtual`, `cpu` (software) or `other`.
    pub kind: &'static str,
    /// Vulkan, Metal or DX12.
    pub backend: String,
    /// PCI vendor id (0x10de NVIDIA, 0x1002 AMD, 0x8086 Intel).
    pub vendor: u32,
    /// `domain:bus:device.function` where the driver says (Vulkan's PCI bus info), else empty.
    pub pci_bus: String,
    /// Driver name and version.
    pub driver: String,
}

impl AdapterListing {
    /// Whether it is a software implementation (Mesa's lavapipe).
    pub fn software(&self) -> bool {
        self.kind == "cpu"
    }

    pub(crate) fn of(index: usize, info: &wgpu::AdapterInfo) -> AdapterListing {
        AdapterListing {
            index,
            name: info.name.clone(),
            kind: match info.device_type {
                wgpu::DeviceType::DiscreteGpu => "discrete",
                wgpu::DeviceType::IntegratedGpu => "integrated",
                wgpu::DeviceType::VirtualGpu => "virtual",
                wgpu::DeviceType::Cpu => "cpu",
                wgpu::DeviceType::Other => "other",
            },
            backend: format!("{:?}", info.backend),
            vendor: info.vendor,
            pci_bus: info.device_pci_bus_id.clone(),
            driver: format!("{} {}", info.driver, info.driver_info).trim().to_string(),
        }
    }
}

static CHOSEN_BY_FLAG: OnceLock<String> = OnceLock::new();

/// Names the adapter for the rest of the process, as `HMDIST_GPU` would (the CLI's `--gpu`).
/// The first call wins.
pub fn select_adapter(selector: &str) {
    let _ = CHOSEN_BY_FLAG.set(selector.to_string());
}

/// What decides the adapter, read from the process's environment.
#[derive(Clone, Debug, Default)]
pub(crate) struct Assignment {
    /// `--gpu` or `HMDIST_GPU`, with which one it was.
    pub explicit: Option<(&'static str, String)>,
    pub cuda_visible: Option<String>,
    pub slurm_local_id: Option<usize>,
    /// `nvidia-smi`'s (index, UUID, PCI bus id) rows, where it runs.
    pub nvidia: Option<Vec<(String, String, String)>>,
}

impl Assignment {
    /// Nothing assigns an adapter: wgpu chooses.
    pub fn is_empty(&self) -> bool {
        self.explicit.is_none() && self.cuda_visible.is_none() && self.slurm_local_id.is_none()
    }

    /// The process's own: flag, variables and, only where `CUDA_VISIBLE_DEVICES` must be
    /// mapped, `nvidia-smi`.
    pub fn from_process() -> Assignment {
        let var = |name: &str| std::env::var(name).ok().filter(|v| !v.trim().is_empty());
        let explicit = match CHOSEN_BY_FLAG.get() {
            Some(flag) => Some(("--gpu", flag.clone())),
            None => var(SELECT_GPU).map(|v| (SELECT_GPU, v)),
        };
        let cuda_visible = var("CUDA_VISIBLE_DEVICES");
        let nvidia = match (&explicit, &cuda_visible) {
            (None, Some(_)) => nvidia_smi(),
            _ => None,
        };
        Assignment {
            explicit,
            cuda_visible,
            slurm_local_id: var("SLURM_LOCALID").and_then(|v| v.trim().parse().ok()),
            nvidia,
        }
    }
}

/// `nvidia-smi`'s GPUs as (index, UUID, PCI bus id), where it runs.
fn nvidia_smi() -> Option<Vec<(String, String, String)>> {
    let out = std::process::Command::new("nvidia-smi")
        .args(["--query-gpu=index,uuid,pci.bus_id", "--format=csv,noheader"])
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let rows = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|line| {
            let mut fields = line.split(',').map(|f| f.trim().to_string());
            Some((fields.next()?, fields.next()?, fields.next()?))
        })
        .collect();
    Some(rows)
}

/// A PCI bus id as (domain, rest): `00000000:19:00.0` (nvidia-smi) and `0000:19:00.0`
/// (Vulkan) are the same bus.
fn pci_key(id: &str) -> Option<(u32, String)> {
    let (domain, rest) = id.trim().split_once(':')?;
    Some((u32::from_str_radix(domain, 16).ok()?, rest.to_ascii_lowercase()))
}

/// Hardware adapters of `vendor` (any, for `None`), in PCI bus order.
fn hardware_in_bus_order(adapters: &[AdapterListing], vendor: Option<u32>) -> Vec<&AdapterListing> {
    let mut hardware: Vec<&AdapterListing> = adapters
        .iter()
        .filter(|a| !a.software() && vendor.is_none_or(|v| a.vendor == v))
        .collect();
    hardware.sort_by_key(|a| (pci_key(&a.pci_bus), a.index));
    hardware
}

fn no_such(what: String, adapters: &[AdapterListing]) -> Error {
    let listed: Vec<String> = adapters
        .iter()
        .map(|a| format!("{}: {} ({}, {})", a.index, a.name, a.kind, a.backend))
        .collect();
    let there = if listed.is_empty() {
        "none".to_string()
    } else {
        listed.join("; ")
    };
    Error::device(
        DeviceErrorKind::NoAdapter,
        format!("{what}; the adapters here (hmdist gpu list): {there}"),
    )
}

/// The adapter `assignment` picks among `adapters` (see the module docs): its index, or
/// `None` to let wgpu choose.
pub(crate) fn choose(adapters: &[AdapterListing], assignment: &Assignment) -> Result<Option<usize>> {
    if let Some((source, selector)) = &assignment.explicit {
        let selector = selector.trim();
        if let Ok(index) = selector.parse::<usize>() {
            return match adapters.get(index) {
                Some(a) => Ok(Some(a.index)),
                None => Err(no_such(format!("{source} {selector} names no adapter"), adapters)),
            };
        }
        let wanted = selector.to_lowercase();
        return adapters
            .iter()
            .find(|a| a.name.to_lowercase().contains(&wanted) || a.pci_bus.to_lowercase().contains(&wanted))
            .map(|a| Some(a.index))
            .ok_or_else(|| {
                no_such(
                    format!("{source} {selector:?} matches no adapter's name or PCI bus"),
                    adapters,
                )
            });
    }
    if let Some(visible) = &assignment.cuda_visible {
        let first = visible.split(',').next().unwrap_or("").trim();
        const NVIDIA: u32 = 0x10de;
        let nvidia = hardware_in_bus_order(adapters, Some(NVIDIA));
        if let Some(rows) = &assignment.nvidia {
            let bus = rows
                .iter()
                .find(|(index, uuid, _)| index == first || (!first.is_empty() && uuid.starts_with(first)))
                .and_then(|(_, _, bus)| pci_key(bus));
            if let Some(bus) = bus {
                return match nvidia.iter().find(|a| pci_key(&a.pci_bus).as_ref() == Some(&bus)) {
                    Some(a) => Ok(Some(a.index)),
                    None => Err(no_such(
                        format!("CUDA_VISIBLE_DEVICES={visible}: no Vulkan adapter is on the PCI bus nvidia-smi gives for {first}"),
                        adapters,
                    )),
                };
            }
        }
        if let Ok(index) = first.parse::<usize>() {
            if nvidia.len() > 1 || (nvidia.len() == 1 && index == 0) {
                return match nvidia.get(index) {
                    Some(a) => Ok(Some(a.index)),
                    None => Err(no_such(
                        format!("CUDA_VISIBLE_DEVICES={visible}: there is no NVIDIA adapter {index}"),
                        adapters,
                    )),
                };
            }
        }
    }
    if let Some(local) = assignment.slurm_local_id {
        let hardware = hardware_in_bus_order(adapters, None);
        if hardware.len() > 1 {
            return Ok(Some(hardware[local % hardware.len()].index));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn adapter(index: usize, name: &str, kind: &'static str, vendor: u32, pci_bus: &str) -> AdapterListing {
        AdapterListing {
            index,
            name: name.into(),
            kind,
            backend: "Vulkan".into(),
            vendor,
            pci_bus: pci_bus.into(),
            driver: String::new(),
        }
    }

    /// A 4-GPU node as Vulkan lists it: not in PCI bus order, lavapipe among them.
    fn node() -> Vec<AdapterListing> {
        vec![
            adapter(0, "NVIDIA H200", "discrete", 0x10de, "0000:b3:00.0"),
            adapter(1, "NVIDIA H200", "discrete", 0x10de, "0000:19:00.0"),
            adapter(2, "llvmpipe (LLVM 15.0.6, 256 bits)", "cpu", 0x10005, ""),
            adapter(3, "NVIDIA H200", "discrete", 0x10de, "0000:3b:00.0"),
        ]
    }

    fn explicit(value: &str) -> Assignment {
        Assignment {
            explicit: Some((SELECT_GPU, value.into())),
            ..Default::default()
        }
    }

    #[test]
    fn the_flag_or_variable_picks_by_index_name_or_bus_and_says_what_there_is() {
        let node = node();
        assert_eq!(choose(&node, &explicit("3")).unwrap(), Some(3));
        assert_eq!(choose(&node, &explicit("LLVMpipe")).unwrap(), Some(2));
        assert_eq!(choose(&node, &explicit("3b:00")).unwrap(), Some(3));
        for bad in ["4", "A100"] {
            let e = choose(&node, &explicit(bad)).unwrap_err().to_string();
            assert!(e.contains(bad) && e.contains("2: llvmpipe"), "{e}");
        }
        // The flag wins over the environment's assignment.
        let both = Assignment {
            cuda_visible: Some("0".into()),
            slurm_local_id: Some(1),
            ..explicit("1")
        };
        assert_eq!(choose(&node, &both).unwrap(), Some(1));
    }

    #[test]
    fn cuda_visible_devices_maps_through_nvidia_smi_or_else_pci_order() {
        let node = node();
        let rows = vec![
            ("0".into(), "GPU-aaaa".into(), "00000000:19:00.0".into()),
            ("1".into(), "GPU-bbbb".into(), "00000000:3B:00.0".into()),
            ("2".into(), "GPU-cccc".into(), "00000000:B3:00.0".into()),
        ];
        let cuda = |visible: &str, nvidia: bool| Assignment {
            cuda_visible: Some(visible.into()),
            nvidia: nvidia.then(|| rows.clone()),
            ..Default::default()
        };
        assert_eq!(choose(&node, &cuda("1", true)).unwrap(), Some(3)); // bus 3b
        assert_eq!(choose(&node, &cuda("GPU-cccc,GPU-aaaa", true)).unwrap(), Some(0)); // bus b3
                                                                                       // Without nvidia-smi: the NVIDIA adapters in bus order (19, 3b, b3).
        assert_eq!(choose(&node, &cuda("0", false)).unwrap(), Some(1));
        assert_eq!(choose(&node, &cuda("2", false)).unwrap(), Some(0));
        assert!(choose(&node, &cuda("7", false)).is_err());
        // One GPU, as a container with --gpus 1 shows it: index 0 is it, whatever its bus.
        let one = vec![adapter(0, "NVIDIA H200", "discrete", 0x10de, "0000:b3:00.0")];
        assert_eq!(choose(&one, &cuda("0", false)).unwrap(), Some(0));
    }

    #[test]
    fn slurm_tasks_share_a_nodes_gpus_in_turn_and_one_gpu_is_left_to_wgpu() {
        let node = node();
        let task = |id| Assignment {
            slurm_local_id: Some(id),
            ..Default::default()
        };
        let picked: Vec<_> = (0..4).map(|id| choose(&node, &task(id)).unwrap()).collect();
        assert_eq!(picked, [Some(1), Some(3), Some(0), Some(1)]);
        let laptop = vec![
            node[2].clone(),
            adapter(1, "Intel UHD", "integrated", 0x8086, "0000:00:02.0"),
        ];
        assert_eq!(choose(&laptop, &task(3)).unwrap(), None);
        assert_eq!(choose(&node, &Assignment::default()).unwrap(), None);
    }
}
