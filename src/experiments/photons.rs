//! The photon studies: gather cost and accuracy by photon count and K, methods I and II, path
//! sources and lengths, map build cost and memory (paper Tables 3–4, Fig. 10, 14–17).

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use super::grid::{crop, windows_differing_most, write_grid, write_labelled_grid, Labels, Tile};
use super::paper;
use super::plot::{log_log_beside_paper, Series};
use super::rays::reference;
use super::runner::Runner;
use super::section::Section;
use super::table::Table;
use crate::accel::{Accel, BuildQuality};
use crate::error::Result;
use crate::estimators::photon::{
    trace_photons, PathRules, PhotonMap, PhotonMethod, PhotonParams, PhotonSource, SourceKind,
    DEFAULT_ABSORPTION,
};
use crate::image::picture::grey;
use crate::image::HmdImage;
use crate::metrics::f_diff;

/// The paper's short paths (Table 3, Fig. 10).
const SHORT_PATHS: u32 = paper::BOUNCES[0];
/// The paper's long paths (Table 4).
const LONG_PATHS: u32 = paper::BOUNCES[1];

/// A photon method's configuration: `photons`, `k` gathered, `source`, `max_bounces`,
/// others default.
fn photon_config(photons: usize, k: usize, source: SourceKind, max_bounces: u32) -> PhotonParams {
    PhotonParams {
        photons,
        nearest: k,
        source,
        max_bounces,
        ..PhotonParams::default()
    }
}

/// Where Table 3's paths start: the camera, as for the paper's Fig. 14 and 15, which show
/// Table 3's photon counts and K (its captions: camera-sourced photons, 20 bounces).
pub(super) const TABLE3_SOURCE: SourceKind = SourceKind::Camera;

/// A photon count as the figures label it: `130 K`, `1.06 M`.
pub(super) fn photon_count(photons: usize) -> String {
    if photons >= 1_000_000 {
        format!("{:.2} M", photons as f64 / 1e6)
    } else {
        format!("{} K", photons / 1000)
    }
}

/// The light source where the scene has a spot light, else the camera.
pub(super) fn default_source(runner: &Runner) -> SourceKind {
    if runner.scene.light.is_some() {
        SourceKind::Light
    } else {
        SourceKind::Camera
    }
}

/// Fig. 10's close-ups: how many windows.
const CROPS: usize = 3;

/// One method's figures in one cell of Table 3.
struct Table3Cell {
    gather_seconds: f64,
    f_diff: f64,
    holes: u64,
}

