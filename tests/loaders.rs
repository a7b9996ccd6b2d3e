//! Scene files (spec §7): every format loads to the triangles, camera and light written into
//! it, the OBJ export reads back exactly, and bad files give errors that name the file (and
//! the line, where the format has lines). Test files are written at run time into a fresh
//! directory under the system temp dir.

mod common;

use std::path::Path;

use common::Scratch;

use glam::Vec3;
use hmdist::scene::export::write_obj;
use hmdist::scene::load::load_file;
use hmdist::scene::{Mesh, Scene};

/// Writes `contents` to the file named at the start of `expected` ("name.obj:4: what") in
/// `dir`, loads it, and asserts that this fails with a message containing `expected`.
fn assert_fails(dir: &Scratch, contents: impl AsRef<[u8]>, expected: &str) {
    let name = expected.split(':').next().unwrap();
    let message = error_of(&dir.write(name, contents));
    assert!(message.contains(expected), "{message}");
}

/// The corners of every triangle, in order: independent of how a loader numbers vertices.
fn corners(mesh: &Mesh) -> Vec<[Vec3; 3]> {
    (0..mesh.triangle_count()).map(|i| mesh.triangle(i)).collect()
}

fn assert_close(a: Vec3, b: Vec3) {
    assert!((a - b).length() < 1e-5, "{a} != {b}");
}

/// The error message of loading `path`, which must fail.
fn error_of(path: &Path) -> String {
    match load_file(path) {
        Ok(scene) => panic!(
            "{} loaded ({} triangles)",
            path.display(),
            scene.mesh.triangle_count()
        ),
        Err(e) => e.to_string(),
    }
}

// Square (0,0,0)-(1,1,0) as a quad plus one triangle: fan triangulation gives these three.
const SQUARE: [[f32; 3]; 5] = [
    [0., 0., 0.],
    [1., 0., 0.],
    [1., 1., 0.],
    [0., 1., 0.],
    [2., 0.5, -1.25],
];
const SQUARE_TRIANGLES: [[usize; 3]; 3] = [[0, 1, 2], [0, 2, 3], [1, 4, 2]];

fn square_corners() -> Vec<[Vec3; 3]> {
    SQUARE_TRIANGLES
        .iter()
        .map(|t| t.map(|v| Vec3::from(SQUARE[v])))
        .collect()
}

#[test]
fn obj_export_reads_back_exactly() {
    let dir = Scratch::new("obj-round-trip");
    let mut mesh = Mesh::new();
    mesh.add_vertices([
        Vec3::new(0.1, 1.0 / 3.0, -2.5e-7),
        Vec3::new(12345.678, -0.0, 7.0),
        Vec3::new(f32::MIN_POSITIVE, 1e-3, 3.0e5),
        Vec3::new(-1.0, 2.0, -3.0),
    ]);
    mesh.add_triangle(0, 1, 2);
    mesh.add_triangle(2, 1, 3);
    let path = dir.join("mesh.obj");
    write_obj(&mesh, &path).unwrap();

    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with("# ") && text.lines().next().unwrap().contains("2 triangles"));
    let scene = load_file(&path).unwrap();
    assert_eq!(scene.mesh, mesh, "same vertices, same order, same triangles");
    assert_eq!(scene.name, "mesh.obj");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no temporary file left"
    );
}

#[test]
fn obj_polygons_are_fan_triangulated_and_objects_merged() {
    let dir = Scratch::new("obj-polygons");
    let obj = "# a quad, then a triangle in another object with relative indices\n\
               o square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n\
               o other\nv 2 0.5 -1.25\nl 1 2 3\nf 2 -1 3\n";
    let scene = load_file(&dir.write("square.obj", obj)).unwrap();
    assert_eq!(corners(&scene.mesh), square_corners());
}

