//! The photon map: a kd-tree of our own over photon positions, with each method's payload and
//! nothing else (spec §3.3), and its K-nearest gather.
//!
//! **Layout.** Photons are reordered so that each leaf (at most [`LEAF`] photons) is a
//! contiguous range, and stored structure-of-arrays in that order: positions (3 × f32), the
//! surface normal for the orientation filter, octahedral-encoded in 2 × u16 (error below
//! 0.01°, far inside the filter's 25.8° cone), and
//! - method I: the distance to the next hit (f32, `+inf` when the path escaped): 20 B;
//! - method II: the next-hit point `q = x + d·ω` (3 × f32, NaN when escaped): 28 B.
//!
//! The tree is complete: every leaf at the same depth, each node splitting its photons in
//! half at the median of its widest axis, nodes in depth-first order (one f32 plane and one
//! axis byte each, about 0.2 B per photon). The same photons give the same tree whatever the
//! thread count.
//!
//! **The gather.** The K photons nearest `x` are the K smallest keys `(d², index)`, `d²` the
//! squared distance as kiddo's `SquaredEuclidean` computes it and `index` the photon's place
//! in the tree order (which breaks exact ties). A query collects every photon within a radius
//! `R`, in tree order, and keeps the K smallest keys, in tree order: so H, whose sum runs in
//! that order, does not depend on `R`. `R` comes from the previous query of the same worker
//! (`r_prev + |x − x_prev|` holds the previous K photons, so neighbouring pixels need one
//! pass that collects little more than K photons), else from the density of the leaf around
//! `x`; a pass that finds fewer than K photons doubles `R` and runs again. Measured against
//! kiddo's own `nearest_n_within` in `cargo bench --bench photon`.

use std::num::NonZero;

use glam::Vec3;

mod file;
mod octahedral;

pub use file::MapHeader;
pub use octahedral::{decode_octahedral, encode_octahedral};

use super::trace::TracedPhoton;
use crate::error::{Error, Result};

/// Most photons per leaf.
pub const LEAF: usize = 32;

/// Which distance a gathered photon contributes (spec §3.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhotonMethod {
    /// Method I: the photon's own stored distance `d_j`.
    StoredDistance,
    /// Method II: the distance from the query point to the photon's next hit, `|q_j − x|`.
    NextHitPoint,
}

impl PhotonMethod {
    /// Both methods, I then II.
    pub const ALL: [PhotonMethod; 2] = [PhotonMethod::StoredDistance, PhotonMethod::NextHitPoint];

    /// The name the CLI and the report use (`photon1`, `photon2`): the one mapping between
    /// the two (the registry's entries are named so; a test holds them to it).
    pub fn name(self) -> &'static str {
        match self {
            PhotonMethod::StoredDistance => "photon1",
            PhotonMethod::NextHitPoint => "photon2",
        }
    }

    /// The method named `name` ([`PhotonMethod::name`]), if any.
    pub fn from_name(name: &str) -> Option<PhotonMethod> {
        PhotonMethod::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Payload bytes per photon: the normal and the method's distance or next-hit point.
    pub fn payload_bytes(self) -> usize {
        match self {
            PhotonMethod::StoredDistance => 4 + 4,
            PhotonMethod::NextHitPoint => 4 + 12,
        }
    }

    /// Bytes per photon of the finished map: position and payload (the tree's planes add
    /// under 0.2 B).
    pub fn bytes_per_photon(self) -> usize {
        12 + self.payload_bytes()
    }

    /// Peak bytes while building a map of `photons`: the traced photons, the positions being
    /// sorted into tree order (with their index) and the finished map.
    pub fn peak_build_bytes(self, photons: usize) -> u128 {
        let per_photon = std::mem::size_of::<TracedPhoton>() + 16 + self.bytes_per_photon();
        photons as u128 * per_photon as u128
    }
}

/// Each method's payload, in tree order.
enum Payloads {
    StoredDistance {
        distance: Vec<f32>,
    },
    NextHitPoint {
        qx: Vec<f32>,
        qy: Vec<f32>,
        qz: Vec<f32>,
    },
}

