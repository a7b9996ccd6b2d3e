//! The scene on the GPU: the wide BVH uploaded once in the layout `traverse.wgsl` reads, and
//! the pipelines that traverse it.

use std::time::Instant;

use glam::Vec3;

use super::device::Device;
use crate::accel::wide::{WideBvh, EMPTY, LEAF, WIDTH};
use crate::accel::Accel;
use crate::error::Result;

/// vec4s per wide node in `traverse.wgsl`'s layout: six rows of eight bounds, eight children.
const NODE_VEC4S: usize = 14;

/// A ray for [`GpuScene::hit_distances`].
#[derive(Clone, Copy, Debug)]
pub struct GpuRay {
    /// Where it starts.
    pub origin: Vec3,
    /// Its direction, unit length for the distance to be one.
    pub direction: Vec3,
    /// Hits beyond this distance are not seen (`f32::INFINITY` for none).
    pub t_max: f32,
    /// The triangle it leaves, as [`crate::accel::RayCaster::closest_hit`] takes it.
    pub leaving: Option<u32>,
}

/// A scene's BVH on a GPU, ready to cast rays from a compute shader.
pub struct GpuScene {
    pub(crate) device: Device,
    /// Group 0 of both pipelines: nodes, triangles, locations.
    pub(crate) bvh: [wgpu::Buffer; 3],
    pub(crate) gather: wgpu::ComputePipeline,
    trace: wgpu::ComputePipeline,
    /// Seconds the upload took (buffers and pipelines).
    pub upload_seconds: f64,
}

/// Largest f32 below infinity: "no limit" for the shader's `t_max`, which stays finite.
pub(crate) fn shader_t_max(t_max: f32) -> f32 {
    t_max.min(f32::MAX)
}

/// Bit pattern of `leaving` for the shader (`NONE` = `u32::MAX` for none).
pub(crate) fn leaving_bits(leaving: Option<u32>) -> f32 {
    f32::from_bits(leaving.unwrap_or(u32::MAX))
}

impl GpuScene {
    /// Uploads `accel`'s BVH to the first hardware adapter, or to a software one (Mesa's
    /// lavapipe) where `allow_software`.
    pub fn new(accel: &Accel, allow_software: bool) -> Result<GpuScene> {
        let start = Instant::now();
        let device = Device::open("hmdist rays", allow_software, wgpu::Features::empty())?;
        let (wide, location) = accel.wide();
        let (nodes, triangles) = flatten(wide);
        // In bytes (the elements are [f32; 4]: counting elements made the check 4x too lax).
        let buffers = [
            ("nodes", std::mem::size_of_val(&nodes[..])),
            ("triangles", std::mem::size_of_val(&triangles[..])),
            ("locations", std::mem::size_of_val(location)),
        ];
        super::device::check_buffers(&device, "the BVH", &buffers)?;
        let stack = (WIDTH - 1) * wide.depth + 1;
        let traverse = traverse_source(stack);
        let (gather, trace, bvh) = device.checked("uploading the scene to the GPU", || {
            let module = |label, parts: &[&str]| {
                device.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some(label),
                    source: wgpu::ShaderSource::Wgsl(parts.concat().into()),
                })
            };
            let pipeline = |module: &wgpu::ShaderModule, entry| {
                device
                    .device
                    .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                        label: Some(entry),
                        layout: None,
                        module,
                        entry_point: Some(entry),
                        compilation_options: Default::default(),
                        cache: None,
                    })
            };
            let gather_module = module(
                "gather.wgsl",
                &[
                    &traverse,
                    include_str!("sampling.wgsl"),
                    include_str!("gather.wgsl"),
                ],
            );
            let trace_module = module("trace.wgsl", &[&traverse, include_str!("trace.wgsl")]);
            let none = wgpu::BufferUsages::empty();
            let bvh = [
                device.storage("nodes", bytemuck::cast_slice(&nodes), none),
                device.storage("triangles", bytemuck::cast_slice(&triangles), none),
                device.storage("locations", bytemuck::cast_slice(location), none),
            ];
            Ok((
                pipeline(&gather_module, "gather"),
                pipeline(&trace_module, "trace"),
                bvh,
            ))
        })?;
        device.wait();
        Ok(GpuScene {
            device,
            bvh,
            gather,
            trace,
            upload_seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// The adapter's name and backend.
    pub fn adapter(&self) -> &str {
        &self.device.adapter_name
    }

    /// The hit distance of each ray (`+inf` where it hits nothing within its `t_max`), as
    /// [`crate::accel::RayCaster::hit_distance`] gives it on the CPU to within a few ulps.
    pub fn hit_distances(&self, rays: &[GpuRay]) -> Result<Vec<f32>> {
        let mut distances = vec![f32::INFINITY; rays.len()];
        let chunk = 1usize << 22;
        for (part, out) in rays.chunks(chunk).zip(distances.chunks_mut(chunk)) {
            crate::interrupt::check()?;
            let packed: Vec<[f32; 8]> = part
                .iter()
                .map(|r| {
                    // A ray with a non-finite component would pass every box test; the CPU
                    // misses it, and so does the GPU, without casting it.
                    let finite = r.origin.is_finite() && r.direction.is_finite();
                    let (o, d) = if finite {
                        (r.origin, r.direction)
                    } else {
                        (Vec3::ZERO, Vec3::ZERO)
                    };
                    let t_max = if finite { shader_t_max(r.t_max) } else { 0.0 };
                    [o.x, o.y, o.z, t_max, d.x, d.y, d.z, leaving_bits(r.leaving)]
                })
                .collect();
            let found = self.device.checked("casting rays on the GPU", || {
                let none = wgpu::BufferUsages::empty();
                let input = self.device.storage("rays", bytemuck::cast_slice(&packed), none);
                let output = self.device.storage(
                    "distances",
                    &vec![0u8; part.len() * 4],
                    wgpu::BufferUsages::COPY_SRC,
                );
                let groups = self.bind_groups(&self.trace, &[&input, &output]);
                self.dispatch(&self.trace, &groups, part.len() as u32);
                self.device.read_back(&output)
            })?;
            for (o, bits) in out.iter_mut().zip(found.chunks_exact(4)) {
                *o = f32::from_le_bytes(bits.try_into().expect("4 bytes"));
            }
        }
        Ok(distances)
    }

    /// Bind groups 0 (the BVH) and 1 (`buffers`, bindings 0, 1, ...) of `pipeline`.
    pub(crate) fn bind_groups(
        &self,
        pipeline: &wgpu::ComputePipeline,
        buffers: &[&wgpu::Buffer],
    ) -> [wgpu::BindGroup; 2] {
        let group = |index, buffers: &[&wgpu::Buffer]| {
            let entries: Vec<wgpu::BindGroupEntry> = buffers
                .iter()
                .enumerate()
                .map(|(binding, buffer)| wgpu::BindGroupEntry {
                    binding: binding as u32,
                    resource: buffer.as_entire_binding(),
                })
                .collect();
            self.device.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &pipeline.get_bind_group_layout(index),
                entries: &entries,
            })
        };
        let bvh: Vec<&wgpu::Buffer> = self.bvh.iter().collect();
        [group(0, &bvh), group(1, buffers)]
    }

    /// Runs `pipeline` over `invocations` invocations and waits for it.
    pub(crate) fn dispatch(
        &self,
        pipeline: &wgpu::ComputePipeline,
        groups: &[wgpu::BindGroup; 2],
        invocations: u32,
    ) {
        let (x, y) = super::device::workgroups(
            invocations,
            self.device.limits.max_compute_workgroups_per_dimension,
        );
        let mut encoder = self.device.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &groups[0], &[]);
            pass.set_bind_group(1, &groups[1], &[]);
            pass.dispatch_workgroups(x, y, 1);
        }
        self.device.queue.submit([encoder.finish()]);
        self.device.wait();
    }
}

