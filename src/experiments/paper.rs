//! Every number the paper publishes that the experiments compare against (spec §6), named.
//! Scene A and scene B are the paper's own scenes; its machines were a Xeon E5420 at 2.5 GHz
//! (plain C++) and a GeForce 8800 GTX.

/// Table 1's ray counts as its two halves are headed (one column of each half was lost, so
/// which count each value belongs to is uncertain).
pub const TABLE1_HEADED_RAYS: [u32; 9] = [32, 64, 128, 256, 512, 1024, 2048, 4096, 8192];

/// The paper's two scenes, whose findings differ (Fig. 16/17: light-sourced photons do better
/// in A, camera-sourced in B).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PaperScene {
    /// A closed cube holding five detailed objects, lit from inside.
    A,
    /// A larger interior lit from outside, seen in part.
    B,
}

/// The paper's scene that the built-in scene `name` stands for (spec §5: `cube` for A, `hall`
/// for B); `None` for any other scene.
pub fn analogue(name: &str) -> Option<PaperScene> {
    match name {
        "cube" => Some(PaperScene::A),
        "hall" => Some(PaperScene::B),
        _ => None,
    }
}

/// The display scale s of the paper's pictures of scene A (grey `s · H`).
pub const DISPLAY_SCALE_A: f32 = 0.14;
/// The display scale of the paper's pictures of scene B.
pub const DISPLAY_SCALE_B: f32 = 0.025;

/// Table 1, `f_diff` of CPU final gathering against the 65,536-ray reference, scene A, in
/// the text's order.
pub const TABLE1_CPU_A: [f64; 8] = [0.5971, 0.3121, 0.1967, 0.1113, 0.0357, 0.0248, 0.0351, 0.0109];

/// Table 1, CPU final gathering, scene B, in the text's order.
pub const TABLE1_CPU_B: [f64; 8] = [0.8255, 0.4799, 0.3003, 0.2181, 0.0994, 0.0460, 0.0454, 0.0211];

/// Table 1, the GPU cube map, scene A, in the text's order.
pub const TABLE1_GPU_A: [f64; 8] = [0.5538, 0.3178, 0.1921, 0.1050, 0.0276, 0.0155, 0.0173, 0.0080];

/// Final gathering's error roughly halves per doubling of rays up to about this many rays,
/// then oscillates down slowly.
pub const LEVEL_OFF_RAYS: u32 = 1024;

/// Mean difference between CPU gathering and the GPU cube map at 65,536 rays, by per-quadrant
/// resolution R.
pub const CPU_VS_GPU_AT_65536: [CubeDifference; 2] = [
    CubeDifference {
        cube_res: 64,
        f_diff: 0.029104,
    },
    CubeDifference {
        cube_res: 128,
        f_diff: 0.029091,
    },
];

/// One cube-map resolution's difference from final gathering.
pub struct CubeDifference {
    /// Per-quadrant resolution R.
    pub cube_res: u32,
    /// Mean |ΔH| in percent of the scene diagonal.
    pub f_diff: f64,
}

/// Table 2: seconds for a 1024 × 1024 image, CPU final gathering against the GPU cube map,
/// every row of the paper.
pub const TABLE2: [Table2Row; 13] = [
    Table2Row::new(16, 61.6, 2412.4),
    Table2Row::new(32, 104.5, 2426.9),
    Table2Row::new(64, 251.6, 2427.8),
    Table2Row::new(128, 486.0, 2433.7),
    Table2Row::new(256, 958.0, 2430.5),
    Table2Row::new(512, 1966.0, 2442.0),
    Table2Row::new(1024, 3809.7, 2448.4),
    Table2Row::new(2048, 7756.2, 2471.0),
    Table2Row::new(4096, 14825.3, 2473.6),
    Table2Row::new(8192, 29689.7, 2495.1),
    Table2Row::new(16384, 56647.8, 2487.8),
    Table2Row::new(32768, 111470.1, 2519.2),
    Table2Row::new(65536, 225910.1, 2596.0),
];

/// The row of [`TABLE2`] for `rays`, if the paper has one.
pub fn table2_row(rays: u32) -> Option<&'static Table2Row> {
    TABLE2.iter().find(|r| r.rays == rays)
}

