//! The experiment runner (spec §4, §6): the paper's Table 1 shape, a report whose links all
//! resolve, and a cache that reuses an image exactly when nothing that determines it changed.

mod common;

use std::collections::BTreeMap;
use std::path::Path;
use std::time::SystemTime;

use common::Scratch;
use hmdist::estimators::Gather;
use hmdist::experiments::{Preset, Runner};
use hmdist::progress::Silent;
use hmdist::sampling::Weighting;

fn column(csv: &str, index: usize) -> Vec<f64> {
    csv.lines()
        .skip(1)
        .map(|l| l.split(',').nth(index).unwrap().parse().unwrap())
        .collect()
}

fn hrefs(html: &str) -> Vec<String> {
    html.split("href=\"")
        .skip(1)
        .map(|s| s[..s.find('"').unwrap()].to_string())
        .collect()
}

/// Each cached file and when it was last written: a render rewrites its files.
fn cache_times(out: &Path) -> BTreeMap<String, SystemTime> {
    std::fs::read_dir(out.join("cache"))
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let name = e.file_name().to_string_lossy().into_owned();
            (name, e.metadata().unwrap().modified().unwrap())
        })
        .collect()
}

/// Dates every cached file back to 2001, so that a file written again (even within the
/// file system's timestamp resolution) shows a later time; returns [`cache_times`].
fn backdate_cache(out: &Path) -> BTreeMap<String, SystemTime> {
    let long_ago = SystemTime::UNIX_EPOCH + std::time::Duration::from_secs(1_000_000_000);
    for e in std::fs::read_dir(out.join("cache")).unwrap() {
        let file = std::fs::File::options()
            .append(true)
            .open(e.unwrap().path())
            .unwrap();
        file.set_modified(long_ago).unwrap();
    }
    cache_times(out)
}

#[test]
fn quick_table1_on_cube_falls_with_rays_and_the_report_links_only_existing_files() {
    let dir = Scratch::new("experiments-table1");
    let out = dir.join("out");
    let mut runner = Runner::new("cube", Preset::Quick, &out, &Silent).unwrap();
    runner.run("table1").unwrap();
    let csv = std::fs::read_to_string(out.join("table1.csv")).unwrap();
    let (rays, gather) = (column(&csv, 0), column(&csv, 1));
    println!("{csv}");
    assert_eq!(rays[..5], [32.0, 64.0, 128.0, 256.0, 512.0]);
    for i in 1..5 {
        assert!(
            gather[i] < gather[i - 1],
            "f_diff at {} rays ({}) not below {} rays ({})",
            rays[i],
            gather[i],
            rays[i - 1],
            gather[i - 1]
        );
    }

    // `cube` stands for the paper's scene A: its plot draws the paper's values beside ours.
    let svg = std::fs::read_to_string(out.join("table1.svg")).unwrap();
    for label in [
        "gather",
        "paper CPU, scene A (as read)",
        "paper GPU, scene A (as read)",
    ] {
        assert!(svg.contains(&format!("\n{label}\n")), "{label} in table1.svg");
    }

    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let links = hrefs(&html);
    assert!(links.iter().any(|l| l == "table1.csv"), "{links:?}");
    for link in &links {
        match link.strip_prefix('#') {
            Some(id) => assert!(
                html.contains(&format!("id=\"{id}\"")),
                "index.html links #{id}, no such section"
            ),
            None => assert!(
                out.join(link).exists(),
                "index.html links {link}, which does not exist"
            ),
        }
    }

    // The pictures by N, as the paper's: Fig. 12 the cube map's, Fig. 13 gather's; the same
    // layout (7 counts: two rows of pictures, each over its difference pictures), other images.
    let (fig12, fig13) = (
        image::open(out.join("fig12.png")).unwrap(),
        image::open(out.join("fig13.png")).unwrap(),
    );
    assert_eq!(fig12.height(), fig13.height());
    assert_ne!(
        fig12.to_luma8().into_raw(),
        fig13.to_luma8().into_raw(),
        "fig12 is not gather's"
    );

    // A rerun renders nothing: every cached file stays as it was written.
    let before = backdate_cache(&out);
    let mut again = Runner::new("cube", Preset::Quick, &out, &Silent).unwrap();
    again.run("table1").unwrap();
    assert_eq!(cache_times(&out), before);
    let csv_again = std::fs::read_to_string(out.join("table1.csv")).unwrap();
    assert_eq!(column(&csv_again, 1), gather);
}

