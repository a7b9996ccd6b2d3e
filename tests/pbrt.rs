//! pbrt-v4 scene files: the triangles a pbrt file places (every transform directive, includes,
//! instances, PLY meshes, gzip) equal the same geometry placed through OBJ + TOML; the camera
//! puts a world point at the pixel pbrt's own projection (written out here from pbrt's
//! definitions, not hmdist's camera) gives; quadrics are closed and within their chord
//! error; a real scene (pbrt-v4-scenes' killeroo, with its `loopsubdiv` mesh) loads; bad files
//! name the file and line.

mod common;

use std::io::Write;

use common::{assert_same_triangles, Scratch, TRI_OBJ as OBJ, TRI_PLY as PLY};
use glam::{DMat4, DVec3, Vec3};
use hmdist::accel::{Accel, BuildQuality};
use hmdist::scene::load::load_file;
use hmdist::scene::Scene;

/// Every triangle's corners, each triangle's corners sorted and the list sorted: the same for
/// any vertex numbering and triangle order.

const PBRT_MESH: &str =
    r#""point3 P" [0 0 0 1 0 0 1 1 0 0 1 0.5 0.3 0.2 2] "integer indices" [0 1 2 0 2 3 1 4 2]"#;

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    encoder.write_all(bytes).unwrap();
    encoder.finish().unwrap()
}

/// The same five placements (scale, rotation about +y, translation), written in pbrt's every
/// way of saying them, and in TOML.
#[test]
fn every_transform_directive_places_triangles_as_toml_does() {
    let dir = Scratch::new("pbrt-placements");
    dir.write("tri.obj", OBJ);
    dir.write("tri.ply", PLY);
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    dir.write("sub/tri.ply.gz", gzip(PLY.as_bytes()));
    // Included files resolve against the loaded file's folder, as pbrt resolves them.
    dir.write("sub/part.pbrt", "AttributeBegin\n Translate 0 -3 0\n Shape \"plymesh\" \"string filename\" \"sub/tri.ply.gz\"\nAttributeEnd\n");
    dir.write(
        "sub/part2.pbrt.gz",
        gzip(format!("Shape \"trianglemesh\" {PBRT_MESH}\n").as_bytes()),
    );
    // A matrix for "scale 2, rotate 30° about +y, translate (1, 2, 3)", column by column as
    // pbrt's Transform reads it.
    let m = DMat4::from_translation(DVec3::new(1.0, 2.0, 3.0))
        * DMat4::from_rotation_y(30f64.to_radians())
        * DMat4::from_scale(DVec3::splat(2.0));
    let columns: Vec<String> = m.to_cols_array().iter().map(|v| format!("{v:.17}")).collect();
    let pbrt = format!(
        r#"# placements
LookAt 0 5 20  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" [64] "integer yresolution" [48]
Sampler "halton" "integer pixelsamples" 4
Integrator "volpath" "integer maxdepth" [5]
WorldBegin
Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]
Texture "checks" "spectrum" "checkerboard" "float uscale" [4]
MakeNamedMaterial "m" "string type" "coateddiffuse"
NamedMaterial "m"
CoordinateSystem "origin"
AttributeBegin
  Translate 1 2 3
  Rotate 30 0 1 0
  Scale 2 2 2
  Shape "trianglemesh" {PBRT_MESH}
AttributeEnd
AttributeBegin
  Transform [ {cols} ]
  Translate 10 0 0
  Shape "plymesh" "string filename" "tri.ply"
AttributeEnd
TransformBegin
  Translate 5 5 5
  CoordinateSystem "moved"
  CoordSysTransform "origin"
  ConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  -4 0 0 1]
  Rotate -90 0 1 0
  Include "sub/part.pbrt"
TransformEnd
AttributeBegin
  CoordSysTransform "moved"
  ReverseOrientation
  MediumInterface "" "fog"
  Import "sub/part2.pbrt.gz"
AttributeEnd
ObjectBegin "thing"
  Scale 0.5 0.5 0.5
  Shape "trianglemesh" {PBRT_MESH}
ObjectEnd
AttributeBegin
  Translate 0 0 -7
  Rotate 90 0 1 0
  ObjectInstance "thing"
AttributeEnd
"#,
        cols = columns.join(" ")
    );
    let toml = r#"
