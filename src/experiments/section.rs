//! What one experiment produced, for the report.

use std::path::PathBuf;

use super::table::Table;

/// What one experiment produced, for the report.
#[derive(Default)]
pub struct Section {
    /// The experiment's name.
    pub name: String,
    /// Its tables, ours and the paper's.
    pub tables: Vec<Table>,
    /// The files it wrote (tables, plots, picture grids).
    pub files: Vec<PathBuf>,
    /// What the reader needs besides the tables: where the numbers come from, what the
    /// pictures show.
    pub notes: Vec<String>,
    /// The paper's findings this experiment tests, one sentence each: the finding, the
    /// verdict, and the number that decides it. The report lists every section's at its top.
    pub findings: Vec<String>,
}