/// In the closed `cube` no path escapes: with nothing absorbed every path runs to its cap and
/// stores a photon at each of its `cap` interactions, so `P / cap` paths store `P` photons; with
/// absorption `a` a path stores `(1 − a)(1 − (1 − a)^cap) / a` photons on average (a photon at
/// interaction k survives k + 1 absorption draws). The paper traced 4× the paths at 20
/// bounces as at 80: only the first case gives that.
#[test]
fn where_nothing_is_absorbed_the_bounce_cap_study_traces_one_path_per_cap_photons() {
    let dir = Scratch::new("experiments-bounce-cap");
    let out = dir.join("out");
    let mut runner = Runner::new("cube", Preset::Quick, &out, &Silent).unwrap();
    runner.run("fig16_17").unwrap();
    let csv = std::fs::read_to_string(out.join("fig16_17_cap.csv")).unwrap();
    let photons = Preset::Quick.params().fig16_photons[0] as f64;
    let mut rows = 0;
    for line in csv.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        let (a, cap, paths): (f64, f64, f64) = (
            cells[1].parse().unwrap(),
            cells[2].parse().unwrap(),
            cells[3].parse().unwrap(),
        );
        if a == 0.0 {
            assert_eq!(paths, (photons / cap).ceil(), "{line}");
        } else {
            let per_path = (1.0 - a) * (1.0 - (1.0 - a).powf(cap)) / a;
            let expected = photons / per_path;
            assert!(
                (paths / expected - 1.0).abs() < 0.02,
                "{line}: {expected:.0} paths expected"
            );
        }
        rows += 1;
    }
    assert_eq!(rows, 2 * 3 * 2, "light and camera, three absorptions, two caps");
    // One picture laid out as the paper's Fig. 16/17: four columns (source by cap) of tiles.
    let picture = image::open(out.join("fig16_17.png")).unwrap();
    assert!(
        picture.width() > 4 * 144 && picture.width() < 6 * 144,
        "{}",
        picture.width()
    );
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        html.contains("where the cap binds"),
        "the finding is decided where the cap binds"
    );
}

/// A floor and a ceiling `height` above it, 20 wide, as OBJ text.
fn slab_obj(height: f32) -> String {
    let mut obj = String::new();
    for y in [0.0, height] {
        for (x, z) in [(-10.0, -10.0), (10.0, -10.0), (10.0, 10.0), (-10.0, 10.0)] {
            obj += &format!("v {x} {y} {z}\n");
        }
    }
    obj + "f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n"
}

#[test]
fn editing_a_mesh_that_a_toml_scene_references_renders_again_and_nothing_else_does() {
    let dir = Scratch::new("experiments-cache");
    let (out, toml) = (dir.join("out"), dir.join("scene.toml"));
    std::fs::write(
        &toml,
        "[[mesh]]\npath = \"slab.obj\"\n[camera]\neye = [0, 0.4, 0]\ntarget = [0, 0, 0]\nup = [0, 0, 1]\nfov_y_deg = 40.0\n",
    )
    .unwrap();
    let scene = toml.to_str().unwrap();
    let gather = Gather::new(16, Weighting::Cosine).unwrap();
    // The median H over the image; about 3h/2 on a slab of height h.
    let median_h = |out: &Path| {
        let runner = Runner::new(scene, Preset::Quick, out, &Silent).unwrap();
        let (image, _) = runner.image(&gather, 5).unwrap();
        common::median(image.data.iter().map(|&h| h as f64).collect())
    };

    dir.write("slab.obj", slab_obj(1.0));
    let low = median_h(&out);
    let written = backdate_cache(&out);
    assert_eq!(written.len(), 2, "one EXR and its JSON: {written:?}");
    assert_eq!(median_h(&out), low);
    assert_eq!(
        cache_times(&out),
        written,
        "an unchanged scene is not rendered again"
    );

    // Raise the ceiling: the TOML file itself is untouched.
    dir.write("slab.obj", slab_obj(2.0));
    let high = median_h(&out);
    println!("median H: {low} at h = 1, {high} at h = 2");
    assert!((high / low - 2.0).abs() < 0.05, "rendered again: {low} -> {high}");

    // An image cached by another version of hmdist is not reused.
    let json = cache_times(&out)
        .into_keys()
        .filter(|n| n.ends_with(".json") && !written.contains_key(n))
        .map(|n| out.join("cache").join(n))
        .next()
        .unwrap();
    let text = std::fs::read_to_string(&json).unwrap();
    let version = format!("\"hmdist_version\": \"{}\"", env!("CARGO_PKG_VERSION"));
    assert!(text.contains(&version), "{text}");
    std::fs::write(&json, text.replace(&version, "\"hmdist_version\": \"0.0.0\"")).unwrap();
    let before = backdate_cache(&out);
    assert_eq!(median_h(&out), high);
    let exr = json.with_extension("exr");
    let name = exr.file_name().unwrap().to_string_lossy().into_owned();
    assert_ne!(cache_times(&out)[&name], before[&name], "rendered again");
}