/// `traverse.wgsl` with the host's layout constants in place of its defaults: the stack size
/// for a BVH of `stack` entries' depth, and the node and block layout [`flatten`] writes.
pub(crate) fn traverse_source(stack: usize) -> String {
    let constants = [
        ("STACK_SIZE", format!("{stack}u")),
        ("NODE_VEC4S", format!("{NODE_VEC4S}u")),
        ("WIDTH", format!("{WIDTH}u")),
        ("LEAF", format!("{LEAF:#x}u")),
        ("EMPTY", format!("{EMPTY:#x}u")),
    ];
    super::device::inject_constants(include_str!("traverse.wgsl"), &constants)
}

/// The BVH in `traverse.wgsl`'s layout: [`NODE_VEC4S`] vec4s per node, three vec4s per block
/// lane (the first corner's w the triangle's index), leaf references rewritten to
/// `LEAF | block << 3 | (triangles − 1)` with the lanes that repeat the last triangle left out.
fn flatten(wide: &WideBvh) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let distinct: Vec<u32> = wide
        .block_triangles
        .iter()
        .map(|lanes| {
            let last = lanes[WIDTH - 1];
            lanes.iter().position(|&t| t == last).unwrap_or(WIDTH - 1) as u32 + 1
        })
        .collect();
    let mut nodes = Vec::with_capacity(wide.nodes.len() * NODE_VEC4S);
    for node in &wide.nodes {
        for row in &node.bounds {
            nodes.push([row[0], row[1], row[2], row[3]]);
            nodes.push([row[4], row[5], row[6], row[7]]);
        }
        let children = node.child.map(|c| {
            let reference = if c != EMPTY && c & LEAF != 0 {
                let block = c & !LEAF;
                LEAF | block << 3 | (distinct[block as usize] - 1)
            } else {
                c
            };
            f32::from_bits(reference)
        });
        nodes.push([children[0], children[1], children[2], children[3]]);
        nodes.push([children[4], children[5], children[6], children[7]]);
    }
    let mut triangles = Vec::with_capacity(wide.blocks.len() * WIDTH * 3);
    for (block, lanes) in wide.blocks.iter().zip(&wide.block_triangles) {
        for (lane, &triangle) in lanes.iter().enumerate() {
            for (k, corner) in block.corner.iter().enumerate() {
                let w = if k == 0 { f32::from_bits(triangle) } else { 0.0 };
                triangles.push([corner[0][lane], corner[1][lane], corner[2][lane], w]);
            }
        }
    }
    (nodes, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_traversal_takes_the_hosts_layout_constants() {
        let source = traverse_source(21);
        for line in [
            "const STACK_SIZE: u32 = 21u;",
            "const NODE_VEC4S: u32 = 14u;",
            "const WIDTH: u32 = 8u;",
            "const LEAF: u32 = 0x80000000u;",
            "const EMPTY: u32 = 0xffffffffu;",
        ] {
            assert!(source.lines().any(|l| l == line), "{line} missing");
        }
        naga::front::wgsl::parse_str(&source).unwrap();
    }
}
