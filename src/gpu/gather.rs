//! Final gathering on the GPU (`gather.wgsl`): each point's rays, its sums of `1/d` per round
//! and its AOV figures, with the CPU's random numbers and in the CPU's ray order.
//!
//! The work is split into dispatches of at most [`MAX_POINTS`] points and a number of rays
//! per point chosen so that one dispatch takes about [`DISPATCH_SECONDS`] (long submissions
//! trip driver timeouts, and the progress bar moves); a point's running sums stay on the GPU
//! between dispatches, so the split does not change a bit of the result.

use std::time::Instant;

use bytemuck::{Pod, Zeroable};

use super::device::Device;
use super::scene::{leaving_bits, shader_t_max, GpuScene};
use crate::accel::GatherStart;
use crate::backend::DispatchSplit;
use crate::error::{DeviceErrorKind, Error, Result};
use crate::progress::Progress;
use crate::sampling::{strata, Sampler, Weighting};

/// Points per dispatch at most: 1 M points hold 64 MB of starts and 32 MB of state.
pub const MAX_POINTS: u32 = 1 << 20;
/// What a dispatch should take, when the split is chosen automatically.
const DISPATCH_SECONDS: f64 = 0.5;
/// Rays of the first dispatch of a batch, over all its points (then scaled to the time taken).
const FIRST_DISPATCH_RAYS: u64 = 1 << 20;
/// Rays per point per dispatch at most on a software implementation. Mesa's llvmpipe
/// (lavapipe) caps every shader loop at 65,535 iterations in one invocation, counted over the
/// whole invocation rather than per entry into the loop: a point casting ~100 rays in one
/// dispatch ran out, and its later rays came back as misses. 16 rays stay far below the cap
/// (a ray visits tens of nodes in our scenes).
const SOFTWARE_MAX_RAYS: u32 = 16;

/// `GatherParams` in `gather.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    count: u32,
    first_ray: u32,
    end_ray: u32,
    per_round: u32,
    rounds: u32,
    grid_a: u32,
    grid_b: u32,
    weighting: u32,
    seed: [u32; 2],
    d_min: f32,
    t_max: f32,
    has_max: u32,
    has_ao: u32,
    ao_radius: f32,
    cube_res: u32,
    sampler: u32,
    padding0: u32,
    padding1: u32,
    padding2: u32,
}

/// `State` in `gather.wgsl`: escaped, dmin, AO open (value, carry), AO total (value,
/// carry), padding.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct State {
    escaped: u32,
    dmin: f32,
    ao_open: [f32; 2],
    ao_total: [f32; 2],
    /// Rays the shader cast for the point, counted by the shader itself.
    rays: u32,
    padding: u32,
}

// The twins' sizes, checked as the crate compiles; the test below checks every member's offset
// against the shader's.
const _: () = assert!(std::mem::size_of::<Params>() == 80);
const _: () = assert!(std::mem::size_of::<State>() == 32);
const _: () = assert!(std::mem::size_of::<[[f32; 4]; 4]>() == 64);

/// A gather on the GPU: each point's figures (as the caller made them from [`GpuPoint`]) and
/// the seconds of each step.
pub(crate) struct GpuGather<T> {
    /// Per point, in the order given.
    pub points: Vec<T>,
    pub upload_seconds: f64,
    pub trace_seconds: f64,
    pub readback_seconds: f64,
}

/// What to gather: `rays` rays per point as `rounds` rounds of `weighting` directions drawn by
/// `sampler` (`gather`'s, see [`crate::estimators::Gather`]) with random numbers of `seed`;
/// hits closer than `d_min` count as `d_min`, and hits beyond `t_max` (finite) as escapes
/// at `t_max`; the `ao` AOV's figures where `ao_radius` is given. With `cube_res` R > 0 it is
/// the cube map by rays (`cubemap --gpu-fill rays`): each direction looks up its texel of a
/// hemicube of resolution R, a ray through that texel's centre gives the depth the texel
/// holds, and the distance is that depth along the direction (the CPU backend's arithmetic,
/// `src/estimators/cubemap/cpu.rs`), clamped as gather's.
#[derive(Clone, Copy)]
pub(crate) struct GatherJob {
    pub rays: u32,
    pub rounds: u32,
    pub weighting: Weighting,
    pub seed: u64,
    pub d_min: f32,
    pub t_max: f32,
    pub ao_radius: Option<f32>,
    pub split: Option<DispatchSplit>,
    pub cube_res: u32,
    /// How the directions are drawn: each round a jittered grid, or (gather's rounds being
    /// replicates) the first points of its own scrambled Sobol sequence.
    pub sampler: Sampler,
}

/// One point's figures as the GPU summed them.
pub(crate) struct GpuPoint<'a> {
    /// Σ 1/d of each round, in round order.
    pub round_sums: &'a [f64],
    /// Rays that escaped (or passed `t_max`).
    pub escaped: u32,
    /// The smallest hit distance.
    pub dmin: f32,
    /// The `ao` AOV's cosine-weighted open and total sums.
    pub ao: (f64, f64),
}

