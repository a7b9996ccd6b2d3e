//! `hall`: the analogue of the paper's scene B (spec §5).
//!
//! A hall 40 × 12 × 25 units (read them as metres; y up, the floor on y = 0, x from −20 to
//! 20, z from −12.5 to 12.5) with a large window cut into its +z wall: the hall is not
//! closed, and rays leaving through the window escape. Two colonnades of fluted columns
//! carry arcades down its length; statues on plinths stand in the aisles; tables and
//! chairs, chandeliers, sculptures and a staircase up to a balustraded gallery at the +x end
//! fill it. About 610,000 triangles (the paper's scene B has 612,613). A spot light outside
//! shines in through the window; the camera sees only part of the hall.

use std::f32::consts::{FRAC_PI_2, PI};

use glam::{Affine3A, Quat, Vec3};

use super::shapes::architecture::{arch, column, straight_balustrade, Staircase};
use super::shapes::figure::{figure, Pose};
use super::shapes::furniture::{chair, chandelier, table};
use super::shapes::ornaments::{box_cluster, bumpy_sphere, pedestal, TorusKnot};
use super::shapes::{cuboid, placement, room};
use crate::scene::{Bounds, Camera, Mesh, Scene, SpotLight};

/// The hall's inside.
pub const HALL: Bounds = Bounds {
    min: Vec3::new(-20.0, 0.0, -12.5),
    max: Vec3::new(20.0, 12.0, 12.5),
};

/// The window: the box whose shell cells are left out of the +z wall.
pub const WINDOW: Bounds = Bounds {
    min: Vec3::new(-4.0, 2.5, 12.4),
    max: Vec3::new(4.0, 9.5, 12.6),
};

/// Grey per unit of H: the median H of the camera's view, about 7, is mid grey.
pub const DISPLAY_SCALE: f32 = 0.07;

/// The colonnades run along x at z = ±COLONNADE_Z, a column every COLUMN_SPACING.
const COLONNADE_Z: f32 = 6.5;
const COLUMN_SPACING: f32 = 5.0;
const COLUMN_HEIGHT: f32 = 7.0;
const COLUMN_RADIUS: f32 = 0.45;
/// The gallery floor at the +x end.
const GALLERY_X: f32 = 16.5;
const GALLERY_Y: f32 = 4.2;

/// The `hall` scene: the hall, its furnishings, camera, light and display scale.
pub fn hall() -> Scene {
    let mut mesh = hall_shell();
    mesh.append(&window_bars());
    for side in [-1.0, 1.0] {
        mesh.append(&colonnade(side * COLONNADE_Z));
    }
    mesh.append(&gallery_and_stairs());
    mesh.append(&statues());
    mesh.append(&dining_tables());
    mesh.append(&sculptures());
    mesh.append(&chandeliers());
    Scene {
        name: "hall".into(),
        mesh,
        camera: Camera {
            eye: Vec3::new(-18.5, 5.5, -2.5),
            target: Vec3::new(0.0, 2.0, 4.0),
            up: Vec3::Y,
            fov_y_deg: 60.0,
            mirrored: false,
        },
        light: Some(SpotLight {
            position: Vec3::new(0.0, 11.0, 17.0),
            direction: Vec3::new(0.0, -11.0, -14.0).normalize(),
            cone_half_angle_deg: 18.0,
        }),
        display_scale: DISPLAY_SCALE,
        notes: Default::default(),
    }
}

/// Walls, floor and ceiling in half-unit cells sharing their edges, less the window.
pub fn hall_shell() -> Mesh {
    room::shell(HALL, 0.5, &[WINDOW])
}

/// Two mullions and a transom in the window opening, inside the wall's plane.
fn window_bars() -> Mesh {
    let (min, max) = (WINDOW.min, WINDOW.max);
    let z = (HALL.max.z - 0.15, HALL.max.z);
    let mut mesh = Mesh::new();
    for x in [-4.0 / 3.0, 4.0 / 3.0] {
        mesh.append(&cuboid(
            Vec3::new(x - 0.06, min.y, z.0),
            Vec3::new(x + 0.06, max.y, z.1),
        ));
    }
    let y = 0.5 * (min.y + max.y) + 1.0;
    mesh.append(&cuboid(
        Vec3::new(min.x, y - 0.06, z.0),
        Vec3::new(max.x, y + 0.06, z.1),
    ));
    mesh
}