/// Table 1's values in the text's order, matched to the ray counts the halves are headed with
/// as they read (the first four headings of each half): `(CPU A, CPU B, GPU A)` at `rays`,
/// where the reading gives one. Which count each value belongs to is uncertain (spec §6).
pub fn table1_as_read(rays: u32) -> Option<(f64, f64, f64)> {
    const READ_RAYS: [u32; 8] = [32, 64, 128, 256, 1024, 2048, 4096, 8192];
    let i = READ_RAYS.iter().position(|&r| r == rays)?;
    Some((TABLE1_CPU_A[i], TABLE1_CPU_B[i], TABLE1_GPU_A[i]))
}

/// `(rays, f_diff)` points of a Table 1 row.
pub type RaysFdiff = Vec<(u32, f64)>;

/// Table 1 as read ([`table1_as_read`]) as `(rays, f_diff)` points: CPU final gathering in
/// `scene`, and the GPU cube map where the paper gives it (scene A only).
pub fn table1_points(scene: PaperScene) -> (RaysFdiff, Option<RaysFdiff>) {
    let read: Vec<(u32, (f64, f64, f64))> = TABLE1_HEADED_RAYS
        .iter()
        .filter_map(|&rays| Some((rays, table1_as_read(rays)?)))
        .collect();
    match scene {
        PaperScene::A => (
            read.iter().map(|&(n, (cpu_a, _, _))| (n, cpu_a)).collect(),
            Some(read.iter().map(|&(n, (_, _, gpu_a))| (n, gpu_a)).collect()),
        ),
        PaperScene::B => (read.iter().map(|&(n, (_, cpu_b, _))| (n, cpu_b)).collect(), None),
    }
}

/// One row of [`TABLE2`].
pub struct Table2Row {
    /// Gather rays per pixel.
    pub rays: u32,
    /// CPU final gathering, seconds.
    pub cpu_seconds: f64,
    /// GPU cube map, seconds.
    pub gpu_seconds: f64,
}

impl Table2Row {
    const fn new(rays: u32, cpu_seconds: f64, gpu_seconds: f64) -> Self {
        Table2Row {
            rays,
            cpu_seconds,
            gpu_seconds,
        }
    }
}

/// Table 3: seconds to gather (map build excluded), scene A, 1024 × 1024, by photons stored
/// and photons gathered K, every cell of the paper (method I at 1.06 M photons and K = 1,024
/// reads 150.1 s in the paper, out of line with its neighbours: kept as printed).
pub const TABLE3: [Table3Cell; 35] = [
    Table3Cell::new(130_000, 64, 17.5, 19.2),
    Table3Cell::new(130_000, 128, 43.2, 40.8),
    Table3Cell::new(130_000, 256, 66.7, 71.9),
    Table3Cell::new(130_000, 512, 119.7, 131.4),
    Table3Cell::new(130_000, 1024, 195.8, 221.2),
    Table3Cell::new(260_000, 64, 20.5, 22.2),
    Table3Cell::new(260_000, 128, 51.8, 48.9),
    Table3Cell::new(260_000, 256, 71.5, 76.0),
    Table3Cell::new(260_000, 512, 126.7, 140.1),
    Table3Cell::new(260_000, 1024, 214.0, 242.2),
    Table3Cell::new(530_000, 64, 23.2, 25.7),
    Table3Cell::new(530_000, 128, 51.1, 52.5),
    Table3Cell::new(530_000, 256, 77.3, 83.5),
    Table3Cell::new(530_000, 512, 137.5, 153.6),
    Table3Cell::new(530_000, 1024, 228.7, 256.7),
    Table3Cell::new(1_060_000, 64, 29.6, 32.0),
    Table3Cell::new(1_060_000, 128, 59.6, 60.2),
    Table3Cell::new(1_060_000, 256, 88.4, 94.2),
    Table3Cell::new(1_060_000, 512, 154.3, 169.0),
    Table3Cell::new(1_060_000, 1024, 150.1, 273.5),
    Table3Cell::new(2_130_000, 64, 41.4, 43.2),
    Table3Cell::new(2_130_000, 128, 72.7, 78.2),
    Table3Cell::new(2_130_000, 256, 103.6, 109.3),
    Table3Cell::new(2_130_000, 512, 177.9, 199.4),
    Table3Cell::new(2_130_000, 1024, 278.5, 314.5),
    Table3Cell::new(4_260_000, 64, 75.4, 72.8),
    Table3Cell::new(4_260_000, 128, 98.0, 101.3),
    Table3Cell::new(4_260_000, 256, 131.2, 144.3),
    Table3Cell::new(4_260_000, 512, 221.7, 238.9),
    Table3Cell::new(4_260_000, 1024, 335.8, 365.9),
    Table3Cell::new(8_530_000, 64, 120.2, 122.8),
    Table3Cell::new(8_530_000, 128, 158.6, 148.1),
    Table3Cell::new(8_530_000, 256, 180.8, 190.7),
    Table3Cell::new(8_530_000, 512, 277.8, 289.2),
    Table3Cell::new(8_530_000, 1024, 403.8, 436.1),
];