/// The square as a PLY file: `ascii`, `binary_little_endian` or `binary_big_endian`, with
/// double coordinates in binary, an extra colour property and an int face list.
fn square_ply(format: &str) -> Vec<u8> {
    let scalar = if format == "ascii" { "float" } else { "double" };
    let mut out = format!(
        "ply\nformat {format} 1.0\ncomment made by hand\nelement vertex 5\n\
         property {scalar} x\nproperty {scalar} y\nproperty {scalar} z\nproperty uchar red\n\
         element face 2\nproperty list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes();
    let faces: [&[i32]; 2] = [&[0, 1, 2, 3], &[1, 4, 2]];
    if format == "ascii" {
        for p in SQUARE {
            out.extend(format!("{} {} {} 255\n", p[0], p[1], p[2]).bytes());
        }
        for f in faces {
            let list: Vec<String> = f.iter().map(|i| i.to_string()).collect();
            out.extend(format!("{} {}\n", f.len(), list.join(" ")).bytes());
        }
        return out;
    }
    let big = format == "binary_big_endian";
    for p in SQUARE {
        for c in p {
            let c = c as f64;
            out.extend(if big { c.to_be_bytes() } else { c.to_le_bytes() });
        }
        out.push(255);
    }
    for f in faces {
        out.push(f.len() as u8);
        for &i in f {
            out.extend(if big { i.to_be_bytes() } else { i.to_le_bytes() });
        }
    }
    out
}

#[test]
fn ply_ascii_and_binary_give_the_same_mesh() {
    let dir = Scratch::new("ply");
    for format in ["ascii", "binary_little_endian", "binary_big_endian"] {
        let path = dir.write(&format!("{format}.ply"), square_ply(format));
        let scene = load_file(&path).unwrap_or_else(|e| panic!("{format}: {e}"));
        assert_eq!(corners(&scene.mesh), square_corners(), "{format}");
    }
}

fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let byte = |i: usize| *chunk.get(i).unwrap_or(&0) as u32;
        let n = byte(0) << 16 | byte(1) << 8 | byte(2);
        for i in 0..4 {
            let sextet = (n >> (18 - 6 * i)) as usize & 63;
            out.push(if i <= chunk.len() {
                ALPHABET[sextet] as char
            } else {
                '='
            });
        }
    }
    out
}

const TRIANGLE: [[f32; 3]; 3] = [[0., 0., 0.], [1., 0., 0.], [0., 2., 0.]];

/// One triangle (positions, then u16 indices 0 1 2 and two bytes of padding).
fn triangle_buffer() -> Vec<u8> {
    let mut bytes: Vec<u8> = TRIANGLE.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
    bytes.extend([0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes()));
    bytes
}

/// A glTF document: the triangle at node 0 moved by +10 x; node 1 (moved +1 y) holds the
/// camera in child node 2 (moved +5 z); node 3, turned to look down, holds a spot light at
/// y = 9. `uri`: the buffer's URI, none for a GLB's binary chunk.
fn triangle_gltf(uri: Option<&str>) -> String {
    let uri = uri.map_or(String::new(), |u| format!(r#""uri": "{u}","#));
    format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {{ "KHR_lights_punctual": {{ "lights": [
    {{ "type": "spot", "spot": {{ "innerConeAngle": 0.2, "outerConeAngle": 0.5 }} }} ] }} }},
  "scene": 0,
  "scenes": [ {{ "nodes": [0, 1, 3] }} ],
  "nodes": [
    {{ "mesh": 0, "translation": [10, 0, 0] }},
    {{ "children": [2], "translation": [0, 1, 0] }},
    {{ "camera": 0, "translation": [0, 0, 5] }},
    {{ "translation": [0, 9, 0], "rotation": [-0.70710677, 0, 0, 0.70710677],
      "extensions": {{ "KHR_lights_punctual": {{ "light": 0 }} }} }}
  ],
  "cameras": [ {{ "type": "perspective", "perspective": {{ "yfov": 0.8, "znear": 0.1 }} }} ],
  "meshes": [ {{ "primitives": [ {{ "attributes": {{ "POSITION": 0 }}, "indices": 1 }} ] }} ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
      "min": [0, 0, 0], "max": [1, 2, 0] }},
    {{ "bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR" }}
  ],
  "bufferViews": [
    {{ "buffer": 0, "byteOffset": 0, "byteLength": 36 }},
    {{ "buffer": 0, "byteOffset": 36, "byteLength": 6 }}
  ],
  "buffers": [ {{ {uri} "byteLength": 44 }} ]
}}"#
    )
}

