//! Photon tracing (spec §3.3): diffuse paths from the spot light or the camera, photons stored
//! at the start point of each bounce.
//!
//! Path `i` draws its random numbers from stream `i` of a counter-based generator, and paths
//! are taken in index order until exactly `P` photons are stored, so the stored set is the
//! same whatever the thread count.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::accel::{Hit, RayCaster};
use crate::error::{Error, Result};
use crate::sampling::{hemisphere, random_pair, Frame, Weighting};
use crate::scene::{CameraRays, SpotLight};

/// Keeps photon streams apart from the pixels' gather streams under the same seed.
const PHOTON_STREAM_KEY: u64 = 0x5048_4F54_4F4E_0001;
/// Paths traced per parallel batch.
const BATCH: u64 = 1 << 16;

/// Where photon paths start.
#[derive(Clone, Copy, Debug)]
pub enum PhotonSource {
    /// The scene's spot light: directions uniform over its cone.
    Light(SpotLight),
    /// The camera: rays through uniformly random image positions.
    Camera(CameraRays, u32, u32),
}

/// How paths bounce and end.
#[derive(Clone, Copy, Debug)]
pub struct PathRules {
    /// A path ends at its `max_bounces`-th surface interaction (paper: 20, 80).
    pub max_bounces: u32,
    /// Probability of ending at each interaction before that (paper: 0.2).
    pub absorption: f32,
}

/// One stored photon: the start point of a bounce, the surface's normal there (oriented
/// against the arriving path), the direction it left in and the distance to the next hit
/// (`+inf` if it escaped).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TracedPhoton {
    /// Where the bounce starts: a surface point, in scene units.
    pub position: Vec3,
    /// The surface's unit normal there, facing the side the path arrived from.
    pub normal: Vec3,
    /// The unit direction the path leaves in.
    pub direction: Vec3,
    /// Distance along `direction` to the next hit, in scene units; `+inf` if it escaped.
    pub distance: f32,
}

/// The photons of one tracing run, in path order, and its counts.
pub struct PhotonTrace {
    /// The stored photons, in path order.
    pub photons: Vec<TracedPhoton>,
    /// Paths traced until the budget was filled, those that missed the scene included.
    pub paths_traced: u64,
    /// Stored photons whose continuation escaped the scene.
    pub escaped: u64,
    /// Paths whose emission ray missed the scene (they store no photon).
    pub missed_emissions: u64,
}

impl PhotonTrace {
    /// The rays of the paths that filled the map: one emission ray per path and one
    /// continuation ray per stored photon (rays of a path beyond the budget not counted).
    pub fn rays_cast(&self) -> u64 {
        self.paths_traced + self.photons.len() as u64
    }

    /// Of [`PhotonTrace::rays_cast`], those that met nothing.
    pub fn escaped_rays(&self) -> u64 {
        self.missed_emissions + self.escaped
    }
}

/// Traces paths in index order until exactly `budget` photons are stored.
pub fn trace_photons<R: RayCaster>(
    accel: &R,
    source: &PhotonSource,
    rules: PathRules,
    budget: usize,
    seed: u64,
    progress: &dyn Fn(usize),
) -> Result<PhotonTrace> {
    let mut photons: Vec<TracedPhoton> = Vec::with_capacity(budget);
    let (mut paths_traced, mut missed_emissions) = (0u64, 0u64);
    while photons.len() < budget {
        crate::interrupt::check()?;
        let batch: Vec<Option<Vec<TracedPhoton>>> = (paths_traced..paths_traced + BATCH)
            .into_par_iter()
            .map(|path| trace_path(accel, source, rules, seed, path))
            .collect();
        for path in batch {
            paths_traced += 1;
            let Some(path) = path else {
                missed_emissions += 1;
                continue;
            };
            let room = budget - photons.len();
            photons.extend(path.into_iter().take(room));
            if photons.len() == budget {
                break;
            }
        }
        if photons.is_empty() {
            return Err(Error::scene(format!(
                "no photon path from the {} hits the scene ({paths_traced} paths traced)",
                match source {
                    PhotonSource::Light(_) => "spot light",
                    PhotonSource::Camera(..) => "camera",
                }
            )));
        }
        progress(photons.len());
    }
    let escaped = photons.iter().filter(|p| p.distance.is_infinite()).count() as u64;
    Ok(PhotonTrace {
        photons,
        paths_traced,
        escaped,
        missed_emissions,
    })
}

/// The photons of path `path`; `None` if its emission ray misses the scene.
fn trace_path<R: RayCaster>(
    accel: &R,
    source: &PhotonSource,
    rules: PathRules,
    seed: u64,
    path: u64,
) -> Option<Vec<TracedPhoton>> {
    let mut counter = 0u64;
    let mut next_random = || {
        counter += 1;
        random_pair(seed ^ PHOTON_STREAM_KEY, path, counter)
    };
    let (origin, direction) = source.emit(next_random());
    let mut photons = Vec::new();
    let mut hit = accel.closest_hit(origin, direction, f32::INFINITY, None)?;
    let mut arriving = direction;
    for _ in 0..rules.max_bounces {
        let u = next_random();
        if u.x < rules.absorption {
            break;
        }
        let normal = if hit.normal.dot(arriving) > 0.0 {
            -hit.normal
        } else {
            hit.normal
        };
        let leaving = Frame::from_normal(normal).to_world(hemisphere(Weighting::Cosine, next_random()));
        let from = Hit { normal, ..hit };
        let next = accel.closest_hit(
            from.spawn_origin(leaving),
            leaving,
            f32::INFINITY,
            Some(hit.triangle),
        );
        photons.push(TracedPhoton {
            position: hit.point,
            normal,
            direction: leaving,
            distance: next.map_or(f32::INFINITY, |n| n.t),
        });
        match next {
            Some(n) => hit = n,
            None => break,
        }
        arriving = leaving;
    }
    Some(photons)
}

impl PhotonSource {
    /// A ray from the source for the uniforms `u`.
    fn emit(&self, u: Vec2) -> (Vec3, Vec3) {
        match *self {
            PhotonSource::Light(light) => {
                // Uniform over the cone's solid angle: cos θ uniform in [cos α, 1].
                let cos_alpha = light.cone_half_angle_deg.to_radians().cos();
                let cos_theta = 1.0 - u.x * (1.0 - cos_alpha);
                let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
                let (sin_phi, cos_phi) = crate::sincos::sin_cos(2.0 * PI * u.y);
                let local = Vec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta);
                (
                    light.position,
                    Frame::from_normal(light.direction).to_world(local),
                )
            }
            PhotonSource::Camera(camera, width, height) => {
                let direction = camera.direction_at(u.x * width as f32, u.y * height as f32);
                (camera.eye(), direction)
            }
        }
    }
}