/// The cell of [`TABLE3`] at `photons` and `k`, if the paper has one.
pub fn table3_cell(photons: usize, k: usize) -> Option<&'static Table3Cell> {
    TABLE3.iter().find(|c| c.photons == photons && c.k == k)
}

/// One cell of [`TABLE3`].
pub struct Table3Cell {
    /// Photons stored.
    pub photons: usize,
    /// Photons gathered per pixel K.
    pub k: usize,
    /// Method I, seconds.
    pub method1_seconds: f64,
    /// Method II, seconds.
    pub method2_seconds: f64,
}

impl Table3Cell {
    const fn new(photons: usize, k: usize, method1_seconds: f64, method2_seconds: f64) -> Self {
        Table3Cell {
            photons,
            k,
            method1_seconds,
            method2_seconds,
        }
    }
}

/// The paper's two path lengths (bounce limits): Table 3 and Fig. 10 use the first, Table 4
/// the second, Fig. 16/17 both.
pub const BOUNCES: [u32; 2] = [20, 80];

/// Table 4: seconds to build the photon map (80 bounces, kd-tree included), every row of
/// the paper.
pub const TABLE4: [Table4Row; 7] = [
    Table4Row::new("130 K", 130_000, 1.6, 1.0),
    Table4Row::new("260 K", 260_000, 2.7, 1.9),
    Table4Row::new("530 K", 530_000, 4.9, 3.8),
    Table4Row::new("1.06 M", 1_060_000, 9.4, 6.4),
    Table4Row::new("2.13 M", 2_130_000, 18.9, 12.1),
    Table4Row::new("4.26 M", 4_260_000, 38.9, 26.2),
    Table4Row::new("8.53 M", 8_530_000, 83.8, 54.4),
];

/// The row of [`TABLE4`] for a map of `photons`, if the paper has one.
pub fn table4_row(photons: usize) -> Option<&'static Table4Row> {
    TABLE4.iter().find(|r| r.count == photons)
}

/// One row of [`TABLE4`].
pub struct Table4Row {
    /// Photons stored, as the paper writes it.
    pub photons: &'static str,
    /// Photons stored, as a number (Table 3's row of the same map).
    pub count: usize,
    /// Light source, seconds.
    pub light_seconds: f64,
    /// Camera source, seconds.
    pub camera_seconds: f64,
}

impl Table4Row {
    const fn new(photons: &'static str, count: usize, light_seconds: f64, camera_seconds: f64) -> Self {
        Table4Row {
            photons,
            count,
            light_seconds,
            camera_seconds,
        }
    }
}

/// Bytes per photon, kd-tree included: method I.
pub const BYTES_PER_PHOTON_METHOD1: usize = 46;
/// Bytes per photon, kd-tree included: method II.
pub const BYTES_PER_PHOTON_METHOD2: usize = 58;
/// The paper's largest map, photons.
pub const LARGEST_MAP_PHOTONS: usize = 8_530_000;
/// Memory of the largest map, MB (approximately).
pub const LARGEST_MAP_MB: f64 = 470.0;
