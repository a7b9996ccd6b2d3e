//! A stylised human figure, the statue of the procedural scenes (spec §5): fingers, toes, ears
//! and a nose give the thin parts and tight corners of the paper's scene A.
//!
//! Units: about 1.75 scene units tall (read them as metres), standing on y = 0, facing +z, so
//! its left is +x; scale it to taste. About 19,300 triangles whatever the pose.
//! Built from capsules and ellipsoids that overlap at the joints, as a sculptor's armature.

use glam::{Quat, Vec3};

use super::{capsule, ellipsoid};
use crate::scene::Mesh;

/// Points around a limb, a body part, a finger.
const LIMB_SEGMENTS: usize = 24;
const BODY_SEGMENTS: usize = 32;
const FINGER_SEGMENTS: usize = 10;
const TOE_SEGMENTS: usize = 8;

/// Joint angles in radians; arrays are `[left, right]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// Arm lifted sideways from hanging.
    pub arm_raise: [f32; 2],
    /// Arm swung forward from hanging.
    pub arm_swing: [f32; 2],
    pub elbow_bend: [f32; 2],
    /// Bend at each finger joint, toward the palm.
    pub finger_curl: [f32; 2],
    /// Leg swung forward at the hip.
    pub leg_swing: [f32; 2],
    pub knee_bend: [f32; 2],
    /// Head turned toward the figure's left.
    pub head_turn: f32,
}

impl Pose {
    pub const STANDING: Pose = Pose {
        arm_raise: [0.12, 0.12],
        arm_swing: [0.05, 0.05],
        elbow_bend: [0.25, 0.25],
        finger_curl: [0.3, 0.3],
        leg_swing: [0.0, 0.0],
        knee_bend: [0.0, 0.0],
        head_turn: 0.0,
    };
    /// The right hand up, fingers spread open.
    pub const WAVING: Pose = Pose {
        arm_raise: [0.15, 2.4],
        arm_swing: [0.1, 0.2],
        elbow_bend: [0.3, 0.6],
        finger_curl: [0.5, 0.05],
        leg_swing: [0.0, 0.1],
        knee_bend: [0.0, 0.15],
        head_turn: -0.4,
    };
    /// Mid-step: one leg forward, arms swinging against the legs.
    pub const STRIDING: Pose = Pose {
        arm_raise: [0.1, 0.1],
        arm_swing: [0.45, -0.35],
        elbow_bend: [0.6, 0.3],
        finger_curl: [0.6, 0.6],
        leg_swing: [-0.3, 0.35],
        knee_bend: [0.25, 0.1],
        head_turn: 0.2,
    };
    /// Reaching forward with both hands, as if to take something.
    pub const REACHING: Pose = Pose {
        arm_raise: [0.25, 0.25],
        arm_swing: [1.3, 1.1],
        elbow_bend: [0.2, 0.5],
        finger_curl: [0.2, 0.9],
        leg_swing: [0.15, -0.1],
        knee_bend: [0.3, 0.05],
        head_turn: 0.3,
    };
    pub const ALL: [Pose; 4] = [Pose::STANDING, Pose::WAVING, Pose::STRIDING, Pose::REACHING];
}

/// The figure in `pose`, its lowest point on y = 0.
pub fn figure(pose: &Pose) -> Mesh {
    let mut mesh = trunk_and_head(pose.head_turn);
    for (i, side) in [1.0, -1.0].into_iter().enumerate() {
        mesh.append(&arm(pose, i, side));
        mesh.append(&leg(pose, i, side));
    }
    let lowest = mesh.positions.iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
    for p in &mut mesh.positions {
        p.y -= lowest;
    }
    mesh
}

fn part(center: Vec3, radii: Vec3, segments: usize) -> Mesh {
    ellipsoid(center, radii, Quat::IDENTITY, segments, segments * 3 / 4)
}

fn trunk_and_head(head_turn: f32) -> Mesh {
    let pelvis = Vec3::new(0.16, 0.12, 0.1);
    let mut mesh = part(Vec3::new(0.0, 0.97, 0.0), pelvis, BODY_SEGMENTS);
    let chest = Vec3::new(0.175, 0.15, 0.105);
    mesh.append(&part(Vec3::new(0.0, 1.3, 0.01), chest, BODY_SEGMENTS));
    let waist = [Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 1.22, 0.005)];
    mesh.append(&capsule(waist[0], waist[1], 0.115, 0.13, BODY_SEGMENTS));
    let neck = [Vec3::new(0.0, 1.4, 0.0), Vec3::new(0.0, 1.54, 0.01)];
    mesh.append(&capsule(neck[0], neck[1], 0.05, 0.045, LIMB_SEGMENTS));
    let turn = Quat::from_rotation_y(head_turn);
    mesh.append(&head(Vec3::new(0.0, 1.64, 0.01), turn));
    mesh
}

