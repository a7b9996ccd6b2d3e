//! Every input that once made a fuzz target (`fuzz/`, README "Reliability") fail, through the
//! same entry point: each must now give an error, not a panic and not a result.
//!
//! `tests/data/fuzz-regressions/<format>/NAME` is one input; `NAME.expect`, beside it, holds a
//! piece of the error message it must give: the message of the check that now refuses the
//! input where there is one, so that a panic caught by the loaders' guard ("the parser
//! failed") does not pass for it. Formats: `obj`, `ply`, `gltf`, `glb`, `toml`
//! (meshes looked for in `tests/data/fuzz-regressions/toml/`), `exr`, `npy`, `csv`.

use std::path::{Path, PathBuf};

use hmdist::error::Result;

/// The entry point of each format, given the file's name (extension included) and bytes.
fn load(format: &str, name: &Path, bytes: &[u8]) -> Result<()> {
    match format {
        "obj" | "ply" | "gltf" | "glb" | "toml" => hmdist::scene::load::load_bytes(name, bytes).map(drop),
        "exr" => hmdist::image::exr::decode(bytes, name).map(drop),
        "npy" | "csv" => hmdist::points::file::parse_rows(name, bytes).map(drop),
        other => panic!("unknown format folder {other}"),
    }
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz-regressions")
}

#[test]
fn every_input_that_once_failed_a_fuzz_target_is_refused_with_an_error() {
    let mut checked = 0;
    let mut formats: Vec<_> = std::fs::read_dir(root())
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    formats.sort();
    for folder in formats {
        let format = folder.file_name().unwrap().to_str().unwrap().to_string();
        let mut inputs: Vec<_> = std::fs::read_dir(&folder)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_none_or(|e| e != "expect"))
            .filter(|p| !p.is_dir())
            .collect();
        inputs.sort();
        for input in inputs {
            let expect =
                input.with_file_name(format!("{}.expect", input.file_name().unwrap().to_string_lossy()));
            let expected = std::fs::read_to_string(&expect)
                .unwrap_or_else(|_| panic!("{} has no .expect beside it", input.display()));
            let bytes = std::fs::read(&input).unwrap();
            // Named as the format's file in the input's folder (a TOML's meshes are beside it).
            let name = input.with_extension(&format);
            let what = input.display();
            match load(&format, &name, &bytes) {
                Ok(()) => panic!("{what} loaded"),
                Err(e) => {
                    let message = e.to_string();
                    assert!(message.contains(expected.trim()), "{what}: {message}");
                }
            }
            checked += 1;
        }
    }
    assert!(checked > 0, "no regression inputs found");
}
