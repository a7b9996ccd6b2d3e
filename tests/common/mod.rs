//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod cli;

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::Vec3;
use hmdist::error::{DeviceErrorKind, Error, Result};
use hmdist::estimators::{Estimator, Gather};
use hmdist::image::HmdImage;
use hmdist::progress::Silent;
use hmdist::render::{render, RenderOptions, Rendered};
use hmdist::report::RenderReport;
use hmdist::sampling::Weighting;
use hmdist::scene::{Camera, Mesh, Scene};

/// Renders `scene` with `estimator` at `size × size`, the other options as in `options`: the
/// one render helper of the tests.
pub fn render_square(
    scene: &Scene,
    estimator: &dyn Estimator,
    size: u32,
    options: RenderOptions,
) -> Result<Rendered> {
    let options = RenderOptions {
        width: size,
        height: size,
        ..options
    };
    render(scene, estimator, &options, &Silent)
}

/// Renders `scene` with `rays` cosine- or uniform-weighted gather rays at `width × height`.
pub fn gather(
    scene: &Scene,
    width: u32,
    height: u32,
    rays: u32,
    weighting: Weighting,
    threads: Option<usize>,
) -> (HmdImage, RenderReport) {
    let estimator = Gather::new(rays, weighting).unwrap();
    let options = RenderOptions {
        width,
        height,
        threads,
        ..RenderOptions::default()
    };
    let rendered = render(scene, &estimator, &options, &Silent).unwrap();
    (rendered.image, rendered.report)
}

pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v[v.len() / 2]
}

/// Runs the test `test` of this test binary again, alone, in a child process with `var` set to
/// `value` (for a test that needs a process of its own: its peak memory, a process-wide
/// flag); asserts that it passes and returns its stdout. The child sees `var` and does the
/// work.
pub fn rerun_in_child(test: &str, var: &str, value: &str) -> String {
    let out = std::process::Command::new(std::env::current_exe().unwrap())
        .args([test, "--exact", "--nocapture", "--test-threads=1"])
        .env(var, value)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{var}={value}: {stdout}{stderr}");
    stdout
}