/// Photons in a kd-tree, with each method's payload.
pub struct PhotonMap {
    /// Splitting plane and axis of each internal node, depth-first.
    planes: Vec<f32>,
    axes: Vec<u8>,
    /// Levels of internal nodes: every leaf is at this depth.
    depth: u32,
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    normals: Vec<[u16; 2]>,
    payloads: Payloads,
}

/// A photon on its way into tree order: position and index in the traced list.
#[derive(Clone, Copy)]
struct Entry {
    p: [f32; 3],
    index: u32,
}

impl PhotonMap {
    /// Builds the map for `method` from traced photons.
    pub fn build(photons: &[TracedPhoton], method: PhotonMethod) -> Result<PhotonMap> {
        let (entries, planes, axes, depth) = tree_order(photons)?;
        let column = |f: fn(&Entry) -> f32| entries.iter().map(f).collect::<Vec<f32>>();
        let (x, y, z) = (column(|e| e.p[0]), column(|e| e.p[1]), column(|e| e.p[2]));
        let traced = |e: &Entry| &photons[e.index as usize];
        let normals = entries
            .iter()
            .map(|e| encode_octahedral(traced(e).normal))
            .collect();
        let payloads = match method {
            PhotonMethod::StoredDistance => Payloads::StoredDistance {
                distance: entries.iter().map(|e| traced(e).distance).collect(),
            },
            PhotonMethod::NextHitPoint => {
                // One column at a time: no temporary of all next-hit points.
                let next_hit = |a: usize| {
                    move |e: &Entry| {
                        let p = traced(e);
                        if p.distance.is_finite() {
                            (p.position + p.distance * p.direction)[a]
                        } else {
                            f32::NAN
                        }
                    }
                };
                Payloads::NextHitPoint {
                    qx: entries.iter().map(next_hit(0)).collect(),
                    qy: entries.iter().map(next_hit(1)).collect(),
                    qz: entries.iter().map(next_hit(2)).collect(),
                }
            }
        };
        Ok(PhotonMap {
            planes,
            axes,
            depth,
            x,
            y,
            z,
            normals,
            payloads,
        })
    }

    /// The index in `photons` of each photon of their map, in tree order: the order in which
    /// [`PhotonMap::gather`] visits them (for checks against other searches).
    pub fn order(photons: &[TracedPhoton]) -> Result<Vec<u32>> {
        Ok(tree_order(photons)?.0.iter().map(|e| e.index).collect())
    }

    /// Bytes the map holds on the heap (vectors' lengths, not their spare capacity).
    pub fn heap_bytes(&self) -> usize {
        let payload = match &self.payloads {
            Payloads::StoredDistance { distance } => 4 * distance.len(),
            Payloads::NextHitPoint { qx, qy, qz } => 4 * (qx.len() + qy.len() + qz.len()),
        };
        4 * self.planes.len() + self.axes.len() + 12 * self.len() + 4 * self.normals.len() + payload
    }