/// Table 3 with Fig. 14 (method I) and Fig. 15 (method II): gather seconds and f_diff by
/// photon count and K, and the pictures.
pub fn table3(runner: &Runner) -> Result<Section> {
    let p = &runner.params;
    let reference = reference(runner)?;
    let l_diag = runner.scene.diagonal();
    let s = runner.scene.display_scale;
    let source = TABLE3_SOURCE;
    let mut table = Table::new(
        &format!(
            "Table 3 (preset {}): gather seconds (map build excluded) and f_diff, {}², {} source, {SHORT_PATHS} bounces",
            runner.preset.name(),
            p.size,
            source.name()
        ),
        &[
            "photons",
            "K",
            "source",
            "I gather s",
            "II gather s",
            "paper I s",
            "paper II s",
            "I f_diff",
            "II f_diff",
            "I holes",
            "II holes",
        ],
    );
    // Each method's pictures by (K, photons): the paper's figures have a column per photon
    // count and a row per K.
    let mut pictures = [BTreeMap::new(), BTreeMap::new()];
    let mut sums = [0.0, 0.0];
    // Each method's gather seconds over the table, for its extra cost against method I.
    let mut seconds = [0.0, 0.0];
    // Each row's method II gather seconds over method I's.
    let mut ratios = vec![];
    let mut lower_rows = 0;
    for &photons in &p.photons {
        for &k in &p.nearest {
            let mut cells = vec![];
            for (m, method) in PhotonMethod::ALL.iter().enumerate() {
                let config = photon_config(photons, k, source, SHORT_PATHS);
                let (image, report) = runner.method_image(method.name(), &config, 1)?;
                let d = f_diff(&reference, &image, l_diag)?;
                sums[m] += d.value;
                seconds[m] += report.seconds.phases.gather.unwrap_or(f64::NAN);
                cells.push(Table3Cell {
                    gather_seconds: report.seconds.phases.gather.unwrap_or(f64::NAN),
                    f_diff: d.value,
                    holes: report.details.photon.map_or(0, |p| p.holes),
                });
                pictures[m].insert((k, photons), grey(&image, s));
            }
            if cells[1].f_diff < cells[0].f_diff {
                lower_rows += 1;
            }
            ratios.push(cells[1].gather_seconds / cells[0].gather_seconds);
            let mut row = vec![photons.to_string(), k.to_string(), source.name().to_string()];
            row.extend(cells.iter().map(|c| format!("{:.3}", c.gather_seconds)));
            let published = paper::table3_cell(photons, k);
            row.push(published.map_or(String::new(), |c| c.method1_seconds.to_string()));
            row.push(published.map_or(String::new(), |c| c.method2_seconds.to_string()));
            row.extend(cells.iter().map(|c| format!("{:.4}", c.f_diff)));
            row.extend(cells.iter().map(|c| c.holes.to_string()));
            table.push(row);
        }
    }
    let published = table3_paper();
    let mut files = table.write(&runner.out, "table3")?;
    files.extend(published.write(&runner.out, "table3_paper")?);
    let labels = Labels {
        columns: p.photons.iter().map(|&n| photon_count(n)).collect(),
        rows: p.nearest.iter().map(|k| format!("K={k}")).collect(),
    };
    for (name, pictures) in [("fig14", &pictures[0]), ("fig15", &pictures[1])] {
        let tiles: Vec<Option<Tile>> = pictures
            .values()
            .map(|picture| Some(Tile::grey("", picture)))
            .collect();
        let path = runner.out.join(format!("{name}.png"));
        write_labelled_grid(&path, &tiles, p.photons.len(), &labels)?;
        files.push(path);
    }
    let (findings, note) = table3_findings(&table, sums, seconds, &ratios, lower_rows);
    let pictures = format!(
        "fig14.png (method I) and fig15.png (method II), as the paper's Fig. 14 and 15: a column per photon count stored ({}), a row per K ({}), {} source, {SHORT_PATHS} bounces, grey {} · H{}.",
        labels.columns.join(", "),
        p.nearest.iter().map(|k| k.to_string()).collect::<Vec<_>>().join(", "),
        source.name(),
        s,
        display_scale_against_paper(runner)
    );
    Ok(Section {
        name: "table3".into(),
        tables: vec![table, published],
        files,
        notes: vec![note, pictures],
        findings,
    })
}

/// Where the scene's display scale differs from the paper's for the scene it stands for,
/// a clause that says so (empty where it is the same or the scene stands for neither).
pub(super) fn display_scale_against_paper(runner: &Runner) -> String {
    let s = runner.scene.display_scale;
    let (scene, paper_scale) = match paper::analogue(&runner.scene.name) {
        Some(paper::PaperScene::A) => ("A", paper::DISPLAY_SCALE_A),
        Some(paper::PaperScene::B) => ("B", paper::DISPLAY_SCALE_B),
        None => return String::new(),
    };
    if (s - paper_scale).abs() < 1e-6 {
        String::new()
    } else {
        format!(" (the paper's scene {scene}: {paper_scale} · H; this scene's H spans another range)")
    }
}

