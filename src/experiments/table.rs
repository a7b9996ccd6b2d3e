//! Result tables, written as CSV (for scripts) and Markdown (for people and the report).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::Result;
use crate::image::write_atomically;

/// A titled table of strings; the first column names the rows.
#[derive(Clone, Debug, Default)]
pub struct Table {
    /// What it shows.
    pub title: String,
    /// Column names.
    pub header: Vec<String>,
    /// Rows of cells, as many as the header.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// An empty table.
    pub fn new(title: &str, header: &[&str]) -> Self {
        Table {
            title: title.into(),
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: vec![],
        }
    }

    /// Adds a row.
    pub fn push(&mut self, row: Vec<String>) {
        self.rows.push(row);
    }

    /// The table as CSV, header first; cells with commas or quotes quoted.
    pub fn csv(&self) -> String {
        let quote = |s: &String| {
            if s.contains([',', '"', '\n']) {
                format!("\"{}\"", s.replace('"', "\"\""))
            } else {
                s.clone()
            }
        };
        let mut out = String::new();
        for row in std::iter::once(&self.header).chain(&self.rows) {
            let _ = writeln!(out, "{}", row.iter().map(quote).collect::<Vec<_>>().join(","));
        }
        out
    }

    /// The table as Markdown, under its title.
    pub fn markdown(&self) -> String {
        let mut out = format!("### {}\n\n| {} |\n|", self.title, self.header.join(" | "));
        out += &"---|".repeat(self.header.len());
        out.push('\n');
        for row in &self.rows {
            let _ = writeln!(out, "| {} |", row.join(" | "));
        }
        out
    }

    /// Writes `NAME.csv` and `NAME.md` into `dir`; returns their paths.
    pub fn write(&self, dir: &Path, name: &str) -> Result<Vec<PathBuf>> {
        let (csv, md) = (dir.join(format!("{name}.csv")), dir.join(format!("{name}.md")));
        write_atomically(&csv, self.csv().as_bytes())?;
        write_atomically(&md, self.markdown().as_bytes())?;
        Ok(vec![csv, md])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_quotes_what_needs_quoting_and_markdown_has_a_rule_per_column() {
        let mut t = Table::new("T", &["a", "b"]);
        t.push(vec!["1".into(), "x,y".into()]);
        assert_eq!(t.csv(), "a,b\n1,\"x,y\"\n");
        assert_eq!(t.markdown(), "### T\n\n| a | b |\n|---|---|\n| 1 | x,y |\n");
    }
}
