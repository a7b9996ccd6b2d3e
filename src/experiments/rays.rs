//! The ray studies: accuracy and cost against the number of gather rays, final gathering
//! against the cube map (paper Tables 1–2, Fig. 9, 12, 13).

use super::grid::{write_grid, write_labelled_grid, Labels, Tile};
use super::paper;
use super::plot::{log_log_beside_paper, Series};
use super::presets::REFERENCE_SEED;
use super::runner::Runner;
use super::section::Section;
use super::table::Table;
use crate::error::Result;
use crate::estimators::cubemap::GpuFill;
use crate::estimators::{CubemapParams, GatherParams};
use crate::image::picture::grey;
use crate::image::HmdImage;
use crate::metrics::{difference_picture, f_diff};
use crate::sampling::Sampler;

/// One ray count of a sweep: gather and the cube map, f_diff and seconds.
struct SweepRow {
    rays: u32,
    gather_f_diff: f64,
    /// The cube map's, where the run renders cube maps ([`Runner::with_cubemaps`]).
    cubemap: Option<CubemapCell>,
    gather_seconds: f64,
}

/// One ray count's cube map: f_diff and seconds.
#[derive(Clone, Copy)]
struct CubemapCell {
    f_diff: f64,
    seconds: f64,
}

/// The rows, the reference and gather's image per ray count.
struct RaySweep {
    rows: Vec<SweepRow>,
    excluded: usize,
    reference: HmdImage,
    gathered: Vec<HmdImage>,
    /// The cube map's image per ray count, where the run renders cube maps.
    cubemaps: Vec<HmdImage>,
    /// Where the cube maps were built, as their reports say (`cpu`, `gpu`); `None` where
    /// the run renders no cube map.
    cubemap_backend: Option<String>,
}

impl RaySweep {
    /// One column of the rows against the ray count, for a plot.
    fn series(&self, label: &str, pick: fn(&SweepRow) -> Option<f64>) -> Series {
        Series {
            label: label.into(),
            points: self
                .rows
                .iter()
                .filter_map(|r| pick(r).map(|v| (r.rays as f64, v)))
                .collect(),
        }
    }

    /// The plot's series: gather's column and, where the run made cube maps, theirs.
    fn plot_series(
        &self,
        cubemap: &Option<String>,
        gather: fn(&SweepRow) -> Option<f64>,
        cube: fn(&SweepRow) -> Option<f64>,
    ) -> Vec<Series> {
        let mut series = vec![self.series("gather", gather)];
        if let Some(label) = cubemap {
            series.push(self.series(label, cube));
        }
        series
    }
}

/// `gather` with `rays` rays (on the runner's backend), on the jittered grid of the paper's
/// sampling (spec §3.1), named so that its images and their cache keys stay as published.
pub(super) fn gather_params(rays: u32) -> GatherParams {
    GatherParams {
        rays,
        sampler: Sampler::Grid,
        ..GatherParams::default()
    }
}

/// The cube map with `rays` rays at the preset's resolution (on the runner's backend).
fn cubemap_params(runner: &Runner, rays: u32) -> CubemapParams {
    CubemapParams {
        rays,
        cube_res: runner.params.cube_res,
        ..CubemapParams::default()
    }
}

/// The reference image: gather with [`Runner::reference_params`], its own seed.
pub(super) fn reference(runner: &Runner) -> Result<HmdImage> {
    Ok(runner
        .method_image("gather", &runner.reference_params(), REFERENCE_SEED)?
        .0)
}

/// The cube maps of the preset's resolution that the ray studies of this run need: Table 1's,
/// one per ray count, and, where the run includes Fig. 9 at that resolution, Fig. 9's at the
/// reference's ray count. They share each pixel's hemicube: [`Runner::cubemap_sweep`] makes
/// them in one pass.
fn cubemap_group(runner: &Runner) -> Vec<CubemapParams> {
    let p = &runner.params;
    let mut group: Vec<CubemapParams> = p.rays.iter().map(|&rays| cubemap_params(runner, rays)).collect();
    let fig9_res = paper::CPU_VS_GPU_AT_65536
        .iter()
        .any(|c| c.cube_res == p.cube_res);
    if runner.runs("fig9") && fig9_res {
        group.push(cubemap_params(runner, p.reference_rays));
    }
    group
}

