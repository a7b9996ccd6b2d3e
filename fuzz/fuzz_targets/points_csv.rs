//! A .csv point file through the reader `hmdist points` uses. Any error is fine; a panic, an
//! abort or running out of memory is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = hmdist::points::file::parse_rows(std::path::Path::new("fuzz/input.csv"), data);
});
