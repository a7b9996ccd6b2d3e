//! An EXR file through the reader `hmdist diff` uses. Any error is fine; a panic, an abort or
//! running out of memory is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = hmdist::image::exr::decode(data, std::path::Path::new("fuzz/input.exr"));
});