#[test]
fn the_adaptive_study_compares_every_scheme_at_every_tolerance_and_pictures_the_rays() {
    let dir = Scratch::new("experiments-adaptive");
    let out = dir.join("out");
    let mut runner = Runner::new("slab", Preset::Quick, &out, &Silent).unwrap();
    runner.run("adaptive").unwrap();
    let csv = std::fs::read_to_string(out.join("adaptive.csv")).unwrap();
    println!("{csv}");
    let rays = column(&csv, 2);
    assert_eq!(rays.len(), 15, "one row per scheme and tolerance");
    // In each scheme tighter tolerances cast more rays, within its bounds (128 or 64 …
    // 2,048 per pixel).
    for (scheme, first) in rays.chunks(5).zip([128.0, 64.0, 64.0]) {
        assert!(scheme.windows(2).all(|w| w[0] <= w[1]), "{rays:?}");
        assert!(scheme.iter().all(|r| (first..=2048.0).contains(r)), "{rays:?}");
    }
    for file in [
        "adaptive.svg",
        "adaptive_p95.svg",
        "adaptive_rays.png",
        "index.html",
    ] {
        assert!(out.join(file).exists(), "{file}");
    }
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        html.contains("How many rays does a pixel need"),
        "the note is in the report"
    );
}

#[test]
fn an_experiment_spread_over_shards_renders_each_image_once_and_writes_the_one_machine_tables() {
    use hmdist::shard::Shard;
    let dir = Scratch::new("experiments-shards");
    let (one, spread) = (dir.join("one"), dir.join("spread"));
    Runner::new("slab", Preset::Quick, &one, &Silent)
        .unwrap()
        .run("table1")
        .unwrap();
    let mut rendered = 0;
    for k in [1, 0] {
        let runner = Runner::new("slab", Preset::Quick, &spread, &Silent).unwrap();
        let mut shard = runner.with_shard(Shard::new(k, 2).unwrap()).unwrap();
        shard.run("table1").unwrap();
        rendered += shard.shard_counts().unwrap().0;
        assert!(!spread.join("table1.csv").exists(), "a shard writes no tables");
    }
    assert_eq!(
        cache_times(&spread).len(),
        cache_times(&one).len(),
        "every image, once"
    );
    assert_eq!(
        rendered as usize * 2,
        cache_times(&one).len(),
        "an EXR and a JSON per image"
    );
    let before = backdate_cache(&spread);
    Runner::new("slab", Preset::Quick, &spread, &Silent)
        .unwrap()
        .run("table1")
        .unwrap();
    assert_eq!(cache_times(&spread), before, "the final run renders nothing");
    let csv = |out: &Path| std::fs::read_to_string(out.join("table1.csv")).unwrap();
    assert_eq!(csv(&spread), csv(&one));
}

/// Counts the images a run renders (the runner advances its progress once per image).
#[derive(Default)]
struct Renders(std::sync::atomic::AtomicU64);

impl hmdist::progress::Progress for Renders {
    fn start(&self, _: &str, _: u64) {}
    fn advance(&self, steps: u64) {
        self.0.fetch_add(steps, std::sync::atomic::Ordering::Relaxed);
    }
    fn finish(&self) {}
}

/// The cache's images: the stems of its JSON reports (written last, once the EXR is there).
fn cached_stems(out: &Path) -> std::collections::BTreeSet<String> {
    cache_times(out)
        .into_keys()
        .filter_map(|n| n.strip_suffix(".json").map(String::from))
        .collect()
}