/// Gathers at `starts`, point `i`'s random numbers keyed by `key(i)`; `point` makes each
/// point's result from its sums. The points go in batches that fit the device
/// ([`batch_points`]); each batch is uploaded, traced in dispatches of about half a second
/// ([`trace_batch`]), read back and checked.
pub(crate) fn gather_points<T>(
    scene: &GpuScene,
    job: &GatherJob,
    starts: &[GatherStart],
    key: impl Fn(usize) -> u64,
    progress: &dyn Progress,
    point: impl Fn(GpuPoint) -> T,
) -> Result<GpuGather<T>> {
    let (rays, rounds) = (job.rays, job.rounds);
    let base = base_params(job);
    let batch_points = batch_points(&scene.device, job)?;
    let mut out = GpuGather {
        points: Vec::with_capacity(starts.len()),
        upload_seconds: 0.0,
        trace_seconds: 0.0,
        readback_seconds: 0.0,
    };
    progress.start("gather (gpu)", starts.len() as u64 * rays as u64);
    for (b, batch) in starts.chunks(batch_points).enumerate() {
        let first_point = b * batch_points;
        let packed = pack_starts(batch, |i| key(first_point + i));
        let (states, sums) = trace_batch(scene, job, &base, &packed, progress, &mut out)?;
        let states: Vec<State> = bytemuck::pod_collect_to_vec(&states);
        let sums: Vec<[f32; 2]> = bytemuck::pod_collect_to_vec(&sums);
        // The shader's own count: a loop the driver cut short (lavapipe stops a shader loop
        // after 65,535 iterations) would otherwise come back as a plausible, wrong image.
        if let Some((i, short)) = states.iter().enumerate().find(|(_, s)| s.rays != rays) {
            let message = format!(
                "the GPU cast {} of point {}'s {rays} rays: a shader loop was cut short (a \
                 driver's cap on loop iterations?), so the result was thrown away",
                short.rays,
                first_point + i
            );
            return Err(Error::device(DeviceErrorKind::Failed, message));
        }
        // A Kahan sum is its value less its carry.
        let compensated = |[value, carry]: [f32; 2]| value as f64 - carry as f64;
        let mut round_sums = Vec::with_capacity(rounds as usize);
        for (state, sums) in states.iter().zip(sums.chunks(rounds as usize)) {
            round_sums.clear();
            round_sums.extend(sums.iter().map(|&s| compensated(s)));
            out.points.push(point(GpuPoint {
                round_sums: &round_sums,
                escaped: state.escaped,
                dmin: state.dmin,
                ao: (compensated(state.ao_open), compensated(state.ao_total)),
            }));
        }
    }
    progress.finish();
    Ok(out)
}

/// The shader's parameters for `job`, the batch's count and ray range left at 0.
fn base_params(job: &GatherJob) -> Params {
    let per_round = job.rays / job.rounds;
    let (grid_a, grid_b) = strata(per_round);
    Params {
        count: 0,
        first_ray: 0,
        end_ray: 0,
        per_round,
        rounds: job.rounds,
        grid_a,
        grid_b,
        weighting: (job.weighting == Weighting::Uniform) as u32,
        seed: [job.seed as u32, (job.seed >> 32) as u32],
        d_min: job.d_min,
        t_max: shader_t_max(job.t_max),
        has_max: job.t_max.is_finite() as u32,
        has_ao: job.ao_radius.is_some() as u32,
        ao_radius: job.ao_radius.unwrap_or(0.0),
        cube_res: job.cube_res,
        sampler: (job.sampler == Sampler::Sobol) as u32,
        padding0: 0,
        padding1: 0,
        padding2: 0,
    }
}

/// Points per batch: the split's, or [`MAX_POINTS`], fewer where the sums' `u32` index or the
/// device's largest buffer would not hold them; an error where even these buffers do not fit
/// the device's memory.
fn batch_points(device: &Device, job: &GatherJob) -> Result<usize> {
    let rounds = job.rounds;
    let batch_points = job.split.map_or(MAX_POINTS, |s| s.points.clamp(1, MAX_POINTS)) as usize;
    // The shader indexes sums by `i·rounds + round` in u32, and each buffer must fit the
    // device: fewer points per batch where there are many rounds.
    let batch_points = batch_points.min(u32::MAX as usize / rounds as usize).max(1);
    let largest = device
        .limits
        .max_storage_buffer_binding_size
        .min(device.limits.max_buffer_size);
    let per_point = (rounds as u64 * 8).max(std::mem::size_of::<[[f32; 4]; 4]>() as u64);
    let batch_points = batch_points.min((largest / per_point).max(1) as usize);
    super::device::check_buffers(
        device,
        "the GPU gather",
        &[
            ("starts", batch_points * std::mem::size_of::<[[f32; 4]; 4]>()),
            ("states", batch_points * std::mem::size_of::<State>()),
            ("sums", batch_points * rounds as usize * 8),
        ],
    )?;
    Ok(batch_points)
}

