//! `hmdist scene info|export`.

use std::path::PathBuf;

use clap::Subcommand;

use hmdist::error::Result;
use hmdist::scene::{export, Scene};

#[derive(Subcommand)]
pub enum SceneCommand {
    /// Triangles (by source), bounding box, diagonal, camera, light, display scale, and what
    /// a scene file asked for and hmdist did not use.
    Info {
        /// A built-in (cube, hall, sphere, slab, dome) or a file (.obj, .ply, .gltf, .glb, .toml,
        /// .pbrt, .pbrt.gz, Mitsuba 3 .xml).
        scene: String,
    },
    /// Write a scene's triangles as OBJ, so other tools can run on exactly our geometry.
    Export {
        /// A built-in (cube, hall, sphere, slab, dome) or a file (.obj, .ply, .gltf, .glb, .toml,
        /// .pbrt, .pbrt.gz, Mitsuba 3 .xml).
        scene: String,
        /// The OBJ file to write.
        out: PathBuf,
    },
}

/// Loads a scene and says on stderr (above `bar`) what its file held that hmdist did not use
/// and what it made of it: skipped shapes and lights, flattened instances. Never silently.
pub fn load(name: &str, bar: &super::bar::Bar) -> Result<Scene> {
    let scene = Scene::load(name)?;
    if let Some(skipped) = scene.notes.skipped_line() {
        bar.note(&format!("hmdist: {}: skipped {skipped}", scene.name));
    }
    for remark in &scene.notes.remarks {
        bar.note(&format!("hmdist: {}: {remark}", scene.name));
    }
    Ok(scene)
}

pub fn run(command: SceneCommand) -> Result<()> {
    match command {
        SceneCommand::Info { scene } => {
            let scene = Scene::load(&scene)?;
            let b = scene.bounds();
            let c = &scene.camera;
            println!("scene:         {}", scene.name);
            println!("triangles:     {}", scene.mesh.triangle_count());
            println!("vertices:      {}", scene.mesh.positions.len());
            println!("bounds:        {:?} .. {:?}", b.min.to_array(), b.max.to_array());
            println!("diagonal:      {}", b.diagonal());
            println!(
                "camera:        eye {:?}, target {:?}, up {:?}, fov_y {}°{}",
                c.eye.to_array(),
                c.target.to_array(),
                c.up.to_array(),
                c.fov_y_deg,
                if c.mirrored {
                    ", mirrored (right = up × forward, as pbrt's)"
                } else {
                    ""
                }
            );
            match scene.light {
                Some(l) => println!(
                    "light:         spot at {:?}, direction {:?}, cone half angle {}°",
                    l.position.to_array(),
                    l.direction.to_array(),
                    l.cone_half_angle_deg
                ),
                None => println!("light:         none"),
            }
            println!("display scale: {}", scene.display_scale);
            let notes = &scene.notes;
            if let Some((w, h)) = notes.size {
                println!("size:          {w}x{h} (the file's; --size overrides)");
            }
            for (source, triangles) in &notes.sources {
                println!("from:          {triangles} triangles, {source}");
            }
            for (kind, count) in &notes.skipped {
                println!("skipped:       {count} × {kind}");
            }
            for remark in &notes.remarks {
                println!("note:          {remark}");
            }
            Ok(())
        }
        SceneCommand::Export { scene, out } => {
            // Not over the scene's own files: an export there would replace them.
            let inputs = Scene::files_read(&scene);
            let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
            hmdist::files::check_output(&out, &inputs)?;
            hmdist::files::check_extension(&out, "obj")?;
            let scene = load(&scene, &super::bar::Bar::new(true))?;
            export::write_obj(&scene.mesh, &out)?;
            println!("{} triangles -> {}", scene.mesh.triangle_count(), out.display());
            Ok(())
        }
    }
}