/// A row of columns along x at `z`, arches springing between their capitals and a beam on
/// top of the arches.
fn colonnade(z: f32) -> Mesh {
    let mut mesh = Mesh::new();
    let one = column(COLUMN_HEIGHT, COLUMN_RADIUS, 20);
    let count = 8;
    let first = -0.5 * COLUMN_SPACING * (count - 1) as f32;
    for k in 0..count {
        let x = first + k as f32 * COLUMN_SPACING;
        mesh.append_transformed(&one, placement(Vec3::new(x, 0.0, z), 0.0, 1.0));
    }
    let rise = 0.5 * COLUMN_SPACING;
    let span = arch(rise - COLUMN_RADIUS, COLUMN_RADIUS, 0.6, 32);
    for k in 0..count - 1 {
        let x = first + (k as f32 + 0.5) * COLUMN_SPACING;
        let at = Vec3::new(x, COLUMN_HEIGHT, z);
        mesh.append_transformed(&span, Affine3A::from_translation(at));
    }
    let top = COLUMN_HEIGHT + rise;
    let half = -first + COLUMN_SPACING * 0.2;
    mesh.append(&cuboid(
        Vec3::new(-half, top, z - 0.4),
        Vec3::new(half, top + 0.6, z + 0.4),
    ));
    mesh
}

/// A gallery across the +x end at height GALLERY_Y, reached by a straight flight from the
/// nave, with a balustrade along its edge on both sides of the stair head.
fn gallery_and_stairs() -> Mesh {
    let inset = 0.01;
    let mut mesh = cuboid(
        Vec3::new(GALLERY_X, GALLERY_Y - 0.25, HALL.min.z + inset),
        Vec3::new(HALL.max.x - inset, GALLERY_Y, HALL.max.z - inset),
    );
    let stairs = Staircase {
        steps: 14,
        rise: GALLERY_Y / 14.0,
        run: 0.45,
        width: 2.4,
        rail_height: 0.9,
    };
    let foot = Vec3::new(GALLERY_X - stairs.top().z, 0.0, 0.0);
    mesh.append_transformed(&stairs.mesh(), placement(foot, FRAC_PI_2, 1.0));
    let edge = GALLERY_X + 0.15;
    let stair_head = 0.5 * stairs.width + 0.2;
    for side in [-1.0, 1.0] {
        let from = Vec3::new(edge, GALLERY_Y, side * stair_head);
        let to = Vec3::new(edge, GALLERY_Y, side * (HALL.max.z - 0.3));
        mesh.append(&straight_balustrade(from, to, 1.0, 0.3));
    }
    mesh
}

/// Statues on plinths: three in each aisle facing the nave and two on the gallery facing the
/// stairs, in turn through the poses, each turned a little differently.
fn statues() -> Mesh {
    let aisles = [-15.0, -5.0, 5.0]
        .into_iter()
        .flat_map(|x| [(Vec3::new(x, 0.0, -10.0), 0.0), (Vec3::new(x, 0.0, 10.0), PI)]);
    let gallery = [-7.5, 7.5].map(|z| (Vec3::new(18.5, GALLERY_Y, z), -FRAC_PI_2));
    let poses: Vec<Mesh> = Pose::ALL.iter().map(figure).collect();
    let mut mesh = Mesh::new();
    for (k, (floor, facing)) in aisles.chain(gallery).enumerate() {
        let plinth = if floor.y > 0.0 { 0.6 } else { 1.0 };
        let corner = Vec3::new(0.7, 0.0, 0.7);
        mesh.append(&cuboid(floor - corner, floor + corner + plinth * Vec3::Y));
        let turn = facing + 0.3 * (k as f32 - 3.5);
        let at = placement(floor + plinth * Vec3::Y, turn, 1.4);
        mesh.append_transformed(&poses[k % poses.len()], at);
    }
    mesh
}

/// Four tables down the west end of the nave, each with six chairs.
fn dining_tables() -> Mesh {
    let one_table = table(2.4, 1.0, 0.78);
    let one_chair = chair();
    let mut mesh = Mesh::new();
    for x in [-15.0, -9.5] {
        for z in [-2.6, 2.6] {
            let centre = Vec3::new(x, 0.0, z);
            mesh.append_transformed(&one_table, placement(centre, 0.0, 1.0));
            for (k, dx) in [-0.75, 0.0, 0.75].into_iter().enumerate() {
                for (s, side) in [-1.0, 1.0].into_iter().enumerate() {
                    // Every other chair pulled out a little.
                    let pulled = [0.75, 0.85][(k + s) % 2];
                    let seat = centre + Vec3::new(dx, 0.0, side * pulled);
                    let facing = if side > 0.0 { PI } else { 0.0 };
                    mesh.append_transformed(&one_chair, placement(seat, facing, 1.0));
                }
            }
        }
    }
    mesh
}

