//! The pinhole camera of spec §2.
//!
//! Convention (other tools line up with hmdist pixel for pixel through it):
//! `f = normalize(target − eye)`, `r = normalize(f × up)`, `u = r × f`; pixel (px, py), row 0 at
//! the top, looks along `normalize(f + sx·r + sy·u)` with
//! `sx = (2(px + ½)/W − 1) · tan(fov/2) · W/H` and `sy = (1 − 2(py + ½)/H) · tan(fov/2)`.
//!
//! A **mirrored** camera has `r = normalize(up × f)` instead (`u` unchanged): its picture is
//! the other one's left for right. pbrt's cameras are such, unless their transform reflects
//! (pbrt's camera space is left-handed: a `LookAt` alone gives a frame whose right is
//! `up × f`); hmdist reads them so, and the picture is pbrt's.

use glam::Vec3;

use crate::error::{Error, Result};

/// Where the camera is and what it sees. `fov_y_deg` is the full vertical field of view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// The pinhole: where every primary ray starts.
    pub eye: Vec3,
    /// A point on the view axis: the camera looks along `target − eye`.
    pub target: Vec3,
    /// The world's up direction; need not be perpendicular to the view direction (`u = r × f`).
    pub up: Vec3,
    /// Full vertical field of view, in degrees.
    pub fov_y_deg: f32,
    /// Whether the picture's right is `up × f` rather than `f × up` (see the module docs).
    pub mirrored: bool,
}

/// A camera prepared for one image size: the frame and scale factors of spec §2.
#[derive(Clone, Copy, Debug)]
pub struct CameraRays {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half_fov: f32,
    aspect: f32,
    width: u32,
    height: u32,
}

impl Camera {
    /// Checks that the camera defines a frame: finite, `eye ≠ target`, `up` not along the view
    /// direction, `0 < fov < 180°`.
    pub fn validate(&self) -> Result<()> {
        let finite = self.eye.is_finite() && self.target.is_finite() && self.up.is_finite();
        if !finite || !self.fov_y_deg.is_finite() {
            return Err(Error::scene("the camera has a non-finite coordinate"));
        }
        let f = self.target - self.eye;
        let (Some(f), Some(up)) = (crate::sampling::unit(f), crate::sampling::unit(self.up)) else {
            let what = if f == glam::Vec3::ZERO {
                "eye and target are the same point"
            } else {
                "up vector is zero"
            };
            return Err(Error::scene(format!("the camera's {what}")));
        };
        if f.cross(up).length_squared() < 1e-12 {
            return Err(Error::scene(
                "the camera's up vector is parallel to its view direction",
            ));
        }
        if !(self.fov_y_deg > 0.0 && self.fov_y_deg < 180.0) {
            return Err(Error::scene(format!(
                "the camera's vertical field of view must be between 0 and 180 degrees, not {}",
                self.fov_y_deg
            )));
        }
        Ok(())
    }

    /// The frame for a `width × height` image.
    pub fn rays(&self, width: u32, height: u32) -> CameraRays {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        CameraRays {
            eye: self.eye,
            forward,
            right: if self.mirrored { -right } else { right },
            up: right.cross(forward),
            tan_half_fov: (0.5 * self.fov_y_deg.to_radians()).tan(),
            aspect: width as f32 / height as f32,
            width,
            height,
        }
    }
}

impl CameraRays {
    /// The camera's position, where every primary ray starts.
    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    /// Unit direction through the centre of pixel (px, py), row 0 at the top.
    pub fn pixel_direction(&self, px: u32, py: u32) -> Vec3 {
        self.direction_at(px as f32 + 0.5, py as f32 + 0.5)
    }

    /// Unit direction through image position (x, y) in pixels, (0, 0) the top-left corner.
    pub fn direction_at(&self, x: f32, y: f32) -> Vec3 {
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.tan_half_fov * self.aspect;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.tan_half_fov;
        (self.forward + sx * self.right + sy * self.up).normalize()
    }
}