#[test]
fn a_plan_lists_each_image_once_and_exactly_those_a_run_then_renders_once_each() {
    let dir = Scratch::new("experiments-plan");
    let out = dir.join("out");
    let planned = |out: &Path| {
        let mut runner = Runner::new("slab", Preset::Quick, out, &Silent)
            .unwrap()
            .with_plan()
            .unwrap();
        runner.run("all").unwrap();
        let plan = runner.planned.clone().unwrap();
        let written: hmdist::experiments::Plan =
            serde_json::from_str(&std::fs::read_to_string(out.join("plan.json")).unwrap()).unwrap();
        assert_eq!(written.items.len(), plan.items.len());
        plan
    };

    let plan = planned(&out);
    let stems: Vec<String> = plan.items.iter().filter_map(|i| i.cache.clone()).collect();
    let distinct: std::collections::BTreeSet<String> = stems.iter().cloned().collect();
    assert_eq!(stems.len(), distinct.len(), "each image once");
    assert!(plan.items.iter().all(|i| !i.cached), "nothing cached yet");
    assert!(plan.total_seconds > 0.0);
    // Images that several experiments share are listed under the first, with the others.
    let reference = plan
        .items
        .iter()
        .find(|i| i.what.starts_with("gather, N = 16384"))
        .expect("the reference is planned");
    for other in ["table2", "fig9", "table3", "fig10", "fig16_17", "adaptive"] {
        assert!(
            reference.also_needed_by.iter().any(|e| e == other),
            "{other} uses the reference: {:?}",
            reference.also_needed_by
        );
    }
    // The plan writes nothing but itself.
    let mut files: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert_eq!(
        files,
        ["plan.csv", "plan.json", "plan.md"],
        "no image cache, not even an empty one"
    );

    let renders = Renders::default();
    let mut runner = Runner::new("slab", Preset::Quick, &out, &renders).unwrap();
    runner.run("all").unwrap();
    // `all` ends with the cost plot over the tables it made, and Fig. 10 has its close-ups:
    // three rows (windows) of three tiles (reference, I, II).
    assert!(out.join("cost.svg").exists());
    let crops = image::open(out.join("fig10_crops.png")).unwrap();
    let window = 16 * 2 * 144_u32.div_ceil(32);
    assert!(
        crops.width() > 3 * window && crops.width() < 4 * window,
        "{}",
        crops.width()
    );
    assert!(
        crops.height() > 3 * window && crops.height() < 4 * window,
        "{}",
        crops.height()
    );
    assert_eq!(
        cached_stems(&out),
        distinct,
        "the run renders what the plan listed"
    );
    assert_eq!(
        renders.0.load(std::sync::atomic::Ordering::Relaxed),
        distinct.len() as u64,
        "each image rendered once"
    );
    let comparison = std::fs::read_to_string(out.join("plan_vs_actual.csv")).unwrap();
    assert_eq!(
        comparison.lines().count(),
        1 + hmdist::experiments::EXPERIMENTS.len(),
        "{comparison}"
    );
    let from_earlier_runs = |csv: &str| -> BTreeMap<String, f64> {
        csv.lines()
            .skip(1)
            .map(|l| {
                let cells: Vec<&str> = l.split(',').collect();
                (cells[0].to_string(), cells[3].parse().unwrap())
            })
            .collect()
    };
    assert!(
        from_earlier_runs(&comparison).values().all(|&s| s == 0.0),
        "this run rendered everything: {comparison}"
    );
    // A run stopped after the plan and resumed: the second finds every image cached, and
    // each experiment's seconds include its images' from their reports (read here).
    Runner::new("slab", Preset::Quick, &out, &Silent)
        .unwrap()
        .run("all")
        .unwrap();
    let resumed = std::fs::read_to_string(out.join("plan_vs_actual.csv")).unwrap();
    for (experiment, seconds) in from_earlier_runs(&resumed) {
        let expected: f64 = plan
            .items
            .iter()
            .filter(|i| i.experiment == experiment)
            .filter_map(|i| i.cache.as_ref())
            .map(|stem| {
                let report: serde_json::Value = serde_json::from_str(
                    &std::fs::read_to_string(out.join("cache").join(format!("{stem}.json"))).unwrap(),
                )
                .unwrap();
                report["seconds"]["total"].as_f64().unwrap()
            })
            .sum();
        assert!(
            (seconds - expected).abs() <= 0.051,
            "{experiment}: {seconds} s from earlier runs, its images' reports say {expected} s"
        );
        if experiment == "table1" {
            assert!(expected > 0.0, "table1 renders images");
        }
    }

    let again = planned(&out);
    assert!(
        again.items.iter().filter(|i| i.cache.is_some()).all(|i| i.cached),
        "after the run, every image is cached"
    );
    let images: std::collections::BTreeSet<String> =
        again.items.iter().filter_map(|i| i.cache.clone()).collect();
    assert_eq!(images, distinct);
    let work: f64 = again
        .items
        .iter()
        .filter(|i| i.cache.is_none())
        .map(|i| i.seconds)
        .sum();
    assert_eq!(
        again.total_seconds, work,
        "only the work that is not an image is left"
    );
}

