//! A binary .ply file through the loader `hmdist render --scene FILE.ply` uses. The first byte
//! picks one of three fixed headers (little or big endian; float or double coordinates; uchar
//! or int list lengths) and the rest is the payload, so that the fuzzer spends its time in the
//! binary reader; a first byte of 255 passes the whole input as the file instead.
#![no_main]

use libfuzzer_sys::fuzz_target;

const HEADERS: [&str; 3] = [
    "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n\
     property float y\nproperty float z\nelement face 2\n\
     property list uchar int vertex_indices\nend_header\n",
    "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\n\
     property double y\nproperty double z\nproperty uchar red\nelement face 2\n\
     property list uchar uint vertex_indices\nend_header\n",
    "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
     property float y\nproperty float z\nelement face 1\n\
     property list int short vertex_index\nelement edge 1\nproperty int vertex1\nend_header\n",
];

fuzz_target!(|data: &[u8]| {
    let Some((&first, payload)) = data.split_first() else {
        return;
    };
    let file = match HEADERS.get(first as usize % 4) {
        Some(header) if first != 255 => [header.as_bytes(), payload].concat(),
        _ => data.to_vec(),
    };
    let _ = hmdist::scene::load::load_bytes(std::path::Path::new("fuzz/input.ply"), &file);
});