/// A head with a face: nose, eyes, brows, lips, chin and ears, in the head's own frame
/// (centre at the origin, facing +z) turned by `turn`.
fn head(center: Vec3, turn: Quat) -> Mesh {
    let at = |p: Vec3| center + turn * p;
    let feature = |c: [f32; 3], radii: Vec3, segments: usize| {
        ellipsoid(at(c.into()), radii, turn, segments, segments * 3 / 4)
    };
    let ridge = |a: [f32; 3], b: [f32; 3], radii: (f32, f32), segments: usize| {
        capsule(at(a.into()), at(b.into()), radii.0, radii.1, segments)
    };
    let skull = Vec3::new(0.078, 0.108, 0.095);
    let mut mesh = feature([0.0; 3], skull, BODY_SEGMENTS);
    let nose = ([0.0, 0.0, 0.085], [0.0, -0.032, 0.108]);
    mesh.append(&ridge(nose.0, nose.1, (0.011, 0.014), FINGER_SEGMENTS + 2));
    let chin = Vec3::new(0.035, 0.026, 0.03);
    mesh.append(&feature([0.0, -0.086, 0.058], chin, 16));
    let lips = ([-0.02, -0.054, 0.086], [0.02, -0.054, 0.086]);
    mesh.append(&ridge(lips.0, lips.1, (0.008, 0.008), FINGER_SEGMENTS));
    for x in [1.0, -1.0] {
        mesh.append(&feature([0.03 * x, 0.018, 0.078], Vec3::splat(0.014), 12));
        let brow = ([0.012 * x, 0.042, 0.088], [0.05 * x, 0.045, 0.075]);
        mesh.append(&ridge(brow.0, brow.1, (0.007, 0.007), FINGER_SEGMENTS));
        let ear = Vec3::new(0.01, 0.03, 0.018);
        mesh.append(&feature([0.078 * x, 0.0, -0.005], ear, 12));
    }
    mesh
}

/// A jointed chain of tapering capsules: an arm, a leg, a finger.
struct Limb<'a> {
    /// Lengths of the links from the root outward.
    lengths: &'a [f32],
    /// Radius at the root and at the tip.
    radii: (f32, f32),
    segments: usize,
}

const ARM: Limb = Limb {
    lengths: &[0.29, 0.26],
    radii: (0.05, 0.028),
    segments: LIMB_SEGMENTS,
};
const LEG: Limb = Limb {
    lengths: &[0.43, 0.42],
    radii: (0.075, 0.036),
    segments: LIMB_SEGMENTS,
};
const THUMB: Limb = Limb {
    lengths: &[0.035, 0.03],
    radii: (0.011, 0.0085),
    segments: FINGER_SEGMENTS,
};

impl Limb<'_> {
    /// Appends the limb from `root`, its first link along −y turned by `rotation`, each
    /// further link turned by `bend` at its joint; returns the tip.
    fn append(&self, mesh: &mut Mesh, root: Vec3, mut rotation: Quat, bend: Quat) -> Vec3 {
        let total: f32 = self.lengths.iter().sum();
        let radius = |t: f32| self.radii.0 + (self.radii.1 - self.radii.0) * t / total;
        let (mut start, mut done) = (root, 0.0);
        for &length in self.lengths {
            let end = start + rotation * Vec3::new(0.0, -length, 0.0);
            let (r0, r1) = (radius(done), radius(done + length));
            mesh.append(&capsule(start, end, r0, r1, self.segments));
            (start, done) = (end, done + length);
            rotation *= bend;
        }
        start
    }
}

/// Shoulder, upper arm, forearm and hand for side `i` (`side` +1 left, −1 right).
fn arm(pose: &Pose, i: usize, side: f32) -> Mesh {
    let shoulder = Vec3::new(side * 0.19, 1.42, 0.0);
    let mut mesh = part(shoulder, Vec3::splat(0.058), LIMB_SEGMENTS);
    let swing = Quat::from_rotation_x(-pose.arm_swing[i]);
    let upper = swing * Quat::from_rotation_z(side * pose.arm_raise[i]);
    let elbow = Quat::from_rotation_x(-pose.elbow_bend[i]);
    let wrist = ARM.append(&mut mesh, shoulder, upper, elbow);
    mesh.append(&hand(wrist, upper * elbow, side, pose.finger_curl[i]));
    mesh
}

