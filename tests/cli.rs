//! The `hmdist` command end to end: bad input exits 2 with a message and leaves no file;
//! TOML scenes follow the camera convention of spec §2 exactly.

mod common;

use common::cli::{hmdist, hmdist_ok, outputs, read_json, refuses, render_args};
use common::Scratch;
use glam::DVec3;
use std::process::Command;

#[test]
fn bad_parameters_exit_2_with_a_message_and_no_output() {
    refuses("size0", &[], &["render", "--size", "0x0"], "0x0");
    refuses("sizegarbage", &[], &["render", "--size", "big"], "WIDTHxHEIGHT");
    refuses("rays0", &[], &["render", "--rays", "0"], "--rays");
    refuses(
        "maxdist",
        &[],
        &render_args(&["--max-distance=-1"]),
        "--max-distance",
    );
    refuses("threads0", &[], &render_args(&["--threads", "0"]), "--threads");
    refuses("method", &[], &render_args(&["--method", "magic"]), "magic");
}

#[test]
fn flags_that_cannot_work_are_refused_before_anything_is_made() {
    // More threads than 4 per CPU only slow a render down; tens of thousands take the machine
    // (issue #51: 17,000 threads, load 1,700, a panic). 1,000 is beyond any CI machine's 4 × CPUs.
    assert!(std::thread::available_parallelism().unwrap().get() * 4 < 1000);
    refuses(
        "threads-huge",
        &[],
        &render_args(&["--threads", "1000"]),
        "--threads 1000 is more than 4 per CPU",
    );
    // A flag nothing reads is refused by name (spec §8): the AO radius without the ao AOV.
    refuses(
        "ao-radius-unread",
        &[],
        &render_args(&["--ao-radius", "1"]),
        "--ao-radius is read only by the ao AOV",
    );
    refuses(
        "ao-radius-unread-adaptive",
        &[],
        &[
            "render",
            "--quiet",
            "--size",
            "8x8",
            "--method",
            "adaptive",
            "--ao-radius",
            "1",
        ],
        "--ao-radius is read only by the ao AOV",
    );
    // An output named for another format than it holds.
    refuses(
        "exr-as-png",
        &[],
        &render_args(&["--out", "a.png", "--png", "b.png"]),
        "a.png: is named .png but would hold EXR",
    );
    refuses(
        "png-as-jpg",
        &[],
        &render_args(&["--png", "a.jpg"]),
        "a.jpg: is named .jpg but would hold PNG",
    );
    // Coordinates float32 geometry cannot hold are named as such, not as a camera problem.
    refuses(
        "huge-coordinates",
        &[("big.obj", b"v 0 0 0\nv 1e30 0 0\nv 0 1e30 0\nf 1 2 3\n")],
        &render_args(&["--scene", "big.obj"]),
        "too far out for float32 geometry",
    );
    // A run refused for its flags creates no output folder.
    refuses(
        "experiment-size0",
        &[],
        &[
            "experiment",
            "table1",
            "--size",
            "0",
            "--plan",
            "--quiet",
            "--out",
            "o",
        ],
        "--size must be at least 1",
    );
    // An output folder whose `cache` is a file is named by that file, not by the folder.
    let dir = Scratch::new("experiment-cache-file");
    std::fs::create_dir(dir.join("o")).unwrap();
    dir.write("o/cache", "not a folder");
    let table1 = [
        "experiment",
        "table1",
        "--scene",
        "slab",
        "--size",
        "8",
        "--quiet",
        "--out",
        "o",
    ];
    let out = hmdist(dir.path(), &table1);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("o/cache")
            && stderr.contains("is not a folder: the experiments keep their image cache there"),
        "{stderr}"
    );
    assert_eq!(std::fs::read(dir.join("o/cache")).unwrap(), b"not a folder");
    // A plan writes its plan and leaves no empty image cache behind.
    let dir = Scratch::new("plan-no-cache");
    let plan = [
        "experiment",
        "table1",
        "--scene",
        "slab",
        "--size",
        "8",
        "--plan",
        "--quiet",
        "--out",
        "o",
    ];
    let out = hmdist(dir.path(), &plan);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(dir.join("o/plan.json").exists());
    assert!(!dir.join("o/cache").exists(), "an empty o/cache left by the plan");
    // A negative value, spaced or not, gets the message about the value, not clap's
    // "unexpected argument '-1'".
    for (flag, value, message) in [
        ("--scale", "-1", "--scale must be a positive number, not -1"),
        ("--max-distance", "-1", "--max-distance must be positive, not -1"),
        ("--seed", "-1", "invalid value '-1' for '--seed"),
    ] {
        let stderr = refuses("negative", &[], &render_args(&[flag, value]), message);
        assert!(!stderr.contains("unexpected argument"), "{stderr}");
    }
    let size = ["render", "--quiet", "--rays", "4", "--size", "-8x8"];
    refuses(
        "negative-size",
        &[],
        &size,
        "'-8' in '-8x8' is not a whole number",
    );
}