[[mesh]]
path = "tri.obj"
scale = 2.0
rotate_y_deg = 30.0
translate = [1, 2, 3]
[[mesh]]
path = "tri.obj"
scale = 2.0
rotate_y_deg = 30.0
translate = [18.3205080756887729, 2, -7]
[[mesh]]
path = "tri.obj"
rotate_y_deg = -90.0
translate = [-4, -3, 0]
[[mesh]]
path = "tri.obj"
translate = [5, 5, 5]
[[mesh]]
path = "tri.obj"
scale = 0.5
rotate_y_deg = 90.0
translate = [0, 0, -7]
"#;
    let from_pbrt = load_file(&dir.write("scene.pbrt", pbrt)).unwrap();
    // Every file the load reads is one no command may write over.
    let mut read = Scene::files_read(dir.join("scene.pbrt").to_str().unwrap());
    read.sort();
    let mut expected: Vec<_> = [
        "scene.pbrt",
        "sub/part.pbrt",
        "sub/part2.pbrt.gz",
        "sub/tri.ply.gz",
        "tri.ply",
    ]
    .iter()
    .map(|f| dir.join(f))
    .collect();
    expected.sort();
    assert_eq!(read, expected);
    let from_toml = load_file(&dir.write("scene.toml", toml)).unwrap();
    assert_same_triangles(&from_pbrt, &from_toml, 1e-5);
    let notes = &from_pbrt.notes;
    assert_eq!(notes.size, Some((64, 48)));
    assert!(
        notes.sources.contains(&("plymesh sub/tri.ply.gz".to_string(), 3)),
        "{notes:?}"
    );
    assert!(
        notes.sources.contains(&("trianglemesh".to_string(), 9)),
        "{notes:?}"
    );
    assert!(
        notes
            .remarks
            .iter()
            .any(|r| r == "1 object instance flattened into the mesh"),
        "{notes:?}"
    );
}

/// Where pbrt's perspective camera puts world point `p` on a `width × height` film, from
/// pbrt-v4's definitions: camera from world is the CTM at `Camera`; screen space divides by
/// z and by tan(fov / 2), the shorter side spanning [-1, 1]; raster x grows with screen x,
/// raster y falls with screen y.
fn pbrt_raster(camera_from_world: DMat4, fov_deg: f64, width: u32, height: u32, p: DVec3) -> (f64, f64) {
    let c = camera_from_world.transform_point3(p);
    let t = (0.5 * fov_deg.to_radians()).tan();
    let (sx, sy) = (c.x / c.z / t, c.y / c.z / t);
    let aspect = width as f64 / height as f64;
    let (hx, hy) = if aspect >= 1.0 {
        (aspect, 1.0)
    } else {
        (1.0, 1.0 / aspect)
    };
    (
        (sx + hx) / (2.0 * hx) * width as f64,
        (hy - sy) / (2.0 * hy) * height as f64,
    )
}

/// pbrt's LookAt, written out from its definition: right = up × dir, new up = dir × right,
/// the camera at `eye` looking along dir; the matrix is camera from world.
fn pbrt_look_at(eye: DVec3, look: DVec3, up: DVec3) -> DMat4 {
    let dir = (look - eye).normalize();
    let right = up.normalize().cross(dir).normalize();
    let new_up = dir.cross(right);
    DMat4::from_cols(
        right.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        eye.extend(1.0),
    )
    .inverse()
}

/// Small markers at known points, and the pixel each lands on in hmdist's picture, checked
/// against pbrt's projection for a wide film, a tall one (the fov spans the shorter side) and
/// a camera under `Scale -1 1 1` (a reflected, right-handed frame).
#[test]
fn the_camera_sees_each_point_where_pbrt_projects_it() {
    let dir = Scratch::new("pbrt-camera");
    let markers = [
        DVec3::new(2.0, 1.0, 0.0),
        DVec3::new(-1.5, -0.7, 1.0),
        DVec3::new(0.4, 1.6, -2.0),
    ];
    let mut shapes = String::new();
    for m in markers {
        // A square 0.3 across (several pixels) around the point, as two triangles.
        let s = 0.15;
        let corner = |dx: f64, dy: f64| format!("{} {} {}", m.x + dx, m.y + dy, m.z);
        shapes += &format!(
            "Shape \"trianglemesh\" \"point3 P\" [{} {} {} {}] \"integer indices\" [0 1 2 0 2 3]\n",
            corner(-s, -s),
            corner(s, -s),
            corner(s, s),
            corner(-s, s)
        );
    }
    let eye = DVec3::new(1.0, 2.0, 9.0);
    let look = DVec3::new(0.0, 0.5, 0.0);
    let up = DVec3::new(0.1, 1.0, 0.0);
    for (width, height, reflect) in [(160, 100, false), (90, 150, false), (160, 100, true)] {
        let fov = 35.0;
        let prefix = if reflect { "Scale -1 1 1\n" } else { "" };
        let text = format!(
            "{prefix}LookAt {} {} {}  {} {} {}  {} {} {}\nCamera \"perspective\" \"float fov\" [{fov}]\n\
             Film \"rgb\" \"integer xresolution\" [{width}] \"integer yresolution\" [{height}]\nWorldBegin\n{shapes}",
            eye.x, eye.y, eye.z, look.x, look.y, look.z, up.x, up.y, up.z
        );
        let scene = load_file(&dir.write("camera.pbrt", text)).unwrap();
        assert_eq!(scene.camera.mirrored, !reflect);
        let mut camera_from_world = pbrt_look_at(eye, look, up);
        if reflect {
            camera_from_world = DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)) * camera_from_world;
        }
        let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
        let hits = hmdist::render::primary_hits(&accel, &scene, width, height);
        for (i, m) in markers.iter().enumerate() {
            let (x, y) = pbrt_raster(camera_from_world, fov, width, height, *m);
            let pixel = (y.floor() as u32 * width + x.floor() as u32) as usize;
            let hit = hits.points[pixel]
                .unwrap_or_else(|| panic!("marker {i} not at pixel ({x:.1}, {y:.1}) of {width}x{height}"));
            assert_eq!(
                hit.triangle as usize / 2,
                i,
                "{width}x{height}, reflected {reflect}"
            );
        }
    }
}

