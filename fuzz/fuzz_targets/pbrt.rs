//! A pbrt-v4 scene through the loader `hmdist render --scene FILE.pbrt` uses. Its includes and
//! PLY meshes are looked for in `fuzz/seeds/meshes/`, so that a scene naming `triangle.obj`'s
//! neighbours loads them. Any error is fine; a panic or an abort is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("seeds/meshes/scene.pbrt");
    let _ = hmdist::scene::load::load_bytes(&path, data);
});