/// Torus knots, bumpy spheres and box clusters on pedestals down the middle of the nave.
fn sculptures() -> Mesh {
    let mut mesh = Mesh::new();
    let knot = TorusKnot {
        p: 3,
        q: 5,
        radius: 0.9,
        winding_radius: 0.35,
        tube_radius: 0.09,
    };
    let knot = knot.mesh(800, 10);
    let stand = pedestal(1.2, 0.6, 48);
    for (k, x) in [-3.0, 6.5].into_iter().enumerate() {
        let at = Vec3::new(x, 0.0, -1.5 + 3.0 * k as f32);
        mesh.append_transformed(&stand, placement(at, 0.0, 1.0));
        let upright = Quat::from_rotation_y(0.7 * k as f32) * Quat::from_rotation_x(FRAC_PI_2);
        let centre = at + Vec3::new(0.0, 1.2 + 1.2, 0.0);
        mesh.append_transformed(&knot, Affine3A::from_rotation_translation(upright, centre));
    }
    let spheres = [(1.5, 2.5), (-17.5, 10.0), (12.0, -10.0)];
    let stand = pedestal(0.8, 0.8, 48);
    for (k, (x, z)) in spheres.into_iter().enumerate() {
        let at = Vec3::new(x, 0.0, z);
        mesh.append_transformed(&stand, placement(at, 0.0, 1.0));
        let sphere = bumpy_sphere(1.0, 0.25, 5, 20 + k as u32);
        let centre = at + Vec3::new(0.0, 0.8 + 0.85, 0.0);
        mesh.append_transformed(&sphere, Affine3A::from_translation(centre));
    }
    for (k, x) in [-1.0, 12.5].into_iter().enumerate() {
        let boxes = box_cluster(14, 10, 0.25, 0.04, 1.5, 40 + k as u32);
        let at = placement(Vec3::new(x, 0.0, 9.5), 0.3 * k as f32, 1.0);
        mesh.append_transformed(&boxes, at);
    }
    mesh
}

/// Three chandeliers hanging from the ceiling over the nave.
fn chandeliers() -> Mesh {
    let one = chandelier(3.5, 1.1, 12);
    let mut mesh = Mesh::new();
    for x in [-12.0, -4.0, 4.0] {
        mesh.append_transformed(&one, Affine3A::from_translation(Vec3::new(x, HALL.max.y, 0.0)));
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::super::shapes::checks::{inside, unshared_edges, zero_area_triangles};
    use super::*;

    #[test]
    fn the_hall_has_about_as_many_triangles_as_scene_b() {
        let n = hall().mesh.triangle_count();
        assert!((590_000..=630_000).contains(&n), "{n} triangles");
    }

    #[test]
    fn the_hall_is_closed_except_for_its_window() {
        let shell = hall_shell();
        let rim = unshared_edges(&shell);
        // The 8 × 7 window in half-unit cells: a perimeter of 2 · (16 + 14) cell edges.
        assert_eq!(rim.len(), 60);
        for (a, b) in rim {
            for p in [shell.positions[a as usize], shell.positions[b as usize]] {
                let on_rim = p.z == HALL.max.z && p.cmpge(WINDOW.min).all() && p.cmple(WINDOW.max).all();
                assert!(on_rim, "{p} is an open edge away from the window");
            }
        }
    }

    #[test]
    fn every_object_is_inside_the_hall() {
        assert_eq!(hall().mesh.bounds(), HALL);
    }

    #[test]
    fn the_camera_is_inside_and_sees_only_part_of_the_hall() {
        let camera = hall().camera;
        assert!(inside(HALL, camera.eye));
        let forward = (camera.target - camera.eye).normalize();
        let half_fov = 0.5 * camera.fov_y_deg.to_radians();
        let corners = (0..8).map(|i| {
            Vec3::select(
                glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0),
                HALL.max,
                HALL.min,
            )
        });
        let unseen = corners
            .filter(|&c| forward.angle_between(c - camera.eye) > half_fov)
            .count();
        assert!(unseen >= 4, "{unseen} corners out of view");
    }

    #[test]
    fn the_light_is_outside_and_its_whole_cone_enters_through_the_window() {
        let light = hall().light.unwrap();
        assert!(!inside(HALL, light.position));
        assert!((light.direction.length() - 1.0).abs() < 1e-6);
        let (u, v) = light.direction.any_orthonormal_pair();
        let half = light.cone_half_angle_deg.to_radians();
        for k in 0..64 {
            let around = std::f32::consts::TAU * k as f32 / 64.0;
            let rim = half.cos() * light.direction + half.sin() * (around.cos() * u + around.sin() * v);
            let t = (HALL.max.z - light.position.z) / rim.z;
            let hit = light.position + t * rim;
            assert!(t > 0.0 && hit.x > WINDOW.min.x && hit.x < WINDOW.max.x, "{hit}");
            assert!(hit.y > WINDOW.min.y && hit.y < WINDOW.max.y, "{hit}");
        }
    }

    #[test]
    fn the_geometry_is_valid_and_has_no_zero_area_triangles() {
        let scene = hall();
        scene.validate().unwrap();
        assert_eq!(zero_area_triangles(&scene.mesh), 0);
    }
}
