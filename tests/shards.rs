//! Shards (`render --shard K/M`) merge (`hmdist merge`) into exactly the one-machine EXR, and
//! merge refuses parts that do not make one render.

mod common;

use common::cli::{hmdist, hmdist_ok};
use common::Scratch;

/// Renders `args` whole into `one.exr` and as 4 shards into `partK.exr`.
fn whole_and_shards(dir: &Scratch, args: &[&str]) {
    let mut whole = vec!["render", "--quiet", "--out", "one.exr"];
    whole.extend_from_slice(args);
    hmdist_ok(dir.path(), &whole);
    for k in 0..4 {
        let (shard, out) = (format!("{k}/4"), format!("part{k}.exr"));
        let mut part = vec!["render", "--quiet", "--shard", &shard, "--out", &out];
        part.extend_from_slice(args);
        hmdist_ok(dir.path(), &part);
    }
}

fn bytes(dir: &Scratch, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(name)).unwrap()
}

#[test]
fn four_shards_merged_in_any_order_give_the_one_machine_exr_byte_for_byte() {
    for (name, args) in [
        (
            "gather",
            vec!["--size", "40x27", "--rays", "16", "--aov", "rays,dmin"],
        ),
        // Denoised: the parts carry their own rays' H and the guide; merge filters.
        (
            "gather-denoise",
            vec!["--size", "40x27", "--rays", "16", "--aov", "dmin", "--denoise"],
        ),
        (
            "adaptive-denoise",
            vec![
                "--size",
                "40x27",
                "--method",
                "adaptive",
                "--tolerance",
                "0.2",
                "--min-rays",
                "16",
                "--denoise",
                "--denoise-passes",
                "2",
            ],
        ),
        (
            "cubemap-denoise",
            vec![
                "--size",
                "40x27",
                "--method",
                "cubemap",
                "--backend",
                "cpu",
                "--rays",
                "16",
                "--denoise",
            ],
        ),
        // Not H: its channel is E, which merge must read and write as E.
        (
            "irradiance",
            vec![
                "--size",
                "40x27",
                "--method",
                "irradiance",
                "--rays",
                "16",
                "--aov",
                "E_direct",
            ],
        ),
        (
            "photon2",
            vec![
                "--size",
                "40x27",
                "--method",
                "photon2",
                "--photons",
                "20000",
                "--gather",
                "32",
            ],
        ),
    ] {
        let dir = Scratch::new(&format!("shards-{name}"));
        whole_and_shards(&dir, &args);
        for (out, order) in [("a.exr", [0, 1, 2, 3]), ("b.exr", [3, 1, 0, 2])] {
            let parts: Vec<String> = order.iter().map(|k| format!("part{k}.exr")).collect();
            let mut merge = vec!["merge", "--quiet", out];
            merge.extend(parts.iter().map(String::as_str));
            hmdist_ok(dir.path(), &merge);
            assert!(
                bytes(&dir, out) == bytes(&dir, "one.exr"),
                "{name}: {out} differs from one.exr"
            );
        }
        assert_ne!(
            bytes(&dir, "part0.exr"),
            bytes(&dir, "one.exr"),
            "a part alone is not the image"
        );
        let one = common::cli::read_json(&dir.join("one.json"));
        let merged = common::cli::read_json(&dir.join("a.json"));
        for key in ["background_pixels", "method", "channels"] {
            assert_eq!(merged[key], one[key], "{name}: {key}");
        }
        if name.ends_with("denoise") {
            let part = common::cli::read_json(&dir.join("part0.json"));
            assert_eq!(
                part["denoise"]["filtered"], false,
                "{name}: a part is not filtered"
            );
            assert_eq!(merged["denoise"]["filtered"], true, "{name}: the merge filters");
            assert_eq!(merged["denoise"]["edge"], one["denoise"]["edge"], "{name}");
        }
        // The merged report sums the rays the shards cast: gather's split the image's, while
        // each photon shard traces the whole map again.
        let shards_trace = if name == "photon2" { 4 } else { 1 };
        for key in ["rays_cast", "escaped_rays"] {
            assert_eq!(
                merged[key],
                serde_json::Value::from(one[key].as_u64().map(|n| shards_trace * n)),
                "{name}: {key}"
            );
        }
        assert_eq!(merged["shards"].as_array().unwrap().len(), 4);
    }
}