#[test]
fn no_output_lands_on_an_input_a_device_or_what_a_failed_run_would_replace() {
    let dir = Scratch::new("cli-inputs-kept");
    let run = |args: &[&str]| hmdist(dir.path(), args);
    let refused = |args: &[&str], message: &str| {
        let out = run(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(message), "{args:?}: {stderr}");
    };
    hmdist_ok(dir.path(), &["scene", "export", "sphere", "s.obj"]);
    let scene = std::fs::read(dir.join("s.obj")).unwrap();
    std::os::unix::fs::symlink("s.obj", dir.join("link.obj")).unwrap();
    fn render<'a>(extra: &[&'a str]) -> Vec<&'a str> {
        [&["render", "--quiet", "--size", "8x8", "--rays", "4"], extra].concat()
    }
    // 1. An output that is an input, by its name or through a link, is refused.
    let is_input = "is an input of this command";
    refused(&render(&["--scene", "s.obj", "--out", "s.obj"]), is_input);
    refused(&render(&["--scene", "s.obj", "--json", "s.obj"]), is_input);
    refused(
        &render(&["--scene", "link.obj", "--out", "s.obj"]),
        "is the same file as the input link.obj",
    );
    std::fs::write(dir.join("p.csv"), "0 0 0 0 0 1\n").unwrap();
    refused(&["points", "--scene", "cube", "p.csv", "p.csv"], is_input);
    hmdist_ok(dir.path(), &render(&["--out", "x.exr"]));
    hmdist_ok(dir.path(), &render(&["--seed", "2", "--out", "r.exr"]));
    let image = std::fs::read(dir.join("x.exr")).unwrap();
    refused(&["diff", "r.exr", "x.exr", "--png", "x.exr"], is_input);
    for k in 0..2 {
        hmdist_ok(
            dir.path(),
            &render(&["--shard", &format!("{k}/2"), "--out", &format!("p{k}.exr")]),
        );
    }
    let part = std::fs::read(dir.join("p1.json")).unwrap();
    refused(&["merge", "p1.exr", "p0.exr", "p1.exr"], is_input);
    refused(
        &["merge", "out.exr", "p0.exr", "p1.exr", "--json", "p1.json"],
        is_input,
    );
    assert_eq!(
        std::fs::read(dir.join("s.obj")).unwrap(),
        scene,
        "the scene is intact"
    );
    assert_eq!(
        std::fs::read(dir.join("x.exr")).unwrap(),
        image,
        "the image under test is intact"
    );
    assert_eq!(
        std::fs::read(dir.join("p1.json")).unwrap(),
        part,
        "the part's report is intact"
    );

    // 4. A run that fails leaves the earlier outputs as they were.
    let old_png = std::fs::read(dir.join("x.png")).unwrap();
    std::fs::remove_file(dir.join("x.json")).unwrap();
    std::fs::create_dir(dir.join("x.json")).unwrap();
    refused(
        &render(&["--seed", "3", "--out", "x.exr"]),
        "x.json: is a directory",
    );
    assert_eq!(std::fs::read(dir.join("x.exr")).unwrap(), image);
    assert_eq!(std::fs::read(dir.join("x.png")).unwrap(), old_png);

    // 6. A device is never renamed over (as root the test makes one; elsewhere /dev/null
    // stands in, which no render may replace either).
    let null = dir.join("null");
    let made = std::process::Command::new("mknod")
        .arg(&null)
        .args(["c", "1", "3"])
        .status();
    let device = if made.is_ok_and(|s| s.success()) {
        "null".to_string()
    } else {
        println!("mknod not permitted here: /dev/null stands in for the device node");
        "/dev/null".to_string()
    };
    refused(
        &render(&["--out", "n.exr", "--png", &device]),
        "is not a regular file",
    );
    let device_path = dir.join(&device); // an absolute path stays as it is
    assert!(
        !std::fs::metadata(&device_path).unwrap().is_file(),
        "{device} is still a device"
    );

    // 7. A scene that is a FIFO, or a link to /dev/zero, is refused at once (no hang, no
    // endless read).
    let fifo = std::ffi::CString::new(dir.join("fifo.obj").to_str().unwrap()).unwrap();
    // SAFETY: a NUL-terminated path and a mode.
    assert_eq!(unsafe { libc::mkfifo(fifo.as_ptr(), 0o600) }, 0);
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.obj")).unwrap();
    for scene in ["fifo.obj", "zero.obj"] {
        refused(
            &render(&["--scene", scene, "--out", "f.exr"]),
            "is not a regular file",
        );
    }
    let left: Vec<String> = common::cli::outputs(dir.path(), &[])
        .into_iter()
        .filter(|n| n.starts_with('.') || n.starts_with("f.") || n.starts_with("n."))
        .collect();
    assert!(left.is_empty(), "no temporary or partial output: {left:?}");
}