    /// Photons in the map.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether the map holds no photon.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Calls `accept(distance)` for each of the `k` photons nearest `x` (within `max_radius`)
    /// whose normal `n_j` satisfies `n_j · n ≥ min_cos`, in tree order; `distance` is method
    /// I's `d_j` or method II's `|q_j − x|` (`+inf` for escaped paths). `scratch` holds one
    /// worker's buffers and its previous query, which only speeds this one up.
    #[allow(clippy::too_many_arguments)]
    pub fn gather(
        &self,
        scratch: &mut GatherScratch,
        x: Vec3,
        n: Vec3,
        k: NonZero<usize>,
        max_radius: f32,
        min_cos: f32,
        mut accept: impl FnMut(f32),
    ) {
        let k = k.get();
        let r2_max = if max_radius.is_finite() {
            max_radius * max_radius
        } else {
            f32::INFINITY
        };
        let mut r = self.first_radius(scratch, x, k);
        loop {
            let r2 = (r * r).min(r2_max);
            scratch.keys.clear();
            self.collect(x, r2, &mut scratch.keys);
            let found = scratch.keys.len();
            if found >= k || r2 >= r2_max || r2 == f32::INFINITY {
                break;
            }
            // On a surface the count grows with r²: aim at 1.2·K, at least ×1.25, at most ×4.
            let grow = (1.2 * k as f32 / found.max(1) as f32).sqrt();
            r *= grow.clamp(1.25, 4.0);
        }
        let keys = &mut scratch.keys;
        scratch.previous = None;
        if keys.len() > k {
            // The K-th smallest key; the K photons are those at or below it.
            scratch.select.clear();
            scratch.select.extend_from_slice(keys);
            let kth = *scratch.select.select_nth_unstable(k - 1).1;
            keys.retain(|&key| key <= kth);
        }
        if keys.len() == k {
            let r_k = f32::from_bits((keys.iter().max().expect("k ≥ 1") >> 32) as u32).sqrt();
            scratch.previous = Some((x, r_k));
        }
        for &key in keys.iter() {
            let i = (key & u32::MAX as u64) as usize;
            if decode_octahedral(self.normals[i]).dot(n) < min_cos {
                continue;
            }
            accept(match &self.payloads {
                Payloads::StoredDistance { distance } => distance[i],
                Payloads::NextHitPoint { qx, qy, qz } => {
                    let q = Vec3::new(qx[i], qy[i], qz[i]);
                    if q.x.is_nan() {
                        f32::INFINITY
                    } else {
                        q.distance(x)
                    }
                }
            });
        }
    }

    /// A radius likely to hold `k` photons around `x`: the previous query's K-th distance,
    /// grown by a tenth of how far `x` moved where it moved less than that distance, by a
    /// tenth where it moved further; else the radius of the leaf around `x` scaled to `k`
    /// photons on a surface. (`r_prev + |x − x_prev|` would surely hold K photons, but the
    /// K-th distance changes far less than the step between neighbouring pixels: on `cube`
    /// with 8.5 M photons the tighter radius, with a second pass where it falls short, gathers
    /// 20–30 % more queries per second.)
    fn first_radius(&self, scratch: &GatherScratch, x: Vec3, k: usize) -> f32 {
        if let Some((x_prev, r_prev)) = scratch.previous {
            let moved = x.distance(x_prev);
            // Widened past the rounding of d², so that one pass holds the K photons.
            return if moved <= r_prev {
                (r_prev + 0.1 * moved) * (1.0 + 1e-5)
            } else {
                r_prev * 1.1
            };
        }
        let (start, len) = self.leaf_around(x);
        if len == 0 {
            return f32::INFINITY;
        }
        let far = (start..start + len)
            .map(|i| self.distance2(x, i))
            .fold(0.0f32, f32::max);
        let scale = (k as f32 / len as f32).sqrt().max(1.0);
        let r = far.sqrt() * scale;
        if r > 0.0 {
            r
        } else {
            f32::MIN_POSITIVE.sqrt()
        }
    }

    /// The range of the leaf whose cell holds `x`.
    fn leaf_around(&self, x: Vec3) -> (usize, usize) {
        let (mut node, mut start, mut len) = (0, 0, self.len());
        for level in 0..self.depth {
            let half = len / 2;
            let right_offset = 1 << (self.depth - level - 1);
            if x[self.axes[node] as usize] < self.planes[node] {
                node += 1;
                len = half;
            } else {
                node += right_offset;
                start += half;
                len -= half;
            }
        }
        (start, len)
    }

    /// Squared distance from `x` to photon `i`, as kiddo's `SquaredEuclidean` computes it.
    #[inline(always)]
    fn distance2(&self, x: Vec3, i: usize) -> f32 {
        let (dx, dy, dz) = (x.x - self.x[i], x.y - self.y[i], x.z - self.z[i]);
        dx * dx + dy * dy + dz * dz
    }

