//! `contrib/slurm` on a real (one-node) Slurm: a 4-task array renders the shards, a dependent
//! job merges them, and the merged EXR is byte for byte the one-machine render's; an
//! experiment spread over an array gives the one-machine table. It starts
//! daemons (munged, slurmctld, slurmd; as root), so it runs only where HMDIST_SLURM_TEST is
//! set: `.ci/run` sets it and installs `slurm-wlm` and `munge`.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::cli::hmdist_ok;
use common::Scratch;

/// The one-node cluster under a folder, stopped when dropped.
struct Cluster(PathBuf);

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new(script("local-cluster.sh"))
            .args(["stop"])
            .arg(&self.0)
            .status();
    }
}

fn script(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("contrib/slurm")
        .join(name)
}

#[test]
fn a_four_task_slurm_array_renders_what_one_machine_renders() {
    if std::env::var_os("HMDIST_SLURM_TEST").is_none() {
        common::skip(
            "a_four_task_slurm_array_renders_what_one_machine_renders",
            "set HMDIST_SLURM_TEST=1 (as root, with slurm-wlm and munge) to run the Slurm test",
            None,
        );
        return;
    }
    let dir = Scratch::new("slurm");
    let state = dir.join("cluster");
    let start = Command::new(script("local-cluster.sh"))
        .arg("start")
        .arg(&state)
        .output()
        .unwrap();
    let _cluster = Cluster(state.clone());
    assert!(
        start.status.success(),
        "{}",
        String::from_utf8_lossy(&start.stderr)
    );
    // Submits a contrib/slurm script and waits for its jobs.
    let submit = |name: &str, args: &[&str]| {
        let out = Command::new(script(name))
            .args(args)
            .current_dir(dir.path())
            .env("SLURM_CONF", state.join("slurm.conf"))
            .env("HMDIST", env!("CARGO_BIN_EXE_hmdist"))
            .env("HMDIST_SLURM_WAIT", "1")
            .output()
            .unwrap();
        let said = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(out.status.success(), "{name}: {said}");
    };
    let render = ["--size", "48x32", "--rays", "16", "--aov", "rays"];
    let mut args = vec!["4", "parts", "merged.exr"];
    args.extend(render);
    submit("render.sh", &args);
    let mut one = vec!["render", "--quiet", "--out", "one.exr"];
    one.extend(render);
    hmdist_ok(dir.path(), &one);
    let bytes = |name: &str| std::fs::read(dir.join(name)).unwrap();
    assert!(
        bytes("merged.exr") == bytes("one.exr"),
        "the merged EXR differs from one machine's"
    );
    let parts = std::fs::read_dir(dir.join("parts")).unwrap().count();
    assert_eq!(parts, 4 * 3, "four parts, each an EXR, a PNG and a JSON");

    // An experiment: a 3-task array renders the images, a dependent job writes the report,
    // whose table is the one-machine run's.
    submit("experiment.sh", &["3", "table1", "spread", "--scene", "slab"]);
    hmdist_ok(
        dir.path(),
        &[
            "experiment",
            "table1",
            "--quiet",
            "--scene",
            "slab",
            "--out",
            "one",
        ],
    );
    let table = |folder: &str| std::fs::read_to_string(dir.join(folder).join("table1.csv")).unwrap();
    assert_eq!(table("spread"), table("one"));
    assert!(dir.join("spread").join("index.html").exists());
}
