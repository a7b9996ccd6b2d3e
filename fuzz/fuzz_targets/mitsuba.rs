//! A Mitsuba 3 scene through the loader `hmdist render --scene FILE.xml` uses. Its includes
//! and meshes are looked for in `fuzz/seeds/meshes/`, so that a scene naming `triangle.obj`
//! loads it. Any error is fine; a panic or an abort is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("seeds/meshes/scene.xml");
    let _ = hmdist::scene::load::load_bytes(&path, data);
});