/// Renders the reference and, for each ray count, gather and (unless the run renders no
/// cube maps) the cube map.
fn ray_sweep(runner: &Runner) -> Result<RaySweep> {
    let reference = reference(runner)?;
    if runner.cubemaps() {
        runner.cubemap_sweep(&cubemap_group(runner), 1)?;
    }
    let l_diag = runner.scene.diagonal();
    let (mut rows, mut gathered, mut cubemaps, mut excluded) = (vec![], vec![], vec![], 0);
    let mut cubemap_backend = None;
    for &rays in &runner.params.rays {
        let (g, g_report) = runner.method_image("gather", &gather_params(rays), 1)?;
        let fg = f_diff(&reference, &g, l_diag)?;
        excluded = excluded.max(fg.excluded);
        let mut cubemap = None;
        if runner.cubemaps() {
            let (c, c_report) = runner.method_image("cubemap", &cubemap_params(runner, rays), 1)?;
            cubemap_backend = Some(backend_of(&c_report));
            let fc = f_diff(&reference, &c, l_diag)?;
            excluded = excluded.max(fc.excluded);
            cubemap = Some(CubemapCell {
                f_diff: fc.value,
                seconds: c_report.seconds.estimate,
            });
            cubemaps.push(c);
        }
        rows.push(SweepRow {
            rays,
            gather_f_diff: fg.value,
            cubemap,
            gather_seconds: g_report.seconds.estimate,
        });
        gathered.push(g);
    }
    Ok(RaySweep {
        rows,
        excluded,
        reference,
        gathered,
        cubemaps,
        cubemap_backend,
    })
}

/// The backend a report says its image was made on (`?` for another shard's stand-in), with
/// `, rays` for a GPU cube map whose texels were filled by rays.
fn backend_of(report: &crate::report::RenderReport) -> String {
    let backend = report
        .details
        .device
        .as_ref()
        .map_or("?".into(), |d| d.backend.clone());
    let fill = report.parameters.typed::<CubemapParams>().map(|c| c.gpu_fill);
    match fill {
        Some(GpuFill::Rays) if backend == "gpu" => format!("{backend}, rays"),
        _ => backend,
    }
}

/// The label of the cube map's column: its resolution and backend, as rendered; `None`
/// where the run rendered no cube map.
fn cubemap_label(runner: &Runner, sweep: &RaySweep) -> Option<String> {
    let backend = sweep.cubemap_backend.as_ref()?;
    Some(format!("cubemap R = {} ({backend})", runner.params.cube_res))
}

/// A table cell: `value` with `digits` decimals, or empty where there is none.
fn cell(value: Option<f64>, digits: usize) -> String {
    value.map_or(String::new(), |v| format!("{v:.digits$}"))
}