/// Asserts that `hmdist ARGS`, one of whose outputs is `read` (a file it reads), is refused
/// as one that would overwrite it (exit 2) and leaves `read` holding `before`.
fn refused_unchanged(dir: &std::path::Path, args: &[&str], read: &str, before: &[u8]) {
    let out = hmdist(dir, args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(stderr.contains("would overwrite it"), "{args:?}: {stderr}");
    assert_eq!(
        std::fs::read(dir.join(read)).unwrap(),
        before,
        "{args:?}: {read} changed"
    );
}

/// The files `hmdist ARGS` reads in `dir`, as the code that opens them logs them
/// (`HMDIST_READS`), each once; the command must succeed.
fn files_read_by(dir: &std::path::Path, args: &[&str]) -> Vec<String> {
    let log = dir.join("reads.log");
    let _ = std::fs::remove_file(&log);
    let out = Command::new(env!("CARGO_BIN_EXE_hmdist"))
        .args(args)
        .current_dir(dir)
        .env("HMDIST_READS", &log)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut reads: Vec<String> = std::fs::read_to_string(&log)
        .unwrap_or_default()
        .lines()
        .map(String::from)
        .collect();
    reads.sort();
    reads.dedup();
    reads
}

/// The promise above as a property: for every command that writes, the files it reads are
/// found by the code that opens them (`HMDIST_READS` logs each path read), and each of them
/// named as each of the command's outputs is refused, exit 2, and left as it was.
#[test]
fn no_command_writes_over_any_file_it_reads() {
    let dir = common::cli::floor_scene("reads-property");
    // A TOML scene of two meshes, one OBJ and one PLY: both are read through the scene.
    dir.write(
        "box.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         -0.5 1 -0.5\n0.5 1 -0.5\n0 1 0.5\n3 0 1 2\n",
    );
    let toml = std::fs::read_to_string(dir.join("floor.toml")).unwrap();
    dir.write("s.toml", format!("{toml}[[mesh]]\npath = \"box.ply\"\n"));
    let tiny = ["--quiet", "--scene", "s.toml", "--size", "8x8"];
    let setup: [&[&str]; 7] = [
        &["render", "--rays", "4", "--out", "h.exr"],
        &["render", "--rays", "4", "--seed", "2", "--out", "h2.exr"],
        &[
            "render",
            "--rays",
            "4",
            "--method",
            "irradiance",
            "--out",
            "e.exr",
        ],
        &["render", "--rays", "4", "--shard", "0/2", "--out", "part0.exr"],
        &["render", "--rays", "4", "--shard", "1/2", "--out", "part1.exr"],
        &["photons", "build", "--photons", "2000", "--out", "m.map"],
        &["scene", "export", "s.toml", "x.obj"],
    ];
    for args in setup {
        let mut args = args.to_vec();
        if args[0] != "scene" {
            args.extend(tiny);
        }
        hmdist_ok(dir.path(), &args);
    }
    dir.write("p.csv", "0 0 0 0 1 0\n1 0 1 0 1 0\n");

    // Each command with its outputs as placeholders (@out, @png, @json, @diff, @csv, @obj).
    let cases: [(&[&str], &[&str]); 10] = [
        (
            &[
                "render", "--rays", "4", "--out", "@out", "--png", "@png", "--json", "@json",
            ],
            &["@out", "@png", "@json"],
        ),
        (
            &[
                "render",
                "--rays",
                "4",
                "--aov",
                "rays",
                "--png-aov",
                "rays",
                "@diff",
                "--out",
                "@out",
            ],
            &["@diff"],
        ),
        (
            &[
                "render",
                "--method",
                "photon2",
                "--photons",
                "2000",
                "--photon-map",
                "m.map",
                "--out",
                "@out",
                "--json",
                "@json",
            ],
            &["@out", "@json"],
        ),
        (
            &[
                "cache",
                "--rays",
                "4",
                "--spacing",
                "oracle",
                "--oracle",
                "h.exr",
                "--reference",
                "e.exr",
                "--out",
                "@out",
                "--png",
                "@png",
                "--json",
                "@json",
                "--diff-png",
                "@diff",
            ],
            &["@out", "@png", "@json", "@diff"],
        ),
        (
            &[
                "cache",
                "--rays",
                "4",
                "--spacing",
                "hmd:photon2:photons=2000,photon_map=m.map",
                "--out",
                "@out",
                "--json",
                "@json",
            ],
            &["@out", "@json"],
        ),
        (&["points", "--rays", "4", "p.csv", "@csv"], &["@csv"]),
        (&["scene", "export", "s.toml", "@obj"], &["@obj"]),
        (
            &["photons", "build", "--photons", "2000", "--out", "@out"],
            &["@out"],
        ),
        (
            &[
                "merge",
                "@out",
                "part0.exr",
                "part1.exr",
                "--png",
                "@png",
                "--json",
                "@json",
            ],
            &["@out", "@png", "@json"],
        ),
        (&["diff", "h.exr", "h2.exr", "--png", "@diff"], &["@diff"]),
    ];
    fn fresh(token: &str) -> &str {
        match token {
            "@out" => "new.exr",
            "@png" => "new.png",
            "@json" => "new.json",
            "@diff" => "new-diff.png",
            "@csv" => "new.csv",
            "@obj" => "new.obj",
            other => other,
        }
    }
    let with_scene = |args: &[&str]| -> Vec<String> {
        let mut args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
        let scene = ["--quiet", "--scene", "s.toml", "--size", "8x8"].map(String::from);
        match args[0].as_str() {
            "merge" | "diff" | "scene" => {}
            "points" => drop(args.splice(1..1, scene[..3].iter().cloned())),
            "photons" => drop(args.splice(2..2, scene)),
            _ => drop(args.splice(1..1, scene)),
        }
        args
    };
    let mut refusals = 0;
    for (template, outputs) in cases {
        let args = with_scene(template);
        let name = args[..2].join(" ");
        // The files the command reads, as it reads them.
        let run: Vec<&str> = args.iter().map(|a| fresh(a)).collect();
        let reads = files_read_by(dir.path(), &run);
        if args.iter().any(|a| a == "s.toml") {
            for mesh in ["s.toml", "floor.obj", "box.ply"] {
                assert!(
                    reads.iter().any(|r| r.ends_with(mesh)),
                    "{name}: {mesh} not among the reads {reads:?}"
                );
            }
        }
        assert!(!reads.is_empty(), "{name} reads nothing?");
        // Each of them as each output.
        for read in &reads {
            let before = std::fs::read(dir.path().join(read)).unwrap();
            for output in outputs {
                let run: Vec<&str> = args
                    .iter()
                    .map(|a| if a == output { read.as_str() } else { fresh(a) })
                    .collect();
                refused_unchanged(dir.path(), &run, read, &before);
                refusals += 1;
            }
        }
    }
    assert!(refusals >= 60, "{refusals} refusals");
}

/// The same for pbrt-v4 and Mitsuba 3 scenes, whose files name other files (includes, meshes):
/// every file a render reads (as `HMDIST_READS` logs it) is one of the scene's, and each named
/// as the render's EXR, PNG or JSON is refused, exit 2, and left as it was.
#[test]
fn pbrt_and_mitsuba_scenes_refuse_every_file_they_read_as_an_output() {
    let dir = Scratch::new("cli-reads-scene-formats");
    std::fs::create_dir_all(dir.join("geometry")).unwrap();
    let obj = "v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nf 1 2 3\nf 1 3 4\n";
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
               property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
               -0.5 1 -0.5\n0.5 1 -0.5\n0 1 0.5\n3 0 1 2\n";
    dir.write("geometry/floor.obj", obj);
    dir.write("geometry/box.ply", ply);
    dir.write(
        "geometry/part.pbrt",
        "Shape \"plymesh\" \"string filename\" \"geometry/box.ply\"\n",
    );
    dir.write(
        "s.pbrt",
        "LookAt 0 3 6  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 50\nWorldBegin\n\
         Shape \"trianglemesh\" \"point3 P\" [-2 0 -2 2 0 -2 2 0 2 -2 0 2] \"integer indices\" [0 1 2 0 2 3]\n\
         Include \"geometry/part.pbrt\"\n",
    );
    dir.write(
        "geometry/part.xml",
        "<scene version=\"3.0.0\"><shape type=\"ply\"><string name=\"filename\" value=\"box.ply\"/></shape></scene>\n",
    );
    dir.write(
        "s.xml",
        "<scene version=\"3.0.0\"><path value=\"geometry\"/>\n\
         <sensor type=\"perspective\"><transform name=\"to_world\"><lookat origin=\"0 3 6\" target=\"0 0 0\" up=\"0 1 0\"/></transform></sensor>\n\
         <shape type=\"obj\"><string name=\"filename\" value=\"floor.obj\"/></shape>\n\
         <include filename=\"part.xml\"/></scene>\n",
    );
    for (scene, files) in [
        (
            "s.pbrt",
            &["s.pbrt", "geometry/part.pbrt", "geometry/box.ply"][..],
        ),
        (
            "s.xml",
            &[
                "s.xml",
                "geometry/part.xml",
                "geometry/floor.obj",
                "geometry/box.ply",
            ][..],
        ),
    ] {
        let args = |out: &str, png: &str, json: &str| -> Vec<String> {
            [
                "render", "--quiet", "--scene", scene, "--size", "8x8", "--rays", "4", "--out", out, "--png",
                png, "--json", json,
            ]
            .map(String::from)
            .to_vec()
        };
        let run = args("new.exr", "new.png", "new.json");
        let reads = files_read_by(dir.path(), &run.iter().map(String::as_str).collect::<Vec<_>>());
        for file in files {
            assert!(
                reads.iter().any(|r| r.ends_with(file)),
                "{scene}: {file} not among the reads {reads:?}"
            );
        }
        for read in &reads {
            let before = std::fs::read(dir.path().join(read)).unwrap();
            for slot in 0..3 {
                let mut names = ["new.exr", "new.png", "new.json"];
                names[slot] = read.as_str();
                let run = args(names[0], names[1], names[2]);
                let run: Vec<&str> = run.iter().map(String::as_str).collect();
                refused_unchanged(dir.path(), &run, read, &before);
            }
        }
    }
}

#[test]
fn a_temporary_a_killed_run_left_is_removed_by_the_next_run_that_writes_there() {
    let dir = Scratch::new("cli-stale-temporaries");
    let args = [
        "render", "--quiet", "--size", "8x8", "--rays", "4", "--out", "o.exr",
    ];
    // A temporary of a run that no longer exists is removed by the next run that writes the
    // same output; one of a live process (this test's) is left alone.
    let mut gone = std::process::Command::new("true").spawn().unwrap();
    gone.wait().unwrap();
    let stale = dir.join(&format!(".o.exr.{}.tmp", gone.id()));
    let live = dir.join(&format!(".o.png.{}.tmp", std::process::id()));
    std::fs::write(&stale, b"left by a killed run").unwrap();
    std::fs::write(&live, b"being written").unwrap();
    common::cli::hmdist_ok(dir.path(), &args);
    assert!(!stale.exists(), "the dead run's temporary is removed");
    assert!(live.exists(), "a live run's temporary is kept");
}

#[test]
fn the_runtime_folder_a_killed_run_left_is_removed_by_the_next_run() {
    // Without XDG_RUNTIME_DIR each run makes an empty private folder, TMPDIR/hmdist-runtime-PID,
    // and removes it at exit; a run killed outright (SIGKILL) left it behind for good.
    let dir = Scratch::new("cli-stale-runtime");
    let temp = dir.join("tmp");
    let mut gone = std::process::Command::new("true").spawn().unwrap();
    gone.wait().unwrap();
    let stale = temp.join(format!("hmdist-runtime-{}", gone.id()));
    let live = temp.join(format!("hmdist-runtime-{}", std::process::id()));
    let not_empty = temp.join(format!("hmdist-runtime-{}x", gone.id()));
    for folder in [&stale, &live, &not_empty] {
        std::fs::create_dir_all(folder).unwrap();
    }
    std::fs::write(not_empty.join("kept"), b"not ours").unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hmdist"))
        .args([
            "render", "--quiet", "--size", "8x8", "--rays", "4", "--out", "o.exr",
        ])
        .current_dir(dir.path())
        .env_remove("XDG_RUNTIME_DIR")
        .env("TMPDIR", &temp)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(!stale.exists(), "the dead run's folder is removed");
    assert!(
        live.exists() && not_empty.exists(),
        "a live run's folder and other folders are kept"
    );
    let mut left: Vec<_> = std::fs::read_dir(&temp)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    left.sort();
    assert_eq!(left.len(), 2, "this run removed its own folder: {left:?}");
}

/// `hmdist render --size SIZE --out o.exr` in a fresh folder under an address-space limit
/// (`ulimit -v`) of `limit` bytes, with `env` set: its output and what it left there.
fn render_under_address_space_limit(
    name: &str,
    size: &str,
    limit: u64,
    env: &[(&str, &str)],
) -> (std::process::Output, Vec<String>) {
    use std::os::unix::process::CommandExt;
    let dir = Scratch::new(name);
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_hmdist"));
    command
        .args([
            "render",
            "--quiet",
            "--backend",
            "cpu",
            "--size",
            size,
            "--rays",
            "1",
            "--out",
            "o.exr",
        ])
        .envs(env.iter().copied())
        .current_dir(dir.path());
    // SAFETY: setrlimit only, between fork and exec.
    unsafe {
        command.pre_exec(move || {
            let limit = libc::rlimit {
                rlim_cur: limit,
                rlim_max: limit,
            };
            match libc::setrlimit(libc::RLIMIT_AS, &limit) {
                0 => Ok(()),
                _ => Err(std::io::Error::last_os_error()),
            }
        });
    }
    let out = command.output().unwrap();
    let left = common::cli::outputs(dir.path(), &[]);
    (out, left)
}

#[test]
fn a_request_over_the_address_space_limit_is_refused_before_allocating() {
    // `ulimit -v` of 1 GB and an 8192² image whose buffers need about 3 GB. Before: the memory
    // check read only the machine and cgroups, the allocation failed, abort 134.
    let (out, left) = render_under_address_space_limit("cli-rlimit-refused", "8192x8192", 1 << 30, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("bad parameter: --size 8192x8192 needs about")
            && stderr.contains("under this process's address-space limit (ulimit -v)"),
        "{stderr}"
    );
    assert_eq!(left, Vec::<String>::new(), "no output, no temporary");
}

#[test]
fn an_allocation_that_fails_under_an_address_space_limit_is_exit_2_with_nothing_left() {
    // `ulimit -v` of 300 MB and an image whose buffers need about 0.8 GB, with the memory
    // check switched off (HMDIST_NO_MEMORY_CHECK) so that the allocation itself fails. Before:
    // abort, status 134, a backtrace and three temporaries left.
    let (out, left) = render_under_address_space_limit(
        "cli-address-space",
        "4096x4096",
        300 << 20,
        &[("HMDIST_NO_MEMORY_CHECK", "1")],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.starts_with("hmdist: error: out of memory: an allocation of"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("panicked") && !stderr.contains("backtrace"),
        "{stderr}"
    );
    assert_eq!(left, Vec::<String>::new(), "no output, no temporary");
}

#[test]
fn unreadable_and_unwritable_paths_exit_2() {
    refuses(
        "missing",
        &[],
        &render_args(&["--scene", "missing.obj"]),
        "missing.obj",
    );
    refuses(
        "unknown-format",
        &[("scene.xyz", b"hello")],
        &render_args(&["--scene", "scene.xyz"]),
        "scene.xyz",
    );
    // Each output by the name the user gave it, not by an internal temporary file's.
    for (option, path) in [
        ("--out", "no/such/folder/hmd.exr"),
        ("--png", "no/such/folder/hmd.png"),
        ("--json", "no/such/folder/hmd.json"),
    ] {
        let message = refuses("unwritable", &[], &render_args(&[option, path]), path);
        assert!(
            message.contains(&format!("error: {path}: cannot write")),
            "{message}"
        );
    }
    refuses(
        "same-output-twice",
        &[],
        &render_args(&["--png", "hmd.exr"]),
        "hmd.exr: is named for two outputs",
    );
    refuses(
        "export-unwritable",
        &[],
        &["scene", "export", "sphere", "no/such/folder/s.obj"],
        "s.obj",
    );
}

#[test]
fn broken_scene_files_exit_2_naming_the_file() {
    let quad = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";
    refuses(
        "obj-garbage",
        &[("bad.obj", b"v 0 0 0\nv 1 zero 0\nv 1 1 0\nf 1 2 3\n")],
        &render_args(&["--scene", "bad.obj"]),
        "bad.obj:2",
    );
    refuses(
        "obj-index",
        &[("bad.obj", b"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 9\n")],
        &render_args(&["--scene", "bad.obj"]),
        "bad.obj",
    );
    refuses(
        "obj-nan",
        &[("nan.obj", b"v 0 0 0\nv nan 0 0\nv 1 1 0\nf 1 2 3\n")],
        &render_args(&["--scene", "nan.obj"]),
        "not finite",
    );
    refuses(
        "obj-inf",
        &[("inf.obj", b"v 0 0 0\nv inf 0 0\nv 1 1 0\nf 1 2 3\n")],
        &render_args(&["--scene", "inf.obj"]),
        "not finite",
    );
    refuses(
        "obj-empty",
        &[("empty.obj", b"# nothing\nv 0 0 0\n")],
        &render_args(&["--scene", "empty.obj"]),
        "no triangles",
    );
    refuses("ply-truncated", &[("t.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n")], &render_args(&["--scene", "t.ply"]), "t.ply");
    refuses(
        "gltf-garbage",
        &[("g.gltf", b"{ this is not json")],
        &render_args(&["--scene", "g.gltf"]),
        "g.gltf",
    );
    refuses(
        "glb-garbage",
        &[("g.glb", b"glTF\x02\x00\x00\x00garbage")],
        &render_args(&["--scene", "g.glb"]),
        "g.glb",
    );
    refuses(
        "toml-typo",
        &[
            ("quad.obj", quad),
            ("s.toml", b"[[mesh]]\npath = \"quad.obj\"\ntranslat = [0, 0, 0]\n"),
        ],
        &render_args(&["--scene", "s.toml"]),
        "s.toml",
    );
    refuses(
        "toml-missing-mesh",
        &[("s.toml", b"[[mesh]]\npath = \"nowhere.obj\"\n")],
        &render_args(&["--scene", "s.toml"]),
        "nowhere.obj",
    );
    refuses(
        "toml-garbage",
        &[("s.toml", b"[[mesh]\npath = \n")],
        &render_args(&["--scene", "s.toml"]),
        "s.toml",
    );
}

#[test]
fn a_file_the_gltf_crate_panics_on_gives_our_one_line_error_only() {
    // gltf 1.4.1 decodes a relative buffer URI with `urlencoding::decode(uri).unwrap()`: a
    // panic (and its message on stderr) where the decoded bytes are not UTF-8.
    let gltf = br#"{"asset":{"version":"2.0"},"buffers":[{"uri":"%FF.bin","byteLength":4}]}"#;
    let stderr = refuses(
        "gltf-panic",
        &[("p.gltf", gltf)],
        &render_args(&["--scene", "p.gltf"]),
        "its URI is not percent-encoded UTF-8",
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.starts_with("hmdist: error: "), "{stderr}");
}

/// spec §2's ray direction for pixel (px, py), computed here in f64, independently of hmdist.
fn spec_direction(
    eye: DVec3,
    target: DVec3,
    up: DVec3,
    fov_deg: f64,
    (w, h): (u32, u32),
    px: u32,
    py: u32,
) -> DVec3 {
    let f = (target - eye).normalize();
    let r = f.cross(up).normalize();
    let u = r.cross(f);
    let t = (fov_deg.to_radians() / 2.0).tan();
    let sx = (2.0 * (px as f64 + 0.5) / w as f64 - 1.0) * t * w as f64 / h as f64;
    let sy = (1.0 - 2.0 * (py as f64 + 0.5) / h as f64) * t;
    (f + sx * r + sy * u).normalize()
}

#[test]
fn toml_scene_follows_the_spec_camera_convention_pixel_for_pixel() {
    // A huge tilted plane: a pixel sees it exactly when its spec §2 ray heads towards it, so
    // the boundary between hit and background pixels is a slanted line that moves if the
    // camera's orientation, handedness, aspect or pixel centres differ in the least.
    let dir = Scratch::new("camera");
    let n = DVec3::new(0.3, 1.0, 0.2).normalize();
    let (a, b) = (
        n.cross(DVec3::Z).normalize(),
        n.cross(n.cross(DVec3::Z)).normalize(),
    );
    let s = 1.0e4;
    let corners: Vec<DVec3> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .map(|&(i, j)| s * (i * a + j * b))
        .collect();
    let mut obj = String::new();
    for c in &corners {
        obj += &format!("v {} {} {}\n", c.x, c.y, c.z);
    }
    obj += "f 1 2 3\nf 1 3 4\n";
    std::fs::write(dir.join("plane.obj"), obj).unwrap();
    let (eye, target, up, fov) = (
        DVec3::new(1.0, 3.0, 2.0),
        DVec3::new(-4.0, 1.5, -6.0),
        DVec3::new(0.1, 1.0, 0.0),
        70.0,
    );
    let toml = format!(
        "[[mesh]]\npath = \"plane.obj\"\n[camera]\neye = [{}, {}, {}]\ntarget = [{}, {}, {}]\nup = [{}, {}, {}]\nfov_y_deg = {fov}\n",
        eye.x, eye.y, eye.z, target.x, target.y, target.z, up.x, up.y, up.z
    );
    std::fs::write(dir.join("scene.toml"), toml).unwrap();
    let size = (96, 64);
    let out = hmdist(
        dir.path(),
        &[
            "render",
            "--quiet",
            "--scene",
            "scene.toml",
            "--size",
            "96x64",
            "--rays",
            "1",
            "--out",
            "plane.exr",
        ],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let image = hmdist::image::exr::read(&dir.join("plane.exr")).unwrap();
    assert_eq!((image.width, image.height), size);
    let eye_side = n.dot(eye).signum();
    let (mut checked, mut hits) = (0, 0);
    for py in 0..size.1 {
        for px in 0..size.0 {
            let d = spec_direction(eye, target, up, fov, size, px, py);
            let towards = -eye_side * n.dot(d);
            if towards.abs() < 1e-3 {
                continue; // too close to the horizon line to call
            }
            let hit = !image.at(px, py).is_nan();
            assert_eq!(hit, towards > 0.0, "pixel ({px}, {py})");
            checked += 1;
            hits += hit as u32;
        }
    }
    assert!(
        hits > 500 && checked - hits > 500,
        "the horizon crosses the image: {hits} of {checked}"
    );
}

#[test]
fn render_writes_exr_png_and_json_with_the_spec_keys() {
    let dir = Scratch::new("outputs");
    let out = hmdist(dir.path(), &render_args(&["--scene", "slab"]));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(outputs(dir.path(), &[]), ["hmd.exr", "hmd.json", "hmd.png"]);
    let exr = exr::meta::MetaData::read_from_file(dir.join("hmd.exr"), false).unwrap();
    let channels: Vec<(String, exr::meta::attribute::SampleType)> = exr.headers[0]
        .channels
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_type))
        .collect();
    assert_eq!(
        channels,
        [("Y".to_string(), exr::meta::attribute::SampleType::F32)],
        "spec §7: one float32 channel named Y"
    );
    let report = read_json(&dir.join("hmd.json"));
    for key in [
        "method",
        "width",
        "height",
        "seed",
        "rays",
        "triangles",
        "l_diag",
        "background_pixels",
        "rays_cast",
        "escaped_rays",
        "mrays_per_s",
    ] {
        assert!(report.get(key).is_some(), "JSON lacks '{key}'");
    }
    for key in ["load", "accel_build", "primary", "estimate", "total"] {
        assert!(report["seconds"][key].is_number(), "JSON lacks seconds.{key}");
    }
    assert_eq!(
        report["rays_cast"],
        8 * 8 * 4 - 4 * report["background_pixels"].as_u64().unwrap()
    );
}

#[test]
fn same_exr_bytes_with_1_and_2_threads() {
    let dir = Scratch::new("threads");
    for t in ["1", "2"] {
        let exr = format!("t{t}.exr");
        let out = hmdist(
            dir.path(),
            &[
                "render",
                "--quiet",
                "--scene",
                "cube",
                "--size",
                "200x150",
                "--rays",
                "4",
                "--threads",
                t,
                "--out",
                &exr,
            ],
        );
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let (one, two) = (
        std::fs::read(dir.join("t1.exr")).unwrap(),
        std::fs::read(dir.join("t2.exr")).unwrap(),
    );
    assert!(one == two, "EXR bytes differ between 1 and 2 threads");
}

/// The closest hit does not depend on the BVH (ties of `t` go to the lowest triangle index),
/// so the two presets render the same image, bit for bit, primary hits through shared edges
/// included. (Before that rule, these two images differed between the presets: the sizes are
/// the smallest found that showed it.)
#[test]
fn same_exr_bytes_from_both_bvh_presets() {
    let dir = Scratch::new("presets");
    for (scene, size) in [("cube", "160x120"), ("hall", "512x512")] {
        for preset in ["fast", "high"] {
            let exr = format!("{scene}-{preset}.exr");
            let args = [
                "render", "--quiet", "--scene", scene, "--size", size, "--rays", "16", "--bvh", preset,
                "--out", &exr,
            ];
            let out = hmdist(dir.path(), &args);
            assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        }
        let read = |preset: &str| std::fs::read(dir.join(&format!("{scene}-{preset}.exr"))).unwrap();
        assert!(
            read("fast") == read("high"),
            "{scene}: EXR bytes differ between --bvh fast and high"
        );
    }
}

#[test]
fn bad_photon_arguments_exit_2_with_a_message_and_no_output() {
    refuses(
        "photons0",
        &[],
        &render_args(&["--method", "photon1", "--photons", "0"]),
        "--photons",
    );
    refuses(
        "nearest0",
        &[],
        &render_args(&["--method", "photon2", "--nearest", "0"]),
        "--nearest",
    );
    // `--gather` is K's older name: the same refusal, spelled by K's name.
    refuses(
        "gather0",
        &[],
        &render_args(&["--method", "photon2", "--gather", "0"]),
        "--nearest must be at least 1",
    );
    // A flag the method does not read is refused, named, before anything is rendered.
    refuses(
        "unread",
        &[],
        &render_args(&["--method", "photon2", "--rays", "16"]),
        "--method photon2 does not read --rays",
    );
    refuses(
        "unread-backend",
        &[],
        &render_args(&["--method", "adaptive", "--backend", "cpu"]),
        "--method adaptive does not read --backend",
    );
    refuses(
        "nolight",
        &[],
        &render_args(&["--method", "photon2", "--scene", "slab", "--photons", "10"]),
        "no spot light",
    );
    refuses(
        "huge",
        &[],
        &render_args(&["--method", "photon2", "--photons", "100000000000000"]),
        "memory",
    );
}

#[test]
fn diff_of_an_image_with_itself_is_zero_and_mismatched_sizes_exit_2() {
    let dir = Scratch::new("diff");
    for (out, size) in [("a.exr", "16x12"), ("b.exr", "8x8")] {
        let r = hmdist(
            dir.path(),
            &[
                "render", "--quiet", "--scene", "cube", "--size", size, "--rays", "4", "--out", out,
            ],
        );
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    }
    let same = hmdist(dir.path(), &["diff", "a.exr", "a.exr", "--png", "d.png"]);
    let text = String::from_utf8_lossy(&same.stdout);
    assert!(
        same.status.success() && text.contains("f_diff:              0.000000"),
        "{text}"
    );
    assert!(text.contains("pixels compared:     192"), "{text}");
    assert!(text.contains("bit for bit:         identical"), "{text}");
    assert!(dir.join("d.png").exists());
    // --exact: status 0 for the same bits, 1 where one pixel is one ulp off (f_diff prints
    // 0.000000 there: only the bit count tells), and the count names it.
    let exact = hmdist(dir.path(), &["diff", "a.exr", "a.exr", "--exact"]);
    assert_eq!(exact.status.code(), Some(0));
    let mut image = hmdist::image::exr::read(&dir.join("a.exr")).unwrap();
    image.data[100] = f32::from_bits(image.data[100].to_bits() + 1);
    hmdist::image::exr::write(&image, &dir.join("c.exr")).unwrap();
    std::fs::copy(dir.join("a.json"), dir.join("c.json")).unwrap();
    for flags in [&[][..], &["--exact"][..]] {
        let ulp = hmdist(dir.path(), &[&["diff", "a.exr", "c.exr"][..], flags].concat());
        let text = String::from_utf8_lossy(&ulp.stdout);
        assert!(text.contains("f_diff:              0.000000"), "{text}");
        assert!(
            text.contains("bit for bit:         1 of 192 pixels differ"),
            "{text}"
        );
        assert_eq!(
            ulp.status.code(),
            Some(if flags.is_empty() { 0 } else { 1 }),
            "{text}"
        );
    }
    let mismatch = hmdist(dir.path(), &["diff", "a.exr", "b.exr"]);
    assert_eq!(mismatch.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&mismatch.stderr).contains("differ in size"));
}

#[cfg(unix)]
#[test]
fn printing_to_a_closed_pipe_is_not_a_panic() {
    // `hmdist scene info cube | head -0`: the reader is gone before hmdist prints.
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_hmdist"))
        .args(["scene", "info", "cube"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
}
