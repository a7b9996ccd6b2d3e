//! `cube`: the analogue of the paper's scene A (spec §5).
//!
//! A closed, watertight cube room 10 units a side (read them as metres; y up, the floor on
//! y = 0, x and z from −5 to 5) holding five finely detailed objects: a statue of a waving
//! figure, a torus knot on a pedestal, a staircase with balusters, a bumpy sphere on a low
//! pedestal and a cluster of small boxes. About 77,000 triangles (the paper's scene A has
//! 76,787). A spot light under the centre of the ceiling points down; the camera stands in
//! the room, so every primary ray hits something.

use std::f32::consts::PI;

use glam::{Affine3A, Quat, Vec3};

use super::shapes::architecture::Staircase;
use super::shapes::figure::{figure, Pose};
use super::shapes::ornaments::{box_cluster, bumpy_sphere, pedestal, TorusKnot};
use super::shapes::{placement, room};
use crate::scene::{Bounds, Camera, Mesh, Scene, SpotLight};

/// The room's inside: a cube of side 10 standing on the floor y = 0.
pub const ROOM: Bounds = Bounds {
    min: Vec3::new(-5.0, 0.0, -5.0),
    max: Vec3::new(5.0, 10.0, 5.0),
};

/// Grey per unit of H: the median H of the camera's view, about 3.3, is mid grey; the
/// middle of an open wall (H ≈ 7.8) is white.
pub const DISPLAY_SCALE: f32 = 0.15;

/// The `cube` scene: the room, its five objects, camera, light and display scale.
pub fn cube() -> Scene {
    let mut mesh = room_shell();
    let statue = figure(&Pose::WAVING);
    mesh.append_transformed(&statue, placement(Vec3::new(-0.6, 0.0, -1.0), 0.15, 2.0));
    mesh.append(&knot_on_pedestal());
    let stairs = Staircase {
        steps: 8,
        rise: 0.35,
        run: 0.45,
        width: 1.6,
        rail_height: 0.9,
    };
    mesh.append_transformed(&stairs.mesh(), placement(Vec3::new(-3.8, 0.0, 0.6), PI, 1.0));
    mesh.append(&sphere_on_pedestal());
    let boxes = box_cluster(12, 10, 0.2, 0.03, 1.2, 5);
    mesh.append_transformed(&boxes, placement(Vec3::new(0.6, 0.0, -3.6), 0.2, 1.0));
    Scene {
        name: "cube".into(),
        mesh,
        camera: Camera {
            eye: Vec3::new(0.3, 4.3, 4.7),
            target: Vec3::new(0.0, 1.6, -1.6),
            up: Vec3::Y,
            fov_y_deg: 60.0,
            mirrored: false,
        },
        light: Some(SpotLight {
            position: Vec3::new(0.0, ROOM.max.y - 0.2, 0.0),
            direction: Vec3::NEG_Y,
            cone_half_angle_deg: 55.0,
        }),
        display_scale: DISPLAY_SCALE,
        notes: Default::default(),
    }
}

/// Walls, floor and ceiling in half-unit cells sharing their edges: 4,800 triangles.
pub fn room_shell() -> Mesh {
    room::shell(ROOM, 0.5, &[])
}

/// A trefoil knot standing upright on a turned pedestal at the back right.
fn knot_on_pedestal() -> Mesh {
    let at = Vec3::new(2.9, 0.0, -2.7);
    let height = 1.3;
    let mut mesh = pedestal(height, 0.65, 48);
    mesh.transform(placement(at, 0.0, 1.0));
    let knot = TorusKnot {
        p: 2,
        q: 3,
        radius: 1.0,
        winding_radius: 0.45,
        tube_radius: 0.13,
    };
    let upright = Quat::from_rotation_y(-0.5) * Quat::from_rotation_x(0.5 * PI);
    let centre = at + Vec3::new(0.0, height + 1.5, 0.0);
    mesh.append_transformed(
        &knot.mesh(800, 12),
        Affine3A::from_rotation_translation(upright, centre),
    );
    mesh
}

/// A rough sphere of radius 1.1 resting on a low pedestal at the front right.
fn sphere_on_pedestal() -> Mesh {
    let at = Vec3::new(2.3, 0.0, 0.0);
    let mut mesh = pedestal(0.5, 0.75, 48);
    mesh.transform(placement(at, 0.0, 1.0));
    let sphere = bumpy_sphere(1.1, 0.2, 5, 11);
    mesh.append_transformed(
        &sphere,
        Affine3A::from_translation(at + Vec3::new(0.0, 0.5 + 0.88, 0.0)),
    );
    mesh
}

#[cfg(test)]
mod tests {
    use super::super::shapes::checks::{inside, unshared_edges, zero_area_triangles};
    use super::*;

    #[test]
    fn the_cube_has_about_as_many_triangles_as_scene_a() {
        let n = cube().mesh.triangle_count();
        assert!((75_000..=79_000).contains(&n), "{n} triangles");
    }

    #[test]
    fn the_room_is_closed_every_edge_of_its_shell_in_two_triangles() {
        let shell = room_shell();
        assert_eq!(shell.triangle_count(), 4_800);
        assert_eq!(unshared_edges(&shell), vec![]);
    }

    #[test]
    fn every_object_is_inside_the_room() {
        assert_eq!(cube().mesh.bounds(), ROOM);
    }

    #[test]
    fn the_camera_and_the_light_are_inside_the_room() {
        let scene = cube();
        assert!(inside(ROOM, scene.camera.eye));
        let light = scene.light.unwrap();
        assert!(inside(ROOM, light.position));
        assert_eq!(light.direction, Vec3::NEG_Y);
        assert!(
            ROOM.max.y - light.position.y < 0.5,
            "the light is just under the ceiling"
        );
    }

    #[test]
    fn the_geometry_is_valid_and_has_no_zero_area_triangles() {
        let scene = cube();
        scene.validate().unwrap();
        assert_eq!(zero_area_triangles(&scene.mesh), 0);
    }
}