/// Table 1: f_diff against the reference by number of gather rays, gather and cube map.
pub fn table1(runner: &Runner) -> Result<Section> {
    let sweep = ray_sweep(runner)?;
    let p = &runner.params;
    let cubemap = cubemap_label(runner, &sweep);
    let mut ours = Table::new(
        &format!(
            "Table 1 (preset {}): f_diff against gather with {} rays, {}², `{}`",
            runner.preset.name(),
            p.reference_rays,
            p.size,
            runner.scene.name
        ),
        &strs(&columns(
            &["rays", "gather f_diff"],
            cubemap.as_ref().map(|c| format!("{c} f_diff")),
            &[
                "gather step ratio",
                "paper CPU, A",
                "paper CPU, B",
                "paper GPU, A",
            ],
        )),
    );
    let mut previous: Option<f64> = None;
    for row in &sweep.rows {
        let fg = row.gather_f_diff;
        let ratio = previous.map_or("".to_string(), |q| format!("{:.2}", fg / q));
        let cube = cubemap.as_ref().map(|_| cell(row.cubemap.map(|c| c.f_diff), 4));
        let published = paper::table1_as_read(row.rays);
        let paper_cell = |pick: fn((f64, f64, f64)) -> f64| cell(published.map(pick), 4);
        ours.push(columns(
            &[&row.rays.to_string(), &format!("{fg:.4}")],
            cube,
            &[
                &ratio,
                &paper_cell(|p| p.0),
                &paper_cell(|p| p.1),
                &paper_cell(|p| p.2),
            ],
        ));
        previous = Some(fg);
    }
    let published = table1_paper();
    let mut files = ours.write(&runner.out, "table1")?;
    files.extend(published.write(&runner.out, "table1_paper")?);
    let plot = runner.out.join("table1.svg");
    let paper_series = table1_paper_series(runner, &cubemap);
    log_log_beside_paper(
        &plot,
        "f_diff against the reference",
        "gather rays N",
        "f_diff (% of l_diag)",
        &sweep.plot_series(
            &cubemap,
            |r| Some(r.gather_f_diff),
            |r| r.cubemap.map(|c| c.f_diff),
        ),
        &paper_series,
    )?;
    files.push(plot);
    files.extend(ray_grids(runner, &sweep)?);
    Ok(Section {
        name: "table1".into(),
        findings: table1_findings(&sweep),
        notes: vec![format!(
            "Pixels excluded from f_diff (not finite in one of the images): {}. The paper's columns are read in the text's order against the headings of its two halves (32 … 256, then 1,024 … 8,192); one column of each half was lost, so which N each value belongs to is uncertain (spec §6).",
            sweep.excluded
        )],
        tables: vec![ours, published],
        files,
    })
}

/// The paper's Table 1 as published, in the text's order.
fn table1_paper() -> Table {
    let mut published = Table::new(
        "Table 1, the paper's values (in the text's order; the ray count of each value is uncertain)",
        &["#", "CPU, scene A", "CPU, scene B", "GPU, scene A"],
    );
    for i in 0..paper::TABLE1_CPU_A.len() {
        published.push(vec![
            (i + 1).to_string(),
            format!("{:.4}", paper::TABLE1_CPU_A[i]),
            format!("{:.4}", paper::TABLE1_CPU_B[i]),
            format!("{:.4}", paper::TABLE1_GPU_A[i]),
        ]);
    }
    published
}

/// The paper's Table 1 as series for the plot, for this scene's paper analogue: its CPU
/// column, and its GPU column where our cube map is drawn (`cubemap`).
fn table1_paper_series(runner: &Runner, cubemap: &Option<String>) -> Vec<Series> {
    let mut paper_series = vec![];
    if let Some(scene) = paper::analogue(&runner.scene.name) {
        let name = if scene == paper::PaperScene::A { "A" } else { "B" };
        let as_xy = |points: Vec<(u32, f64)>| points.into_iter().map(|(n, f)| (n as f64, f)).collect();
        let (cpu, gpu) = paper::table1_points(scene);
        paper_series.push(Series {
            label: format!("paper CPU, scene {name} (as read)"),
            points: as_xy(cpu),
        });
        // The paper's GPU cube map beside ours only where ours is drawn (same colour).
        if let (Some(gpu), Some(_)) = (gpu, cubemap) {
            paper_series.push(Series {
                label: format!("paper GPU, scene {name} (as read)"),
                points: as_xy(gpu),
            });
        }
    }
    paper_series
}

