//! [`Accel`]: the scene's triangles in an 8-wide BVH ([`super::wide`]), traversed by the
//! fastest SIMD kernel the CPU has ([`super::kernel`]) with our watertight triangle test.
//!
//! Choices, measured on the `cube` and `hall` rooms and a 5 M-triangle sphere (see
//! `cargo bench --bench gather`, `benches/embree/compare.sh` and `docs/engine.md`):
//! - Our own wide BVH and kernels instead of obvhs's compressed wide BVH: its quantised nodes
//!   cost about 250 instructions per node test on a CPU; a float node's eight slab tests are
//!   about 25 AVX2 instructions, and a leaf block's eight triangle tests about 90.
//! - The binary BVH that is collapsed comes from our binned SAH builder
//!   ([`BuildQuality::Fast`]: about 10× faster to build than obvhs's best, a little slower to
//!   trace) or from obvhs's slowest, best preset ([`BuildQuality::High`]); the default picks
//!   by the rays to come ([`BuildQuality::Auto`]).
//! - The node test is pbrt-v4's conservative one: slab distances `(b − o)·(1/d)` carry at most
//!   three roundings, so the far distance is scaled by `1 + 2γ(3)`; with the watertight
//!   triangle test, no ray slips through a closed mesh.

use std::mem::MaybeUninit;
use std::sync::atomic::{AtomicU32, Ordering};

use glam::{DVec3, Vec3, Vec3A};
use obvhs::BvhBuildParams;
use rayon::prelude::*;

use super::kernel::{Kernel, RayData};
use super::traverse::{closest, stack_size, Closest, Counter, Entry, TraversalStats};
use super::triangle::barycentric_point_error;
use super::wide::{BinaryBuilder, WideBvh, WIDTH};
use super::{Hit, RayCaster, RayLanes, PACKET};
use crate::error::Result;
use crate::scene::Mesh;

/// BVH build presets: build time against trace speed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum BuildQuality {
    /// `High` when the work to come casts at least [`AUTO_RAYS_PER_TRIANGLE`] rays per
    /// triangle, else `Fast` ([`BuildQuality::resolve`]); `High` where the work is unknown.
    #[default]
    #[cfg_attr(
        feature = "cli",
        value(help = "high when the render casts at least 500 rays per triangle, else fast")
    )]
    Auto,
    /// Our binned SAH builder (`sah.rs`), parallel: `cube` in 0.03 s and `hall` in 0.24 s on
    /// 2 cores, tracing 3–8 % slower than `High`.
    #[cfg_attr(
        feature = "cli",
        value(help = "Binned SAH, parallel: builds about 10x faster than high, traces 3-8% slower")
    )]
    Fast,
    /// obvhs `very_slow_build` (spatial splits, whole-tree reinsertion): the fastest tracing,
    /// for about 4 µs per triangle on one core (`hall`: 2.6 s).
    #[cfg_attr(
        feature = "cli",
        value(help = "Spatial splits and whole-tree reinsertion: the fastest tracing")
    )]
    High,
}

/// Where [`BuildQuality::Auto`] switches to `High`. Measured break-even: on `hall` the high
/// build costs about 2.3 s more and saves about 5 % of the tracing, which pays from about 300
/// M gather rays (500 per triangle); on `cube` from about 600 per triangle.
pub const AUTO_RAYS_PER_TRIANGLE: u64 = 500;

impl BuildQuality {
    /// The preset's name, as the CLI and the render report spell it (`fast`, `high`, `auto`).
    pub fn name(self) -> &'static str {
        match self {
            BuildQuality::Fast => "fast",
            BuildQuality::High => "high",
            BuildQuality::Auto => "auto",
        }
    }

    /// The preset for casting about `rays` rays against `triangles` triangles: `Auto`
    /// becomes `Fast` or `High`, the others stay.
    pub fn resolve(self, rays: u64, triangles: usize) -> BuildQuality {
        match self {
            BuildQuality::Auto if rays < AUTO_RAYS_PER_TRIANGLE * triangles as u64 => BuildQuality::Fast,
            BuildQuality::Auto => BuildQuality::High,
            chosen => chosen,
        }
    }

    fn builder(self) -> BinaryBuilder {
        match self {
            BuildQuality::Fast => BinaryBuilder::Sah { pre_split: false },
            // A leaf block of up to eight triangles costs one kernel call however full it
            // is, so leaves are made fuller than obvhs's default (3.0): 70 instead of 93
            // bytes per triangle on `cube`, and about 5 % faster.
            BuildQuality::High | BuildQuality::Auto => BinaryBuilder::Obvhs(BvhBuildParams {
                collapse_traversal_cost: 5.0,
                ..BvhBuildParams::very_slow_build()
            }),
        }
    }
}

