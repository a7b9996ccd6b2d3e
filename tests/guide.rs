//! The guide and the program say the same thing: every flag `hmdist CMD --help` lists is in
//! docs/guide.md, and every flag a `hmdist CMD ...` command of the guide or the README uses
//! is one `hmdist CMD --help` lists (issue #52).

use std::collections::BTreeSet;
use std::path::Path;

/// The commands, as their words after `hmdist`.
const COMMANDS: [&[&str]; 10] = [
    &["render"],
    &["cache"],
    &["points"],
    &["merge"],
    &["photons", "build"],
    &["diff"],
    &["experiment"],
    &["scene", "info"],
    &["scene", "export"],
    &["gpu", "list"],
];

/// The flags `hmdist WORDS --help` lists (each option line's own flag, not the ones its
/// description mentions), less `--help` and `--version`.
fn help_flags(words: &[&str]) -> BTreeSet<String> {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hmdist"))
        .args(words)
        .arg("--help")
        .output()
        .unwrap();
    assert!(out.status.success(), "hmdist {} --help", words.join(" "));
    let text = String::from_utf8(out.stdout).unwrap();
    let flags: BTreeSet<String> = text
        .lines()
        .filter_map(|line| {
            let option = line.trim_start();
            let option = option
                .strip_prefix("-")
                .filter(|o| o.len() > 2 && o.as_bytes()[1] == b',')
                .map_or(option, |o| o[2..].trim_start());
            let name = option.strip_prefix("--")?;
            let end = name
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
                .unwrap_or(name.len());
            Some(format!("--{}", &name[..end]))
        })
        .filter(|f| f != "--help" && f != "--version")
        .collect();
    assert!(
        !flags.is_empty(),
        "no flags found in hmdist {} --help:\n{text}",
        words.join(" ")
    );
    flags
}

/// The flags (`--name`) in `text`.
fn flags_in(text: &str) -> Vec<String> {
    let mut flags = vec![];
    let mut rest = text;
    while let Some(at) = rest.find("--") {
        let before = rest[..at].chars().next_back();
        let name = &rest[at + 2..];
        let end = name
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
            .unwrap_or(name.len());
        if !before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '-') && end > 0 {
            flags.push(format!("--{}", &name[..end]));
        }
        rest = &name[end..];
    }
    flags
}

/// Each `hmdist ...` command of a Markdown page, with the line it is on: the lines of shell
/// blocks (a synopsis's continuation lines, indented and starting with `[`, belong to the
/// command above) and the inline code spans that start with `hmdist `.
fn commands(markdown: &str) -> Vec<(usize, String)> {
    let mut found: Vec<(usize, String)> = vec![];
    let mut shell = false;
    let mut in_code = false;
    for (n, line) in markdown.lines().enumerate() {
        let trimmed = line.trim_start();
        if trimmed.starts_with("```") {
            in_code = !in_code;
            shell = in_code && (trimmed == "```sh" || trimmed == "```bash");
            continue;
        }
        if shell {
            let code = line.split(" # ").next().unwrap_or(line);
            if let Some(at) = code.find("hmdist ") {
                found.push((n + 1, code[at..].to_string()));
            } else if trimmed.starts_with('[') {
                if let Some(last) = found.last_mut() {
                    last.1.push(' ');
                    last.1.push_str(trimmed);
                }
            }
        } else if !in_code {
            for span in line.split('`').skip(1).step_by(2) {
                if span.starts_with("hmdist ") {
                    found.push((n + 1, span.to_string()));
                }
            }
        }
    }
    found
}

/// The command of `line` (`hmdist WORDS ...`): its index in [`COMMANDS`], if it names one.
fn command_of(line: &str) -> Option<usize> {
    let words: Vec<&str> = line.split_whitespace().skip(1).collect();
    COMMANDS
        .iter()
        .position(|c| words.len() >= c.len() && words[..c.len()] == **c)
}

#[test]
fn the_guide_names_every_flag_of_every_command_and_no_flag_that_does_not_exist() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let guide = std::fs::read_to_string(root.join("docs/guide.md")).unwrap();
    let known: Vec<BTreeSet<String>> = COMMANDS.iter().map(|c| help_flags(c)).collect();
    let in_guide: BTreeSet<String> = flags_in(&guide).into_iter().collect();
    let mut wrong = vec![];
    for (command, flags) in COMMANDS.iter().zip(&known) {
        for flag in flags.difference(&in_guide) {
            wrong.push(format!(
                "docs/guide.md never names `hmdist {} {flag}`",
                command.join(" ")
            ));
        }
    }
    let mut checked = 0;
    for page in ["docs/guide.md", "README.md", "docs/python.md"] {
        let text = std::fs::read_to_string(root.join(page)).unwrap();
        for (line, command) in commands(&text) {
            let Some(c) = command_of(&command) else {
                let first = command.split_whitespace().nth(1).unwrap_or("");
                if !first.is_empty() && !first.starts_with('-') && first != "..." {
                    wrong.push(format!("{page}:{line}: `{command}`: no such command"));
                }
                continue;
            };
            for flag in flags_in(&command) {
                checked += 1;
                if !known[c].contains(&flag) && flag != "--help" {
                    wrong.push(format!(
                        "{page}:{line}: `hmdist {} {flag}`: no such flag",
                        COMMANDS[c].join(" ")
                    ));
                }
            }
        }
    }
    assert!(
        checked > 50,
        "only {checked} flags of commands found: the scan is broken"
    );
    assert!(
        wrong.is_empty(),
        "{} mismatches:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}
