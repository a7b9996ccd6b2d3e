//! The experiment runner (SPEC §4, §6): the paper's Table 1 shape, a report whose links all
//! resolve, and reruns that reuse the cached images.

use std::path::Path;

use hmdist::experiments::{Preset, Runner};
use hmdist::progress::Silent;

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

#[test]
fn quick_table1_on_cube_falls_with_rays_and_the_report_links_only_existing_files() {
    let out = std::env::temp_dir().join(format!("hmdist-experiments-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
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

    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let links = hrefs(&html);
    assert!(links.iter().any(|l| l == "table1.csv"), "{links:?}");
    for link in &links {
        assert!(
            out.join(link).exists(),
            "index.html links {link}, which does not exist"
        );
    }

    // A rerun renders nothing new: the same cached images give the same table.
    let cached = |dir: &Path| std::fs::read_dir(dir.join("cache")).unwrap().count();
    let before = cached(&out);
    let mut again = Runner::new("cube", Preset::Quick, &out, &Silent).unwrap();
    again.run("table1").unwrap();
    assert_eq!(cached(&out), before);
    let csv_again = std::fs::read_to_string(out.join("table1.csv")).unwrap();
    assert_eq!(column(&csv_again, 1), gather);
    let _ = std::fs::remove_dir_all(&out);
}
