//! The spot light that light-sourced photons start from (spec §3.3).

use glam::Vec3;

/// A point light emitting uniformly into a cone around `direction` (unit length).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotLight {
    /// The point the light emits from.
    pub position: Vec3,
    /// The cone's axis, unit length.
    pub direction: Vec3,
    /// Angle between the axis and the cone's edge, in degrees (0 < angle ≤ 180).
    pub cone_half_angle_deg: f32,
}
