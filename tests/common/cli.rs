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
    args.extend_from_slice(&TINY);
    args.extend_from_slice(extra);
    args
}

/// The JSON file at `path`.
pub fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}