#[test]
fn an_image_rendered_in_parts_is_the_whole_image_bit_for_bit_and_leaves_no_parts() {
    let dir = Scratch::new("experiments-parts");
    let (whole, parted) = (dir.join("whole"), dir.join("parted"));
    Runner::new("slab", Preset::Quick, &whole, &Silent)
        .unwrap()
        .run("table1")
        .unwrap();
    // Every image of 48² × 256 rays or more (the reference, gather and the cube map from
    // N = 256 up) in 16 parts.
    Runner::new("slab", Preset::Quick, &parted, &Silent)
        .unwrap()
        .with_part_rays(48 * 48 * 256)
        .run("table1")
        .unwrap();
    let exrs = |out: &Path| -> BTreeMap<String, Vec<u8>> {
        std::fs::read_dir(out.join("cache"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "exr"))
            .map(|p| {
                (
                    p.file_name().unwrap().to_string_lossy().into_owned(),
                    std::fs::read(&p).unwrap(),
                )
            })
            .collect()
    };
    let (a, b) = (exrs(&whole), exrs(&parted));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "the same images, no parts left"
    );
    for (name, bytes) in &a {
        assert!(&b[name] == bytes, "{name} differs");
    }
    let csv = |out: &Path, column_index: usize| {
        column(
            &std::fs::read_to_string(out.join("table1.csv")).unwrap(),
            column_index,
        )
    };
    assert_eq!(csv(&whole, 2), csv(&parted, 2), "the cube map's f_diff");
    // The parts' reports are summed: the merged report counts every lookup once.
    let report = |out: &Path| -> serde_json::Value {
        let cache = out.join("cache");
        let json = std::fs::read_dir(&cache)
            .unwrap()
            .map(|e| e.unwrap().path())
            .find(|p| {
                let text = std::fs::read_to_string(p).unwrap_or_default();
                p.extension().is_some_and(|e| e == "json")
                    && text.contains("\"cube_res\"")
                    && text.contains("\"rays\": 2048")
            })
            .unwrap();
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap()
    };
    let (w, p) = (report(&whole), report(&parted));
    for field in ["rays_cast", "lookups", "texels_rasterised", "escaped_lookups"] {
        assert!(
            w[field].as_u64().is_some_and(|n| n > 0) || field == "escaped_lookups",
            "{field}: {}",
            w[field]
        );
        assert_eq!(w[field], p[field], "{field}");
    }
    assert_eq!(p["shards"].as_array().unwrap().len(), 16);
}

#[test]
fn a_reference_passed_in_is_used_instead_of_rendered_and_one_that_does_not_fit_is_refused() {
    let dir = Scratch::new("experiments-reference");
    let (first, second) = (dir.join("first"), dir.join("second"));
    fn runner<'a>(out: &Path, size: u32, progress: &'a Renders) -> Runner<'a> {
        Runner::new("slab", Preset::Quick, out, progress)
            .unwrap()
            .with_size(Some(size))
            .unwrap()
    }
    let rendered_first = Renders::default();
    runner(&first, 12, &rendered_first).run("fig9").unwrap();
    // The reference is the one gather image fig9 renders (the others are cube maps).
    let reference = cached_stems(&first)
        .into_iter()
        .find(|s| s.starts_with("gather-"))
        .expect("fig9 rendered its reference");
    let given = dir.join("given.exr");
    std::fs::copy(first.join("cache").join(format!("{reference}.exr")), &given).unwrap();
    let report = std::fs::read_to_string(first.join("cache").join(format!("{reference}.json"))).unwrap();
    std::fs::write(dir.join("given.json"), &report).unwrap();

    let rendered_second = Renders::default();
    runner(&second, 12, &rendered_second)
        .with_reference(&given)
        .unwrap()
        .run("fig9")
        .unwrap();
    let count = |r: &Renders| r.0.load(std::sync::atomic::Ordering::Relaxed);
    assert_eq!(
        count(&rendered_second),
        count(&rendered_first) - 1,
        "all but the reference"
    );
    assert_eq!(cached_stems(&first), cached_stems(&second));
    for file in ["fig9.csv", "fig9.png"] {
        assert_eq!(
            std::fs::read(first.join(file)).unwrap(),
            std::fs::read(second.join(file)).unwrap(),
            "{file}"
        );
    }

    // Another size, another seed, a missing report: refused, naming what differs.
    let refused = |size: u32, exr: &Path| {
        let out = dir.join("refused");
        match runner(&out, size, &Renders::default()).with_reference(exr) {
            Ok(_) => panic!("{} at {size}² was taken", exr.display()),
            Err(e) => e.to_string(),
        }
    };
    assert!(refused(16, &given).contains("its size is 12x12, this run's is 16x16"));
    std::fs::write(
        dir.join("given.json"),
        report.replace("\"seed\": 1000003", "\"seed\": 7"),
    )
    .unwrap();
    assert!(refused(12, &given).contains("its seed is 7"));
    std::fs::remove_file(dir.join("given.json")).unwrap();
    assert!(refused(12, &given).contains("given.json"));
}