/// A hand at `wrist`: fingers along the hand's −y, palm facing −x·side, thumb toward +z.
fn hand(wrist: Vec3, rotation: Quat, side: f32, curl: f32) -> Mesh {
    let at = |p: Vec3| wrist + rotation * p;
    let palm = Vec3::new(0.018, 0.05, 0.042);
    let mut mesh = ellipsoid(at(Vec3::new(0.0, -0.05, 0.0)), palm, rotation, 20, 14);
    let bend = Quat::from_rotation_z(-side * curl);
    // (offset toward the thumb, length): index, middle, ring and little finger.
    let fingers = [(0.027, 0.075), (0.009, 0.085), (-0.009, 0.08), (-0.027, 0.062)];
    for (offset, length) in fingers {
        let finger = Limb {
            lengths: &[0.45 * length, 0.3 * length, 0.25 * length],
            radii: (0.0085, 0.0065),
            segments: FINGER_SEGMENTS,
        };
        let spread = Quat::from_rotation_x(-1.5 * offset);
        let knuckle = at(Vec3::new(0.0, -0.088, offset));
        finger.append(&mut mesh, knuckle, rotation * spread * bend, bend);
    }
    let thumb = Vec3::new(-side * 0.25, -0.6, 0.75).normalize();
    let thumb = Quat::from_rotation_arc(Vec3::NEG_Y, thumb);
    let bend = Quat::from_rotation_z(-side * 0.6 * curl);
    let root = at(Vec3::new(-side * 0.006, -0.025, 0.035));
    THUMB.append(&mut mesh, root, rotation * thumb, bend);
    mesh
}

/// Hip, thigh, shin and foot for side `i` (`side` +1 left, −1 right).
fn leg(pose: &Pose, i: usize, side: f32) -> Mesh {
    let hip = Vec3::new(side * 0.095, 0.93, 0.0);
    let mut mesh = Mesh::new();
    let thigh = Quat::from_rotation_x(-pose.leg_swing[i]);
    let knee = Quat::from_rotation_x(pose.knee_bend[i]);
    let ankle = LEG.append(&mut mesh, hip, thigh, knee);
    mesh.append(&foot(ankle, side));
    mesh
}

/// A foot kept level under `ankle`, with five toes, the big toe on the inside.
fn foot(ankle: Vec3, side: f32) -> Mesh {
    let sole = Vec3::new(0.045, 0.035, 0.115);
    let mut mesh = part(ankle + Vec3::new(0.0, -0.035, 0.055), sole, LIMB_SEGMENTS);
    let floor = ankle.y - 0.07;
    // (offset outward from the ankle, radius, length): big toe to little toe.
    let toes = [
        (-0.03, 0.012, 0.045),
        (-0.011, 0.0085, 0.038),
        (0.004, 0.0075, 0.034),
        (0.017, 0.007, 0.03),
        (0.029, 0.0065, 0.026),
    ];
    for (k, (offset, radius, length)) in toes.into_iter().enumerate() {
        let back = 0.008 * k as f32;
        let start = Vec3::new(ankle.x + side * offset, floor + radius, ankle.z + 0.13 - back);
        let end = start + Vec3::new(0.0, -0.15 * radius, length);
        mesh.append(&capsule(start, end, radius, 0.9 * radius, TOE_SEGMENTS));
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_pose_stands_on_the_floor_at_human_height() {
        for pose in Pose::ALL {
            let mesh = figure(&pose);
            mesh.validate().unwrap();
            let b = mesh.bounds();
            assert_eq!(b.min.y, 0.0);
            assert!(b.max.y > 1.6 && b.max.y < 2.3, "height {}", b.max.y);
            assert!(b.max.x - b.min.x < 1.8);
        }
    }

    #[test]
    fn a_figure_has_about_twenty_thousand_triangles_whatever_the_pose() {
        let counts = Pose::ALL.map(|p| figure(&p).triangle_count());
        assert!(counts.iter().all(|&n| n == counts[0]));
        assert!((18_000..22_000).contains(&counts[0]), "{}", counts[0]);
    }
}