/// The points as the shader reads them: origin and leaving side, the frame, and the key's two
/// halves in the spare lanes.
fn pack_starts(batch: &[GatherStart], key: impl Fn(usize) -> u64) -> Vec<[[f32; 4]; 4]> {
    batch
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let k = key(i);
            let (o, f) = (s.origin, s.frame);
            [
                [o.x, o.y, o.z, leaving_bits(s.leaving)],
                [f.t.x, f.t.y, f.t.z, f32::from_bits(k as u32)],
                [f.b.x, f.b.y, f.b.z, f32::from_bits((k >> 32) as u32)],
                [f.n.x, f.n.y, f.n.z, 0.0],
            ]
        })
        .collect()
}

/// One batch of `packed` points: uploaded, its rays cast in dispatches aimed at
/// [`DISPATCH_SECONDS`] each (or the split's), and its states and sums read back, the
/// seconds of each step added to `out`.
fn trace_batch<T>(
    scene: &GpuScene,
    job: &GatherJob,
    base: &Params,
    packed: &[[[f32; 4]; 4]],
    progress: &dyn Progress,
    out: &mut GpuGather<T>,
) -> Result<(Vec<u8>, Vec<u8>)> {
    let (device, count, rays) = (&scene.device, packed.len(), job.rays);
    let clock = Instant::now();
    let initial = State {
        escaped: 0,
        dmin: f32::INFINITY,
        ao_open: [0.0; 2],
        ao_total: [0.0; 2],
        rays: 0,
        padding: 0,
    };
    device.checked("the GPU gather", || {
        let copy = wgpu::BufferUsages::COPY_SRC;
        let params = device.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("gather params"),
            size: std::mem::size_of::<Params>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let start_buffer = device.storage(
            "starts",
            bytemuck::cast_slice(packed),
            wgpu::BufferUsages::empty(),
        );
        let states = device.storage("states", bytemuck::cast_slice(&vec![initial; count]), copy);
        let sums = device.storage("sums", &vec![0u8; count * job.rounds as usize * 8], copy);
        let groups = scene.bind_groups(&scene.gather, &[&params, &start_buffer, &states, &sums]);
        device.wait();
        out.upload_seconds += clock.elapsed().as_secs_f64();

        let clock = Instant::now();
        let mut first_ray = 0u32;
        let capped = device.software && !job.split.is_some_and(|s| s.past_software_cap);
        let most = if capped { SOFTWARE_MAX_RAYS } else { rays };
        let mut step = match job.split {
            Some(split) => split.rays.clamp(1, most),
            None => (FIRST_DISPATCH_RAYS / count as u64).clamp(1, most as u64) as u32,
        };
        while first_ray < rays {
            // Between dispatches of about half a second: Ctrl-C stops within one.
            crate::interrupt::check()?;
            let end_ray = first_ray.saturating_add(step).min(rays);
            let dispatch = Params {
                count: count as u32,
                first_ray,
                end_ray,
                ..*base
            };
            device
                .queue
                .write_buffer(&params, 0, bytemuck::bytes_of(&dispatch));
            let took = Instant::now();
            scene.dispatch(&scene.gather, &groups, count as u32);
            let seconds = took.elapsed().as_secs_f64();
            progress.advance(count as u64 * (end_ray - first_ray) as u64);
            if job.split.is_none() {
                // Aim the next dispatch at DISPATCH_SECONDS, growing at most 16-fold.
                let scale = (DISPATCH_SECONDS / seconds.max(1e-4)).clamp(0.25, 16.0);
                step = ((step as f64 * scale) as u32).clamp(1, most);
            }
            first_ray = end_ray;
        }
        out.trace_seconds += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let read = (device.read_back(&states)?, device.read_back(&sums)?);
        out.readback_seconds += clock.elapsed().as_secs_f64();
        Ok(read)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::{host_layout, wgsl_struct_layout};

    /// `Params` and `State` are `GatherParams` and `State` of `gather.wgsl` member by member,
    /// and a start is the shader's `Start`.
    #[test]
    fn the_host_structs_match_the_shaders() {
        let source = [
            super::super::scene::traverse_source(64),
            include_str!("sampling.wgsl").into(),
            include_str!("gather.wgsl").into(),
        ]
        .concat();
        let params = host_layout!(Params: count, first_ray, end_ray, per_round, rounds, grid_a, grid_b,
            weighting, seed, d_min, t_max, has_max, has_ao, ao_radius, cube_res, sampler, padding0, padding1,
            padding2);
        assert_eq!(wgsl_struct_layout(&source, "GatherParams"), params);
        let state = host_layout!(State: escaped, dmin, ao_open, ao_total, rays, padding);
        assert_eq!(wgsl_struct_layout(&source, "State"), state);
        let start = wgsl_struct_layout(&source, "Start");
        assert_eq!(start.1 as usize, std::mem::size_of::<[[f32; 4]; 4]>());
    }
}