/// Stack entries kept on the thread's stack; deeper trees (pathological inputs) use the heap.
const INLINE_STACK: usize = 256;

/// The scene's triangles in a BVH, ready for closest-hit queries from many threads.
pub struct Accel {
    bvh: WideBvh,
    kernel: Kernel,
    /// For each mesh triangle, one block lane that holds it (`8·block + lane`).
    location: Vec<u32>,
}

impl Accel {
    /// Builds the BVH (`Auto` builds `High`: resolve it first where the work is known), with
    /// the best kernel ([`Kernel::best`]; [`Accel::with_kernel`] picks another). The library
    /// never reads `HMDIST_KERNEL`: the CLI and Python do ([`Kernel::from_env`]).
    pub fn build(mesh: &Mesh, quality: BuildQuality) -> Accel {
        let bvh = WideBvh::build(mesh, quality.builder());
        // Filled on all threads; where several lanes hold a triangle (a block's spare lanes,
        // or spatial splits) the last of them, as one thread in block order would leave it.
        let location: Vec<AtomicU32> = (0..mesh.triangle_count())
            .into_par_iter()
            .map(|_| AtomicU32::new(0))
            .collect();
        bvh.block_triangles
            .par_iter()
            .enumerate()
            .for_each(|(block, lanes)| {
                for (lane, &triangle) in lanes.iter().enumerate() {
                    location[triangle as usize].fetch_max((block * WIDTH + lane) as u32, Ordering::Relaxed);
                }
            });
        let location = location.into_iter().map(AtomicU32::into_inner).collect();
        Accel {
            bvh,
            kernel: Kernel::best(),
            location,
        }
    }

    /// The accelerator for a job that casts about `rays` rays, built the one way every job
    /// builds it: the preset `quality` resolved for that work ([`BuildQuality::resolve`]), the
    /// memory the build takes checked first ([`crate::memory::check_bvh`]), then the build,
    /// traversed by `kernel`. Returns it with the preset it built.
    pub fn for_work(
        mesh: &Mesh,
        quality: BuildQuality,
        rays: u64,
        kernel: Kernel,
    ) -> Result<(Accel, BuildQuality)> {
        let quality = quality.resolve(rays, mesh.triangle_count());
        crate::memory::check_bvh(mesh.triangle_count())?;
        Ok((Accel::build(mesh, quality).with_kernel(kernel), quality))
    }

    /// The same BVH traversed by `kernel`, which this CPU must be able to run.
    pub fn with_kernel(mut self, kernel: Kernel) -> Accel {
        assert!(
            kernel.available(),
            "this CPU cannot run the {} kernel",
            kernel.name()
        );
        self.kernel = kernel;
        self
    }

    /// The kernel that traverses the BVH.
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// The wide BVH and, for each mesh triangle, the block lane that holds it (`8·block +
    /// lane`): what the GPU uploads.
    #[cfg(feature = "gpu")]
    pub(crate) fn wide(&self) -> (&WideBvh, &[u32]) {
        (&self.bvh, &self.location)
    }

    /// Wide nodes, leaf blocks, and the bytes they take.
    pub fn size(&self) -> (usize, usize, usize) {
        (self.bvh.nodes.len(), self.bvh.blocks.len(), self.bvh.bytes())
    }

    /// [`RayCaster::hit_distance`], counting the nodes and leaf blocks it visits.
    pub fn hit_distance_counted(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_max: f32,
        leaving: Option<u32>,
        stats: &mut TraversalStats,
    ) -> f32 {
        self.distance(origin, direction, t_max, leaving, stats)
    }

    /// One ray's hit distance (`+inf` if it escapes), counted by `counter`: every ray-by-ray
    /// path of the distance queries.
    #[inline(always)]
    fn distance<C: Counter>(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_max: f32,
        leaving: Option<u32>,
        counter: &mut C,
    ) -> f32 {
        self.trace(&RayData::new(origin, direction), t_max, leaving, counter)
            .map_or(f32::INFINITY, |c| c.t)
    }

