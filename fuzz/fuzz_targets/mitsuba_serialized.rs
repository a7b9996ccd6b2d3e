//! A Mitsuba `.serialized` mesh file through the reader `<shape type="serialized">` uses: its
//! first byte picks the `shape_index` (0 to 3), the rest is the file. Any error is fine; a
//! panic, an abort or an allocation past the fuzzer's limit is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&index, file)) = data.split_first() else { return };
    let path = std::path::Path::new("fuzz.serialized");
    let _ = hmdist::scene::load::load_serialized_bytes(path, file, (index % 4) as usize);
});
