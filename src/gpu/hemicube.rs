//! Hemicubes on the GPU, for the cube-map estimator's GPU backend: wgpu rasterises the five
//! faces of many points' hemicubes per submission into one R32Float atlas, and a compute pass
//! does the lookups, so only H per point comes back (spec §3.2). The estimator
//! ([`crate::estimators::Cubemap`]) turns that into its image and report.
//!
//! Batching: each hemicube is a `2R × 6R` block of the atlas (top face `2R × 2R`, then the four
//! side faces `2R × R`); one instanced draw renders the scene once per (hemicube, face), the
//! vertex shader placing it in its block and clip distances cutting it to the block's edges.
//! Needs the CLIP_DISTANCES feature (present on Vulkan, including Mesa's lavapipe), and no
//! multiview.

use std::time::Instant;

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::accel::GatherStart;
use crate::error::{DeviceErrorKind, Error, Result};
use crate::progress::Progress;
use crate::sampling::{strata, Weighting};
use crate::scene::Mesh;

/// Largest atlas side we ask for (the device limit may be lower).
const MAX_ATLAS: u32 = 4096;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    atlas_size: [f32; 2],
    atlas_cols: u32,
    resolution: u32,
    count: u32,
    rays: u32,
    grid_a: u32,
    grid_b: u32,
    weighting: u32,
    has_max: u32,
    seed: [u32; 2],
    near: f32,
    far: f32,
    d_min: f32,
    d_max: f32,
    /// The lookups of this dispatch: directions `first_ray..end_ray` of every hemicube.
    first_ray: u32,
    end_ray: u32,
    padding: [u32; 2],
}

// The twins' sizes, checked as the crate compiles; the test at the end checks every member's
// offset against the shader's.
const _: () = assert!(std::mem::size_of::<Params>() == 80);
const _: () = assert!(std::mem::size_of::<Cube>() == 64);
const _: () = assert!(std::mem::size_of::<LookupResult>() == 16);

/// Lookups per hemicube per dispatch on a software adapter: lavapipe stops a shader loop
/// after 65,535 iterations per invocation, and a 65,536-direction loop ran into it.
const SOFTWARE_MAX_LOOKUPS: u32 = 4096;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Cube {
    origin: [f32; 4],
    t: [f32; 4],
    b: [f32; 4],
    n: [f32; 4],
}

/// What the lookup pass accumulates per hemicube over its dispatches (`Lookup` in the shader).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct LookupResult {
    /// Kahan sum of `1/d` and its carry.
    sum: f32,
    carry: f32,
    /// Lookups whose texel holds no surface (within `--max-distance`).
    escaped: u32,
    /// Lookups made, counted by the shader (checked against the directions asked for).
    looked: u32,
}

/// One batch's results per hemicube, and the seconds of each half.
struct Batch {
    values: Vec<LookupResult>,
    raster_seconds: f64,
    lookup_seconds: f64,
}

/// What to rasterise and look up: `mesh`'s hemicubes of per-quadrant resolution
/// `resolution`, looked up in `rays` stratified `weighting` directions (gather's, with random
/// numbers of `seed`); depths from `d_min` (the near plane) to `far`, distances clamped below
/// at `d_min`, and beyond `t_max` (where finite) counted as escaped lookups.
pub(crate) struct HemicubeJob<'a> {
    pub mesh: &'a Mesh,
    pub resolution: u32,
    pub rays: u32,
    pub weighting: Weighting,
    pub seed: u64,
    pub d_min: f32,
    pub t_max: f32,
    pub far: f32,
}

/// H at each point, `rays / Σ 1/d` over its lookups (`+inf` where none saw a surface), and
/// what it took.
pub(crate) struct HemicubeLookups {
    pub hmd: Vec<f32>,
    /// Lookups whose texel holds no surface (within `t_max`).
    pub escaped_lookups: u64,
    pub raster_seconds: f64,
    pub lookup_seconds: f64,
}