fn table1_findings(sweep: &RaySweep) -> Vec<String> {
    let ratios: Vec<String> = sweep
        .rows
        .windows(2)
        .map(|w| {
            let ratio = w[1].gather_f_diff / w[0].gather_f_diff;
            format!("{}→{}: ×{ratio:.2}", w[0].rays, w[1].rays)
        })
        .collect();
    let below_level_off: Vec<&SweepRow> = sweep
        .rows
        .iter()
        .filter(|r| r.rays <= paper::LEVEL_OFF_RAYS / 2)
        .collect();
    let falls = below_level_off
        .windows(2)
        .all(|w| w[1].gather_f_diff < w[0].gather_f_diff);
    // From the level-off on, a step of more than ×0.95 is flat or up: the paper's
    // oscillation (its scene A steps ×1.42 once, its scene B ×0.99).
    let late: Vec<f64> = sweep
        .rows
        .windows(2)
        .filter(|w| w[0].rays >= paper::LEVEL_OFF_RAYS)
        .map(|w| w[1].gather_f_diff / w[0].gather_f_diff)
        .collect();
    let largest = late.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let from_level_off = if late.is_empty() {
        "the run has no ray counts past it".to_string()
    } else if largest > 0.95 {
        format!(
            "from {} rays on it oscillates (a step of ×{largest:.2})",
            paper::LEVEL_OFF_RAYS
        )
    } else {
        format!(
            "from {} rays on it keeps falling at every step (at most ×{largest:.2}): no oscillation",
            paper::LEVEL_OFF_RAYS
        )
    };
    vec![format!(
        "Final gathering's error falls with each doubling of rays, then oscillates down slowly from about {} rays (paper): {} up to {} rays; {from_level_off}. Per doubling {}.",
        paper::LEVEL_OFF_RAYS,
        if falls { "it falls at every step" } else { "it does NOT fall at every step" },
        paper::LEVEL_OFF_RAYS / 2,
        ratios.join(", "),
    )]
}

/// Table 2: seconds per image against gather rays, gather and cube map.
pub fn table2(runner: &Runner) -> Result<Section> {
    let sweep = ray_sweep(runner)?;
    let p = &runner.params;
    let cubemap = cubemap_label(runner, &sweep);
    let mut ours = Table::new(
        &format!(
            "Table 2 (preset {}): seconds per {}² image of `{}`",
            runner.preset.name(),
            p.size,
            runner.scene.name
        ),
        &strs(&columns(
            &["rays", "gather s"],
            cubemap.as_ref().map(|c| format!("{c} s")),
            &["paper CPU s", "paper GPU s"],
        )),
    );
    for row in &sweep.rows {
        let cube = cubemap.as_ref().map(|_| cell(row.cubemap.map(|c| c.seconds), 3));
        let published = paper::table2_row(row.rays);
        ours.push(columns(
            &[&row.rays.to_string(), &format!("{:.3}", row.gather_seconds)],
            cube,
            &[
                &cell(published.map(|p| p.cpu_seconds), 1),
                &cell(published.map(|p| p.gpu_seconds), 1),
            ],
        ));
    }
    let published = table2_paper();
    let findings = table2_findings(&sweep);
    let mut files = ours.write(&runner.out, "table2")?;
    files.extend(published.write(&runner.out, "table2_paper")?);
    let plot = runner.out.join("table2.svg");
    let paper_seconds = |label: &str, seconds: fn(&paper::Table2Row) -> f64| Series {
        label: label.into(),
        points: paper::TABLE2
            .iter()
            .map(|r| (r.rays as f64, seconds(r)))
            .collect(),
    };
    log_log_beside_paper(
        &plot,
        "seconds per image",
        "gather rays N",
        "seconds",
        &sweep.plot_series(
            &cubemap,
            |r| Some(r.gather_seconds),
            |r| r.cubemap.map(|c| c.seconds),
        ),
        &[
            paper_seconds("paper CPU (Xeon E5420)", |r| r.cpu_seconds),
            paper_seconds("paper GPU (8800 GTX)", |r| r.gpu_seconds),
        ],
    )?;
    files.push(plot);
    Ok(Section {
        name: "table2".into(),
        tables: vec![ours, published],
        files,
        findings,
        ..Section::default()
    })
}

