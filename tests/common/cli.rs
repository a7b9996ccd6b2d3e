//! Running the `hmdist` binary in a scratch folder.

use std::path::Path;
use std::process::{Command, Output};

use super::Scratch;

/// Runs `hmdist args...` in `dir`.
pub fn hmdist(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_hmdist"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("hmdist runs")
}

/// Runs `hmdist args...` in `dir` and asserts that it succeeds; returns its stdout.
pub fn hmdist_ok(dir: &Path, args: &[&str]) -> String {
    let out = hmdist(dir, args);
    assert!(
        out.status.success(),
        "hmdist {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Files in `dir` apart from the inputs the test wrote.
pub fn outputs(dir: &Path, inputs: &[&str]) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !inputs.contains(&n.as_str()))
        .collect();
    names.sort();
    names
}

/// Runs `hmdist args...` in a folder holding `files`, and checks the refusal: exit status 2,
/// no panic, a message that mentions `message`, and no file left behind. Returns stderr.
pub fn refuses(case: &str, files: &[(&str, &[u8])], args: &[&str], message: &str) -> String {
    let dir = Scratch::new(case);
    for (name, bytes) in files {
        dir.write(name, bytes);
    }
    let out = hmdist(dir.path(), args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(
        out.status.code(),
        Some(2),
        "{case}: exit status, stderr: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{case}: panicked: {stderr}");
    assert!(
        stderr.to_lowercase().contains(&message.to_lowercase()),
        "{case}: message should mention '{message}', got: {stderr}"
    );
    let names: Vec<&str> = files.iter().map(|(n, _)| *n).collect();
    let left = outputs(dir.path(), &names);
    assert!(left.is_empty(), "{case}: left files behind: {left:?}");
    stderr
}

/// A tiny render: 8 × 8 pixels, 4 rays.
pub const TINY: [&str; 4] = ["--size", "8x8", "--rays", "4"];

/// `render --quiet` at the [`TINY`] size with `extra` arguments.
pub fn render_args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["render", "--quiet"];
    // `--rays` only where the method reads it: another method refuses it.
    let method = extra.windows(2).find(|w| w[0] == "--method").map(|w| w[1]);
    match method {
        None | Some("gather" | "cubemap" | "irradiance") => args.extend_from_slice(&TINY),
        Some(_) => args.extend_from_slice(&TINY[..2]),
    }
    args.extend_from_slice(extra);
    args
}

/// The JSON file at `path`.
pub fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// A 4 × 4.2 floor and nothing else (`floor.obj`, no camera), and `floor.toml` placing it: seen
/// straight down from height 3 with a 90° field of view, a spot light above it whose cone lands
/// on the floor, display scale 0.1. On an 8 × 8 image pixel column px looks at
/// x = 3·((px + ½)/4 − 1), on the floor (|x| ≤ 2) for px = 1 … 6, and so for rows: 6 × 6 =
/// [`SURFACE_PIXELS`], 28 background. (Not square, so that no pixel lands on the edge its two
/// triangles share, where a gather ray can hit the other triangle at t ≈ 1e-7.)
pub fn floor_scene(test: &str) -> Scratch {
    let dir = Scratch::new(test);
    dir.write("floor.obj", FLOOR_OBJ);
    dir.write("floor.toml", FLOOR_TOML);
    dir
}

/// Surface pixels of an 8 × 8 image of [`floor_scene`].
pub const SURFACE_PIXELS: u64 = 36;
/// `l_diag` of [`floor_scene`].
pub const FLOOR_DIAGONAL: f64 = 5.8; // √(4² + 4.2²)

const FLOOR_OBJ: &str = "v -2 0 -2.2\nv 2 0 -2.2\nv 2 0 2\nv -2 0 2\nf 1 2 3\nf 1 3 4\n";
const FLOOR_TOML: &str = r#"[[mesh]]
path = "floor.obj"
[camera]
eye = [0, 3, 0]
target = [0, 0, 0]
up = [0, 0, 1]
fov_y_deg = 90.0
[light]
position = [0, 1, 0]
direction = [0, -1, 0]
cone_half_angle_deg = 30.0
[display]
scale = 0.1
"#;