/// A device that can run the hemicube pipeline, and what it is called.
pub(crate) struct HemicubeGpu {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pub(crate) adapter_name: String,
    max_texture: u32,
    /// The device's limits, for the buffer checks.
    limits: wgpu::Limits,
    /// A software implementation (lavapipe): lookups are split into short dispatches.
    pub(crate) software: bool,
}

impl HemicubeGpu {
    /// The first Vulkan, Metal or DX12 adapter with clip distances, if any (see
    /// [`crate::gpu`]). A software rasteriser (Mesa's lavapipe) is taken only when
    /// `allow_software`.
    pub fn open(allow_software: bool) -> Result<HemicubeGpu> {
        let super::device::Device {
            device,
            queue,
            adapter_name,
            limits,
            software: device_software,
        } = super::device::Device::open("hmdist hemicubes", allow_software, wgpu::Features::CLIP_DISTANCES)?;
        Ok(HemicubeGpu {
            device,
            queue,
            adapter_name,
            max_texture: limits.max_texture_dimension_2d,
            limits,
            software: device_software,
        })
    }
}

/// H at `starts` (their keys, the random numbers' and the shader's, from `key`), with what it
/// took: see [`HemicubeLookups`].
pub(crate) fn look_up(
    gpu: &HemicubeGpu,
    job: &HemicubeJob,
    starts: &[GatherStart],
    key: impl Fn(usize) -> u32,
    progress: &dyn Progress,
) -> Result<HemicubeLookups> {
    let r = job.resolution;
    let side = MAX_ATLAS.min(gpu.max_texture);
    let (cols, rows) = (side / (2 * r), side / (6 * r));
    if cols == 0 || rows == 0 {
        let message = format!("cube_res {r} does not fit the GPU's largest texture ({side} texels)");
        return Err(Error::device(DeviceErrorKind::Unsupported, message));
    }
    let capacity = (cols * rows) as usize;
    let atlas_size = (cols * 2 * r, rows * 6 * r);
    let mesh = job.mesh;
    let what = "the cube map";
    let storage = [
        ("cubes", capacity * std::mem::size_of::<Cube>()),
        ("results", capacity * std::mem::size_of::<LookupResult>()),
    ];
    super::device::check_buffers_within(&gpu.limits, &gpu.adapter_name, what, &storage)?;
    // Vertex and index buffers are not storage bindings: only the buffer size limit applies.
    let unbound = wgpu::Limits {
        max_storage_buffer_binding_size: gpu.limits.max_buffer_size,
        ..gpu.limits.clone()
    };
    let geometry = [
        ("vertices", mesh.positions.len() * 12),
        ("indices", mesh.indices.len() * 12),
    ];
    super::device::check_buffers_within(&unbound, &gpu.adapter_name, what, &geometry)?;
    // Catch the device's errors here rather than let wgpu panic on them.
    super::device::checked(&gpu.device, "the cube-map pipeline", || {
        look_up_in_batches(gpu, job, starts, key, progress, atlas_size, (cols, capacity))
    })
}

