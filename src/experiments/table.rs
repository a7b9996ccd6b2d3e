//! Result tables, written as CSV (for scripts) and Markdown (for people and the report).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
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

    /// A table read back from the CSV [`Table::csv`] writes (no title): quoted cells
    /// unquoted. `None` where `path` does not exist; an error where a row's cells are not as
    /// many as the header's.
    pub fn read_csv(path: &Path) -> Result<Option<Table>> {
        let text = match std::fs::read_to_string(path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(Error::file(path, format!("cannot read it: {e}"))),
        };
        let mut lines = text.lines().map(csv_cells);
        let header = lines.next().unwrap_or_default();
        let rows: Vec<Vec<String>> = lines.collect();
        if let Some(i) = rows.iter().position(|r| r.len() != header.len()) {
            return Err(Error::file(
                path,
                format!(
                    "row {} has {} cells, the header {}",
                    i + 1,
                    rows[i].len(),
                    header.len()
                ),
            ));
        }
        Ok(Some(Table {
            title: String::new(),
            header,
            rows,
        }))
    }

    /// The column named `name`, if there is one.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }

    /// Writes `NAME.csv` and `NAME.md` into `dir`; returns their paths.
    pub fn write(&self, dir: &Path, name: &str) -> Result<Vec<PathBuf>> {
        let (csv, md) = (dir.join(format!("{name}.csv")), dir.join(format!("{name}.md")));
        write_atomically(&csv, self.csv().as_bytes())?;
        write_atomically(&md, self.markdown().as_bytes())?;
        Ok(vec![csv, md])
    }
}

/// One CSV line's cells, as [`Table::csv`] quotes them (a table's cells hold no line breaks).
fn csv_cells(line: &str) -> Vec<String> {
    let mut cells = vec![String::new()];
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                chars.next();
                cells.last_mut().unwrap().push('"');
            }
            ('"', _) => quoted = !quoted,
            (',', false) => cells.push(String::new()),
            _ => cells.last_mut().unwrap().push(c),
        }
    }
    cells
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

    #[test]
    fn a_table_read_back_from_its_csv_has_the_same_cells() {
        let mut t = Table::new("T", &["rays", "paper CPU, A", "say \"hi\""]);
        t.push(vec!["32".into(), "0.5971".into(), "a, \"b\"".into()]);
        t.push(vec!["64".into(), String::new(), "c".into()]);
        let dir = std::env::temp_dir().join(format!("hmdist-table-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = t.write(&dir, "t").unwrap().remove(0);
        let back = Table::read_csv(&path).unwrap().unwrap();
        assert_eq!((back.header, back.rows), (t.header, t.rows));
        assert!(Table::read_csv(&dir.join("none.csv")).unwrap().is_none());
        std::fs::write(&path, "a,b\n1\n").unwrap();
        assert!(Table::read_csv(&path).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
