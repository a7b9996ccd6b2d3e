//! Built-in scenes, generated in code and deterministic: the same triangles on every machine
//! (SPEC §5). No data files.
//!
//! - `cube` and `hall`: analogues of the paper's scenes A and B.
//! - `sphere`, `slab`, `dome`: validation scenes whose H is known in closed form (SPEC §1).

pub mod cube;
pub mod hall;
pub mod shapes;
pub mod validation;

use super::model::Scene;

/// Names accepted by [`builtin`], in the order `--help` lists them.
pub const BUILTIN_NAMES: [&str; 5] = ["cube", "hall", "sphere", "slab", "dome"];

/// The built-in scene called `name`, or `None` if there is none by that name.
pub fn builtin(name: &str) -> Option<Scene> {
    match name {
        "cube" => Some(cube::cube()),
        "hall" => Some(hall::hall()),
        "sphere" => Some(validation::sphere(validation::SPHERE_RADIUS, 7)),
        "slab" => Some(validation::slab(validation::SLAB_HEIGHT, 1000.0)),
        "dome" => Some(validation::dome(validation::DOME_RADIUS, 512, 256)),
        _ => None,
    }
}