/// The paper's Table 2 as published.
fn table2_paper() -> Table {
    let mut published = Table::new(
        "Table 2, the paper's values (1024², Xeon E5420 vs GeForce 8800 GTX)",
        &["rays", "CPU s", "GPU s"],
    );
    for row in &paper::TABLE2 {
        published.push(vec![
            row.rays.to_string(),
            format!("{}", row.cpu_seconds),
            format!("{}", row.gpu_seconds),
        ]);
    }
    published
}

/// Table 2's finding: how the cube map's seconds grow with N against gather's, beside the
/// paper's GPU.
fn table2_findings(sweep: &RaySweep) -> Vec<String> {
    let (first, last) = (sweep.rows.first(), sweep.rows.last());
    let (paper_first, paper_last) = (&paper::TABLE2[0], &paper::TABLE2[paper::TABLE2.len() - 1]);
    let cube_ends = first.and_then(|a| a.cubemap).zip(last.and_then(|b| b.cubemap));
    match (first, last, cube_ends) {
        (Some(a), Some(b), Some((ca, cb))) => vec![format!(
            "The cube map's cost hardly depends on N (paper, GPU: ×{:.2} from {} to {} rays): here, from {} to {} rays, gather's seconds grow ×{:.1} and the cube map's ({}) ×{:.1} — the CPU backend fills only the texels it looks up, so it scales like gathering; the GPU backend renders whole hemicubes (see `cargo bench --bench cubemap`).",
            paper_last.gpu_seconds / paper_first.gpu_seconds,
            paper_first.rays,
            paper_last.rays,
            a.rays,
            b.rays,
            b.gather_seconds / a.gather_seconds,
            sweep.cubemap_backend.as_deref().unwrap_or("?"),
            cb.seconds / ca.seconds
        )],
        // No cube map in the run (`--no-cubemap`): the finding is named, not tested.
        _ => vec![format!(
            "The cube map's cost hardly depends on N (paper, GPU: ×{:.2} from {} to {} rays): not tested here — this run made no cube maps.",
            paper_last.gpu_seconds / paper_first.gpu_seconds,
            paper_first.rays,
            paper_last.rays
        )],
    }
}

/// A table row or header: `head`, then `middle` where there is one, then `tail`.
fn columns<S: AsRef<str>>(head: &[S], middle: Option<String>, tail: &[S]) -> Vec<String> {
    let head = head.iter().map(|s| s.as_ref().to_string());
    let tail = tail.iter().map(|s| s.as_ref().to_string());
    head.chain(middle).chain(tail).collect()
}

/// `cells` borrowed, for [`Table::new`].
fn strs(cells: &[String]) -> Vec<&str> {
    cells.iter().map(String::as_str).collect()
}

/// Fig. 12 (the cube map by N, where the run renders cube maps) and Fig. 13 (gather by N),
/// laid out as the paper's: the counts in reading order, five to a row, each row of
/// pictures followed by a row of their difference pictures against the reference.
fn ray_grids(runner: &Runner, sweep: &RaySweep) -> Result<Vec<std::path::PathBuf>> {
    let mut files = vec![];
    // The cube map's figure where the run made cube maps; the rows are labelled by estimator.
    let cubemap = sweep
        .cubemap_backend
        .as_ref()
        .map(|_| ("fig12", "cubemap", &sweep.cubemaps));
    let gather = Some(("fig13", "gather", &sweep.gathered));
    for (name, label, images) in cubemap.into_iter().chain(gather) {
        let path = runner.out.join(format!("{name}.png"));
        let (tiles, labels) = by_rays(runner, sweep, label, images);
        write_labelled_grid(&path, &tiles, BY_RAYS_COLUMNS, &labels)?;
        files.push(path);
    }
    Ok(files)
}

/// How many ray counts a row of Fig. 12 and 13 shows (the paper's: 32 … 512, then 1,024 …
/// 16,384).
const BY_RAYS_COLUMNS: usize = 5;

