//! Progress reporting from long loops, without tying the library to a terminal.

/// Receives progress from the estimators; called from many threads.
pub trait Progress: Sync {
    /// A new phase called `label` with `total` steps begins.
    fn start(&self, label: &str, total: u64);
    /// `steps` more steps are done.
    fn advance(&self, steps: u64);
    /// The phase is over.
    fn finish(&self);
}

/// Reports nothing: for tests, benchmarks and `--quiet`.
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _: &str, _: u64) {}
    fn advance(&self, _: u64) {}
    fn finish(&self) {}
}