/// Merges `part0..3.exr` into `merged.exr` and returns its JSON with the one-machine JSON.
fn merged_and_one(dir: &Scratch) -> (serde_json::Value, serde_json::Value) {
    hmdist_ok(
        dir.path(),
        &[
            "merge",
            "--quiet",
            "merged.exr",
            "part0.exr",
            "part1.exr",
            "part2.exr",
            "part3.exr",
        ],
    );
    (
        common::cli::read_json(&dir.join("merged.json")),
        common::cli::read_json(&dir.join("one.json")),
    )
}

#[test]
fn a_merged_report_counts_the_whole_image_not_shard_0_and_draws_the_png_at_the_parts_scale() {
    // Photon holes sum over the shards (a small radius leaves many).
    let dir = Scratch::new("shards-holes");
    whole_and_shards(
        &dir,
        &[
            "--size",
            "40x27",
            "--method",
            "photon1",
            "--photons",
            "2000",
            "--gather",
            "16",
            "--max-radius",
            "0.02",
        ],
    );
    let (merged, one) = merged_and_one(&dir);
    let part = common::cli::read_json(&dir.join("part0.json"));
    assert!(
        one["holes"].as_u64().unwrap() > part["holes"].as_u64().unwrap(),
        "{one}"
    );
    assert_eq!(merged["holes"], one["holes"]);
    assert!(merged["gather_queries_per_s"].as_f64().unwrap() > 0.0);

    // Adaptive's mean rays per pixel is the image's mean.
    let dir = Scratch::new("shards-adaptive");
    whole_and_shards(
        &dir,
        &[
            "--size",
            "40x27",
            "--method",
            "adaptive",
            "--max-rays",
            "256",
            "--tolerance",
            "0.05",
        ],
    );
    let (merged, one) = merged_and_one(&dir);
    let (merged, one) = (
        merged["mean_rays_per_pixel"].as_f64().unwrap(),
        one["mean_rays_per_pixel"].as_f64().unwrap(),
    );
    assert!(
        (merged - one).abs() <= 1e-9 * one,
        "merged {merged}, one machine {one}"
    );

    // The merged PNG is drawn at the parts' --scale, as the one-machine PNG is.
    let dir = Scratch::new("shards-scale");
    whole_and_shards(&dir, &["--size", "40x27", "--rays", "16", "--scale", "0.5"]);
    let (merged, one) = merged_and_one(&dir);
    assert_eq!(one["display_scale"].as_f64(), Some(0.5));
    assert_eq!(merged["display_scale"], one["display_scale"]);
    assert!(
        bytes(&dir, "merged.png") == bytes(&dir, "one.png"),
        "merged PNG at another scale"
    );
}

#[test]
fn merge_refuses_a_missing_a_repeated_and_a_foreign_part_and_writes_nothing() {
    let dir = Scratch::new("shards-refused");
    whole_and_shards(&dir, &["--size", "16x9", "--rays", "4"]);
    hmdist_ok(
        dir.path(),
        &[
            "render",
            "--quiet",
            "--size",
            "16x9",
            "--rays",
            "4",
            "--seed",
            "9",
            "--shard",
            "3/4",
            "--out",
            "seed9.exr",
        ],
    );
    hmdist_ok(
        dir.path(),
        &[
            "render", "--quiet", "--scene", "slab", "--size", "16x9", "--rays", "4", "--shard", "3/4",
            "--out", "slab.exr",
        ],
    );
    for (parts, message) in [
        (vec!["part0.exr", "part1.exr", "part2.exr"], "lack shard 3/4"),
        (
            vec!["part0.exr", "part1.exr", "part2.exr", "part2.exr"],
            "include shard 2/4 twice",
        ),
        (
            vec!["part0.exr", "part1.exr", "part2.exr", "seed9.exr"],
            "not of one render",
        ),
        (
            vec!["part0.exr", "part1.exr", "part2.exr", "slab.exr"],
            "not of one render",
        ),
        (vec!["one.exr"], "is not a shard"),
    ] {
        let mut args = vec!["merge", "out.exr"];
        args.extend(parts);
        let out = hmdist(dir.path(), &args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(message), "{message}: {stderr}");
        assert!(!dir.join("out.exr").exists() && !dir.join("out.json").exists());
    }
    let bad = hmdist(
        dir.path(),
        &["render", "--quiet", "--shard", "4/4", "--size", "4x4"],
    );
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--shard"));
}

