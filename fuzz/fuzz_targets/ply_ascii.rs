//! An ascii .ply file (header and data fuzzed) through the loader `hmdist render --scene
//! FILE.ply` uses. Any error is fine; a panic, an abort or running out of memory is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = hmdist::scene::load::load_bytes(std::path::Path::new("fuzz/input.ply"), data);
});