    /// Appends the key `(d², index)` of every photon with `d² ≤ r2`, in tree order.
    fn collect(&self, x: Vec3, r2: f32, keys: &mut Vec<u64>) {
        // Cells are skipped only when they lie further than `r` by more than the rounding of
        // d² (relative 6·2⁻²⁴), in f64, where the plane offsets are exact.
        let reach2 = r2 as f64 * (1.0 + 1e-6);
        let query = [x.x as f64, x.y as f64, x.z as f64];
        let mut stack: [(u32, u32, u32, u32, [f64; 3]); 64] = [(0, 0, 0, 0, [0.0; 3]); 64];
        let mut top = 1;
        stack[0] = (0, 0, 0, self.len() as u32, [0.0; 3]);
        while top > 0 {
            top -= 1;
            let (node, level, start, len, offsets) = stack[top];
            let (node, level, start, len) = (node as usize, level, start as usize, len as usize);
            if level == self.depth {
                self.collect_leaf(x, r2, start, len, keys);
                continue;
            }
            let axis = self.axes[node] as usize;
            let delta = query[axis] - self.planes[node] as f64;
            let half = len / 2;
            let left = (node as u32 + 1, level + 1, start as u32, half as u32);
            let right_node = node + (1 << (self.depth - level - 1));
            let right = (
                right_node as u32,
                level + 1,
                (start + half) as u32,
                (len - half) as u32,
            );
            // The far side's cell is at least |delta| away along this axis.
            let rd = offsets.iter().map(|o| o * o).sum::<f64>() - offsets[axis] * offsets[axis];
            let mut far_offsets = offsets;
            far_offsets[axis] = delta.abs();
            let far_in_reach = rd + delta * delta <= reach2;
            // Pushed right first, so that the left subtree is visited first: tree order.
            if delta < 0.0 {
                if far_in_reach {
                    stack[top] = (right.0, right.1, right.2, right.3, far_offsets);
                    top += 1;
                }
                stack[top] = (left.0, left.1, left.2, left.3, offsets);
                top += 1;
            } else {
                stack[top] = (right.0, right.1, right.2, right.3, offsets);
                top += 1;
                if far_in_reach {
                    stack[top] = (left.0, left.1, left.2, left.3, far_offsets);
                    top += 1;
                }
            }
        }
    }

    /// Appends the keys of leaf `start..start + len` within `r2`.
    #[inline(always)]
    fn collect_leaf(&self, x: Vec3, r2: f32, start: usize, len: usize, keys: &mut Vec<u64>) {
        let end = start + len;
        let (xs, ys, zs) = (&self.x[start..end], &self.y[start..end], &self.z[start..end]);
        keys.reserve(len);
        let mut count = keys.len();
        let spare = keys.spare_capacity_mut();
        let mut written = 0;
        for j in 0..len {
            let (dx, dy, dz) = (x.x - xs[j], x.y - ys[j], x.z - zs[j]);
            let d2 = dx * dx + dy * dy + dz * dz;
            spare[written].write(((d2.to_bits() as u64) << 32) | (start + j) as u64);
            written += (d2 <= r2) as usize;
        }
        count += written;
        // SAFETY: the first `written` spare slots were written above.
        unsafe { keys.set_len(count) };
    }
}

/// One worker's gather buffers and its previous query.
#[derive(Default)]
pub struct GatherScratch {
    keys: Vec<u64>,
    select: Vec<u64>,
    /// The previous query's point and K-th distance, where it found K photons.
    previous: Option<(Vec3, f32)>,
}

/// The photons in tree order, with the tree's planes, axes and depth.
#[allow(clippy::type_complexity)]
fn tree_order(photons: &[TracedPhoton]) -> Result<(Vec<Entry>, Vec<f32>, Vec<u8>, u32)> {
    if photons.len() > u32::MAX as usize {
        return Err(Error::invalid(
            "photons",
            "must be at most 4,294,967,295 in one map",
        ));
    }
    let n = photons.len();
    let leaves = n.div_ceil(LEAF).max(1);
    let depth = leaves.next_power_of_two().trailing_zeros();
    let mut entries: Vec<Entry> = photons
        .iter()
        .enumerate()
        .map(|(i, p)| Entry {
            p: p.position.to_array(),
            index: i as u32,
        })
        .collect();
    let internal = (1usize << depth) - 1;
    let (mut planes, mut axes) = (vec![0.0f32; internal], vec![0u8; internal]);
    split(&mut entries, &mut planes, &mut axes, depth);
    Ok((entries, planes, axes, depth))
}