/// One of Fig. 12 and 13: `images` (one per ray count of `sweep`) of the estimator `label`
/// (its rows' label),
/// five to a row, each row of pictures over a row of difference pictures; rows labelled.
fn by_rays(
    runner: &Runner,
    sweep: &RaySweep,
    label: &str,
    images: &[HmdImage],
) -> (Vec<Option<Tile>>, Labels) {
    let s = runner.scene.display_scale;
    let mut tiles = vec![];
    let mut rows = vec![];
    let counts: Vec<u32> = sweep.rows.iter().map(|r| r.rays).collect();
    for (counts, images) in counts.chunks(BY_RAYS_COLUMNS).zip(images.chunks(BY_RAYS_COLUMNS)) {
        let blank = BY_RAYS_COLUMNS - counts.len();
        for (&rays, image) in counts.iter().zip(images) {
            tiles.push(Some(Tile::grey(format!("N={rays}"), &grey(image, s))));
        }
        tiles.extend((0..blank).map(|_| None));
        for (&rays, image) in counts.iter().zip(images) {
            let picture = difference_picture(&sweep.reference, image, s);
            tiles.push(Some(Tile::colour(format!("N={rays}"), picture)));
        }
        tiles.extend((0..blank).map(|_| None));
        rows.push(label.to_string());
        rows.push("diff".to_string());
    }
    (
        tiles,
        Labels {
            columns: vec![],
            rows,
        },
    )
}

/// Fig. 9: gather against the cube map at the paper's two resolutions, all at the reference
/// ray count, with difference pictures.
pub fn fig9(runner: &Runner) -> Result<Section> {
    let p = &runner.params;
    let config = cubemap_params(runner, p.reference_rays);
    // The paper's Fig. 9 compares CPU final gathering with the reference's ray count against
    // the cube map: that gather image *is* the reference, so it is not rendered again.
    let g = reference(runner)?;
    let l_diag = runner.scene.diagonal();
    let s = runner.scene.display_scale;
    let mut table = Table::new(
        &format!(
            "Fig. 9 (preset {}): cube map against gather, {} rays, {}²",
            runner.preset.name(),
            p.reference_rays,
            p.size
        ),
        &["R", "f_diff", "pixels compared"],
    );
    let mut top = vec![Some(Tile::grey("gather (ref)", &grey(&g, s)))];
    let mut bottom = vec![None];
    let mut notes = vec![];
    // (the paper's f_diff, ours) at each R.
    let mut values = vec![];
    for published in &paper::CPU_VS_GPU_AT_65536 {
        let r = published.cube_res;
        let config = CubemapParams {
            cube_res: r,
            ..config.clone()
        };
        let (c, c_report) = runner.method_image("cubemap", &config, 1)?;
        let d = f_diff(&g, &c, l_diag)?;
        table.push(vec![
            r.to_string(),
            format!("{:.4}", d.value),
            d.compared.to_string(),
        ]);
        values.push((published.f_diff, d.value));
        notes.push(format!(
            "R = {r}: paper {}, here {:.4} (cube map on {})",
            published.f_diff,
            d.value,
            backend_of(&c_report)
        ));
        top.push(Some(Tile::grey(format!("cube R={r}"), &grey(&c, s))));
        bottom.push(Some(Tile::colour(
            format!("diff R={r}"),
            difference_picture(&g, &c, s),
        )));
    }
    let path = runner.out.join("fig9.png");
    top.extend(bottom);
    write_grid(&path, &top, 3)?;
    let mut files = table.write(&runner.out, "fig9")?;
    files.push(path);
    Ok(Section {
        name: "fig9".into(),
        tables: vec![table],
        files,
        findings: vec![format!(
            "The cube map agrees with final gathering to about 0.029 at R = 64 and 128 alike (paper, its CPU gather against its GPU cube map): {} — {}.",
            fig9_verdict(&values),
            notes.join("; ")
        )],
        ..Section::default()
    })
}