/// The paper's Table 3 as published: gather seconds by photons stored and method (rows) and
/// K (columns), every cell.
fn table3_paper() -> Table {
    let ks: Vec<usize> = {
        let mut ks: Vec<usize> = paper::TABLE3.iter().map(|c| c.k).collect();
        ks.sort_unstable();
        ks.dedup();
        ks
    };
    let mut header = vec!["photons".to_string(), "method".to_string()];
    header.extend(ks.iter().map(|k| format!("K = {k}")));
    let mut published = Table::new(
        "Table 3, the paper's values (scene A, 1024², gather seconds, map build excluded)",
        &header.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    let mut photons: Vec<usize> = paper::TABLE3.iter().map(|c| c.photons).collect();
    photons.dedup();
    for n in photons {
        let methods: [(&str, fn(&paper::Table3Cell) -> f64); 2] =
            [("I", |c| c.method1_seconds), ("II", |c| c.method2_seconds)];
        for (method, pick) in methods {
            let mut row = vec![n.to_string(), method.to_string()];
            row.extend(
                ks.iter()
                    .map(|&k| paper::table3_cell(n, k).map_or(String::new(), |c| pick(c).to_string())),
            );
            published.push(row);
        }
    }
    published
}

/// Table 3's findings (method II's error and its extra seconds against method I's, from
/// `sums` of f_diff and of seconds over `table`'s rows, each row's II/I seconds `ratios`, II
/// lower in `lower_rows`), and the note of the paper's corner cells.
fn table3_findings(
    table: &Table,
    sums: [f64; 2],
    seconds: [f64; 2],
    ratios: &[f64],
    lower_rows: usize,
) -> (Vec<String>, String) {
    let n = table.rows.len() as f64;
    let (fewest, most) = (
        paper::TABLE3[0].photons,
        paper::TABLE3[paper::TABLE3.len() - 1].photons,
    );
    let corners: Vec<String> = paper::TABLE3
        .iter()
        .filter(|c| [fewest, most].contains(&c.photons) && [64, 1024].contains(&c.k))
        .map(|c| {
            format!(
                "{} photons, K = {}: {} / {} s",
                c.photons, c.k, c.method1_seconds, c.method2_seconds
            )
        })
        .collect();
    let [seconds1, seconds2] = seconds;
    let paper_ratio = paper::TABLE3.iter().map(|c| c.method2_seconds).sum::<f64>()
        / paper::TABLE3.iter().map(|c| c.method1_seconds).sum::<f64>();
    let findings = vec![
        format!(
            "Method II reduces method I's error near corners and thin parts (paper Fig. 6–7, 10): mean f_diff over this table {:.4} (I) against {:.4} (II); II lower in {} of {} rows.",
            sums[0] / n,
            sums[1] / n,
            lower_rows,
            table.rows.len()
        ),
        cost_finding(paper_ratio, seconds2 / seconds1, ratios),
    ];
    let note = format!(
        "The paper's Table 3 (1024², method I / II, scene A): {}.",
        corners.join("; ")
    );
    (findings, note)
}

/// Whether method II costs 1–9 % more than method I, as the paper says: row by row (every
/// row's II/I `ratios` within), in aggregate only (the table's sum `summed` within 1–9 % or
/// within 3 points of the paper's own sum `paper_ratio`, its rows spread wider), or not.
fn cost_finding(paper_ratio: f64, summed: f64, ratios: &[f64]) -> String {
    let percent = |r: f64| 100.0 * (r - 1.0);
    let inside = ratios.iter().filter(|&&r| (1.01..=1.09).contains(&r)).count();
    let faster = ratios.iter().filter(|&&r| r < 1.0).count();
    let (low, high) = ratios
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &r| {
            (l.min(r), h.max(r))
        });
    let verdict = if inside == ratios.len() {
        "agrees row by row"
    } else if (1.01..=1.09).contains(&summed) || (percent(summed) - percent(paper_ratio)).abs() <= 3.0 {
        "agrees in aggregate only"
    } else {
        "does not agree"
    };
    format!(
        "Method II costs 1–9 % more than method I (paper §4.3; its Table 3 sums to +{:.0} %): {verdict} — here its gathers take {:+.1} % summed over the table, {:+.0} % to {:+.0} % row by row, {inside} of {} rows inside 1–9 %, method II faster in {faster} (each gather timed once).",
        percent(paper_ratio),
        percent(summed),
        percent(low),
        percent(high),
        ratios.len()
    )
}

/// Fig. 10: methods I and II side by side with very many photons and a very large gather.
pub fn fig10(runner: &Runner) -> Result<Section> {
    let p = &runner.params;
    let reference = reference(runner)?;
    let (photons, k) = (p.fig10_photons, p.fig10_nearest);
    let source = default_source(runner);
    let s = runner.scene.display_scale;
    let mut table = Table::new(
        &format!(
            "Fig. 10 (preset {}): {photons} photons, K = {k}, {} source, {SHORT_PATHS} bounces",
            runner.preset.name(),
            source.name()
        ),
        &["method", "f_diff", "holes"],
    );
    let mut tiles = vec![Some(Tile::grey("reference", &grey(&reference, s)))];
    let mut errors = vec![];
    let mut images = vec![];
    for method in PhotonMethod::ALL {
        let config = photon_config(photons, k, source, SHORT_PATHS);
        let (image, report) = runner.method_image(method.name(), &config, 1)?;
        let d = f_diff(&reference, &image, runner.scene.diagonal())?;
        errors.push(d.value);
        table.push(vec![
            method.name().into(),
            format!("{:.4}", d.value),
            report.details.photon.map_or(0, |p| p.holes).to_string(),
        ]);
        tiles.push(Some(Tile::grey(method.name(), &grey(&image, s))));
        images.push(image);
    }
    let path = runner.out.join("fig10.png");
    write_grid(&path, &tiles, 3)?;
    let mut files = table.write(&runner.out, "fig10")?;
    files.push(path);
    let notes = closeups(runner, &reference, &images, &mut files)?;
    Ok(Section {
        name: "fig10".into(),
        tables: vec![table],
        files,
        findings: vec![format!(
            "With very many photons and a very large K, method I's small distances spread into dark discs and method II avoids them (paper Fig. 10): f_diff {:.4} (I) against {:.4} (II).",
            errors[0], errors[1]
        )],
        notes,
        ..Section::default()
    })
}

