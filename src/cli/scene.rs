//! `hmdist scene info|export`.

use std::path::PathBuf;

use clap::Subcommand;

use hmdist::error::Result;
use hmdist::scene::{export, Scene};

#[derive(Subcommand)]
pub enum SceneCommand {
    /// Triangles, bounding box, diagonal, camera, light and display scale of a scene.
    Info {
        /// A built-in (cube, hall, sphere, slab, dome) or a file (.obj, .ply, .gltf, .glb, .toml).
        scene: String,
    },
    /// Write a scene's triangles as OBJ, so other tools can run on exactly our geometry.
    Export {
        /// A built-in (cube, hall, sphere, slab, dome) or a file (.obj, .ply, .gltf, .glb, .toml).
        scene: String,
        /// The OBJ file to write.
        out: PathBuf,
    },
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
                "camera:        eye {:?}, target {:?}, up {:?}, fov_y {}°",
                c.eye.to_array(),
                c.target.to_array(),
                c.up.to_array(),
                c.fov_y_deg
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
            Ok(())
        }
        SceneCommand::Export { scene, out } => {
            // Not over the scene's own files: an export there would replace them.
            let inputs = Scene::files_read(&scene);
            let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
            hmdist::files::check_output(&out, &inputs)?;
            hmdist::files::check_extension(&out, "obj")?;
            let scene = Scene::load(&scene)?;
            export::write_obj(&scene.mesh, &out)?;
            println!("{} triangles -> {}", scene.mesh.triangle_count(), out.display());
            Ok(())
        }
    }
}
