//! The photon map: compact per-photon payloads and a kd-tree over photon positions (kiddo's
//! immutable tree), with what each method needs and nothing else (SPEC §3.3).
//!
//! Per photon: the kd-tree holds the position (3 × f32) and an index (u32); the payload holds
//! the surface normal for the orientation filter, octahedral-encoded in 2 × u16 (error below
//! 0.01°, far inside the filter's 25.8° cone), and
//! - method I: the distance to the next hit (f32, `+inf` when the path escaped): 8 B;
//! - method II: the next-hit point `q = x + d·ω` (3 × f32, NaN when escaped): 16 B.
//!
//! That is 24 B per photon for method I and 32 B for method II, tree included (the paper
//! needed 46 and 58 B).

use std::num::NonZero;

use glam::{Vec2, Vec3};
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use kiddo::SquaredEuclidean;

use super::trace::TracedPhoton;
use crate::error::{Error, Result};

/// Points per kd-tree leaf bucket.
const BUCKET: usize = 32;

/// Which distance a gathered photon contributes (SPEC §3.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhotonMethod {
    /// Method I: the photon's own stored distance `d_j`.
    StoredDistance,
    /// Method II: the distance from the query point to the photon's next hit, `|q_j − x|`.
    NextHitPoint,
}

impl PhotonMethod {
    /// The name the CLI and the report use (`photon1`, `photon2`).
    pub fn name(self) -> &'static str {
        match self {
            PhotonMethod::StoredDistance => "photon1",
            PhotonMethod::NextHitPoint => "photon2",
        }
    }

    /// Payload bytes per photon, tree excluded.
    pub fn payload_bytes(self) -> usize {
        match self {
            PhotonMethod::StoredDistance => std::mem::size_of::<StoredDistance>(),
            PhotonMethod::NextHitPoint => std::mem::size_of::<NextHitPoint>(),
        }
    }

    /// Bytes per photon of the finished map: payload plus the tree's position and index.
    pub fn bytes_per_photon(self) -> usize {
        self.payload_bytes() + TREE_BYTES_PER_PHOTON
    }

    /// Peak bytes while building a map of `photons`: traced photons, positions handed to the
    /// tree, the tree and the payloads.
    pub fn peak_build_bytes(self, photons: usize) -> u128 {
        let per_photon = std::mem::size_of::<TracedPhoton>() + 12 + self.bytes_per_photon();
        photons as u128 * per_photon as u128
    }
}

/// The kd-tree's share: 3 × f32 position and a u32 index per photon (its splitting planes add
/// about 4 bytes per bucket of 32, under 0.2 B per photon).
const TREE_BYTES_PER_PHOTON: usize = 16;

#[derive(Clone, Copy)]
struct StoredDistance {
    normal: [u16; 2],
    distance: f32,
}

#[derive(Clone, Copy)]
struct NextHitPoint {
    normal: [u16; 2],
    next_hit: [f32; 3],
}

enum Payloads {
    StoredDistance(Vec<StoredDistance>),
    NextHitPoint(Vec<NextHitPoint>),
}

/// Photons in a kd-tree, with each method's payload.
pub struct PhotonMap {
    tree: ImmutableKdTree<f32, u32, 3, BUCKET>,
    payloads: Payloads,
}

impl PhotonMap {
    /// Builds the map for `method` from traced photons.
    pub fn build(photons: &[TracedPhoton], method: PhotonMethod) -> Result<PhotonMap> {
        if photons.len() > u32::MAX as usize {
            return Err(Error::invalid(
                "photons",
                "must be at most 4,294,967,295 in one map",
            ));
        }
        let positions: Vec<[f32; 3]> = photons.iter().map(|p| p.position.to_array()).collect();
        let tree = ImmutableKdTree::new_from_slice(&positions);
        let payloads = match method {
            PhotonMethod::StoredDistance => Payloads::StoredDistance(
                photons
                    .iter()
                    .map(|p| StoredDistance {
                        normal: encode_octahedral(p.normal),
                        distance: p.distance,
                    })
                    .collect(),
            ),
            PhotonMethod::NextHitPoint => Payloads::NextHitPoint(
                photons
                    .iter()
                    .map(|p| NextHitPoint {
                        normal: encode_octahedral(p.normal),
                        next_hit: if p.distance.is_finite() {
                            (p.position + p.distance * p.direction).to_array()
                        } else {
                            [f32::NAN; 3]
                        },
                    })
                    .collect(),
            ),
        };
        Ok(PhotonMap { tree, payloads })
    }