/// Fig. 10's close-ups, as the paper shows its figures' hands and feet: per window a row of
/// the reference, method I and method II at twice the size, into `fig10_crops.png`; the note
/// that says which windows they are.
fn closeups(
    runner: &Runner,
    reference: &HmdImage,
    images: &[HmdImage],
    files: &mut Vec<PathBuf>,
) -> Result<Vec<String>> {
    let size = runner.params.size;
    let side = (size / 8).max(16).min(size);
    let (windows, chosen): (Vec<(&str, (u32, u32))>, _) = match fine_parts(&runner.scene.name) {
        Some(parts) => {
            let corner = |f: f64| ((f * size as f64) as u32).min(size - side);
            let windows = parts.map(|(name, x, y)| (name, (corner(x), corner(y))));
            (windows.to_vec(), "chosen by hand on the scene's fine parts")
        }
        None => {
            let found = windows_differing_most(&images[0], &images[1], side, CROPS);
            let windows = found.into_iter().map(|at| ("", at)).collect();
            (windows, "where methods I and II differ most")
        }
    };
    // Each image's picture once, then its windows cut from it.
    let s = runner.scene.display_scale;
    let pictures = [
        ("reference", grey(reference, s)),
        ("photon1", grey(&images[0], s)),
        ("photon2", grey(&images[1], s)),
    ];
    let crops: Vec<Option<Tile>> = windows
        .iter()
        .flat_map(|&(part, at)| {
            pictures.iter().map(move |(name, picture)| {
                Some(Tile::grey(format!("{name} {part}"), &crop(picture, at, side, 2)))
            })
        })
        .collect();
    if crops.is_empty() {
        return Ok(vec![]);
    }
    let path = runner.out.join("fig10_crops.png");
    write_grid(&path, &crops, 3)?;
    files.push(path);
    let listed: Vec<String> = windows
        .iter()
        .map(|(part, (x, y))| format!("{part} at {x},{y}").trim_start().to_string())
        .collect();
    Ok(vec![format!(
        "fig10_crops.png: close-ups, as the paper's Fig. 10 shows its figures' hands and feet: {} windows of {side}² pixels {chosen} ({}: x, y of the top-left corner), at twice the size; per row the reference, method I, method II.",
        windows.len(),
        listed.join("; ")
    )])
}