/// A part's EXR must be the image its JSON describes: another shard's, another render's or
/// an edited EXR beside a valid JSON is refused, and so is an edited fingerprint.
#[test]
fn merge_refuses_a_part_whose_exr_is_not_the_image_its_json_describes() {
    let dir = Scratch::new("shards-swapped");
    whole_and_shards(&dir, &["--size", "16x9", "--rays", "4"]);
    let render = |extra: &[&str]| {
        let mut args = vec!["render", "--quiet", "--rays", "4"];
        args.extend_from_slice(extra);
        hmdist_ok(dir.path(), &args);
    };
    render(&[
        "--size",
        "16x9",
        "--seed",
        "9",
        "--shard",
        "1/4",
        "--out",
        "seed9.exr",
    ]);
    render(&["--size", "16x10", "--shard", "1/4", "--out", "tall.exr"]);
    let merge = || {
        hmdist(
            dir.path(),
            &[
                "merge",
                "out.exr",
                "part0.exr",
                "part1.exr",
                "part2.exr",
                "part3.exr",
            ],
        )
    };
    let (exr, json) = (bytes(&dir, "part1.exr"), bytes(&dir, "part1.json"));
    let refused = |message: &str| {
        let out = merge();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{message}: {stderr}");
        assert!(stderr.contains(message), "{message}: {stderr}");
        assert!(!dir.join("out.exr").exists() && !dir.join("out.json").exists());
    };
    for (other, message) in [
        ("part0.exr", "shard 1/4's EXR is not the image its JSON describes"),
        ("seed9.exr", "shard 1/4's EXR is not the image its JSON describes"),
        ("tall.exr", "shard 1/4's EXR is 16x10, its report says 16x9"),
    ] {
        std::fs::copy(dir.join(other), dir.join("part1.exr")).unwrap();
        refused(message);
    }
    std::fs::write(dir.join("part1.exr"), &exr).unwrap();
    let edited = String::from_utf8(json.clone()).unwrap();
    let fingerprint = serde_json::from_str::<serde_json::Value>(&edited).unwrap()["shard"]["fingerprint"]
        .as_str()
        .unwrap()
        .to_string();
    std::fs::write(
        dir.join("part1.json"),
        edited.replace(&fingerprint, "0123456789abcdef"),
    )
    .unwrap();
    refused("a report was edited");
    // The control: the parts as rendered merge.
    std::fs::write(dir.join("part1.json"), &json).unwrap();
    assert!(merge().status.success());
}

/// Parts that differ only where the old fingerprint did not look (the `ao` radius, the
/// backend) are not one image: merge refuses them and names the field.
#[test]
fn merge_refuses_parts_of_another_ao_radius_or_backend_and_names_the_field() {
    let test = "merge_refuses_parts_of_another_ao_radius_or_backend_and_names_the_field";
    let dir = Scratch::new("shards-keys");
    let render = |shard: &str, out: &str, extra: &[&str]| {
        let mut args = vec!["render", "--quiet", "--size", "16x9", "--rays", "8"];
        args.extend_from_slice(&["--shard", shard, "--out", out]);
        args.extend_from_slice(extra);
        hmdist(dir.path(), &args)
    };
    let cpu = |radius| ["--backend", "cpu", "--aov", "ao", "--ao-radius", radius];
    for k in 0..4 {
        let out = render(&format!("{k}/4"), &format!("ao{k}.exr"), &cpu("1"));
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    assert!(render("3/4", "ao3-radius2.exr", &cpu("2")).status.success());
    let merge = |last: &str| {
        let args = ["merge", "out.exr", "ao0.exr", "ao1.exr", "ao2.exr", last];
        hmdist(dir.path(), &args)
    };
    // The control: the same four parts with one radius merge.
    assert!(merge("ao3.exr").status.success());
    std::fs::remove_file(dir.join("out.exr")).unwrap();
    std::fs::remove_file(dir.join("out.json")).unwrap();
    let refused = merge("ao3-radius2.exr");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("ao_radius (1.0 against 2.0)"), "{stderr}");
    assert!(!dir.join("out.exr").exists());

    let gpu = ["--backend", "gpu-software", "--aov", "ao", "--ao-radius", "1"];
    let gpu = render("3/4", "gpu3.exr", &gpu);
    let stderr = String::from_utf8_lossy(&gpu.stderr);
    if !gpu.status.success() && common::gpu_missing(test, &stderr) {
        return;
    }
    assert!(gpu.status.success(), "{stderr}");
    let refused = merge("gpu3.exr");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("backend (\"cpu\" against \"gpu\")"), "{stderr}");
    assert!(
        stderr.contains("adapter_class (null against \"software\")"),
        "{stderr}"
    );
}