/// A sphere, a cylinder and a disk: vertices on the surface, chords within the stated error
/// of the diagonal, the sphere closed (every edge shared by two triangles).
#[test]
fn quadrics_are_closed_and_within_their_chord_error() {
    let dir = Scratch::new("pbrt-quadrics");
    let text = "WorldBegin\nAttributeBegin\nTranslate 1 2 3\nScale 2 2 2\nShape \"sphere\" \"float radius\" [1.5]\nAttributeEnd\n\
                Shape \"cylinder\" \"float radius\" 0.5 \"float zmin\" 10 \"float zmax\" 12\n\
                Shape \"disk\" \"float radius\" 1 \"float innerradius\" 0.25 \"float height\" -4 \"float phimax\" 180\n";
    let scene = load_file(&dir.write("q.pbrt", text)).unwrap();
    let diagonal = scene.diagonal();
    let mut edges = std::collections::HashMap::new();
    let sphere = scene.notes.sources.iter().find(|(s, _)| s == "sphere").unwrap().1;
    for t in 0..sphere {
        // Quadrics are tessellated in the order given, after every mesh (this file has none).
        let first = 0;
        let [a, b, c] = scene.mesh.indices[first + t];
        for (p, q) in [(a, b), (b, c), (c, a)] {
            *edges.entry((p.min(q), p.max(q))).or_insert(0) += 1;
        }
        let corners = scene.mesh.triangle(first + t);
        for p in corners {
            assert!(((p - Vec3::new(1.0, 2.0, 3.0)).length() - 3.0).abs() < 1e-5);
        }
        let centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
        let sag = 3.0 - (centroid - Vec3::new(1.0, 2.0, 3.0)).length();
        assert!(
            sag <= 2.0 * 2e-4 * diagonal,
            "sag {sag} against diagonal {diagonal}"
        );
    }
    assert!(edges.values().all(|&n| n == 2), "the sphere is not closed");
    for (_, n) in &scene.notes.sources {
        assert!(*n > 0);
    }
}

/// pbrt-v4-scenes' killeroo-simple (tests/data/pbrt/killeroos, unmodified): two killeroos,
/// each a `loopsubdiv` of one level, a floor and a wall, a sphere light; its camera; its film.
#[test]
fn the_killeroo_scene_loads_with_its_camera_and_film() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/pbrt/killeroos/killeroo-simple.pbrt");
    let scene = load_file(&path).unwrap();
    let notes = &scene.notes;
    assert_eq!(notes.size, Some((700, 700)));
    let base = {
        let text = std::fs::read_to_string(path.with_file_name("geometry/killeroo.pbrt")).unwrap();
        let start = text.find("\"integer indices\"").unwrap();
        let list = &text[start..];
        let list = &list[list.find('[').unwrap() + 1..list.find(']').unwrap()];
        list.split_whitespace().count() / 3
    };
    let killeroos = notes.sources.iter().find(|(s, _)| s == "loopsubdiv").unwrap().1;
    assert_eq!(
        killeroos,
        2 * 4 * base,
        "one level of Loop subdivision: four times the triangles"
    );
    assert_eq!(
        notes.sources.iter().find(|(s, _)| s == "trianglemesh").unwrap().1,
        4
    );
    // The file: LookAt 400 20 30  0 63 -110  0 0 1, then Rotate -5 0 0 1, then Camera
    // "perspective" "float fov" [39] on a square film.
    let camera_from_world = pbrt_look_at(
        DVec3::new(400.0, 20.0, 30.0),
        DVec3::new(0.0, 63.0, -110.0),
        DVec3::Z,
    ) * DMat4::from_axis_angle(DVec3::Z, (-5f64).to_radians());
    let world_from_camera = camera_from_world.inverse();
    let c = &scene.camera;
    assert!(c.mirrored);
    // The Rotate comes after LookAt, so it turns the world first: the eye is (400, 20, 30)
    // turned 5° about +z.
    let eye = world_from_camera.transform_point3(DVec3::ZERO).as_vec3();
    assert!((c.eye - eye).length() < 1e-3 && (eye - Vec3::new(400.0, 20.0, 30.0)).length() > 30.0);
    let forward = world_from_camera
        .transform_vector3(DVec3::Z)
        .normalize()
        .as_vec3();
    let up = world_from_camera
        .transform_vector3(DVec3::Y)
        .normalize()
        .as_vec3();
    assert!(((c.target - c.eye).normalize() - forward).length() < 1e-5);
    assert!((c.up.normalize() - up).length() < 1e-5, "{} against {up}", c.up);
    assert!((c.fov_y_deg - 39.0).abs() < 1e-4);
}

