//! The built-in scenes are the same triangles on every machine (spec §5): each is pinned by a
//! hash of its triangles' corners, computed here independently of hmdist's own hashing.
//!
//! A change to a generator that moves any corner by one bit changes its hash. If such a change
//! is intended, the images of that scene change too: update the pin in the same commit and say
//! so. If a pin fails on one machine only, the generator depends on the platform (e.g. on a
//! libm's `sin`), which spec §5 forbids.

use hmdist::scene::procedural::{builtin, BUILTIN_NAMES};

/// FNV-1a, 64-bit, over the little-endian bits of every corner of every triangle, in order.
fn triangle_hash(name: &str) -> (usize, u64) {
    let mesh = builtin(name).unwrap().mesh;
    let hash = (0..mesh.triangle_count())
        .flat_map(|i| mesh.triangle(i))
        .flat_map(|corner| corner.to_array())
        .flat_map(|x| x.to_bits().to_le_bytes())
        .fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
            (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
        });
    (mesh.triangle_count(), hash)
}

#[test]
fn every_built_in_scene_is_the_same_triangles_as_when_it_was_pinned() {
    let pinned: [(&str, usize, u64); 5] = [
        ("cube", 77_188, 0x8ad2_24a6_283a_decb),
        ("hall", 607_596, 0x5344_04bf_fa21_fec7),
        ("sphere", 327_680, 0x2679_c1fd_77ee_0755),
        ("slab", 4, 0x87d2_f9a8_ca9f_6cbd),
        ("dome", 262_144, 0x0bf3_1330_b670_887b),
    ];
    assert_eq!(
        pinned.map(|p| p.0),
        BUILTIN_NAMES,
        "every built-in scene is pinned"
    );
    let found: Vec<(&str, usize, u64)> = BUILTIN_NAMES
        .iter()
        .map(|&name| {
            let (triangles, hash) = triangle_hash(name);
            (name, triangles, hash)
        })
        .collect();
    for (name, triangles, hash) in &found {
        println!("(\"{name}\", {triangles}, 0x{hash:016x}),");
    }
    assert_eq!(found, pinned);
}