    /// [`RayCaster::hit_distances`], counting the nodes (once per packet visit) and leaf
    /// blocks (once per ray) it visits.
    pub fn hit_distances_counted(
        &self,
        origins: &[Vec3],
        directions: &[Vec3],
        leaving: &[Option<u32>],
        t_max: f32,
        out: &mut [f32],
        stats: &mut TraversalStats,
    ) {
        self.cast_packet(origins, directions, leaving, t_max, out, stats);
    }

    /// [`RayCaster::hit_distances_of_lanes`], counting the nodes (once per packet visit) and
    /// leaf blocks (once per ray) it visits.
    pub fn hit_distances_of_lanes_counted(
        &self,
        rays: &RayLanes,
        len: usize,
        leaving: Option<u32>,
        t_max: f32,
        out: &mut [f32],
        stats: &mut TraversalStats,
    ) {
        self.cast_lanes_checked(rays, len, leaving, t_max, out, stats);
    }

    /// The first `len` rays of `rays` (at most [`PACKET`]), all leaving `leaving`: as a packet
    /// where the kernel has one, else ray by ray.
    #[inline]
    fn cast_lanes_checked<C: Counter>(
        &self,
        rays: &RayLanes,
        len: usize,
        leaving: Option<u32>,
        t_max: f32,
        out: &mut [f32],
        counter: &mut C,
    ) {
        assert!(
            len <= PACKET && out.len() >= len,
            "hit_distances_of_lanes: {len} rays (at most {PACKET}), {} outputs",
            out.len()
        );
        if len >= 2 && self.kernel.has_packets() {
            self.cast_lanes(rays, &[leaving; PACKET][..len], t_max, out, counter);
            return;
        }
        for (i, out) in out[..len].iter_mut().enumerate() {
            *out = self.distance(rays.origin(i), rays.direction(i), t_max, leaving, counter);
        }
    }

    /// Up to [`PACKET`] rays: as a packet where the kernel has one, else ray by ray.
    #[inline]
    fn cast_packet<C: Counter>(
        &self,
        origins: &[Vec3],
        directions: &[Vec3],
        leaving: &[Option<u32>],
        t_max: f32,
        out: &mut [f32],
        counter: &mut C,
    ) {
        let n = directions.len();
        assert!(
            n <= PACKET && origins.len() == n && leaving.len() == n && out.len() >= n,
            "hit_distances: {n} rays (at most {PACKET}), {} origins, {} leaving, {} outputs",
            origins.len(),
            leaving.len(),
            out.len()
        );
        if n >= 2 && self.kernel.has_packets() {
            let packet = RayLanes::from_rays(origins, directions);
            self.cast_lanes(&packet, leaving, t_max, out, counter);
            return;
        }
        for i in 0..n {
            out[i] = self.distance(origins[i], directions[i], t_max, leaving[i], counter);
        }
    }