fn look_up_in_batches(
    gpu: &HemicubeGpu,
    job: &HemicubeJob,
    starts: &[GatherStart],
    key: impl Fn(usize) -> u32,
    progress: &dyn Progress,
    atlas_size: (u32, u32),
    (cols, capacity): (u32, usize),
) -> Result<HemicubeLookups> {
    let r = job.resolution;
    let pipeline = Pipeline::new(gpu, job.mesh, atlas_size);

    let cubes: Vec<Cube> = starts
        .iter()
        .enumerate()
        .map(|(i, start)| {
            let (o, frame) = (start.origin, start.frame);
            let v = |v: glam::Vec3, w: f32| [v.x, v.y, v.z, w];
            Cube {
                origin: v(o, 0.0),
                t: v(frame.t, 0.0),
                b: v(frame.b, 0.0),
                n: v(frame.n, f32::from_bits(key(i))),
            }
        })
        .collect();

    let (a, b) = strata(job.rays);
    let base = Params {
        atlas_size: [atlas_size.0 as f32, atlas_size.1 as f32],
        atlas_cols: cols,
        resolution: r,
        count: 0,
        rays: job.rays,
        grid_a: a,
        grid_b: b,
        weighting: (job.weighting == Weighting::Uniform) as u32,
        has_max: job.t_max.is_finite() as u32,
        seed: [job.seed as u32, (job.seed >> 32) as u32],
        near: job.d_min,
        far: job.far,
        d_min: job.d_min,
        d_max: if job.t_max.is_finite() { job.t_max } else { 0.0 },
        first_ray: 0,
        end_ray: 0,
        padding: [0; 2],
    };
    let rays = base.rays;
    let per_dispatch = if gpu.software { SOFTWARE_MAX_LOOKUPS } else { rays };

    let mut hmd = Vec::with_capacity(cubes.len());
    let (mut raster, mut lookup, mut escaped) = (0.0, 0.0, 0);
    progress.start("cube maps", cubes.len() as u64);
    for (b, batch) in cubes.chunks(capacity).enumerate() {
        crate::interrupt::check()?;
        let params = Params {
            count: batch.len() as u32,
            ..base
        };
        let done = pipeline.run(gpu, &params, batch, per_dispatch)?;
        raster += done.raster_seconds;
        lookup += done.lookup_seconds;
        for (j, result) in done.values.iter().enumerate() {
            if result.looked != rays {
                let message = format!(
                    "the GPU made {} of point {}'s {rays} cube-map lookups: a shader loop was cut \
                     short (a driver's cap on loop iterations?), so the result was thrown away",
                    result.looked,
                    b * capacity + j
                );
                return Err(Error::device(DeviceErrorKind::Failed, message));
            }
            // As the shader did before the lookups were split: H = N / Σ 1/d.
            hmd.push(if result.sum > 0.0 {
                rays as f32 / result.sum
            } else {
                f32::INFINITY
            });
            escaped += result.escaped as u64;
        }
        progress.advance(batch.len() as u64);
    }
    progress.finish();
    Ok(HemicubeLookups {
        hmd,
        escaped_lookups: escaped,
        raster_seconds: raster,
        lookup_seconds: lookup,
    })
}

/// The render and compute pipelines and the resources that live across batches.
struct Pipeline {
    render: wgpu::RenderPipeline,
    compute: wgpu::ComputePipeline,
    render_layout: wgpu::BindGroupLayout,
    compute_layout: wgpu::BindGroupLayout,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    atlas: wgpu::Texture,
    depth: wgpu::Texture,
}

/// The bind group layouts of the rasterising pass (the uniform and the cubes' views) and of
/// the lookup (the uniform, the directions, the depth atlas and the sums).
fn bind_group_layouts(device: &wgpu::Device) -> (wgpu::BindGroupLayout, wgpu::BindGroupLayout) {
    let entry = |binding, visibility, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty,
        count: None,
    };
    let uniform = wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Uniform,
        has_dynamic_offset: false,
        min_binding_size: None,
    };
    let storage = |read_only| wgpu::BindingType::Buffer {
        ty: wgpu::BufferBindingType::Storage { read_only },
        has_dynamic_offset: false,
        min_binding_size: None,
    };
    let render_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("rasterise"),
        entries: &[
            entry(0, wgpu::ShaderStages::VERTEX, uniform),
            entry(1, wgpu::ShaderStages::VERTEX, storage(true)),
        ],
    });
    let compute_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("lookup"),
        entries: &[
            entry(0, wgpu::ShaderStages::COMPUTE, uniform),
            entry(1, wgpu::ShaderStages::COMPUTE, storage(true)),
            entry(
                2,
                wgpu::ShaderStages::COMPUTE,
                wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
            ),
            entry(3, wgpu::ShaderStages::COMPUTE, storage(false)),
        ],
    });
    (render_layout, compute_layout)
}