/// Sorts `entries` into tree order: splits at the median of the widest axis, `depth` levels,
/// writing each internal node's plane and axis depth-first. Halves run in parallel; the
/// result does not depend on how.
fn split(entries: &mut [Entry], planes: &mut [f32], axes: &mut [u8], depth: u32) {
    if depth == 0 {
        return;
    }
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for e in entries.iter() {
        for a in 0..3 {
            lo[a] = lo[a].min(e.p[a]);
            hi[a] = hi[a].max(e.p[a]);
        }
    }
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])).then(b.cmp(&a)))
        .unwrap_or(0);
    let half = entries.len() / 2;
    let plane = if entries.is_empty() {
        0.0
    } else {
        let by_axis = |a: &Entry, b: &Entry| a.p[axis].total_cmp(&b.p[axis]).then(a.index.cmp(&b.index));
        if half < entries.len() {
            entries.select_nth_unstable_by(half, by_axis);
            entries[half].p[axis]
        } else {
            f32::INFINITY
        }
    };
    planes[0] = plane;
    axes[0] = axis as u8;
    let (left, right) = entries.split_at_mut(half);
    let subtree = (1usize << (depth - 1)) - 1;
    let (left_planes, right_planes) = planes[1..].split_at_mut(subtree);
    let (left_axes, right_axes) = axes[1..].split_at_mut(subtree);
    let go = |e: &mut [Entry], p: &mut [f32], a: &mut [u8]| split(e, p, a, depth - 1);
    if entries_worth_splitting(left.len() + right.len()) {
        rayon::join(
            || go(left, left_planes, left_axes),
            || go(right, right_planes, right_axes),
        );
    } else {
        go(left, left_planes, left_axes);
        go(right, right_planes, right_axes);
    }
}

/// Whether a node is big enough to split its halves across threads.
fn entries_worth_splitting(len: usize) -> bool {
    len >= 1 << 14
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::random_pair;

    #[test]
    fn bytes_per_photon_is_what_the_map_holds() {
        let photons: Vec<TracedPhoton> = (0..100_000u64)
            .map(|i| {
                let u = random_pair(5, 1, i);
                TracedPhoton {
                    position: Vec3::new(u.x, u.y, (i % 7) as f32),
                    normal: Vec3::Y,
                    direction: Vec3::Z,
                    distance: if i % 3 == 0 { f32::INFINITY } else { 1.0 + u.x },
                }
            })
            .collect();
        for method in [PhotonMethod::StoredDistance, PhotonMethod::NextHitPoint] {
            let map = PhotonMap::build(&photons, method).unwrap();
            let per_photon = map.heap_bytes() as f64 / photons.len() as f64;
            let stated = method.bytes_per_photon() as f64;
            assert!(
                (stated..stated + 0.5).contains(&per_photon),
                "{per_photon} B against {stated} B"
            );
        }
    }

    #[test]
    fn gather_returns_each_methods_distance_and_filters_by_orientation() {
        let photon = |x: f32, normal: Vec3, distance: f32| TracedPhoton {
            position: Vec3::new(x, 0.0, 0.0),
            normal,
            direction: Vec3::Y,
            distance,
        };
        let photons = [
            photon(0.0, Vec3::Y, 2.0),
            photon(0.1, Vec3::NEG_Y, 3.0),
            photon(0.2, Vec3::Y, f32::INFINITY),
        ];
        let k = NonZero::new(8).unwrap();
        let x = Vec3::new(0.05, 0.0, 0.0);
        let collect = |method| {
            let map = PhotonMap::build(&photons, method).unwrap();
            let mut got = vec![];
            let mut scratch = GatherScratch::default();
            map.gather(&mut scratch, x, Vec3::Y, k, f32::INFINITY, 0.9, |d| got.push(d));
            got.sort_by(|a, b| a.partial_cmp(b).unwrap());
            got
        };
        assert_eq!(collect(PhotonMethod::StoredDistance), vec![2.0, f32::INFINITY]);
        let method2 = collect(PhotonMethod::NextHitPoint);
        assert!((method2[0] - Vec3::new(0.0, 2.0, 0.0).distance(x)).abs() < 1e-6);
        assert_eq!(method2[1], f32::INFINITY);
    }
}