/// A fresh, empty folder for one test under the system temp dir. Removed when the test
/// passes; kept (and named on stderr) when it fails, to look at.
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(test: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("hmdist-test-{}-{test}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    pub fn path(&self) -> &Path {
        &self.0
    }

    pub fn join(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    /// Writes `contents` to `name` in the folder and returns its path.
    pub fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, contents).unwrap();
        path
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("test files kept in {}", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// Set (by `.ci/run`, or any CI that sets `CI`) where a GPU test must run, never skip.
pub const REQUIRE_GPU: &str = "HMDIST_REQUIRE_GPU";

/// Set (by `.ci/run`) where no test may skip: every skip fails instead.
pub const NO_SKIPS: &str = "HMDIST_NO_SKIPS";

/// Skips (the caller returns) `test` for `reason`, visibly: "SKIPPED test: reason" goes to
/// stderr directly (libtest hides `eprintln!` of a passing test). Where [`NO_SKIPS`] or the
/// environment variable `required_by` is set, the skip is a failure instead.
pub fn skip(test: &str, reason: &str, required_by: Option<&str>) {
    for variable in [Some(NO_SKIPS), required_by].into_iter().flatten() {
        assert!(
            std::env::var_os(variable).is_none(),
            "{test} must run here ({variable} is set), but would be skipped: {reason}"
        );
    }
    let _ = writeln!(std::io::stderr(), "SKIPPED {test}: {reason}");
}

/// The result of a render on the cube map's GPU backend, or `None` where this machine has no
/// Vulkan, Metal or DX12 adapter (see [`gpu_missing`]).
pub fn gpu_or_skip(test: &str, result: Result<Rendered>) -> Option<Rendered> {
    match result {
        Ok(rendered) => Some(rendered),
        Err(
            e @ Error::Device {
                kind: DeviceErrorKind::NoAdapter,
                ..
            },
        ) => {
            assert!(gpu_missing(test, &e.to_string()), "{e}");
            None
        }
        Err(e) => panic!("{test}: the GPU backend must run here: {e}"),
    }
}

/// Whether `error` says that this machine has no Vulkan, Metal or DX12 adapter and the test
/// may skip: then the skip and its reason go to stderr, written to it directly (libtest would
/// hide `eprintln!` of a passing test). Where `HMDIST_REQUIRE_GPU` or `CI` is set, a missing
/// adapter fails the test instead.
pub fn gpu_missing(test: &str, error: &str) -> bool {
    if !error.contains("no Vulkan") {
        return false;
    }
    let required = if std::env::var_os("CI").is_some() {
        Some("CI")
    } else {
        Some(REQUIRE_GPU)
    };
    let reason = format!(
        "{}. Install a Vulkan driver (Debian: mesa-vulkan-drivers libvulkan1); set {REQUIRE_GPU}=1 \
         to make this a failure.",
        error.trim()
    );
    skip(test, &reason, required);
    true
}

/// A square floor at y = 0, `2·half_width` wide, seen straight down from `eye_height` by a
/// camera over the origin: nothing above it, so every ray from it escapes. Its centre, and
/// the edge its two triangles share, are off the origin, where a 1 × 1 image looks.
pub fn floor(half_width: f32, eye_height: f32) -> Scene {
    let mut mesh = Mesh::new();
    let centre = Vec3::new(0.3, 0.0, 0.1);
    add_square(&mut mesh, centre, Vec3::X * half_width, Vec3::Z * half_width);
    Scene {
        name: "floor".into(),
        mesh,
        camera: Camera {
            eye: Vec3::new(0.0, eye_height, 0.0),
            target: Vec3::ZERO,
            up: Vec3::Z,
            fov_y_deg: 60.0,
            mirrored: false,
        },
        light: None,
        display_scale: 0.25,
        notes: Default::default(),
    }
}

/// Adds the square `centre ± a ± b` as two triangles.
pub fn add_square(mesh: &mut Mesh, centre: Vec3, a: Vec3, b: Vec3) {
    let first = mesh.add_vertices([centre - a - b, centre + a - b, centre + a + b, centre - a + b]);
    mesh.add_triangle(first, first + 1, first + 2);
    mesh.add_triangle(first, first + 2, first + 3);
}

/// A scene's triangles as a sorted set of sorted corners: two scenes hold the same geometry
/// when their sets match, whatever the order of triangles and corners. Coordinates are rounded
/// to 1e-4 for sorting, so float noise around a tie cannot reorder them.
pub fn triangle_set(scene: &Scene) -> Vec<[[f32; 3]; 3]> {
    let key = |p: Vec3| [p.x, p.y, p.z].map(|v| (v * 1e4).round() / 1e4);
    let mut set: Vec<[[f32; 3]; 3]> = (0..scene.mesh.triangle_count())
        .map(|i| {
            let mut t = scene.mesh.triangle(i).map(key);
            t.sort_by(|a, b| a.partial_cmp(b).unwrap());
            t
        })
        .collect();
    set.sort_by(|a, b| a.partial_cmp(b).unwrap());
    set
}

/// Asserts that two scenes hold the same triangles (`triangle_set`), corner for corner within
/// `tolerance`.
pub fn assert_same_triangles(a: &Scene, b: &Scene, tolerance: f32) {
    let (a, b) = (triangle_set(a), triangle_set(b));
    assert_eq!(a.len(), b.len(), "triangle counts differ");
    for (s, t) in a.iter().zip(&b) {
        for (p, q) in s.iter().zip(t) {
            let d = Vec3::from(*p) - Vec3::from(*q);
            assert!(d.length() <= tolerance, "{p:?} != {q:?}");
        }
    }
}

/// Five vertices and three triangles, as OBJ and as ASCII PLY: the mesh the scene-format
/// tests place in every way a format can say it.
pub const TRI_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0.5\nv 0.3 0.2 2\nf 1 2 3\nf 1 3 4\nf 2 5 3\n";
pub const TRI_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n\
    element face 3\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0.5\n0.3 0.2 2\n\
    3 0 1 2\n3 0 2 3\n3 1 4 2\n";
