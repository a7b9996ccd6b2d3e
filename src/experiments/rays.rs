//! The ray studies: accuracy and cost against the number of gather rays, final gathering
//! against the cube map (paper Tables 1–2, Fig. 9, 12, 13).

use super::grid::{write_grid, Tile};
use super::paper;
use super::plot::{log_log, Series};
use super::{Runner, Section, Table, REFERENCE_SEED};
use crate::error::Result;
use crate::estimators::cubemap::GpuFill;
use crate::estimators::{CubemapParams, GatherParams};
use crate::image::picture::grey;
use crate::image::HmdImage;
use crate::metrics::{difference_picture, f_diff};

/// One ray count of a sweep: gather and the cube map, f_diff and seconds.
struct SweepRow {
    rays: u32,
    gather_f_diff: f64,
    cubemap_f_diff: f64,
    gather_seconds: f64,
    cubemap_seconds: f64,
}

/// The rows, the reference and gather's image per ray count.
struct RaySweep {
    rows: Vec<SweepRow>,
    excluded: usize,
    reference: HmdImage,
    gathered: Vec<HmdImage>,
    /// Where the cube maps were built, as their reports say (`cpu`, `gpu`).
    cubemap_backend: String,
}

impl RaySweep {
    /// One column of the rows against the ray count, for a plot.
    fn series(&self, label: &str, pick: fn(&SweepRow) -> f64) -> Series {
        Series {
            label: label.into(),
            points: self.rows.iter().map(|r| (r.rays as f64, pick(r))).collect(),
        }
    }
}

