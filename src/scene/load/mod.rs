//! Placeholder: being written.
use std::path::Path;
use crate::{error::{Error, Result}, scene::Scene};
pub fn load_file(path: &Path) -> Result<Scene> {
    Err(Error::file(path, "loaders not yet written"))
}
