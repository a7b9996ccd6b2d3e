//! Interrupted runs (issue #16): Ctrl-C or SIGTERM during a long render ends `hmdist` with
//! status 130 or 143, a one-line message and no file in the output folder, final or
//! temporary; the library stops its loops when asked, and counts progress in pixels.

mod common;

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant, SystemTime};

use common::cli::outputs;
use common::Scratch;
use hmdist::error::Error;
use hmdist::estimators::{Backend, Cubemap, Gather};
use hmdist::progress::Progress;
use hmdist::render::{render, RenderOptions};
use hmdist::sampling::Weighting;
use hmdist::scene::Scene;

/// Starts `hmdist args...` in `dir`, its stderr captured.
fn start(dir: &Path, args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_hmdist"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("hmdist starts")
}

/// Sends `signal` (`INT`, `TERM`) to `child` after `after`, then waits at most 20 s for it to
/// end: its exit code (`None`: ended by the signal itself) and stderr.
#[cfg(unix)]
fn interrupt(mut child: Child, signal: &str, after: Duration) -> (Option<i32>, String) {
    std::thread::sleep(after);
    assert!(
        child.try_wait().unwrap().is_none(),
        "hmdist ended before the signal"
    );
    let sent = Command::new("kill")
        .args([format!("-{signal}"), child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(sent.success());
    let deadline = Instant::now() + Duration::from_secs(20);
    while child.try_wait().unwrap().is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("hmdist did not stop within 20 s of SIG{signal}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = child.wait_with_output().unwrap();
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(
        out.status.signal(),
        None,
        "ended by the signal itself, not by hmdist"
    );
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A render of 8 × 8 pixels with 2³² − 1 rays each: hours of work, most of it inside single
/// pixels, so only the polling within a pixel can stop it within seconds.
const LONG_RENDER: [&str; 6] = ["render", "--size", "8x8", "--rays", "4294967295", "--threads"];

#[cfg(unix)]
#[test]
fn sigterm_during_a_render_exits_143_and_leaves_no_file() {
    let dir = Scratch::new("sigterm-render");
    let mut args = LONG_RENDER.to_vec();
    args.extend(["2", "--out", "long.exr"]);
    let (code, stderr) = interrupt(start(dir.path(), &args), "TERM", Duration::from_secs(1));
    assert_eq!(code, Some(143), "{stderr}");
    assert_eq!(
        stderr.trim(),
        "hmdist: interrupted by SIGTERM: no output was written"
    );
    assert_eq!(
        outputs(dir.path(), &[]),
        Vec::<String>::new(),
        "no output, no temporary"
    );
}

#[cfg(unix)]
#[test]
fn sigint_during_a_render_exits_130_and_leaves_no_file() {
    let dir = Scratch::new("sigint-render");
    dir.write("keep.txt", "an unrelated file");
    let mut args = LONG_RENDER.to_vec();
    // With AOVs, as 3 rounds (2³² − 1 = 3 · 1431655765).
    args.extend(["1", "--aov", "relerr,dmin", "--rounds", "3"]);
    let (code, stderr) = interrupt(start(dir.path(), &args), "INT", Duration::from_millis(1500));
    assert_eq!(code, Some(130), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert_eq!(outputs(dir.path(), &[]), ["keep.txt"], "no output, no temporary");
}

#[cfg(unix)]
#[test]
fn sigterm_during_points_exits_143_and_leaves_no_file() {
    let dir = Scratch::new("sigterm-points");
    dir.write("in.csv", "0,0.5,0,0,1,0\n2,3,-1,-1,0,0\n");
    let args = ["points", "in.csv", "out.csv", "--rays", "4294967295", "--quiet"];
    let (code, stderr) = interrupt(start(dir.path(), &args), "TERM", Duration::from_secs(1));
    assert_eq!(code, Some(143), "{stderr}");
    assert_eq!(outputs(dir.path(), &[]), ["in.csv"]);
}

/// The files under `dir`, recursively, as paths relative to it; none if it does not exist.
fn tree(dir: &Path) -> Vec<String> {
    let mut names = vec![];
    for entry in std::fs::read_dir(dir).into_iter().flatten() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if path.is_dir() {
            names.extend(tree(&path).into_iter().map(|n| format!("{name}/{n}")));
        } else {
            names.push(name);
        }
    }
    names.sort();
    names
}

#[cfg(unix)]
#[test]
fn an_interrupted_experiment_keeps_whole_cached_images_and_resumes_from_them() {
    let dir = Scratch::new("sigterm-experiment");
    let args = [
        "experiment",
        "table1",
        "--scene",
        "cube",
        "--out",
        "out",
        "--quiet",
    ];
    let child = start(dir.path(), &args);
    // Wait for the first cached image (the reference), then interrupt the next render.
    let cache = dir.join("out/cache");
    let deadline = Instant::now() + Duration::from_secs(120);
    while !tree(&cache).iter().any(|n| n.ends_with(".json")) {
        assert!(Instant::now() < deadline, "no image cached within 120 s");
        std::thread::sleep(Duration::from_millis(50));
    }
    let (code, stderr) = interrupt(child, "TERM", Duration::from_millis(300));
    assert_eq!(code, Some(143), "{stderr}");
    // It says what it kept, not that nothing was written.
    assert!(
        stderr.contains("interrupted by SIGTERM: the images it finished are kept in out/cache"),
        "{stderr}"
    );
    let cached = tree(&dir.join("out"));
    assert!(cached.iter().all(|n| n.starts_with("cache/")), "{cached:?}");
    assert!(!cached.iter().any(|n| n.contains(".tmp")), "{cached:?}");
    for json in cached.iter().filter(|n| n.ends_with(".json")) {
        let exr = json.replace(".json", ".exr");
        assert!(cached.contains(&exr), "{json} without {exr}: {cached:?}");
        let image = hmdist::image::exr::read(&dir.join("out").join(&exr)).expect("a whole EXR");
        assert_eq!(image.width, 48);
    }

    // The rerun renders the rest and leaves the cached images as they were.
    let stamp = SystemTime::UNIX_EPOCH + Duration::from_secs(1_000_000_000);
    for name in &cached {
        let file = std::fs::File::options()
            .append(true)
            .open(dir.join("out").join(name));
        file.unwrap().set_modified(stamp).unwrap();
    }
    let out = Command::new(env!("CARGO_BIN_EXE_hmdist"))
        .args(args)
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for name in cached.iter().filter(|n| n.ends_with(".json")) {
        let modified = std::fs::metadata(dir.join("out").join(name))
            .unwrap()
            .modified()
            .unwrap();
        assert_eq!(modified, stamp, "{name} was rendered again");
    }
    assert!(dir.join("out/table1.csv").exists());
}

/// Records the progress the driver reports.
#[derive(Default)]
struct Recorder {
    total: AtomicU64,
    steps: AtomicU64,
    calls: AtomicU64,
    labels: Mutex<Vec<String>>,
}

impl Progress for Recorder {
    fn start(&self, label: &str, total: u64) {
        self.total.store(total, Ordering::Relaxed);
        self.labels.lock().unwrap().push(label.into());
    }
    fn advance(&self, steps: u64) {
        self.steps.fetch_add(steps, Ordering::Relaxed);
        self.calls.fetch_add(1, Ordering::Relaxed);
    }
    fn finish(&self) {}
}

#[test]
fn progress_counts_surface_pixels_not_rows() {
    // One row of 32 pixels: counted in rows it would be one step, never moving until the
    // row is done. (The CPU cube map counts pixels; gather counts rays, below.)
    let scene = Scene::load("cube").unwrap();
    let options = RenderOptions {
        width: 32,
        height: 1,
        ..RenderOptions::default()
    };
    let progress = Recorder::default();
    let gather = Gather::new(4, Weighting::Cosine).unwrap();
    let cubemap = Cubemap::new(gather, 4, Backend::Cpu).unwrap();
    let rendered = render(&scene, &cubemap, &options, &progress).unwrap();
    let surface = 32 - rendered.report.background_pixels as u64;
    assert!(surface > 16, "{surface}");
    assert_eq!(progress.total.load(Ordering::Relaxed), surface);
    assert_eq!(progress.steps.load(Ordering::Relaxed), surface);
    assert_eq!(progress.calls.load(Ordering::Relaxed), surface);
}

#[test]
fn gather_progress_moves_within_a_pixel() {
    // One pixel of 100,000 rays: counted in pixels, the bar would stand still (and show no
    // ETA) until the pixel is done; counted in rays it moves every 16,384 rays.
    let scene = Scene::load("cube").unwrap();
    let options = RenderOptions {
        width: 1,
        height: 1,
        ..RenderOptions::default()
    };
    let progress = Recorder::default();
    for rounds in [1, 4] {
        progress.steps.store(0, Ordering::Relaxed);
        progress.calls.store(0, Ordering::Relaxed);
        let gather = Gather::new(100_000, Weighting::Cosine)
            .unwrap()
            .with_rounds(rounds)
            .unwrap();
        render(&scene, &gather, &options, &progress).unwrap();
        assert_eq!(progress.total.load(Ordering::Relaxed), 100_000);
        assert_eq!(progress.steps.load(Ordering::Relaxed), 100_000, "{rounds} rounds");
        // 25,000 rays a round: one step at 16,384 and the rest at its end.
        let calls = if rounds == 1 {
            100_000 / 16_384 + 1
        } else {
            2 * rounds
        };
        assert_eq!(
            progress.calls.load(Ordering::Relaxed),
            calls as u64,
            "{rounds} rounds"
        );
    }
}

#[test]
fn a_requested_interruption_stops_a_render_inside_its_pixels() {
    // Run in a child process: the request is process-wide and the other tests of this file
    // render too.
    const CHILD: &str = "HMDIST_TEST_INTERRUPT_CHILD";
    if std::env::var_os(CHILD).is_none() {
        let test = "a_requested_interruption_stops_a_render_inside_its_pixels";
        let stdout = common::rerun_in_child(test, CHILD, "1");
        assert!(stdout.contains("interrupted after"), "{stdout}");
        return;
    }
    let scene = Scene::load("cube").unwrap();
    let options = RenderOptions {
        width: 4,
        height: 4,
        threads: Some(1),
        ..RenderOptions::default()
    };
    let gather = Gather::new(u32::MAX, Weighting::Cosine).unwrap();
    let started = Instant::now();
    std::thread::spawn(|| {
        std::thread::sleep(Duration::from_millis(300));
        hmdist::interrupt::request();
    });
    let result = render(&scene, &gather, &options, &hmdist::progress::Silent);
    let seconds = started.elapsed().as_secs_f64();
    assert!(matches!(result, Err(Error::Interrupted)), "{:?}", result.err());
    assert!(seconds < 10.0, "took {seconds} s");
    // Until cleared, the next render stops too; after, it runs.
    let small = Gather::new(4, Weighting::Cosine).unwrap();
    let again = render(&scene, &small, &options, &hmdist::progress::Silent);
    assert!(matches!(again, Err(Error::Interrupted)));
    hmdist::interrupt::clear();
    render(&scene, &small, &options, &hmdist::progress::Silent).unwrap();
    println!("interrupted after {seconds:.2} s");
}

#[cfg(unix)]
#[test]
fn sigint_during_a_gpu_gather_exits_130_and_leaves_no_file() {
    // On the GPU the flag is looked at between dispatches (at most 16 rays per pixel each on
    // lavapipe, about half a second each on a hardware GPU).
    let dir = Scratch::new("sigint-gpu-render");
    let mut args = LONG_RENDER.to_vec();
    args.extend(["1", "--backend", "gpu-software", "--out", "long.exr"]);
    let (code, stderr) = interrupt(start(dir.path(), &args), "INT", Duration::from_secs(2));
    if code == Some(2)
        && common::gpu_missing("sigint_during_a_gpu_gather_exits_130_and_leaves_no_file", &stderr)
    {
        return;
    }
    assert_eq!(code, Some(130), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert_eq!(
        outputs(dir.path(), &[]),
        Vec::<String>::new(),
        "no output, no temporary"
    );
}

/// SIGTERM one second into `args` (in a fresh folder): hmdist exits 143 within 2 s of the
/// signal, saying so, and leaves no file.
#[cfg(unix)]
fn stops_soon_after_sigterm(case: &str, args: &[&str]) {
    let dir = Scratch::new(case);
    let child = start(dir.path(), args);
    let started = Instant::now();
    let (code, stderr) = interrupt(child, "TERM", Duration::from_secs(1));
    let after = started.elapsed().saturating_sub(Duration::from_secs(1));
    assert_eq!(code, Some(143), "{case}: {stderr}");
    assert!(after < Duration::from_secs(2), "{case}: {after:?} after SIGTERM");
    assert_eq!(
        outputs(dir.path(), &[]),
        Vec::<String>::new(),
        "{case}: no output, no temporary"
    );
}

#[cfg(unix)]
#[test]
fn sigterm_inside_one_points_millions_of_rays_stops_irradiance_and_the_cache() {
    // One pixel's (or one record's) rays are looked at every 4,096 rays, not only between
    // pixels: before, 8² pixels of 10⁷ rays took 6–17 s to stop, a record of 4·10⁹ rays 1,422 s.
    stops_soon_after_sigterm(
        "sigterm-irradiance",
        &[
            "render",
            "--method",
            "irradiance",
            "--size",
            "2x2",
            "--rays",
            "2000000000",
            "--threads",
            "1",
        ],
    );
    stops_soon_after_sigterm(
        "sigterm-cache",
        &[
            "cache",
            "--size",
            "2x2",
            "--rays",
            "2000000000",
            "--threads",
            "1",
            "--out",
            "c.exr",
        ],
    );
}
