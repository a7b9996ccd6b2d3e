//! A .toml scene description through the loader `hmdist render --scene FILE.toml` uses. Its
//! meshes are looked for in `fuzz/seeds/meshes/` (where `triangle.obj` is), so that a
//! description naming it loads a mesh. Any error is fine; a panic or an abort is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("seeds/meshes/scene.toml");
    let _ = hmdist::scene::load::load_bytes(&path, data);
});
