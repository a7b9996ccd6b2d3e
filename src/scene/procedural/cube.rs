//! Placeholder: being written.
use crate::scene::Scene;
pub fn cube() -> Scene {
    let mut s = super::validation::sphere(5.0, 4);
    s.name = "cube".into();
    s
}
