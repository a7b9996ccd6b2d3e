//! `index.html`: every experiment's tables, the paper's values beside ours, notes on the
//! paper's findings, and links to the files written. Links only files that exist.

use std::fmt::Write as _;

use super::runner::Runner;
use super::table::Table;
use crate::error::Result;
use crate::image::write_atomically;

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

fn html_table(t: &Table) -> String {
    let mut out = format!("<h3>{}</h3>\n<table>\n<tr>", escape(&t.title));
    for h in &t.header {
        let _ = write!(out, "<th>{}</th>", escape(h));
    }
    out += "</tr>\n";
    for row in &t.rows {
        out += "<tr>";
        for cell in row {
            let _ = write!(out, "<td>{}</td>", escape(cell));
        }
        out += "</tr>\n";
    }
    out + "</table>\n"
}

/// The experiments whose findings are ours, not the paper's: studies beyond it. The page
/// lists their findings apart (`publish.sh` keeps the same list).
pub const BEYOND_THE_PAPER: [&str; 4] = ["adaptive", "cache", "memory", "cost"];

/// The findings the run tested, each with its verdict and number and a link to its section:
/// the page's first sections, the paper's findings and then ours (`publish.sh` makes them
/// again from every section when it merges runs into one page).
fn findings_summary(runner: &Runner) -> String {
    let items = |ours: bool| -> Vec<String> {
        runner
            .sections
            .iter()
            .filter(|section| BEYOND_THE_PAPER.contains(&section.name.as_str()) == ours)
            .flat_map(|section| {
                section.findings.iter().map(move |f| {
                    format!(
                        "<li><a href=\"#{0}\">{0}</a>: {1}</li>",
                        escape(&section.name),
                        escape(f)
                    )
                })
            })
            .collect()
    };
    let mut out = String::new();
    for (id, heading, ours) in [
        ("findings", "The paper's findings", false),
        ("our-findings", "Findings of our own, beyond the paper", true),
    ] {
        let items = items(ours);
        if !items.is_empty() {
            out += &format!(
                "<h2 id=\"{id}\">{heading}</h2>\n<ul>\n{}\n</ul>\n",
                items.join("\n")
            );
        }
    }
    out
}

pub fn write(runner: &Runner) -> Result<()> {
    let mut body = format!(
        "<h1>hmdist experiments: <code>{}</code>, preset {}</h1>\n<p>{}² pixels, reference: gather with {} rays. \
         f_diff is spec §4's mean |ΔH| in percent of the scene diagonal ({:.3}).</p>\n",
        escape(&runner.scene.name),
        runner.preset.name(),
        runner.params.size,
        runner.params.reference_rays,
        runner.scene.diagonal()
    );
    if let Some(table) = runner.plan_against_run() {
        table.write(&runner.out, "plan_vs_actual")?;
        body += &html_table(&table);
        body += "<p>From <a href=\"plan.md\">plan.md</a>: each image's seconds count in the first experiment that needs it; \
                 an image the plan found cached costs nothing, and one an earlier run rendered after the plan (a run stopped, \
                 then resumed) counts with the seconds its report gives.</p>\n";
    }
    // After the plan's paragraph: `publish.sh` takes what precedes the first section as the
    // run's plan against run.
    body += &findings_summary(runner);
    for section in &runner.sections {
        let _ = writeln!(body, "<h2 id=\"{0}\">{0}</h2>", escape(&section.name));
        if !section.findings.is_empty() {
            body += "<ul class=\"findings\">\n";
            for finding in &section.findings {
                let _ = writeln!(body, "<li class=\"finding\">{}</li>", escape(finding));
            }
            body += "</ul>\n";
        }
        for table in &section.tables {
            body += &html_table(table);
        }
        if !section.notes.is_empty() {
            body += "<ul>\n";
            for note in &section.notes {
                let _ = writeln!(body, "<li>{}</li>", escape(note));
            }
            body += "</ul>\n";
        }
        for picture in section
            .files
            .iter()
            .filter(|f| f.extension().is_some_and(|e| e == "svg" || e == "png") && f.exists())
        {
            if let Ok(name) = picture.strip_prefix(&runner.out) {
                let _ = writeln!(
                    body,
                    "<p><a href=\"{0}\"><img src=\"{0}\" alt=\"{0}\"></a></p>",
                    escape(&name.to_string_lossy())
                );
            }
        }
        let links: Vec<String> = section
            .files
            .iter()
            .filter(|f| f.exists())
            .filter_map(|f| f.strip_prefix(&runner.out).ok())
            .map(|f| format!("<a href=\"{0}\">{0}</a>", escape(&f.to_string_lossy())))
            .collect();
        if !links.is_empty() {
            let _ = writeln!(body, "<p>Files: {}</p>", links.join(" · "));
        }
    }
    let page = format!(
        "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>hmdist experiments</title>\n\
         <style>body{{font-family:sans-serif;max-width:60em;margin:2em auto}}\
         table{{border-collapse:collapse;display:block;max-width:100%;overflow-x:auto}}\
         td,th{{border:1px solid #ccc;padding:2px 8px;text-align:right}}img{{max-width:100%;height:auto}}\
         li.finding{{font-weight:bold}}</style></head><body>\n{body}</body></html>\n"
    );
    write_atomically(&runner.out.join("index.html"), page.as_bytes())
}