#[test]
fn several_experiments_run_in_the_listed_order_of_experiments_each_once() {
    let names = |list: &str| -> Vec<&str> {
        hmdist::experiments::select(list)
            .unwrap()
            .iter()
            .map(|e| e.name)
            .collect()
    };
    assert_eq!(names("fig9,table1, fig9"), ["table1", "fig9"]);
    assert_eq!(names("table3,all").len(), hmdist::experiments::EXPERIMENTS.len());
    let error = match hmdist::experiments::select("table1,tabel3") {
        Ok(_) => panic!("a misspelt name was taken"),
        Err(e) => e.to_string(),
    };
    assert!(error.contains("'tabel3' is not all or one of table1"), "{error}");
}

#[test]
fn cube_maps_made_in_parts_by_the_multi_output_pass_are_not_rendered_again() {
    // The paper preset's sweep (ten cube maps up to N = 16,384) at 8², every image of
    // 8² × 256 rays or more in parts: each image is rendered (and counted) once.
    let dir = Scratch::new("experiments-sweep-parts");
    let out = dir.join("out");
    let renders = Renders::default();
    let mut runner = Runner::new("slab", Preset::Paper, &out, &renders)
        .unwrap()
        .with_size(Some(8))
        .unwrap()
        .with_part_rays(8 * 8 * 256);
    runner.run("table1").unwrap();
    let stems = cached_stems(&out);
    assert_eq!(
        renders.0.load(std::sync::atomic::Ordering::Relaxed),
        stems.len() as u64,
        "one render per image: {stems:?}"
    );
    for stem in stems.iter().filter(|s| s.starts_with("cubemap-")) {
        let json = std::fs::read_to_string(out.join("cache").join(format!("{stem}.json"))).unwrap();
        assert!(json.contains("\"shards\""), "{stem} is the merged pass's image");
    }
}

#[test]
fn tables_1_and_2_without_cube_maps_render_the_same_gather_images_and_no_cube_map() {
    // The paper's scene-B row of Table 1 has no cube-map column: `--no-cubemap` asks for
    // gather's images only, under the keys a run with cube maps gives them.
    let dir = Scratch::new("experiments-no-cubemap");
    let out = dir.join("out");
    let gather_only = |out: &Path| {
        Runner::new("slab", Preset::Quick, out, &Silent)
            .unwrap()
            .with_size(Some(8))
            .unwrap()
            .with_cubemaps(false)
    };
    gather_only(&out).run("table1,table2").unwrap();
    let stems = cached_stems(&out);
    assert!(!stems.is_empty());
    assert!(stems.iter().all(|s| s.starts_with("gather-")), "{stems:?}");
    for table in ["table1.csv", "table2.csv"] {
        let csv = std::fs::read_to_string(out.join(table)).unwrap();
        let header = csv.lines().next().unwrap();
        assert!(!header.contains("cubemap"), "{table}: {header}");
        assert!(column(&csv, 1).iter().all(|v| v.is_finite()), "{table}:\n{csv}");
    }

    let before = backdate_cache(&out);
    let renders = Renders::default();
    let mut both = Runner::new("slab", Preset::Quick, &out, &renders)
        .unwrap()
        .with_size(Some(8))
        .unwrap();
    both.run("table1,table2").unwrap();
    let after = cache_times(&out);
    for (name, time) in &before {
        assert_eq!(
            after.get(name),
            Some(time),
            "{name} was found cached, not rendered again"
        );
    }
    let new: Vec<&String> = after.keys().filter(|n| !before.contains_key(*n)).collect();
    assert!(
        new.iter().all(|n| n.starts_with("cubemap-")),
        "only cube maps are new: {new:?}"
    );
    let csv = std::fs::read_to_string(out.join("table1.csv")).unwrap();
    assert!(csv.lines().next().unwrap().contains("cubemap"), "{csv}");
    // The page opens with the findings the run tested, each linked to its section.
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let summary = html.find("<h2 id=\"findings\">").expect("a findings section");
    assert!(
        summary < html.find("<h2 id=\"table1\">").unwrap(),
        "findings come first"
    );
    assert!(
        html.contains("<li><a href=\"#table1\">table1</a>: Final gathering"),
        "{html}"
    );
    assert!(
        html.contains("<li><a href=\"#table2\">table2</a>: The cube map's cost"),
        "{html}"
    );
}