/// The fine parts of the built-in scenes that Fig. 10's close-ups show, named, with the
/// top-left corner of each window as fractions of the image's side (the windows are an
/// eighth of the side). Other scenes get the windows where the two methods differ most.
fn fine_parts(scene: &str) -> Option<[(&'static str, f64, f64); CROPS]> {
    match scene {
        "cube" => Some([
            ("hand", 0.146, 0.186),
            ("feet", 0.344, 0.664),
            ("knot", 0.781, 0.391),
        ]),
        "hall" => Some([
            ("chandelier", 0.264, 0.098),
            ("figure", 0.791, 0.449),
            ("chairs", 0.547, 0.684),
        ]),
        _ => None,
    }
}

/// Absorption probabilities of the bounce-cap study: the paper's 0.2, where few paths live to
/// the cap, and two where most do.
pub const CAP_ABSORPTIONS: [f32; 3] = [0.0, 0.02, DEFAULT_ABSORPTION];
/// Caps of the bounce-cap study: the paper's two.
pub const BOUNCE_CAPS: usize = paper::BOUNCES.len();
/// K of the bounce-cap study.
const CAP_NEAREST: usize = 256;

/// Fig. 16 and 17 (the paper's scenes A and B): method II by source and max bounces (the
/// paper's two path lengths; equal stored photons), K and photon count, with f_diff against
/// the reference, in one picture laid out as the paper's; and where the bounce cap binds:
/// the same at absorptions where paths live to the cap, with the paths traced per photon.
pub fn fig16_17(runner: &Runner) -> Result<Section> {
    let p = &runner.params;
    let reference = reference(runner)?;
    let l_diag = runner.scene.diagonal();
    let s = runner.scene.display_scale;
    let mut sources = vec![SourceKind::Camera];
    if runner.scene.light.is_some() {
        sources.insert(0, SourceKind::Light);
    }
    let mut table = Table::new(
        &format!(
            "Fig. 16/17 (preset {}): method II f_diff by source, bounces, K and photons",
            runner.preset.name()
        ),
        &["source", "max bounces", "K", "photons", "f_diff"],
    );
    let mut by = BTreeMap::<(SourceKind, u32), Vec<f64>>::new();
    // The pictures by (K, photons, source, bounces): the paper's rows are K by photons, its
    // columns source by bounces.
    let mut pictures = BTreeMap::new();
    for &source in &sources {
        for bounces in paper::BOUNCES {
            for &photons in &p.fig16_photons {
                for &k in &p.fig16_nearest {
                    let config = photon_config(photons, k, source, bounces);
                    let (image, _) = runner.method_image("photon2", &config, 1)?;
                    let d = f_diff(&reference, &image, l_diag)?;
                    by.entry((source, bounces)).or_default().push(d.value);
                    table.push(vec![
                        source.name().into(),
                        bounces.to_string(),
                        k.to_string(),
                        photons.to_string(),
                        format!("{:.4}", d.value),
                    ]);
                    pictures.insert((k, photons, source, bounces), grey(&image, s));
                }
            }
        }
    }
    let columns: Vec<String> = sources
        .iter()
        .flat_map(|source| paper::BOUNCES.map(|b| format!("{} {b}", source.name())))
        .collect();
    let labels = Labels {
        columns,
        rows: p
            .fig16_nearest
            .iter()
            .flat_map(|k| {
                p.fig16_photons
                    .iter()
                    .map(move |&n| format!("K={k} {}", photon_count(n).replace(' ', "")))
            })
            .collect(),
    };
    let tiles: Vec<Option<Tile>> = pictures
        .values()
        .map(|picture| Some(Tile::grey("", picture)))
        .collect();
    let path = runner.out.join("fig16_17.png");
    write_labelled_grid(&path, &tiles, sources.len() * paper::BOUNCES.len(), &labels)?;
    let mut files = table.write(&runner.out, "fig16_17")?;
    files.push(path);
    let figure = match paper::analogue(&runner.scene.name) {
        Some(paper::PaperScene::A) => "the paper's Fig. 16 (its scene A, which `cube` stands for)",
        Some(paper::PaperScene::B) => "the paper's Fig. 17 (its scene B, which `hall` stands for)",
        None => "the paper's Fig. 16 and 17 (its scenes A and B)",
    };
    let mut notes = vec![format!(
        "fig16_17.png is laid out as {figure}: a column per source and max bounces ({}), a row per K and photons stored ({}), method II, grey {s} · H{}. Equal photons are stored at both caps: the shorter cap traces more paths.",
        labels.columns.join(", "),
        labels.rows.join(", "),
        display_scale_against_paper(runner)
    )];
    let cap = bounce_cap(runner, &reference, &sources)?;
    files.extend(cap.table.write(&runner.out, "fig16_17_cap")?);
    notes.push(cap.note.clone());
    let mut findings = fig16_17_findings(runner, &by);
    findings.push(cap.finding);
    Ok(Section {
        name: "fig16_17".into(),
        tables: vec![table, cap.table],
        files,
        notes,
        findings,
    })
}

/// The bounce-cap study's table, its note and the finding it decides.
struct BounceCap {
    table: Table,
    note: String,
    finding: String,
}

/// Method II at the first of Fig. 16/17's photon counts and K = [`CAP_NEAREST`] for every
/// source, absorption of [`CAP_ABSORPTIONS`] and cap of the paper's two: f_diff and the paths
/// traced per photon stored. Where the cap binds (absorption 0) the shorter cap traces about
/// 80/20 = 4× the paths, as the paper's Fig. 16/17 captions say theirs did.
fn bounce_cap(runner: &Runner, reference: &HmdImage, sources: &[SourceKind]) -> Result<BounceCap> {
    let photons = runner.params.fig16_photons[0];
    let mut table = Table::new(
        &format!(
            "Where the bounce cap binds (preset {}): method II, {} photons stored, K = {CAP_NEAREST}",
            runner.preset.name(),
            photon_count(photons)
        ),
        &[
            "source",
            "absorption",
            "max bounces",
            "paths traced",
            "paths per stored photon",
            "f_diff",
        ],
    );
    // (source, absorption index) -> [(paths per photon, f_diff) at 20, at 80].
    let mut cells = BTreeMap::<(SourceKind, usize), Vec<(f64, f64)>>::new();
    for &source in sources {
        for (a, &absorption) in CAP_ABSORPTIONS.iter().enumerate() {
            for bounces in paper::BOUNCES {
                let config = PhotonParams {
                    absorption,
                    ..photon_config(photons, CAP_NEAREST, source, bounces)
                };
                let (image, report) = runner.method_image("photon2", &config, 1)?;
                let d = f_diff(reference, &image, runner.scene.diagonal())?;
                // A shard's stand-in has no photon details.
                let (paths, stored) = report
                    .details
                    .photon
                    .map_or((0, 0), |d| (d.paths_traced, d.photons_stored));
                let per_photon = paths as f64 / stored.max(1) as f64;
                cells.entry((source, a)).or_default().push((per_photon, d.value));
                table.push(vec![
                    source.name().into(),
                    format!("{absorption}"),
                    bounces.to_string(),
                    paths.to_string(),
                    format!("{per_photon:.4}"),
                    format!("{:.4}", d.value),
                ]);
            }
        }
    }
    let ratio = |v: &[(f64, f64)]| v[0].0 / v[1].0;
    let paper_ratio = paper::BOUNCES[1] as f64 / paper::BOUNCES[0] as f64;
    let ratios: Vec<String> = cells
        .iter()
        .map(|(&(source, a), v)| {
            format!(
                "{} at absorption {}: ×{:.2}",
                source.name(),
                CAP_ABSORPTIONS[a],
                ratio(v)
            )
        })
        .collect();
    let note = format!(
        "Paths traced at {} bounces over those at {} for the same photons stored: {}. The paper's Fig. 16/17 captions trace ×{paper_ratio:.0} the paths at {} bounces, which only happens where nearly every path runs to the cap: read so, its paths were hardly absorbed, whatever its \"20 % absorption\" meant.",
        paper::BOUNCES[0],
        paper::BOUNCES[1],
        ratios.join("; "),
        paper::BOUNCES[0]
    );
    // The finding, at the absorption where the cap binds most (0), for the source the paper's
    // scene A was lit by where the scene has a light.
    let source = default_source(runner);
    let binding = &cells[&(source, 0)];
    let (short, long) = (binding[0].1, binding[1].1);
    let verdict = if long < 0.99 * short {
        "holds where the cap binds"
    } else if long > 1.01 * short {
        "does not hold where the cap binds"
    } else {
        "no clear difference where the cap binds (within 1 %)"
    };
    let finding = format!(
        "Fewer, longer paths ({} bounces) do better in scene A (paper; shown for any scene): {verdict} — at absorption 0, {} source, {} photons, K = {CAP_NEAREST}: f_diff {long:.4} ({} bounces, {:.4} paths per photon) against {short:.4} ({} bounces, {:.4}); at the paper's absorption {DEFAULT_ABSORPTION} the two caps trace ×{:.2} the paths, so the cap hardly binds there.",
        paper::BOUNCES[1],
        source.name(),
        photon_count(photons),
        paper::BOUNCES[1],
        binding[1].0,
        paper::BOUNCES[0],
        binding[0].0,
        ratio(&cells[&(source, CAP_ABSORPTIONS.len() - 1)])
    );
    Ok(BounceCap { table, note, finding })
}

/// Fig. 16/17's findings from the f_diffs `by` source and bounces: which source does better
/// on this scene's paper analogue.
fn fig16_17_findings(runner: &Runner, by: &BTreeMap<(SourceKind, u32), Vec<f64>>) -> Vec<String> {
    let mean = |source: SourceKind| {
        let v: Vec<f64> = by
            .iter()
            .filter(|((s, _), _)| *s == source)
            .flat_map(|(_, v)| v.iter().copied())
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    // Whether `better` beats `other` by more than 1 %, the noise between such runs.
    let verdict = |better: f64, other: f64| {
        if better < 0.99 * other {
            "holds here"
        } else if better > 1.01 * other {
            "does not hold here"
        } else {
            "no clear difference here (within 1 %)"
        }
    };
    let mut findings = vec![];
    if runner.scene.light.is_some() {
        let (light, camera) = (mean(SourceKind::Light), mean(SourceKind::Camera));
        let measured = format!("mean f_diff {light:.4} (light) against {camera:.4} (camera)");
        let scene = &runner.scene.name;
        findings.push(match paper::analogue(scene) {
            Some(paper::PaperScene::A) => format!(
                "Light-sourced photons do better in scene A (paper; `{scene}` stands for A): {} — {measured}.",
                verdict(light, camera)
            ),
            Some(paper::PaperScene::B) => format!(
                "Camera-sourced photons do better in scene B (paper; `{scene}` stands for B): {} — {measured}.",
                verdict(camera, light)
            ),
            None => format!(
                "Light-sourced photons do better in the paper's scene A, camera-sourced in its scene B; `{scene}` is neither: {measured}."
            ),
        });
    }
    findings
}

/// Table 4: photon map build seconds (trace and kd-tree) against photon count, light vs camera.
pub fn table4(runner: &Runner) -> Result<Section> {
    let p = &runner.params;
    let start = Instant::now();
    let accel = Accel::build(&runner.scene.mesh, BuildQuality::High);
    let camera = runner.scene.camera.rays(p.size, p.size);
    let mut sources = vec![("camera", PhotonSource::Camera(camera, p.size, p.size))];
    if let Some(light) = runner.scene.light {
        sources.insert(0, ("light", PhotonSource::Light(light)));
    }
    let rules = PathRules {
        max_bounces: LONG_PATHS,
        absorption: DEFAULT_ABSORPTION,
    };
    // Traces `photons` from `source` and indexes them: the seconds of each.
    let build = |source: &PhotonSource, photons: usize| -> Result<(f64, f64)> {
        let start = Instant::now();
        let traced = trace_photons(&accel, source, rules, photons, 1, &|_| {})?;
        let trace = start.elapsed().as_secs_f64();
        let start = Instant::now();
        drop(PhotonMap::build(&traced.photons, PhotonMethod::StoredDistance)?);
        Ok((trace, start.elapsed().as_secs_f64()))
    };
    if runner.planning() {
        plan_table4(runner, &sources, start.elapsed().as_secs_f64(), build)?;
        return Ok(Section::default());
    }
    let mut ours = Table::new(
        &format!(
            "Table 4 (preset {}): photon map build seconds, {LONG_PATHS} bounces, `{}`",
            runner.preset.name(),
            runner.scene.name
        ),
        &["photons", "source", "trace s", "kd-tree s", "total s"],
    );
    let mut series: Vec<Series> = sources
        .iter()
        .map(|(name, _)| Series {
            label: format!("{name} source"),
            points: vec![],
        })
        .collect();
    for &photons in &p.photons {
        for ((name, source), series) in sources.iter().zip(&mut series) {
            let (trace, index) = build(source, photons)?;
            series.points.push((photons as f64, trace + index));
            ours.push(vec![
                photons.to_string(),
                name.to_string(),
                format!("{trace:.2}"),
                format!("{index:.2}"),
                format!("{:.2}", trace + index),
            ]);
        }
    }
    let published = table4_paper();
    let mut files = ours.write(&runner.out, "table4")?;
    files.extend(published.write(&runner.out, "table4_paper")?);
    files.push(table4_plot(runner, &sources, &series)?);
    Ok(Section {
        name: "table4".into(),
        tables: vec![ours, published],
        files,
        ..Section::default()
    })
}

/// The paper's Table 4 as published.
fn table4_paper() -> Table {
    let mut published = Table::new(
        &format!("Table 4, the paper's values ({LONG_PATHS} bounces, light / camera, seconds)"),
        &["photons", "light", "camera"],
    );
    for row in &paper::TABLE4 {
        published.push(vec![
            row.photons.into(),
            format!("{}", row.light_seconds),
            format!("{}", row.camera_seconds),
        ]);
    }
    published
}

/// `table4.svg`: the build seconds against photons, each source beside the paper's in its
/// colour.
fn table4_plot(runner: &Runner, sources: &[(&str, PhotonSource)], series: &[Series]) -> Result<PathBuf> {
    let plot = runner.out.join("table4.svg");
    // The paper's build seconds, each source beside ours in its colour.
    let paper_series: Vec<Series> = sources
        .iter()
        .map(|(name, _)| Series {
            label: format!("paper, {name} source"),
            points: paper::TABLE4
                .iter()
                .map(|r| {
                    let seconds = if *name == "light" {
                        r.light_seconds
                    } else {
                        r.camera_seconds
                    };
                    (r.count as f64, seconds)
                })
                .collect(),
        })
        .collect();
    log_log_beside_paper(
        &plot,
        "photon map build (trace + kd-tree)",
        "photons stored",
        "seconds",
        &series,
        &paper_series,
    )?;
    Ok(plot)
}

/// Table 4's plan: its photon map builds, estimated in proportion to one build timed per
/// source, of the largest count up to a quarter of all counts together (small maps are
/// timed too noisily: at 130 K photons a build is a tenth of a second), plus the BVH build
/// (`accel_seconds`).
fn plan_table4(
    runner: &Runner,
    sources: &[(&str, PhotonSource)],
    accel_seconds: f64,
    build: impl Fn(&PhotonSource, usize) -> Result<(f64, f64)>,
) -> Result<()> {
    let counts = &runner.params.photons;
    let all: usize = counts.iter().sum();
    let timed = counts
        .iter()
        .copied()
        .filter(|&n| n <= all / 4)
        .max()
        .unwrap_or(counts[0]);
    let mut seconds = accel_seconds;
    for (_, source) in sources {
        let (trace, index) = build(source, timed)?;
        seconds += (trace + index) * all as f64 / timed as f64;
    }
    let names: Vec<&str> = sources.iter().map(|(name, _)| *name).collect();
    runner.plan_work(
        format!(
            "photon map builds: {} counts from {} to {}, {} source, {LONG_PATHS} bounces",
            counts.len(),
            counts[0],
            counts[counts.len() - 1],
            names.join(" and ")
        ),
        format!("{:.3e} photons", all as f64 * sources.len() as f64),
        seconds,
    );
    Ok(())
}

/// Memory per photon, ours against the paper's.
pub fn memory(runner: &Runner) -> Result<Section> {
    let mut table = Table::new(
        "Bytes per photon, kd-tree included",
        &["method", "hmdist", "paper"],
    );
    let published = [paper::BYTES_PER_PHOTON_METHOD1, paper::BYTES_PER_PHOTON_METHOD2];
    for (method, paper) in PhotonMethod::ALL.iter().zip(published) {
        table.push(vec![
            method.name().into(),
            method.bytes_per_photon().to_string(),
            paper.to_string(),
        ]);
    }
    let files = table.write(&runner.out, "memory")?;
    let photons = paper::LARGEST_MAP_PHOTONS as f64;
    let megabytes = |m: PhotonMethod| photons * m.bytes_per_photon() as f64 / 1e6;
    let notes = vec![format!(
        "{:.2} M photons take {:.0} MB (method I) and {:.0} MB (method II); the paper needed ≈{:.0} MB.",
        photons / 1e6,
        megabytes(PhotonMethod::StoredDistance),
        megabytes(PhotonMethod::NextHitPoint),
        paper::LARGEST_MAP_MB
    )];
    Ok(Section {
        name: "memory".into(),
        tables: vec![table],
        files,
        notes,
        ..Section::default()
    })
}

#[cfg(test)]
mod tests {
    use super::cost_finding;

    /// The verdict on method II's extra cost follows the rows: every row inside 1–9 % agrees
    /// row by row; a sum near the paper's with rows outside agrees in aggregate only; a sum
    /// far from it does not agree.
    #[test]
    fn the_cost_verdict_follows_the_rows() {
        let paper = 1.10;
        let rows = cost_finding(paper, 1.05, &[1.02, 1.05, 1.08]);
        assert!(
            rows.contains("agrees row by row") && rows.contains("3 of 3 rows inside"),
            "{rows}"
        );
        let spread = cost_finding(paper, 1.11, &[0.87, 1.05, 1.41]);
        assert!(spread.contains("agrees in aggregate only"), "{spread}");
        assert!(
            spread.contains("-13 % to +41 %") && spread.contains("method II faster in 1"),
            "{spread}"
        );
        let far = cost_finding(paper, 1.30, &[1.25, 1.35]);
        assert!(far.contains("does not agree"), "{far}");
    }
}