/// A part whose report predates keys (as one an experiment rendered in an earlier session)
/// still merges with parts that have keys where its fingerprint agrees, and not where not.
#[test]
fn a_part_without_a_key_is_compared_by_fingerprint() {
    let dir = Scratch::new("shards-keyless");
    whole_and_shards(&dir, &["--size", "16x9", "--rays", "4", "--backend", "cpu"]);
    let args = [
        "render",
        "--quiet",
        "--size",
        "16x9",
        "--rays",
        "4",
        "--backend",
        "cpu",
        "--seed",
        "9",
        "--shard",
        "3/4",
        "--out",
        "seed9.exr",
    ];
    hmdist_ok(dir.path(), &args);
    let without_key = |name: &str| {
        let path = dir.join(name);
        let mut json = common::cli::read_json(&path);
        json["shard"]
            .as_object_mut()
            .unwrap()
            .remove("key")
            .expect("a key to remove");
        std::fs::write(&path, serde_json::to_string_pretty(&json).unwrap()).unwrap();
    };
    without_key("part3.json");
    without_key("seed9.json");
    merged_and_one(&dir);
    assert!(bytes(&dir, "merged.exr") == bytes(&dir, "one.exr"));
    let refused = hmdist(
        dir.path(),
        &[
            "merge",
            "out.exr",
            "part0.exr",
            "part1.exr",
            "part2.exr",
            "seed9.exr",
        ],
    );
    let stderr = String::from_utf8_lossy(&refused.stderr);
    assert_eq!(refused.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("differ in fingerprint"), "{stderr}");
}

#[test]
fn a_photon_map_built_once_gives_every_shard_the_one_machine_pixels() {
    let dir = Scratch::new("shards-photon-map");
    let photon = [
        "--method",
        "photon2",
        "--photons",
        "30000",
        "--gather",
        "32",
        "--size",
        "40x27",
    ];
    let build = [
        "photons",
        "build",
        "--quiet",
        "--photons",
        "30000",
        "--size",
        "40x27",
        "--out",
        "m.map",
    ];
    hmdist_ok(dir.path(), &build);
    let mut one = vec!["render", "--quiet", "--out", "one.exr"];
    one.extend(photon);
    hmdist_ok(dir.path(), &one);
    for k in 0..4 {
        let (shard, out) = (format!("{k}/4"), format!("part{k}.exr"));
        let mut part = vec![
            "render",
            "--quiet",
            "--photon-map",
            "m.map",
            "--shard",
            &shard,
            "--out",
            &out,
        ];
        part.extend(photon);
        hmdist_ok(dir.path(), &part);
    }
    hmdist_ok(
        dir.path(),
        &[
            "merge",
            "--quiet",
            "merged.exr",
            "part2.exr",
            "part0.exr",
            "part1.exr",
            "part3.exr",
        ],
    );
    assert!(bytes(&dir, "merged.exr") == bytes(&dir, "one.exr"));
    let part = common::cli::read_json(&dir.join("part0.json"));
    assert_eq!(
        part["rays_cast"],
        serde_json::Value::Null,
        "a shard over a prebuilt map traces nothing"
    );
    assert_eq!(part["seconds"]["photon_trace"], 0.0);

    // A map for another seed, another method, or a damaged file is refused.
    let refused = |extra: &[&str], message: &str| {
        let mut args = vec!["render", "--quiet", "--out", "x.exr"];
        args.extend(extra);
        if !extra.contains(&"--method") {
            args.extend(["--method", "photon2"]);
        }
        args.extend(&photon[2..]);
        let out = hmdist(dir.path(), &args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(message), "{message}: {stderr}");
    };
    refused(
        &["--photon-map", "m.map", "--seed", "2"],
        "is not this render's photon map",
    );
    refused(
        &["--photon-map", "m.map", "--method", "photon1"],
        "is a map for photon2, not photon1",
    );
    let map = bytes(&dir, "m.map");
    dir.write("short.map", &map[..map.len() - 5]);
    refused(&["--photon-map", "short.map"], "short.map: is truncated");
    dir.write("junk.map", b"not a map at all");
    refused(&["--photon-map", "junk.map"], "is not an hmdist photon map");
    // Bytes changed inside the map's columns, its length intact (issue #51: such a map
    // rendered a different image with exit 0).
    let mut damaged = map.clone();
    let middle = damaged.len() / 2;
    for (i, b) in damaged.iter_mut().enumerate().skip(middle).step_by(7).take(200) {
        *b ^= (i % 251) as u8 | 1;
    }
    dir.write("damaged.map", &damaged);
    refused(
        &["--photon-map", "damaged.map"],
        "damaged.map: is damaged: its checksum does not match",
    );
}