/// `gather` with `rays` rays (on the runner's backend).
fn gather_params(rays: u32) -> GatherParams {
    GatherParams {
        rays,
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

/// The reference image's parameters: gather with the preset's reference ray count.
pub(super) fn reference_params(runner: &Runner) -> GatherParams {
    gather_params(runner.params.reference_rays)
}

/// The reference image: gather with [`reference_params`], its own seed.
pub(super) fn reference(runner: &Runner) -> Result<HmdImage> {
    Ok(runner
        .method_image("gather", &reference_params(runner), REFERENCE_SEED)?
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

/// Renders the reference and, for each ray count, gather and the cube map.
fn ray_sweep(runner: &Runner) -> Result<RaySweep> {
    let reference = reference(runner)?;
    runner.cubemap_sweep(&cubemap_group(runner), 1)?;
    let l_diag = runner.scene.diagonal();
    let (mut rows, mut gathered, mut excluded) = (vec![], vec![], 0);
    let mut cubemap_backend = String::new();
    for &rays in &runner.params.rays {
        let (g, g_report) = runner.method_image("gather", &gather_params(rays), 1)?;
        let (c, c_report) = runner.method_image("cubemap", &cubemap_params(runner, rays), 1)?;
        cubemap_backend = backend_of(&c_report);
        let (fg, fc) = (f_diff(&reference, &g, l_diag)?, f_diff(&reference, &c, l_diag)?);
        excluded = excluded.max(fg.excluded).max(fc.excluded);
        rows.push(SweepRow {
            rays,
            gather_f_diff: fg.value,
            cubemap_f_diff: fc.value,
            gather_seconds: g_report.seconds.estimate,
            cubemap_seconds: c_report.seconds.estimate,
        });
        gathered.push(g);
    }
    Ok(RaySweep {
        rows,
        excluded,
        reference,
        gathered,
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
    match &report.parameters.cubemap {
        Some(c) if c.gpu_fill == GpuFill::Rays && backend == "gpu" => format!("{backend}, rays"),
        _ => backend,
    }
}

/// The label of the cube map's column: its resolution and backend, as rendered.
fn cubemap_label(runner: &Runner, sweep: &RaySweep) -> String {
    format!(
        "cubemap R = {} ({})",
        runner.params.cube_res, sweep.cubemap_backend
    )
}

/// Table 1: f_diff against the reference by number of gather rays, gather and cube map.
pub fn table1(runner: &Runner) -> Result<Section> {
    let sweep = ray_sweep(runner)?;
    let p = &runner.params;
    let cubemap = cubemap_label(runner, &sweep);
    let mut ours = Table::new(
        &format!(
            "Table 1 ({}): f_diff against gather with {} rays, {}², `{}`",
            runner.preset.name(),
            p.reference_rays,
            p.size,
            runner.scene.name
        ),
        &[
            "rays",
            "gather f_diff",
            &format!("{cubemap} f_diff"),
            "gather step ratio",
        ],
    );
    let mut previous: Option<f64> = None;
    for row in &sweep.rows {
        let fg = row.gather_f_diff;
        let ratio = previous.map_or("".to_string(), |q| format!("{:.2}", fg / q));
        ours.push(vec![
            row.rays.to_string(),
            format!("{fg:.4}"),
            format!("{:.4}", row.cubemap_f_diff),
            ratio,
        ]);
        previous = Some(fg);
    }
    let mut published = Table::new(
        "Table 1 (paper, in the text's order; the ray count of each value is uncertain)",
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
    let mut files = ours.write(&runner.out, "table1")?;
    files.extend(published.write(&runner.out, "table1_paper")?);
    let plot = runner.out.join("table1.svg");
    log_log(
        &plot,
        "f_diff against the reference",
        "gather rays N",
        "f_diff (% of l_diag)",
        &[
            sweep.series("gather", |r| r.gather_f_diff),
            sweep.series(&cubemap, |r| r.cubemap_f_diff),
        ],
    )?;
    files.push(plot);
    files.extend(ray_grids(runner, &sweep)?);
    Ok(Section {
        name: "table1".into(),
        notes: table1_notes(&sweep),
        tables: vec![ours, published],
        files,
    })
}

fn table1_notes(sweep: &RaySweep) -> Vec<String> {
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
    vec![
        format!(
            "Error halves per doubling up to about {} rays (paper): gather's f_diff changes per doubling {}; {} up to {} rays.",
            paper::LEVEL_OFF_RAYS,
            ratios.join(", "),
            if falls { "it falls at every step" } else { "it does NOT fall at every step" },
            paper::LEVEL_OFF_RAYS / 2,
        ),
        format!(
            "Pixels excluded from f_diff (not finite in one of the images): {}.",
            sweep.excluded
        ),
    ]
}

/// Table 2: seconds per image against gather rays, gather and cube map.
pub fn table2(runner: &Runner) -> Result<Section> {
    let sweep = ray_sweep(runner)?;
    let p = &runner.params;
    let cubemap = cubemap_label(runner, &sweep);
    let mut ours = Table::new(
        &format!(
            "Table 2 ({}): seconds per {}² image of `{}`",
            runner.preset.name(),
            p.size,
            runner.scene.name
        ),
        &["rays", "gather s", &format!("{cubemap} s")],
    );
    for row in &sweep.rows {
        ours.push(vec![
            row.rays.to_string(),
            format!("{:.3}", row.gather_seconds),
            format!("{:.3}", row.cubemap_seconds),
        ]);
    }
    let mut published = Table::new(
        "Table 2 (paper, 1024², Xeon E5420 vs GeForce 8800 GTX)",
        &["rays", "CPU s", "GPU s"],
    );
    for row in &paper::TABLE2 {
        published.push(vec![
            row.rays.to_string(),
            format!("{}", row.cpu_seconds),
            format!("{}", row.gpu_seconds),
        ]);
    }
    let (first, last) = (sweep.rows.first(), sweep.rows.last());
    let (paper_first, paper_last) = (&paper::TABLE2[0], &paper::TABLE2[paper::TABLE2.len() - 1]);
    let notes = match (first, last) {
        (Some(a), Some(b)) => vec![format!(
            "Cube-map cost hardly depends on N (paper, GPU: ×{:.2} from {} to {} rays): here, from {} to {} rays, gather's seconds grow ×{:.1} and the cube map's ({}) ×{:.1} — the CPU backend fills only the texels it looks up, so it scales like gathering; the GPU backend renders whole hemicubes (see `cargo bench --bench cubemap`).",
            paper_last.gpu_seconds / paper_first.gpu_seconds,
            paper_first.rays,
            paper_last.rays,
            a.rays,
            b.rays,
            b.gather_seconds / a.gather_seconds,
            sweep.cubemap_backend,
            b.cubemap_seconds / a.cubemap_seconds
        )],
        _ => vec![],
    };
    let mut files = ours.write(&runner.out, "table2")?;
    files.extend(published.write(&runner.out, "table2_paper")?);
    let plot = runner.out.join("table2.svg");
    log_log(
        &plot,
        "seconds per image",
        "gather rays N",
        "seconds",
        &[
            sweep.series("gather", |r| r.gather_seconds),
            sweep.series(&cubemap, |r| r.cubemap_seconds),
        ],
    )?;
    files.push(plot);
    Ok(Section {
        name: "table2".into(),
        tables: vec![ours, published],
        files,
        notes,
    })
}

/// Fig. 12 and 13: gather's HMD picture and its difference picture against the reference,
/// per ray count.
fn ray_grids(runner: &Runner, sweep: &RaySweep) -> Result<Vec<std::path::PathBuf>> {
    let s = runner.scene.display_scale;
    let mut hmd = vec![Some(Tile {
        caption: format!("ref {}", runner.params.reference_rays),
        picture: grey(&sweep.reference, s),
    })];
    let mut diff = vec![];
    for (row, image) in sweep.rows.iter().zip(&sweep.gathered) {
        hmd.push(Some(Tile {
            caption: format!("N={}", row.rays),
            picture: grey(image, s),
        }));
        diff.push(Some(Tile {
            caption: format!("N={}", row.rays),
            picture: difference_picture(&sweep.reference, image, s),
        }));
    }
    let (fig12, fig13) = (runner.out.join("fig12.png"), runner.out.join("fig13.png"));
    write_grid(&fig12, &hmd, 4)?;
    write_grid(&fig13, &diff, 4)?;
    Ok(vec![fig12, fig13])
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
            "Fig. 9 ({}): cube map against gather, {} rays, {}²",
            runner.preset.name(),
            p.reference_rays,
            p.size
        ),
        &["R", "f_diff", "pixels compared"],
    );
    let mut top = vec![Some(Tile {
        caption: "gather (ref)".into(),
        picture: grey(&g, s),
    })];
    let mut bottom = vec![None];
    let mut notes = vec![];
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
        notes.push(format!(
            "R = {r}: paper {} (CPU vs GPU at 65,536 rays), here {:.4} (cube map on {})",
            published.f_diff,
            d.value,
            backend_of(&c_report)
        ));
        top.push(Some(Tile {
            caption: format!("cube R={r}"),
            picture: grey(&c, s),
        }));
        bottom.push(Some(Tile {
            caption: format!("diff R={r}"),
            picture: difference_picture(&g, &c, s),
        }));
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
        notes: vec![format!("Cube map against gather: {}.", notes.join("; "))],
    })
}