/// A pipeline layout of the one bind group `layout`.
fn pipeline_layout(device: &wgpu::Device, layout: &wgpu::BindGroupLayout) -> wgpu::PipelineLayout {
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(layout)],
        immediate_size: 0,
    })
}

/// The rasterising pipeline: every triangle into each hemicube face's viewport, the nearest
/// depth kept, its distance stored.
fn render_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
) -> wgpu::RenderPipeline {
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("rasterise hemicubes"),
        layout: Some(&pipeline_layout(device, layout)),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("rasterise"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: 12,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3],
            })],
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: None,
            ..Default::default()
        },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("store_depth"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: wgpu::TextureFormat::R32Float,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

impl Pipeline {
    fn new(gpu: &HemicubeGpu, mesh: &Mesh, atlas_size: (u32, u32)) -> Pipeline {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("hemicube.wgsl"),
            source: wgpu::ShaderSource::Wgsl(
                [include_str!("hemicube.wgsl"), include_str!("sampling.wgsl")]
                    .concat()
                    .into(),
            ),
        });
        let positions: Vec<[f32; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
        let indices: Vec<u32> = mesh.indices.iter().flatten().copied().collect();
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("vertices"),
            contents: bytemuck::cast_slice(&positions),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let index_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });
        let (render_layout, compute_layout) = bind_group_layouts(device);
        let render = render_pipeline(device, &module, &render_layout);
        let compute = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("look hemicubes up"),
            layout: Some(&pipeline_layout(device, &compute_layout)),
            module: &module,
            entry_point: Some("lookup"),
            compilation_options: Default::default(),
            cache: None,
        });
        let texture = |format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: None,
                size: wgpu::Extent3d {
                    width: atlas_size.0,
                    height: atlas_size.1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        Pipeline {
            render,
            compute,
            render_layout,
            compute_layout,
            vertices,
            indices: index_buffer,
            index_count: indices.len() as u32,
            atlas: texture(
                wgpu::TextureFormat::R32Float,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            ),
            depth: texture(
                wgpu::TextureFormat::Depth32Float,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            ),
        }
    }

    /// Rasterises `cubes`' hemicubes, then looks their directions up in dispatches of at most
    /// `per_dispatch` directions each (the sums carried between them): the result per
    /// hemicube and the seconds of each half.
    fn run(&self, gpu: &HemicubeGpu, params: &Params, cubes: &[Cube], per_dispatch: u32) -> Result<Batch> {
        let device = &gpu.device;
        let init = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let params_buffer = init(
            "params",
            bytemuck::bytes_of(params),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let cube_buffer = init("cubes", bytemuck::cast_slice(cubes), wgpu::BufferUsages::STORAGE);
        let out_size = (cubes.len() * std::mem::size_of::<LookupResult>()) as u64;
        let output = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("hmd"),
            size: out_size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let atlas_view = self.atlas.create_view(&Default::default());

        let raster_seconds = self.rasterise(gpu, &params_buffer, &cube_buffer, &atlas_view, cubes.len());
        let start = Instant::now();
        let buffers = [&params_buffer, &cube_buffer, &output];
        self.look_up(gpu, params, buffers, &atlas_view, cubes.len(), per_dispatch);
        let values = read_back(gpu, &output)?;
        Ok(Batch {
            values,
            raster_seconds,
            lookup_seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// Rasterises `count` hemicubes into the atlas; the seconds it took.
    fn rasterise(
        &self,
        gpu: &HemicubeGpu,
        params_buffer: &wgpu::Buffer,
        cube_buffer: &wgpu::Buffer,
        atlas_view: &wgpu::TextureView,
        count: usize,
    ) -> f64 {
        let device = &gpu.device;
        let start = Instant::now();
        let depth_view = self.depth.create_view(&Default::default());
        let render_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &self.render_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: cube_buffer.as_entire_binding(),
                },
            ],
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("hemicubes"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: atlas_view,
                    depth_slice: None,
                    resolve_target: None,
                    // -1: no surface through this texel (the direction escapes).
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: -1.0,
                            g: 0.0,
                            b: 0.0,
                            a: 1.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.render);
            pass.set_bind_group(0, &render_group, &[]);
            pass.set_vertex_buffer(0, self.vertices.slice(..));
            pass.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..self.index_count, 0, 0..(count as u32 * 5));
        }
        gpu.queue.submit([encoder.finish()]);
        let _ = device.poll(wgpu::PollType::wait_indefinitely());
        start.elapsed().as_secs_f64()
    }

    /// Looks the directions of `count` hemicubes up in the atlas, in dispatches of at most
    /// `per_dispatch` directions, into `output`; `buffers`: the parameters, the cubes, the
    /// output.
    fn look_up(
        &self,
        gpu: &HemicubeGpu,
        params: &Params,
        [params_buffer, cube_buffer, output]: [&wgpu::Buffer; 3],
        atlas_view: &wgpu::TextureView,
        count: usize,
        per_dispatch: u32,
    ) {
        let device = &gpu.device;
        let compute_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &self.compute_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: cube_buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(atlas_view),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: output.as_entire_binding(),
                },
            ],
        });
        let mut first_ray = 0;
        while first_ray < params.rays {
            let end_ray = first_ray.saturating_add(per_dispatch.max(1)).min(params.rays);
            let dispatch = Params {
                first_ray,
                end_ray,
                ..*params
            };
            gpu.queue
                .write_buffer(params_buffer, 0, bytemuck::bytes_of(&dispatch));
            let mut encoder = device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&self.compute);
                pass.set_bind_group(0, &compute_group, &[]);
                pass.dispatch_workgroups((count as u32).div_ceil(64), 1, 1);
            }
            gpu.queue.submit([encoder.finish()]);
            first_ray = end_ray;
        }
    }
}