    /// Calls `accept(distance)` for each of the `k` photons nearest `x` (within `max_radius`)
    /// whose normal `n_j` satisfies `n_j · n ≥ min_cos`; `distance` is method I's `d_j` or
    /// method II's `|q_j − x|` (`+inf` for escaped paths).
    pub fn gather(
        &self,
        x: Vec3,
        n: Vec3,
        k: NonZero<usize>,
        max_radius: f32,
        min_cos: f32,
        mut accept: impl FnMut(f32),
    ) {
        let r2 = if max_radius.is_finite() {
            max_radius * max_radius
        } else {
            f32::INFINITY
        };
        let found = self
            .tree
            .nearest_n_within::<SquaredEuclidean>(&x.to_array(), r2, k, false);
        let facing = |normal: [u16; 2]| decode_octahedral(normal).dot(n) >= min_cos;
        match &self.payloads {
            Payloads::StoredDistance(p) => {
                for f in found {
                    let photon = p[f.item as usize];
                    if facing(photon.normal) {
                        accept(photon.distance);
                    }
                }
            }
            Payloads::NextHitPoint(p) => {
                for f in found {
                    let photon = p[f.item as usize];
                    if facing(photon.normal) {
                        let q = Vec3::from_array(photon.next_hit);
                        accept(if q.x.is_nan() {
                            f32::INFINITY
                        } else {
                            q.distance(x)
                        });
                    }
                }
            }
        }
    }
}

/// A unit vector as two 16-bit octahedral coordinates (Cigolle et al. 2014).
pub fn encode_octahedral(v: Vec3) -> [u16; 2] {
    let p = Vec2::new(v.x, v.y) / (v.x.abs() + v.y.abs() + v.z.abs());
    let p = if v.z < 0.0 {
        (Vec2::ONE - Vec2::new(p.y, p.x).abs()) * Vec2::new(p.x.signum(), p.y.signum())
    } else {
        p
    };
    let q = |c: f32| ((c.clamp(-1.0, 1.0) * 0.5 + 0.5) * 65535.0).round() as u16;
    [q(p.x), q(p.y)]
}

/// The unit vector of [`encode_octahedral`].
pub fn decode_octahedral(e: [u16; 2]) -> Vec3 {
    let p = Vec2::new(e[0] as f32, e[1] as f32) / 65535.0 * 2.0 - Vec2::ONE;
    let z = 1.0 - p.x.abs() - p.y.abs();
    let t = (-z).max(0.0);
    let x = p.x - t.copysign(p.x);
    let y = p.y - t.copysign(p.y);
    Vec3::new(x, y, z).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::random_pair;

    #[test]
    fn octahedral_normals_round_trip_within_a_hundredth_of_a_degree() {
        for i in 0..100_000 {
            let u = random_pair(3, 0, i);
            let z = 2.0 * u.x - 1.0;
            let r = (1.0 - z * z).sqrt();
            let v = Vec3::new(r * (6.2831855 * u.y).cos(), r * (6.2831855 * u.y).sin(), z);
            let back = decode_octahedral(encode_octahedral(v));
            // The angle from |v × back| (a cosine this close to 1 rounds to 1 in f32).
            let angle = v.cross(back).length().asin().to_degrees();
            assert!(angle < 0.01 && back.dot(v) > 0.0, "{v} -> {back}: {angle}°");
        }
        for v in [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z] {
            assert!(decode_octahedral(encode_octahedral(v)).dot(v) > 0.99999);
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
            map.gather(x, Vec3::Y, k, f32::INFINITY, 0.9, |d| got.push(d));
            got.sort_by(|a, b| a.partial_cmp(b).unwrap());
            got
        };
        assert_eq!(collect(PhotonMethod::StoredDistance), vec![2.0, f32::INFINITY]);
        let method2 = collect(PhotonMethod::NextHitPoint);
        assert!((method2[0] - Vec3::new(0.0, 2.0, 0.0).distance(x)).abs() < 1e-6);
        assert_eq!(method2[1], f32::INFINITY);
    }
}
