//! Everything hmdist does on a GPU, in one place: the adapter choice ([`open_for`], `select.rs`)
//! and the device; ray casting, the scene's wide BVH traversed by a wgpu compute shader
//! (`traverse.wgsl`, `scene.rs`), for `gather --backend gpu` and H at points (`gather.rs`,
//! `gather.wgsl`); and the cube map's hemicubes, rasterised and looked up (`hemicube.rs`,
//! `hemicube.wgsl`). It knows nothing of the estimators, which turn its sums into images.
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

mod device;
pub(crate) mod gather;
pub(crate) mod hemicube;
mod scene;
mod select;

pub use crate::backend::DispatchSplit;
pub use device::{adapters, SOFTWARE_GPU};
pub(crate) use device::{auto_uses_gpu, open_for};
pub use scene::{GpuRay, GpuScene};
pub use select::{select_adapter, AdapterListing, SELECT_GPU};

#[cfg(test)]
pub(crate) fn wgsl_struct_layout(source: &str, name: &str) -> (Vec<(String, u32)>, u32) {
    let module =
        naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, ty)| ty.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no struct {name} in the shader"));
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("{name} is not a struct");
    };
    let members = members
        .iter()
        .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
        .collect();
    (members, *span)
}

/// The members (name, byte offset) and size of a host struct, for comparing with
/// [`wgsl_struct_layout`].
#[cfg(test)]
macro_rules! host_layout {
    ($t:ty: $($field:ident),* $(,)?) => {
        (
            vec![$((stringify!($field).to_string(), std::mem::offset_of!($t, $field) as u32)),*],
            std::mem::size_of::<$t>() as u32,
        )
    };
}
#[cfg(test)]
pub(crate) use host_layout;