#[test]
fn fig11_compares_the_cube_map_at_the_reference_rays_with_the_reference_and_shares_fig9s_image() {
    let dir = Scratch::new("experiments-fig11");
    let out = dir.join("out");
    let mut first = Runner::new("slab", Preset::Quick, &out, &Silent)
        .unwrap()
        .with_size(Some(8))
        .unwrap();
    first.run("fig11").unwrap();
    let csv = std::fs::read_to_string(out.join("fig11.csv")).unwrap();
    let f_diff = column(&csv, 2);
    assert_eq!(f_diff.len(), 1, "{csv}");
    assert!(f_diff[0].is_finite() && f_diff[0] >= 0.0, "{csv}");
    assert!(out.join("fig11.png").exists());
    // Fig. 9 needs the same R = 64 image and renders only R = 128.
    let renders = Renders::default();
    let mut second = Runner::new("slab", Preset::Quick, &out, &renders)
        .unwrap()
        .with_size(Some(8))
        .unwrap();
    second.run("fig9").unwrap();
    assert_eq!(renders.0.load(std::sync::atomic::Ordering::Relaxed), 1);
}

#[test]
fn the_cost_plot_has_every_image_of_tables_1_to_3_and_its_front_is_the_undominated_ones() {
    use hmdist::experiments::Table;
    let dir = Scratch::new("experiments-cost");
    let out = dir.join("out");
    let runner = || {
        Runner::new("slab", Preset::Quick, &out, &Silent)
            .unwrap()
            .with_size(Some(8))
            .unwrap()
    };
    // Before the tables exist it says so and plots nothing.
    runner().run("cost").unwrap();
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        html.contains("Not found in this folder: table1, table2, table3"),
        "{html}"
    );
    assert!(!out.join("cost.svg").exists());

    runner().run("table1,table2,table3,table4,cost").unwrap();
    let read = |name: &str| Table::read_csv(&out.join(name)).unwrap().unwrap();
    let (table2, table3, cost) = (read("table2.csv"), read("table3.csv"), read("cost.csv"));
    let at = |t: &Table, row: &[String], name: &str| -> f64 { row[t.column(name).unwrap()].parse().unwrap() };
    let p = Preset::Quick.params();
    assert_eq!(
        cost.rows.len(),
        3 * p.rays.len() + 2 * p.photons.len() * p.nearest.len(),
        "gather, gather + denoise and cube map by N, methods I and II by photons and K:\n{}",
        cost.csv()
    );
    // Each image's seconds are its table's: gather's Table 2's, a photon image's Table 3's
    // gather and its map's build (more than the gather alone).
    for row in &table2.rows {
        let n = format!("N = {}", row[0]);
        let ours = cost.rows.iter().find(|r| r[0] == "gather" && r[1] == n).unwrap();
        let (a, b) = (at(&cost, ours, "seconds"), at(&table2, row, "gather s"));
        assert!((a - b).abs() <= 1e-3 * b.max(1.0), "{a} against Table 2's {b}");
        // The denoised gather costs its gather and the filter, and is its own image.
        let denoised = cost
            .rows
            .iter()
            .find(|r| r[0] == "gather + denoise" && r[1] == n)
            .unwrap();
        assert!(at(&cost, denoised, "seconds") > b, "{denoised:?}");
        assert_ne!(
            at(&cost, denoised, "f_diff"),
            at(&cost, ours, "f_diff"),
            "{denoised:?}"
        );
    }
    for row in &table3.rows {
        let k = row[table3.column("K").unwrap()].clone();
        let ours = cost
            .rows
            .iter()
            .filter(|r| r[0] == "photon II" && r[1].ends_with(&format!("K = {k}")))
            .map(|r| at(&cost, r, "seconds"))
            .collect::<Vec<_>>();
        assert!(
            ours.iter().any(|&s| s > at(&table3, row, "II gather s")),
            "{ours:?}"
        );
    }
    // On the front exactly where no other image is as fast and more accurate, or faster and
    // as accurate (of images equal in both, the first listed).
    let points: Vec<(f64, f64)> = cost
        .rows
        .iter()
        .map(|r| (at(&cost, r, "seconds"), at(&cost, r, "f_diff")))
        .collect();
    for (i, (row, &(s, f))) in cost.rows.iter().zip(&points).enumerate() {
        let beaten = points.iter().enumerate().any(|(j, &(s2, f2))| {
            (s2 <= s && f2 < f) || (s2 < s && f2 <= f) || (s2 == s && f2 == f && j < i)
        });
        assert_eq!(
            row[cost.column("on the front").unwrap()] == "yes",
            !beaten,
            "{row:?}"
        );
    }
    assert!(cost.rows.iter().any(|r| r[4] == "yes"));
    assert!(out.join("cost.svg").exists());
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("<h2 id=\"cost\">"), "{html}");
    assert!(
        html.contains("Which estimator for which accuracy at which cost"),
        "{html}"
    );
}