fn triangle_data_uri() -> String {
    format!(
        "data:application/octet-stream;base64,{}",
        base64(&triangle_buffer())
    )
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    json.resize(json.len().next_multiple_of(4), b' ');
    let length = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    for word in [2, length as u32, json.len() as u32, 0x4E4F_534A] {
        out.extend(word.to_le_bytes());
    }
    out.extend(&json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(0x004E_4942u32.to_le_bytes());
    out.extend(bin);
    out
}

fn assert_is_the_triangle_gltf(scene: &Scene) {
    let expected = TRIANGLE.map(|p| Vec3::from(p) + Vec3::new(10.0, 0.0, 0.0));
    assert_eq!(corners(&scene.mesh), vec![expected]);
    let camera = scene.camera;
    assert_close(camera.eye, Vec3::new(0.0, 1.0, 5.0));
    assert_close(camera.target, Vec3::new(0.0, 1.0, 4.0));
    assert_close(camera.up, Vec3::Y);
    assert!((camera.fov_y_deg - 0.8f32.to_degrees()).abs() < 1e-4);
    let light = scene.light.expect("the spot light");
    assert_close(light.position, Vec3::new(0.0, 9.0, 0.0));
    assert_close(light.direction, Vec3::NEG_Y);
    assert!((light.cone_half_angle_deg - 0.5f32.to_degrees()).abs() < 1e-4);
}

#[test]
fn gltf_applies_node_transforms_and_reads_camera_and_spot_light() {
    let dir = Scratch::new("gltf");
    let data_uri = triangle_data_uri();
    let embedded = dir.write("embedded.gltf", triangle_gltf(Some(&data_uri)));
    assert_is_the_triangle_gltf(&load_file(&embedded).unwrap());

    dir.write("triangle.bin", triangle_buffer());
    let external = dir.write("external.GLTF", triangle_gltf(Some("triangle.bin")));
    assert_is_the_triangle_gltf(&load_file(&external).unwrap());

    let glb = glb(&triangle_gltf(None), &triangle_buffer());
    let binary = dir.write("binary.glb", glb);
    assert_is_the_triangle_gltf(&load_file(&binary).unwrap());

    let missing = triangle_gltf(Some("nowhere.bin"));
    let message = error_of(&dir.write("missing.gltf", missing));
    let named = message.contains("missing.gltf: cannot read buffer 0 (");
    assert!(named && message.contains("nowhere.bin"), "{message}");
}

#[test]
fn toml_places_meshes_and_sets_camera_light_and_display() {
    let dir = Scratch::new("toml");
    dir.write("triangle.obj", "v 0 0 0\nv 1 0 0\nv 0 2 0\nf 1 2 3\n");
    let toml = r#"
[[mesh]]
path = "triangle.obj"
scale = 2
rotate_y_deg = 90.0
translate = [1, 2, 3]
[camera]
eye = [1.0, 4.0, 8.0]
target = [0.0, 1.5, 0.0]
fov_y_deg = 60.0
[light]
position = [0, 9.9, 0]
direction = [0, -2, 0]
cone_half_angle_deg = 45.0
[display]
scale = 0.25
"#;
    let scene = load_file(&dir.write("scene.toml", toml)).unwrap();
    // Scaled by 2, turned +90° about y ((x, y, z) -> (z, y, -x)), moved by (1, 2, 3).
    let expected = [[1., 2., 3.], [1., 2., 1.], [1., 6., 3.]].map(Vec3::from);
    let got = scene.mesh.triangle(0);
    (0..3).for_each(|i| assert_close(got[i], expected[i]));
    assert_eq!(scene.camera.eye, Vec3::new(1.0, 4.0, 8.0));
    assert_eq!(scene.camera.target, Vec3::new(0.0, 1.5, 0.0));
    assert_eq!(scene.camera.up, Vec3::Y);
    assert_eq!(scene.camera.fov_y_deg, 60.0);
    let light = scene.light.unwrap();
    assert_eq!(
        (light.position, light.direction),
        (Vec3::new(0.0, 9.9, 0.0), Vec3::NEG_Y)
    );
    assert_eq!(light.cone_half_angle_deg, 45.0);
    assert_eq!(scene.display_scale, 0.25);
    assert_eq!(scene.name, "scene.toml");
}

#[test]
fn toml_without_camera_takes_the_gltf_camera_moved_with_its_mesh() {
    let dir = Scratch::new("toml-gltf");
    let gltf = triangle_gltf(Some(&triangle_data_uri()));
    dir.write("triangle.gltf", gltf);
    let toml = "[[mesh]]\npath = \"triangle.gltf\"\ntranslate = [0, 0, 100]\n";
    let scene = load_file(&dir.write("scene.toml", toml)).unwrap();
    assert_close(scene.camera.eye, Vec3::new(0.0, 1.0, 105.0));
    assert_close(scene.camera.target, Vec3::new(0.0, 1.0, 104.0));
    assert_close(scene.light.unwrap().position, Vec3::new(0.0, 9.0, 100.0));
}

#[test]
fn bad_obj_files_name_the_file_and_line() {
    let dir = Scratch::new("bad-obj");
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let garbage = format!("{tri}hello world\nf 1 2 3\n");
    assert_fails(&dir, garbage, "garbage.obj:4: 'hello' is not an OBJ statement");
    let short = format!("{tri}f 1 2 3\nf 1 2\n");
    assert_fails(&dir, short, "short.obj:5: a face needs at least 3 corners");
    let range = format!("{tri}f 1 2 3\n# c\nf 1 2 12\nv 5 5 5\n");
    assert_fails(&dir, range, "range.obj:6: face refers to vertex 12 but");
    let zero = format!("{tri}f 0 1 2\n");
    assert_fails(&dir, zero, "zero.obj:4: vertex numbers start at 1, not 0");
    let nan = tri.replace("v 1 0 0", "v nan 0 0") + "f 1 2 3";
    assert_fails(&dir, nan, "nan.obj:2: vertex 2 is not finite: (NaN, 0");
    let word = format!("{tri}v 1 x 0\nf 1 2 3\n");
    assert_fails(&dir, word, "word.obj:4: cannot read the vertex coordinates");
    let letters = format!("{tri}f 1 2 three\n");
    assert_fails(&dir, letters, "letters.obj:4: cannot read the face's corners");
    let elf = [0x7f, b'E', b'L', b'F', 0xff, 0xfe, b'\n'];
    assert_fails(&dir, elf, "elf.obj:1: the line is not UTF-8 text");
    assert_fails(&dir, tri, "points.obj: the scene has no triangles");
}

#[test]
fn bad_ply_files_name_the_file_and_line() {
    let dir = Scratch::new("bad-ply");
    let binary = square_ply("binary_little_endian");
    let cut = |n: usize| &binary[..binary.len() - n];
    let eof = "Unexpected end of file while reading";
    assert_fails(&dir, cut(1), &format!("cut1.ply: {eof} binary element 'face'"));
    assert_fails(&dir, cut(60), &format!("cut2.ply: {eof} binary element 'vertex'"));
    let header = String::from_utf8_lossy(&binary).find("end_header").unwrap();
    assert_fails(&dir, &binary[..header], &format!("cut3.ply:11: {eof} header"));
    let extra = [binary.as_slice(), b"\0"].concat();
    assert_fails(&dir, extra, "extra.ply: 1 bytes after the last element");

    let ascii = String::from_utf8(square_ply("ascii")).unwrap();
    let short = ascii.replace("3 1 4 2\n", "");
    assert_fails(&dir, short, &format!("short.ply:18: {eof} element 'face'"));
    let range = ascii.replace("3 1 4 2", "3 1 9 2");
    assert_fails(&dir, range, "range.ply:18: face 1 refers to vertex 9 but");
    let inf = ascii.replacen("1 1 0", "1 1e39 0", 1); // ascii PLY has no "nan"
    assert_fails(&dir, inf, "inf.ply:14: vertex 2 is not finite: (1, inf");
    let more = format!("{ascii}0 1 2\n");
    assert_fails(&dir, more, "more.ply:19: data after the last element");
    let typo = "ply\nformat ascii 1.0\nelemnt vertex 3\n";
    assert_fails(&dir, typo, "typo.ply:3: Couldn't parse line");
    let cloud = ascii.replace("element face 2", "element face 0");
    let cloud = &cloud[..cloud.find("4 0 1 2 3").unwrap()];
    assert_fails(&dir, cloud, "cloud.ply: the scene has no triangles");
}

#[test]
fn bad_gltf_files_name_the_file() {
    let dir = Scratch::new("bad-gltf");
    let garbage = "{\n  \"asset\": [ nonsense\n";
    assert_fails(&dir, garbage, "garbage.gltf:2: not valid glTF JSON");
    assert_fails(&dir, "glTF\x02\0\0\0?", "garbage.glb: not a valid glTF file");
    let gltf = triangle_gltf(Some(&triangle_data_uri()));
    // The gltf crate's own validation looks the accessor up with this index (a panic): we
    // look first.
    let index = gltf.replace(r#""POSITION": 0"#, r#""POSITION": 7"#);
    let message = "index.gltf: mesh 0 primitive 0 names accessor 7, but the file has 2 accessors";
    assert_fails(&dir, index, message);
    let cycle = gltf.replace(r#""camera": 0,"#, r#""camera": 0, "children": [1],"#);
    assert_fails(&dir, cycle, "cycle.gltf: node 1 is reached twice");
    let odd = gltf.replace(
        r#""count": 3, "type": "SCALAR""#,
        r#""count": 2, "type": "SCALAR""#,
    );
    assert_fails(&dir, odd, "odd.gltf: mesh 0 primitive 0: 2 corners is not");
}

#[test]
fn bad_toml_files_name_the_file_and_line() {
    let dir = Scratch::new("bad-toml");
    dir.write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let mesh = "[[mesh]]\npath = \"t.obj\"\n";
    let camera = "[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\nfov_y_deg = 60\n";
    let typo = format!("{mesh}{camera}fov = 50\n");
    assert_fails(&dir, typo, "typo.toml:7: unknown field `fov`");
    let missing = format!("{mesh}\n[[mesh]]\npath = \"gone.obj\"\n");
    assert_fails(&dir, missing, "missing.toml:4: mesh 'gone.obj': ");
    let message = error_of(&dir.join("missing.toml"));
    assert!(message.contains("gone.obj: cannot read file: "), "{message}");
    let light = "[light]\nposition = [0, 1, 0]\ndirection = [0, 0, 0]\ncone_half_angle_deg = 30\n";
    let dark = format!("{mesh}{light}");
    assert_fails(&dir, dark, "dark.toml:3: the light's direction must not be");
    let blind = format!("{mesh}{}", camera.replace("[0, 0, 5]", "[0, 0, 0]"));
    assert_fails(&dir, blind, "blind.toml:3: the camera's eye and target are");
    assert_fails(&dir, "# nothing\n", "empty.toml: the scene names no meshes");
    // Exactly three numbers: a fourth is not ignored, two are not enough.
    let four = format!("{mesh}{}", light.replace("[0, 1, 0]", "[0, 9.8, 0, 123]"));
    assert_fails(
        &dir,
        four,
        "four.toml:4: expected exactly three numbers [x, y, z], found 4",
    );
    let eye = format!("{mesh}{}", camera.replace("[0, 0, 5]", "[0, 5]"));
    assert_fails(
        &dir,
        eye,
        "eye.toml:4: expected exactly three numbers [x, y, z], found 2",
    );
}

#[test]
fn a_light_direction_of_any_finite_length_is_the_unit_direction() {
    // 3e19 squared overflows f32: normalised naively it became [0, -0, 0] (E = 0 everywhere).
    let dir = Scratch::new("toml-light-length");
    dir.write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    for (name, direction) in [("huge", "[0, -3e19, 0]"), ("tiny", "[0, -1e-25, 0]")] {
        let light =
            format!("[light]\nposition = [0, 1, 0]\ndirection = {direction}\ncone_half_angle_deg = 30\n");
        let path = dir.write(
            &format!("{name}.toml"),
            format!("[[mesh]]\npath = \"t.obj\"\n{light}"),
        );
        let scene = Scene::load(path.to_str().unwrap()).unwrap();
        assert_eq!(scene.light.unwrap().direction, glam::Vec3::NEG_Y, "{name}");
    }
}

#[test]
fn missing_files_and_unknown_formats_are_errors() {
    let dir = Scratch::new("missing");
    let message = error_of(&dir.join("nothing.obj"));
    assert!(message.contains("nothing.obj: cannot read file: "), "{message}");
    assert_fails(&dir, "v 0 0 0", "scene.xyz: unknown scene format '.xyz'");
}

/// The peak virtual memory of this process so far, in MiB (Linux: `VmPeak` of
/// /proc/self/status), counting memory reserved but never touched, as a `Vec::with_capacity`
/// of the declared count would be.
#[cfg(target_os = "linux")]
fn peak_virtual_mib() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status.lines().find(|l| l.starts_with("VmPeak:")).unwrap();
    let kib: u64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    kib / 1024
}

#[cfg(target_os = "linux")]
#[test]
fn a_ply_declaring_50_million_triangles_without_their_data_is_refused_without_reserving_for_them() {
    // In a child process of its own (this test's binary, run for this test only), so that
    // its peak memory is that of the load alone.
    const CHILD: &str = "HMDIST_TEST_PLY_CHILD";
    let Some(format) = std::env::var_os(CHILD) else {
        let test =
            "a_ply_declaring_50_million_triangles_without_their_data_is_refused_without_reserving_for_them";
        for format in ["ascii", "binary_little_endian"] {
            let stdout = common::rerun_in_child(test, CHILD, format);
            assert!(stdout.contains("refused in"), "{format}: {stdout}");
        }
        return;
    };
    let format = format.to_string_lossy();
    let dir = Scratch::new(&format!("ply-50m-{format}"));
    // 50 M vertices of 12 bytes and 50 M triangles of 13 bytes declared; 3 vertices given.
    let mut bytes = format!(
        "ply\nformat {format} 1.0\nelement vertex 50000000\nproperty float x\nproperty float y\n\
         property float z\nelement face 50000000\nproperty list uchar int vertex_indices\n\
         end_header\n"
    )
    .into_bytes();
    if format == "ascii" {
        bytes.extend(b"0 0 0\n1 0 0\n0 1 0\n");
    } else {
        bytes.extend(
            [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
                .iter()
                .flat_map(|v| v.to_le_bytes()),
        );
    }
    let path = dir.write("huge.ply", &bytes);
    let before = peak_virtual_mib();
    let start = std::time::Instant::now();
    let message = error_of(&path);
    let seconds = start.elapsed().as_secs_f64();
    let grown = peak_virtual_mib() - before;
    assert!(message.contains("Unexpected end of file"), "{message}");
    assert!(seconds < 1.0, "took {seconds} s");
    // Room for 50 M vertices alone would be 600 MB (as parsed records, 2 GB).
    assert!(grown < 200, "peak virtual memory grew by {grown} MiB");
    println!("refused in {seconds:.3} s, peak virtual memory +{grown} MiB: {message}");
}
