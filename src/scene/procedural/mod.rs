//! Built-in scenes, generated in code and deterministic: the same triangles on every machine
//! (spec §5). No data files.
//!
//! - `cube` and `hall`: analogues of the paper's scenes A and B.
//! - `sphere`, `slab`, `dome`: validation scenes whose H is known in closed form (spec §1).

pub mod cube;
pub mod hall;
pub mod shapes;
pub mod validation;

use super::model::Scene;

/// Names accepted by [`builtin`], in the order `--help` lists them.
pub const BUILTIN_NAMES: [&str; 5] = ["cube", "hall", "sphere", "slab", "dome"];

/// The built-in scenes that have a spot light (the others are for closed forms).
pub const LIT_BUILTINS: [&str; 4] = ["cube", "hall", "sphere", "dome"];

/// What to do about `scene` having no spot light, for a message: a built-in cannot be given
/// one (name those that have one), a file can, through a TOML file's `[light]`.
pub fn light_advice(scene: &Scene) -> String {
    if BUILTIN_NAMES.contains(&scene.name.as_str()) {
        format!(
            "the built-in '{}' has none (the built-ins with a light: {}); for your own, place the meshes in a TOML file with a [light]",
            scene.name,
            LIT_BUILTINS.join(", ")
        )
    } else if scene.name.ends_with(".toml") {
        "add a [light] to its TOML file".into()
    } else {
        format!(
            "place '{}' in a TOML file with a [light] (guide: the TOML format)",
            scene.name
        )
    }
}

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