/// `output` read back from the GPU.
fn read_back(gpu: &HemicubeGpu, output: &wgpu::Buffer) -> Result<Vec<LookupResult>> {
    let device = &gpu.device;
    let out_size = output.size();
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("hmd readback"),
        size: out_size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(output, 0, &readback, 0, out_size);
    gpu.queue.submit([encoder.finish()]);
    let slice = readback.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    let _ = device.poll(wgpu::PollType::wait_indefinitely());
    let values: Vec<LookupResult> = match slice.get_mapped_range() {
        Ok(view) => bytemuck::cast_slice(&view).to_vec(),
        Err(e) => {
            let message = format!("cannot read the results back: {e}");
            return Err(Error::device(DeviceErrorKind::Readback, message));
        }
    };
    readback.unmap();
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::{host_layout, wgsl_struct_layout};

    /// `Params`, `Cube` and `LookupResult` are `Params`, `Cube` and `Lookup` of
    /// `hemicube.wgsl`, member by member.
    #[test]
    fn the_host_structs_match_the_shaders() {
        let source = [include_str!("hemicube.wgsl"), include_str!("sampling.wgsl")].concat();
        let params = host_layout!(Params: atlas_size, atlas_cols, resolution, count, rays, grid_a,
            grid_b, weighting, has_max, seed, near, far, d_min, d_max, first_ray, end_ray, padding);
        assert_eq!(wgsl_struct_layout(&source, "Params"), params);
        assert_eq!(
            wgsl_struct_layout(&source, "Cube"),
            host_layout!(Cube: origin, t, b, n)
        );
        let lookup = host_layout!(LookupResult: sum, carry, escaped, looked);
        assert_eq!(wgsl_struct_layout(&source, "Lookup"), lookup);
    }
}