#[test]
fn the_cache_study_measures_every_source_at_every_accuracy_and_a_rerun_reuses_the_caches() {
    let dir = Scratch::new("experiments-caches");
    let out = dir.join("out");
    let study = |out: &Path| {
        let mut runner = Runner::new("cube", Preset::Quick, out, &Silent)
            .unwrap()
            .with_size(Some(24))
            .unwrap();
        runner.run("cache").unwrap();
    };
    study(&out);
    let csv = std::fs::read_to_string(out.join("cache.csv")).unwrap();
    assert_eq!(
        csv.lines().count(),
        1 + 13 * 6,
        "one row per source and accuracy:\n{csv}"
    );
    // Every cache errs, by less with a finer accuracy for the records' own H (its rows come
    // first, coarsest a first), and costs more.
    let hmd: Vec<&str> = csv.lines().skip(1).take(6).collect();
    let hmd = format!("header\n{}", hmd.join("\n"));
    let (mean, rays) = (column(&hmd, 5), column(&hmd, 3));
    println!("{csv}");
    assert!(
        mean.iter().all(|&e| e > 0.0) && mean.first() > mean.last(),
        "{mean:?}"
    );
    assert!(rays.windows(2).all(|w| w[0] <= w[1]), "{rays:?}");
    for file in [
        "cache.svg",
        "cache_p95.svg",
        "cache_records.png",
        "cache_equal_error.md",
    ] {
        assert!(out.join(file).exists(), "{file}");
    }
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        html.contains("Does a more accurate H make a better cache"),
        "the findings"
    );
    // The cached images of E name their channel E, as `render --method irradiance` does, so
    // that `hmdist cache --reference` takes them.
    let cached_e: Vec<_> = std::fs::read_dir(out.join("cache"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "exr"))
        .filter(|p| {
            p.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("irradiance-")
        })
        .collect();
    assert_eq!(cached_e.len(), 2, "{cached_e:?}");
    for path in &cached_e {
        hmdist::image::exr::read_channel(path, "E").unwrap();
    }
    // A rerun reads every cache back: none is written again.
    let kept = |out: &Path| -> BTreeMap<String, SystemTime> {
        std::fs::read_dir(out.join("cache-irradiance"))
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                (
                    e.file_name().to_string_lossy().into_owned(),
                    e.metadata().unwrap().modified().unwrap(),
                )
            })
            .collect()
    };
    let before = kept(&out);
    assert_eq!(before.keys().filter(|k| k.ends_with(".json")).count(), 13 * 6);
    study(&out);
    assert_eq!(kept(&out), before);
    assert_eq!(std::fs::read_to_string(out.join("cache.csv")).unwrap(), csv);
    // A scene without a spot light has nothing to cache: a note, and no images.
    let slab = dir.join("slab");
    let mut runner = Runner::new("slab", Preset::Quick, &slab, &Silent).unwrap();
    runner.run("cache").unwrap();
    assert!(runner.sections[0].notes[0].contains("has no spot light"));
}