#[test]
fn bad_files_name_the_file_line_and_directive() {
    let dir = Scratch::new("pbrt-bad");
    let cases: [(&str, &str); 9] = [
        ("WorldBegin\n\nFrobnicate 1 2\n", "bad.pbrt:3: unknown directive 'Frobnicate'"),
        ("Translate 1 2\nWorldBegin\n", "bad.pbrt:2: Translate: 'WorldBegin' is not a number"),
        ("WorldBegin\nShape \"trianglemesh\" \"integer indices\" [0 1 2]\n", "bad.pbrt:2: Shape \"trianglemesh\": no \"point3 P\""),
        ("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 1]\n  \"integer indices\" [0 1 7]\n", "bad.pbrt:3: Shape \"trianglemesh\": index 7, but there are 4 points"),
        ("WorldBegin\nInclude \"nowhere/x.pbrt\"\n", "bad.pbrt:2: Include \"nowhere/x.pbrt\" (looked for "),
        ("WorldBegin\nShape \"plymesh\" \"string filename\" \"gone.ply\"\n", "bad.pbrt:2: Shape \"plymesh\" \"gone.ply\" (looked for "),
        (
            "WorldBegin\nShape \"loopsubdiv\" \"integer levels\" 16 \"point3 P\" [0 0 0 1 0 0 0 1 0]\n",
            "bad.pbrt:2: Shape \"loopsubdiv\": 16 levels of 1 triangles is more than hmdist subdivides",
        ),
        ("WorldBegin\nAttributeEnd\n", "bad.pbrt:2: AttributeEnd without a matching begin"),
        ("Camera \"perspective\" \"float fov\" [200]\nWorldBegin\nShape \"sphere\"\n", "bad.pbrt:1: Camera \"perspective\": fov must be in (0, 180), not 200"),
    ];
    for (text, expected) in cases {
        let message = load_file(&dir.write("bad.pbrt", text))
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(message.contains(expected), "{message}\n  expected: {expected}");
    }
    // A file that includes itself stops, saying so.
    dir.write("loop.pbrt", "Include \"loop.pbrt\"\n");
    let message = load_file(&dir.join("loop.pbrt"))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(message.contains("nested more than 32 deep"), "{message}");
}

/// Skipped shapes and lights are counted and named, the first spot light is the scene's.
#[test]
fn skipped_things_are_counted_and_the_spot_light_is_placed() {
    let dir = Scratch::new("pbrt-skipped");
    let text = "WorldBegin\nAttributeBegin\nTranslate 0 10 0\nLightSource \"spot\" \"point3 from\" [1 0 0] \"point3 to\" [1 -1 0] \"float coneangle\" [25]\nAttributeEnd\n\
                LightSource \"spot\"\nLightSource \"infinite\"\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n\
                Shape \"curve\" \"point3 P\" [0 0 0 1 1 1 2 2 2 3 3 3]\nShape \"curve\" \"point3 P\" [0 0 0 1 1 1 2 2 2 3 3 3]\n\
                Shape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0]\n";
    let scene = load_file(&dir.write("s.pbrt", text)).unwrap();
    let light = scene.light.unwrap();
    assert!((light.position - Vec3::new(1.0, 10.0, 0.0)).length() < 1e-6);
    assert!((light.direction - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-6);
    assert_eq!(light.cone_half_angle_deg, 25.0);
    assert_eq!(scene.notes.skipped_line().unwrap(), "1 × spot light (only the first is used), 1 × infinite light, 1 × diffuse area light (emission; its shapes are geometry), 2 × curve shape");
    assert_eq!(scene.mesh.triangle_count(), 2);
    assert_eq!(scene.notes.size, Some((1280, 720)));
    assert!(scene.notes.remarks.iter().any(|r| r.starts_with("no Camera")));
}