/// Fig. 9's verdict from (the paper's f_diff, ours) at each R: the paper's finding is a size
/// that does not depend on R, so both must hold — each of ours within a quarter of the
/// paper's, and ours at the two R within 10 % of each other. A size alone cannot say whether
/// the cause is the paper's (an error of the cube map, far above the images' noise), which
/// `docs/paper-scale/fig9-anatomy` measures.
fn fig9_verdict(values: &[(f64, f64)]) -> &'static str {
    let sized = values
        .iter()
        .all(|&(paper, ours)| (ours / paper - 1.0).abs() <= 0.25);
    let (low, high) = values
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), &(_, v)| (l.min(v), h.max(v)));
    let same = high <= 1.1 * low;
    match (sized, same) {
        (true, true) => "agrees in size and does not depend on R (whether for the paper's reason, the noise floor decides)",
        (true, false) => "not reproduced: the size is near the paper's but depends on R",
        (false, true) => "not reproduced: it does not depend on R, but its size is not the paper's",
        (false, false) => "not reproduced: neither its size nor its independence of R is the paper's",
    }
}

/// Fig. 11: the cube map at the preset's resolution and the reference's ray count (the
/// paper's shows scene B's GPU cube map at 65,536 rays), beside the reference and their
/// difference picture.
pub fn fig11(runner: &Runner) -> Result<Section> {
    let p = &runner.params;
    let g = reference(runner)?;
    let (c, c_report) = runner.method_image("cubemap", &cubemap_params(runner, p.reference_rays), 1)?;
    let d = f_diff(&g, &c, runner.scene.diagonal())?;
    let s = runner.scene.display_scale;
    let mut table = Table::new(
        &format!(
            "Fig. 11 (preset {}): cube map R = {} against gather, {} rays, {}², `{}`",
            runner.preset.name(),
            p.cube_res,
            p.reference_rays,
            p.size,
            runner.scene.name
        ),
        &["R", "backend", "f_diff", "pixels compared", "cube map s"],
    );
    table.push(vec![
        p.cube_res.to_string(),
        backend_of(&c_report),
        format!("{:.4}", d.value),
        d.compared.to_string(),
        format!("{:.1}", c_report.seconds.estimate),
    ]);
    let tiles = vec![
        Some(Tile::grey(
            format!("gather {} (ref)", p.reference_rays),
            &grey(&g, s),
        )),
        Some(Tile::grey(format!("cube R={}", p.cube_res), &grey(&c, s))),
        Some(Tile::colour("diff x10", difference_picture(&g, &c, s))),
    ];
    let path = runner.out.join("fig11.png");
    write_grid(&path, &tiles, 3)?;
    let mut files = table.write(&runner.out, "fig11")?;
    files.push(path);
    Ok(Section {
        name: "fig11".into(),
        tables: vec![table],
        files,
        findings: vec![format!(
            "The paper's Fig. 11 shows scene B's GPU cube map at 65,536 rays, an image with no number, as a picture of the reference's shape: here the cube map (R = {}, {}) differs from the {}-ray gather reference by f_diff {:.4} (the picture beside it).",
            p.cube_res,
            backend_of(&c_report),
            p.reference_rays,
            d.value
        )],
        ..Section::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fig9_is_reproduced_only_by_the_papers_size_at_both_resolutions_alike() {
        // This page's 1024² values against the paper's 0.029 at R = 64 and 128.
        let ours = fig9_verdict(&[(0.029, 0.0225), (0.029, 0.0202)]);
        assert!(ours.starts_with("not reproduced: neither"), "{ours}");
        assert!(fig9_verdict(&[(0.029, 0.028), (0.029, 0.030)]).starts_with("agrees"));
        assert!(fig9_verdict(&[(0.029, 0.014), (0.029, 0.0077)]).contains("neither"));
        assert!(fig9_verdict(&[(0.029, 0.027), (0.029, 0.023)]).contains("depends on R"));
        assert!(fig9_verdict(&[(0.029, 0.010), (0.029, 0.0102)]).contains("size is not"));
    }
}