    /// The first `leaving.len()` rays of `packet` (1 to [`PACKET`]) as a packet: the kernel
    /// must have one ([`Kernel::has_packets`]).
    #[inline]
    fn cast_lanes<C: Counter>(
        &self,
        packet: &RayLanes,
        leaving: &[Option<u32>],
        t_max: f32,
        out: &mut [f32],
        counter: &mut C,
    ) {
        let n = leaving.len();
        #[cfg(target_arch = "x86_64")]
        {
            use super::packet::{closest_packet_avx2, closest_packet_avx512, PacketEntry};
            use super::traverse::Search;
            let accept: [_; PACKET] = std::array::from_fn(|i| {
                let leaving = leaving[i.min(n - 1)];
                move |block: u32, lane: usize| self.may_take_within_error_hit(leaving, block, lane)
            });
            let mut searches: [Search; PACKET] = std::array::from_fn(|i| Search::new(t_max, &accept[i]));
            let (mut inline, mut heap) = ([MaybeUninit::<Entry>::uninit(); INLINE_STACK], Vec::new());
            let (mut inline_packet, mut heap_packet) =
                ([MaybeUninit::<PacketEntry>::uninit(); INLINE_STACK], Vec::new());
            let stack = self.stack(&mut inline, &mut heap);
            let packet_stack = self.stack(&mut inline_packet, &mut heap_packet);
            let (bvh, searches) = (&self.bvh, &mut searches[..n]);
            // SAFETY: `Kernel::best` and `with_kernel` only choose kernels the CPU has, and
            // both packet kernels imply AVX2.
            unsafe {
                match self.kernel {
                    Kernel::Avx2 => closest_packet_avx2(bvh, packet, searches, packet_stack, stack, counter),
                    Kernel::Avx512 => {
                        closest_packet_avx512(bvh, packet, searches, packet_stack, stack, counter)
                    }
                    Kernel::Scalar => unreachable!("cast_lanes needs a packet kernel (Kernel::has_packets)"),
                }
            }
            for (out, search) in out.iter_mut().zip(searches.iter()) {
                *out = search.result().map_or(f32::INFINITY, |c| c.t);
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = (packet, n, t_max, out, counter);
            unreachable!("no packet kernel on this architecture (Kernel::has_packets)");
        }
    }

    /// A traversal stack of [`stack_size`] entries for this BVH: `inline` (on the thread's
    /// stack) where it is deep enough, else `heap`, grown to size.
    #[inline(always)]
    fn stack<'s, T: Copy>(
        &self,
        inline: &'s mut [MaybeUninit<T>; INLINE_STACK],
        heap: &'s mut Vec<MaybeUninit<T>>,
    ) -> &'s mut [MaybeUninit<T>] {
        let needed = stack_size(self.bvh.depth);
        if needed <= INLINE_STACK {
            &mut inline[..]
        } else {
            heap.resize(needed, MaybeUninit::uninit());
            &mut heap[..]
        }
    }

    /// The closest hit along `ray`, with the kernel chosen at build; `None` for a ray with a
    /// NaN or infinite component, which would pass every box test (`maxps`/`minps` drop a NaN)
    /// and reach empty slots.
    #[inline]
    fn trace<C: Counter>(
        &self,
        ray: &RayData,
        t_max: f32,
        leaving: Option<u32>,
        counter: &mut C,
    ) -> Option<Closest> {
        if !ray.is_finite() {
            return None;
        }
        let accept = |block: u32, lane: usize| self.may_take_within_error_hit(leaving, block, lane);
        let (mut inline, mut heap) = ([MaybeUninit::<Entry>::uninit(); INLINE_STACK], Vec::new());
        let stack = self.stack(&mut inline, &mut heap);
        match self.kernel {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `Kernel::best` and `with_kernel` only choose kernels the CPU has.
            Kernel::Avx2 => unsafe {
                super::kernel::avx2::closest_avx2(&self.bvh, ray, t_max, &accept, stack, counter)
            },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            Kernel::Avx512 => unsafe {
                super::kernel::avx2::closest_avx512(&self.bvh, ray, t_max, &accept, stack, counter)
            },
            _ => closest::<super::kernel::scalar::Scalar, C>(&self.bvh, ray, t_max, &accept, stack, counter),
        }
    }

    /// The rule for hits within their own `t` error bound (see [`super`]): a ray that would
    /// otherwise escape takes one, unless it lies on the surface the ray leaves: the triangle
    /// itself, or any triangle in its plane (coincident duplicate faces are common in real
    /// scenes, and a ray that left a plane cannot enter it again).
    fn may_take_within_error_hit(&self, leaving: Option<u32>, block: u32, lane: usize) -> bool {
        let Some(leaving) = leaving else { return true };
        if self.bvh.block_triangles[block as usize][lane] == leaving {
            return false;
        }
        let candidate = self.bvh.blocks[block as usize].triangle(lane);
        let location = self.location[leaving as usize] as usize;
        let left = self.bvh.blocks[location / WIDTH].triangle(location % WIDTH);
        !coplanar(left, candidate)
    }

    fn hit_from(&self, closest: Closest, ray: &RayData) -> Hit {
        let corners = self.bvh.blocks[closest.block as usize].triangle(closest.lane);
        let [p0, p1, p2] = corners;
        let b = ray
            .triangle
            .intersect(p0, p1, p2, f32::INFINITY)
            .map_or([1.0 / 3.0; 3], |hit| hit.b);
        let p = corners.map(Vec3::from);
        Hit {
            t: closest.t,
            triangle: self.bvh.block_triangles[closest.block as usize][closest.lane],
            point: b[0] * p[0] + b[1] * p[1] + b[2] * p[2],
            point_error: barycentric_point_error(b, p),
            normal: (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero(),
        }
    }
}

/// Whether all corners of `other` lie in the plane of `triangle`, to within the rounding of
/// their f32 coordinates (evaluated in f64).
fn coplanar(triangle: [Vec3A; 3], other: [Vec3A; 3]) -> bool {
    let [a, b, c] = triangle.map(|v| DVec3::from(Vec3::from(v)));
    let normal = (b - a).cross(c - a);
    let length = normal.length();
    if length == 0.0 {
        return false;
    }
    let scale = [a, b, c]
        .iter()
        .chain(other.map(|v| DVec3::from(Vec3::from(v))).iter())
        .fold(0.0f64, |m, v| m.max(v.abs().max_element()));
    let tolerance = 8.0 * f32::EPSILON as f64 * scale;
    other
        .iter()
        .all(|v| (normal.dot(DVec3::from(Vec3::from(*v)) - a) / length).abs() <= tolerance)
}

