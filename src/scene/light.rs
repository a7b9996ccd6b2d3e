//! The spot light that light-sourced photons start from (SPEC §3.3).

use glam::Vec3;

/// A point light emitting uniformly into a cone around `direction` (unit length).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotLight {
    pub position: Vec3,
    pub direction: Vec3,
    pub cone_half_angle_deg: f32,
}