impl RayCaster for Accel {
    fn closest_hit(&self, origin: Vec3, direction: Vec3, t_max: f32, leaving: Option<u32>) -> Option<Hit> {
        let ray = RayData::new(origin, direction);
        let closest = self.trace(&ray, t_max, leaving, &mut ())?;
        Some(self.hit_from(closest, &ray))
    }

    #[inline]
    fn hit_distance(&self, origin: Vec3, direction: Vec3, t_max: f32, leaving: Option<u32>) -> f32 {
        self.distance(origin, direction, t_max, leaving, &mut ())
    }

    #[inline]
    fn hit_distances(
        &self,
        origins: &[Vec3],
        directions: &[Vec3],
        leaving: &[Option<u32>],
        t_max: f32,
        out: &mut [f32],
    ) {
        self.cast_packet(origins, directions, leaving, t_max, out, &mut ());
    }

    #[inline]
    fn hit_distances_of_lanes(
        &self,
        rays: &RayLanes,
        len: usize,
        leaving: Option<u32>,
        t_max: f32,
        out: &mut [f32],
    ) {
        self.cast_lanes_checked(rays, len, leaving, t_max, out, &mut ());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rays_with_nan_or_infinite_components_miss_without_panicking() {
        // Two triangles: the root has empty slots, which a NaN ray would reach.
        let mut mesh = Mesh::new();
        let first = mesh.add_vertices([
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(1.0, 1.0, -1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, -1.0, 1.0),
        ]);
        mesh.indices = vec![[first, first + 1, first + 2], [first, first + 2, first + 3]];
        let accel = Accel::build(&mesh, BuildQuality::Fast);
        for kernel in Kernel::ALL.into_iter().filter(|k| k.available()) {
            let accel = Accel::build(&mesh, BuildQuality::Fast).with_kernel(kernel);
            for (o, d) in [
                (Vec3::ZERO, Vec3::new(f32::NAN, 0.5, 0.5)),
                (Vec3::ZERO, Vec3::splat(f32::NAN)),
                (Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0)),
                (Vec3::splat(f32::NAN), Vec3::X),
            ] {
                assert_eq!(accel.hit_distance(o, d, f32::INFINITY, None), f32::INFINITY);
                assert!(accel.closest_hit(o, d, f32::INFINITY, Some(0)).is_none());
            }
        }
        // The same rays without the NaN do hit (the test can fail).
        assert!(accel
            .hit_distance(Vec3::ZERO, Vec3::X, f32::INFINITY, None)
            .is_finite());
    }

    #[test]
    fn each_triangle_is_located_in_the_last_lane_that_holds_it_for_any_thread_count() {
        // 81,920 triangles, so blocks are filled on several threads; with spatial splits a
        // triangle can sit in several blocks, and a short block repeats its last triangle.
        let mesh = crate::scene::procedural::shapes::icosphere(6, glam::Vec3::ZERO, 1.0);
        for quality in [BuildQuality::Fast, BuildQuality::High] {
            let mut serial = vec![u32::MAX; mesh.triangle_count()];
            let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
            let accel = one.install(|| Accel::build(&mesh, quality));
            for (block, lanes) in accel.bvh.block_triangles.iter().enumerate() {
                for (lane, &triangle) in lanes.iter().enumerate() {
                    serial[triangle as usize] = (block * WIDTH + lane) as u32;
                }
            }
            assert!(serial.iter().all(|&l| l != u32::MAX));
            assert!(accel.location == serial, "{quality:?}: one thread");
            let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
            let accel = three.install(|| Accel::build(&mesh, quality));
            assert!(accel.location == serial, "{quality:?}: three threads");
        }
    }

    #[test]
    fn auto_builds_high_from_500_rays_per_triangle() {
        assert_eq!(BuildQuality::Auto.resolve(49_999, 100), BuildQuality::Fast);
        assert_eq!(BuildQuality::Auto.resolve(50_000, 100), BuildQuality::High);
        assert_eq!(BuildQuality::Fast.resolve(1 << 40, 100), BuildQuality::Fast);
        assert_eq!(BuildQuality::High.resolve(0, 100), BuildQuality::High);
    }
}
