//! Mitsuba 3 scenes (`.xml`): every element placed as OBJ + TOML place the same geometry, the
//! camera against Mitsuba's own projection, files named and refused as Mitsuba would, and
//! mitsuba-data's shape scenes (tests/data/mitsuba/mitsuba-data, unmodified) against the
//! silhouette in Mitsuba's published picture.

mod common;

use std::io::Write;

use common::{assert_same_triangles, Scratch, TRI_OBJ as OBJ, TRI_PLY as PLY};
use glam::{DMat4, DVec3, Vec3};
use hmdist::accel::{Accel, BuildQuality};
use hmdist::scene::load::load_file;
use hmdist::scene::Scene;

const POSITIONS: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.5],
    [0.3, 0.2, 2.0],
];
const INDICES: [[u32; 3]; 3] = [[0, 1, 2], [0, 2, 3], [1, 4, 2]];

/// One mesh of a `.serialized` file in version 3 or 4, written here from Mitsuba's format
/// description (normals and texture coordinates included, so they must be skipped).
fn serialized_mesh(version: u16, positions: &[[f32; 3]], indices: &[[u32; 3]]) -> Vec<u8> {
    let mut raw = Vec::new();
    raw.extend(0x1003u32.to_le_bytes());
    if version == 4 {
        raw.extend(b"a mesh\0");
    }
    raw.extend((positions.len() as u64).to_le_bytes());
    raw.extend((indices.len() as u64).to_le_bytes());
    for p in positions.iter().flatten() {
        raw.extend(p.to_le_bytes());
    }
    for _ in 0..positions.len() * 5 {
        raw.extend(0.25f32.to_le_bytes());
    }
    for i in indices.iter().flatten() {
        raw.extend(i.to_le_bytes());
    }
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(&raw).unwrap();
    let mut out = 0x041Cu16.to_le_bytes().to_vec();
    out.extend(version.to_le_bytes());
    out.extend(z.finish().unwrap());
    out
}

/// A version-4 file of a decoy mesh then the test mesh, with its table of offsets.
fn serialized_file() -> Vec<u8> {
    let decoy = serialized_mesh(
        4,
        &[[9.0, 9.0, 9.0], [8.0, 9.0, 9.0], [9.0, 8.0, 9.0]],
        &[[0, 1, 2]],
    );
    let mut file = decoy.clone();
    file.extend(serialized_mesh(4, &POSITIONS, &INDICES));
    file.extend(0u64.to_le_bytes());
    file.extend((decoy.len() as u64).to_le_bytes());
    file.extend(2u32.to_le_bytes());
    file
}

/// `points` placed by `m`, as an OBJ of `faces` (1-based in the text).
fn placed_obj(points: &[DVec3], m: &DMat4, faces: &[[u32; 3]]) -> String {
    let mut text = String::new();
    for p in points {
        let q = m.transform_point3(*p);
        text += &format!("v {:.17} {:.17} {:.17}\n", q.x, q.y, q.z);
    }
    for f in faces {
        text += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    text
}

/// Mitsuba's lookat, written out from its definition: left = up × dir, new up = dir × left;
/// the matrix is world from local.
fn mitsuba_look_at(origin: DVec3, target: DVec3, up: DVec3) -> DMat4 {
    let dir = (target - origin).normalize();
    let left = up.normalize().cross(dir).normalize();
    let new_up = dir.cross(left);
    DMat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    )
}

/// The same placements written in Mitsuba's every way of saying them, and in TOML (with OBJ
/// files the test places itself where TOML has no words for the transform).
#[test]
fn every_element_places_triangles_as_toml_does() {
    let dir = Scratch::new("mitsuba-placements");
    for sub in ["meshes", "sub", "sub/deeper"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    dir.write("meshes/tri.obj", OBJ);
    dir.write("tri.obj", OBJ);
    dir.write("meshes/tri.ply", PLY);
    dir.write("meshes/two.serialized", serialized_file());
    // A matrix for "scale 2, rotate 30° about +y, translate (1, 2, 3)", row by row as
    // Mitsuba's <matrix> reads it.
    let m = DMat4::from_translation(DVec3::new(1.0, 2.0, 3.0))
        * DMat4::from_rotation_y(30f64.to_radians())
        * DMat4::from_scale(DVec3::splat(2.0));
    let rows: Vec<String> = m
        .transpose()
        .to_cols_array()
        .iter()
        .map(|v| format!("{v:.17}"))
        .collect();
    // A 3 × 3 matrix: rotate 90° about +y and scale 0.5.
    let r = glam::DMat3::from_rotation_y(90f64.to_radians()) * glam::DMat3::from_diagonal(DVec3::splat(0.5));
    let rows3: Vec<String> = r
        .transpose()
        .to_cols_array()
        .iter()
        .map(|v| format!("{v:.17}"))
        .collect();
    // Included files: one a <scene> (its own <path>, forgotten after it), one a bare <shape>.
    dir.write(
        "sub/part.xml",
        r#"<scene version="3.0.0">
    <path value="deeper"/>
    <shape type="obj">
        <string name="filename" value="tri.obj"/>
        <transform name="to_world"><scale x="1" y="1" z="1"/><translate value="5 5 5"/></transform>
    </shape>
    <include filename="one.xml"/>
</scene>"#,
    );
    dir.write(
        "sub/deeper/one.xml",
        r#"<shape type="ply"><string name="filename" value="meshes/tri.ply"/>
        <transform name="to_world"><rotate value="0 1 0" angle="-90"/><translate x="-4" y="-3"/></transform></shape>"#,
    );
    let xml = format!(
        r#"<?xml version="1.0" encoding="utf-8"?>
<!-- placements, in every element hmdist reads -->
<scene version="3.0.0">
    <default name="s" value="2"/>
    <default name="s" value="99"/>
    <default name="mesh" value="tri"/>
    <path value="meshes"/>
    <integrator type="path"><integer name="max_depth" value="$s"/></integrator>
    <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
    <texture type="checkerboard" id="checks"/>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 5, 20" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/></film>
    </sensor>
    <shape type="obj" id="first">
        <string name="filename" value="$mesh.obj"/>
        <transform name="to_world">
            <scale value="$s"/>
            <rotate y="1" angle="30"/>
            <translate x="1" y="2" z="3"/>
        </transform>
        <ref id="white"/>
    </shape>
    <shape type="ply">
        <string name="filename" value="tri.ply"/>
        <transform name="to_world"><matrix value="{rows}"/><translate value="10 0 0"/></transform>
    </shape>
    <shape type="serialized">
        <string name="filename" value="two.serialized"/>
        <integer name="shape_index" value="1"/>
        <transform name="to_world"><matrix value="{rows3}"/><translate z="-7"/></transform>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>
    <include filename="sub/part.xml"/>
    <shape type="shapegroup" id="group">
        <shape type="obj">
            <string name="filename" value="tri.obj"/>
            <transform name="to_world"><scale value="0.5"/></transform>
        </shape>
    </shape>
    <shape type="instance">
        <ref id="group"/>
        <transform name="to_world"><rotate y="1" angle="90"/><translate z="-7"/></transform>
    </shape>
    <shape type="merge">
        <shape type="obj"><string name="filename" value="tri.obj"/><transform name="to_world"><translate value="0 -9 0"/></transform></shape>
        <shape type="rectangle">
            <transform name="to_world"><scale x="3" y="2"/><lookat origin="1 1 1" target="2 1 1" up="0 1 0"/></transform>
        </shape>
    </shape>
    <shape type="cube"><transform name="to_world"><scale value="0.25"/><translate value="0 0 9"/></transform></shape>
    <shape type="bsplinecurve"><string name="filename" value="curve.txt"/></shape>
    <emitter type="envmap"><string name="filename" value="sky.exr"/></emitter>
    <emitter type="spot">
        <float name="cutoff_angle" value="25"/>
        <transform name="to_world"><lookat origin="1, 10, 0" target="1, 9, 0" up="1 0 0"/></transform>
    </emitter>
</scene>"#,
        rows = rows.join(" "),
        rows3 = rows3.join(" ")
    );
    // The rectangle and cube, placed here from Mitsuba's definitions (±1 in x and y; ±1).
    let rectangle = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| DVec3::new(x, y, 0.0));
    let rectangle_world = mitsuba_look_at(DVec3::ONE, DVec3::new(2.0, 1.0, 1.0), DVec3::Y)
        * DMat4::from_scale(DVec3::new(3.0, 2.0, 1.0));
    dir.write(
        "rectangle.obj",
        placed_obj(&rectangle, &rectangle_world, &[[0, 1, 2], [0, 2, 3]]),
    );
    let cube: Vec<DVec3> = (0..8)
        .map(|i| {
            DVec3::new(
                [-1.0, 1.0][i & 1],
                [-1.0, 1.0][i >> 1 & 1],
                [-1.0, 1.0][i >> 2 & 1],
            )
        })
        .collect();
    let cube_world =
        DMat4::from_translation(DVec3::new(0.0, 0.0, 9.0)) * DMat4::from_scale(DVec3::splat(0.25));
    // The cube's faces, as pairs of triangles over each face's corners.
    let faces = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let cube_faces: Vec<[u32; 3]> = faces
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    dir.write("cube.obj", placed_obj(&cube, &cube_world, &cube_faces));
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
translate = [11, 2, 3]
[[mesh]]
path = "tri.obj"
scale = 0.5
rotate_y_deg = 90.0
translate = [0, 0, -7]
[[mesh]]
path = "tri.obj"
translate = [5, 5, 5]
[[mesh]]
path = "tri.obj"
rotate_y_deg = -90.0
translate = [-4, -3, 0]
[[mesh]]
path = "tri.obj"
scale = 0.5
rotate_y_deg = 90.0
translate = [0, 0, -7]
[[mesh]]
path = "tri.obj"
translate = [0, -9, 0]
[[mesh]]
path = "rectangle.obj"
[[mesh]]
path = "cube.obj"
"#;
    let from_xml = load_file(&dir.write("scene.xml", xml)).unwrap();
    let from_toml = load_file(&dir.write("scene.toml", toml)).unwrap();
    assert_same_triangles(&from_xml, &from_toml, 1e-5);

    // Every file the load reads is one no command may write over.
    let mut read = Scene::files_read(dir.join("scene.xml").to_str().unwrap());
    read.sort();
    let mut expected: Vec<_> = [
        "scene.xml",
        "meshes/tri.obj",
        "meshes/tri.ply",
        "meshes/two.serialized",
        "sub/part.xml",
        "sub/deeper/one.xml",
    ]
    .iter()
    .map(|f| dir.join(f))
    .collect();
    // Each name is looked for in the <path> folders first ("meshes", and "sub/deeper" while
    // sub/part.xml is read), so no shape reads the scene folder's own tri.obj.
    expected.sort();
    let notes = &from_xml.notes;
    assert_eq!(notes.size, Some((64, 48)));
    // tri.obj: the first shape ($mesh.obj), sub/part.xml's, the instance's and the merge's.
    for (source, n) in [
        ("obj tri.obj", 4 * 3),
        ("ply tri.ply", 3),
        ("ply meshes/tri.ply", 3),
        ("serialized two.serialized (mesh 1)", 3),
        ("rectangle", 2),
        ("cube", 12),
    ] {
        let found = notes.sources.iter().find(|(s, _)| s == source).map_or(0, |s| s.1);
        assert_eq!(found, n, "{source}: {notes:?}");
    }
    assert_eq!(
        notes.skipped_line().unwrap(),
        "1 × area emitter (emission; its shapes are geometry), 1 × bsplinecurve shape, 1 × envmap emitter"
    );
    assert!(
        notes
            .remarks
            .iter()
            .any(|r| r == "1 shape instance flattened into the mesh"),
        "{notes:?}"
    );
    let light = from_xml.light.unwrap();
    assert!((light.position - Vec3::new(1.0, 10.0, 0.0)).length() < 1e-6);
    assert!((light.direction - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-6);
    assert_eq!(light.cone_half_angle_deg, 25.0);
    assert_eq!(read, expected);
}

/// Where Mitsuba's perspective sensor puts world point `p` on a `width × height` film, from
/// Mitsuba 3's definitions (`perspective_projection`): camera space divides by z and by
/// tan(fov_x / 2); sample x = (1 − x′) / 2 and y = (1 − aspect · y′) / 2 (camera x is the
/// picture's left, y its up), raster = sample × film.
fn mitsuba_raster(to_world: DMat4, tan_half_x: f64, width: u32, height: u32, p: DVec3) -> (f64, f64) {
    let c = to_world.inverse().transform_point3(p);
    let (x, y) = (c.x / c.z / tan_half_x, c.y / c.z / tan_half_x);
    let aspect = width as f64 / height as f64;
    (
        0.5 * (1.0 - x) * width as f64,
        0.5 * (1.0 - aspect * y) * height as f64,
    )
}

/// tan(fov_x / 2) by Mitsuba's `parse_fov`, written out: `fov` along `axis` (smaller and
/// larger by the film's shape), or a focal length in mm on a 36 × 24 mm frame's diagonal.
fn mitsuba_tan_half_x(fov: Option<f64>, axis: &str, focal_mm: f64, aspect: f64) -> f64 {
    let diagonal_to_x = |t: f64| t / (1.0 + 1.0 / (aspect * aspect)).sqrt();
    let Some(fov) = fov else {
        return diagonal_to_x((36f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * focal_mm));
    };
    let t = (0.5 * fov.to_radians()).tan();
    let axis = match axis {
        "smaller" => {
            if aspect > 1.0 {
                "y"
            } else {
                "x"
            }
        }
        "larger" => {
            if aspect > 1.0 {
                "x"
            } else {
                "y"
            }
        }
        a => a,
    };
    match axis {
        "x" => t,
        "y" => t * aspect,
        _ => diagonal_to_x(t),
    }
}

/// Small markers at known points, and the pixel each lands on in hmdist's picture, checked
/// against Mitsuba's projection for every fov axis, the focal length, wide and tall films, and
/// a reflecting `to_world` (a mirrored camera).
#[test]
fn the_camera_sees_each_point_where_mitsuba_projects_it() {
    let dir = Scratch::new("mitsuba-camera");
    let markers = [
        DVec3::new(2.0, 1.0, 0.0),
        DVec3::new(-1.5, -0.7, 1.0),
        DVec3::new(0.4, 1.6, -2.0),
    ];
    let mut shapes = String::new();
    for m in markers {
        // A rectangle 0.3 across (several pixels) facing the camera's side, as two triangles.
        shapes += &format!(
            "<shape type=\"rectangle\"><transform name=\"to_world\"><scale value=\"0.15\"/><translate value=\"{} {} {}\"/></transform></shape>\n",
            m.x, m.y, m.z
        );
    }
    let (origin, target, up) = (
        DVec3::new(1.0, 2.0, 9.0),
        DVec3::new(0.0, 0.5, 0.0),
        DVec3::new(0.1, 1.0, 0.0),
    );
    let cases = [
        (160, 100, Some(35.0), "x", 50.0, false),
        (160, 100, Some(25.0), "y", 50.0, false),
        (90, 150, Some(75.0), "diagonal", 50.0, false),
        (90, 150, Some(45.0), "smaller", 50.0, false),
        (160, 100, Some(40.0), "larger", 50.0, false),
        (160, 100, None, "", 50.0, false),
        (90, 150, None, "", 20.0, false),
        (160, 100, Some(35.0), "x", 50.0, true),
    ];
    for (width, height, fov, axis, focal, reflect) in cases {
        let lens = match fov {
            Some(fov) => {
                format!("<float name=\"fov\" value=\"{fov}\"/><string name=\"fov_axis\" value=\"{axis}\"/>")
            }
            None if focal == 50.0 => String::new(),
            None => format!("<string name=\"focal_length\" value=\"{focal}mm\"/>"),
        };
        let mirror = if reflect { "<scale x=\"-1\"/>" } else { "" };
        let text = format!(
            "<scene version=\"3.0.0\"><sensor type=\"perspective\">{lens}\
             <transform name=\"to_world\">{mirror}<lookat origin=\"{}, {}, {}\" target=\"{}, {}, {}\" up=\"{}, {}, {}\"/></transform>\
             <film type=\"hdrfilm\"><integer name=\"width\" value=\"{width}\"/><integer name=\"height\" value=\"{height}\"/></film></sensor>\n{shapes}</scene>",
            origin.x, origin.y, origin.z, target.x, target.y, target.z, up.x, up.y, up.z
        );
        let scene = load_file(&dir.write("camera.xml", text)).unwrap();
        assert_eq!(scene.camera.mirrored, reflect);
        let mut to_world = mitsuba_look_at(origin, target, up);
        if reflect {
            to_world = to_world * DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0));
        }
        let aspect = width as f64 / height as f64;
        let tan_x = mitsuba_tan_half_x(fov, axis, focal, aspect);
        let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
        let hits = hmdist::render::primary_hits(&accel, &scene, width, height);
        for (i, m) in markers.iter().enumerate() {
            let (x, y) = mitsuba_raster(to_world, tan_x, width, height, *m);
            let case = format!("{width}x{height}, fov {fov:?} {axis}, focal {focal}, reflected {reflect}");
            assert!(
                x >= 0.0 && y >= 0.0 && x < width as f64 && y < height as f64,
                "marker {i} off the film: {case}"
            );
            let pixel = (y.floor() as u32 * width + x.floor() as u32) as usize;
            let hit = hits.points[pixel]
                .unwrap_or_else(|| panic!("marker {i} not at pixel ({x:.1}, {y:.1}): {case}"));
            assert_eq!(hit.triangle as usize / 2, i, "{case}");
        }
    }
}

/// A sphere (centre, radius, to_world), a disk and an open cylinder between two points: on
/// their surfaces, the sphere closed.
#[test]
fn quadrics_lie_on_their_surfaces() {
    let dir = Scratch::new("mitsuba-quadrics");
    let text = r#"<scene version="3.0.0">
        <shape type="sphere"><point name="center" x="1" y="2" z="3"/><float name="radius" value="1.5"/>
            <transform name="to_world"><scale value="2"/></transform></shape>
        <shape type="cylinder"><point name="p0" value="0 0 10"/><point name="p1" value="0 3 14"/><float name="radius" value="0.5"/></shape>
        <shape type="disk"><transform name="to_world"><scale value="2"/><translate z="-4"/></transform></shape>
    </scene>"#;
    let scene = load_file(&dir.write("q.xml", text)).unwrap();
    let count = |s: &str| scene.notes.sources.iter().find(|(n, _)| n == s).unwrap().1;
    let (spheres, cylinders, disks) = (count("sphere"), count("cylinder"), count("disk"));
    let mut edges = std::collections::HashMap::new();
    // Quadrics are tessellated in the order given.
    for t in 0..spheres + cylinders + disks {
        let [a, b, c] = scene.mesh.indices[t];
        if t < spheres {
            for (u, v) in [(a, b), (b, c), (c, a)] {
                *edges.entry((u.min(v), u.max(v))).or_insert(0) += 1;
            }
        }
        for p in scene.mesh.triangle(t) {
            let p = p.as_dvec3();
            if t < spheres {
                // to_world · translate(centre): the centre is at 2 × (1, 2, 3), the radius 3.
                assert!(
                    ((p - DVec3::new(2.0, 4.0, 6.0)).length() - 3.0).abs() < 1e-5,
                    "{p}"
                );
            } else if t < spheres + cylinders {
                let (p0, axis) = (DVec3::new(0.0, 0.0, 10.0), DVec3::new(0.0, 3.0, 4.0) / 5.0);
                let along = (p - p0).dot(axis);
                let off = (p - p0 - along * axis).length();
                assert!(
                    (off - 0.5).abs() < 1e-5 && (along.abs() < 1e-5 || (along - 5.0).abs() < 1e-5),
                    "{p}"
                );
            } else {
                assert!(
                    (p.z + 4.0).abs() < 1e-6 && p.truncate().length() <= 2.0 + 1e-6,
                    "{p}"
                );
            }
        }
    }
    let open: Vec<_> = edges.iter().filter(|(_, &n)| n != 2).collect();
    assert!(open.is_empty(), "the sphere is not closed: {open:?} of {spheres}");
}

#[test]
fn bad_files_name_the_file_line_and_element() {
    let dir = Scratch::new("mitsuba-bad");
    let scene = |body: &str| format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n");
    let cases: Vec<(String, &str)> = vec![
        ("<scene version=\"3.0.0\">\n<shape type=\"cube\">\n</scene>".into(), "bad.xml:3: not well-formed XML"),
        ("<scene>\n</scene>".into(), "bad.xml:1: <scene> has no version"),
        ("<shape type=\"cube\"/>".into(), "bad.xml:1: the root element is <shape>, not <scene>"),
        (scene("<frobnicate/>"), "bad.xml:2: <frobnicate> is not a Mitsuba 3 scene element"),
        (scene("<shape type=\"obj\">\n<string name=\"filename\" value=\"$where.obj\"/></shape>"), "bad.xml:3: $where is not defined"),
        (scene("<include filename=\"nowhere/x.xml\"/>"), "bad.xml:2: <include> \"nowhere/x.xml\" not found (looked for "),
        (scene("<shape type=\"ply\">\n<string name=\"filename\" value=\"gone.ply\"/></shape>"), "bad.xml:3: <shape type=\"ply\"> \"gone.ply\" not found (looked for "),
        (scene("<shape type=\"obj\"/>"), "bad.xml:2: <shape type=\"obj\">: no <string name=\"filename\">"),
        (scene("<shape type=\"cube\"><transform name=\"to_world\">\n<rotate angle=\"30\"/></transform></shape>"), "bad.xml:3: <rotate>: the rotation axis is zero"),
        (scene("<shape type=\"cube\"><transform name=\"to_world\">\n<matrix value=\"1 2 3\"/></transform></shape>"), "bad.xml:3: <matrix>: a matrix is 16 or 9 numbers"),
        (scene("<shape type=\"sphere\">\n<float name=\"radius\" value=\"big\"/></shape>"), "bad.xml:3: <float name=\"radius\">: \"big\" is not a finite number"),
        (scene("<shape type=\"sphere\"><float name=\"radius\" value=\"-1\"/></shape>"), "bad.xml:2: <shape type=\"sphere\">: the sphere is empty: its radius must be positive, not -1"),
        (scene("<sensor type=\"perspective\">\n<float name=\"fov\" value=\"30\"/><string name=\"fov_axis\" value=\"up\"/></sensor>"), "bad.xml:3: <sensor type=\"perspective\">: fov_axis \"up\""),
        (scene("<shape type=\"instance\"><ref id=\"nothing\"/></shape>"), "bad.xml:2: <shape type=\"instance\">: no shape group \"nothing\""),
        (scene("<shape type=\"serialized\"><string name=\"filename\" value=\"one.serialized\"/>\n<integer name=\"shape_index\" value=\"5\"/></shape>"), "one.serialized: shape_index 5 is out of range: the file holds 2 meshes (0 to 1)"),
    ];
    dir.write("one.serialized", serialized_file());
    for (text, expected) in cases {
        let message = load_file(&dir.write("bad.xml", text))
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(message.contains(expected), "{message}\n  expected: {expected}");
    }
    // A file that includes itself stops, saying so.
    dir.write("loop.xml", scene("<include filename=\"loop.xml\"/>"));
    let message = load_file(&dir.join("loop.xml"))
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(message.contains("nested more than 32 deep"), "{message}");
}

/// Mitsuba 0.6's camelCase names are read as Mitsuba 3 upgrades them.
#[test]
fn mitsuba_0_6_names_are_upgraded() {
    let dir = Scratch::new("mitsuba-old");
    dir.write("one.serialized", serialized_file());
    let old = r#"<scene version="0.5.0">
        <sensor type="perspective"><float name="fov" value="30"/><string name="fovAxis" value="y"/>
            <transform name="toWorld"><lookAt origin="0 0 -10" target="0 0 0" up="0 1 0"/></transform></sensor>
        <shape type="serialized"><string name="filename" value="one.serialized"/><integer name="shapeIndex" value="1"/>
            <transform name="toWorld"><translate x="3"/></transform></shape>
    </scene>"#;
    let scene = load_file(&dir.write("old.xml", old)).unwrap();
    assert!((scene.camera.fov_y_deg - 30.0).abs() < 1e-4);
    assert!((scene.mesh.positions[0] - Vec3::new(3.0, 0.0, 0.0)).length() < 1e-6);
    assert_eq!(scene.mesh.triangle_count(), 3);
}

/// The folder of mitsuba-data's shape scenes (unmodified; tests/data/mitsuba/mitsuba-data).
fn mitsuba_data(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/mitsuba/mitsuba-data/docs/scenes")
        .join(name)
}

/// The left edge of the sphere in Mitsuba's own picture of `shape_sphere_basic.xml`
/// (mitsuba-data's docs/images/render/shape_sphere_basic.jpg, 960 × 720): (row, first column
/// of the sphere), measured by scripts/mitsuba-silhouette.py as the first pixel of the run
/// through column 470 whose blue exceeds the mean of red and green by more than 22. The lit
/// left side stands out against the grey checkerboard; the dark right side does not, so only
/// the left edge is used.
const PUBLISHED_LEFT_EDGE: [(u32, u32); 30] = [
    (45, 432),
    (60, 383),
    (75, 353),
    (90, 330),
    (105, 311),
    (120, 296),
    (135, 283),
    (150, 271),
    (165, 261),
    (180, 253),
    (195, 246),
    (210, 240),
    (225, 235),
    (240, 231),
    (255, 228),
    (270, 226),
    (285, 225),
    (300, 225),
    (315, 225),
    (330, 227),
    (345, 229),
    (360, 232),
    (375, 236),
    (390, 242),
    (405, 248),
    (420, 255),
    (435, 264),
    (450, 274),
    (465, 282),
    (480, 293),
];

/// mitsuba-data's sphere scene: the serialized backdrop and the sphere, its 960 × 720 film,
/// and the sphere's silhouette where Mitsuba's published picture has it.
#[test]
fn the_mitsuba_sphere_scene_matches_its_published_picture() {
    let scene = load_file(&mitsuba_data("shape_sphere_basic.xml")).unwrap();
    let notes = &scene.notes;
    assert_eq!(notes.size, Some((960, 720)));
    let backdrop = notes
        .sources
        .iter()
        .find(|(s, _)| s == "serialized meshes/matpreview.serialized (mesh 0)")
        .unwrap()
        .1;
    assert_eq!(backdrop, 512);
    assert_eq!(notes.skipped_line().unwrap(), "1 × envmap emitter");
    let accel = Accel::build(&scene.mesh, BuildQuality::Fast);
    let (width, height) = (960, 720);
    let hits = hmdist::render::primary_hits(&accel, &scene, width, height);
    // The backdrop's triangles come first; the sphere's are tessellated after.
    let on_sphere = |x: u32, y: u32| {
        hits.points[(y * width + x) as usize].is_some_and(|h| h.triangle as usize >= backdrop)
    };
    // Rows 75 to 450, where the edge runs more down than across (near the top and bottom a
    // pixel up or down moves it many across).
    let rows: Vec<(u32, u32)> = PUBLISHED_LEFT_EDGE
        .into_iter()
        .filter(|(r, _)| (75..=450).contains(r))
        .collect();
    let offsets: Vec<i64> = rows
        .iter()
        .map(|&(row, published)| {
            (0..width).find(|&x| on_sphere(x, row)).unwrap_or(width) as i64 - published as i64
        })
        .collect();
    let worst = offsets.iter().map(|d| d.abs()).max().unwrap();
    let mean = offsets.iter().sum::<i64>() as f64 / offsets.len() as f64;
    // hmdist's edge may lie a little inside: its sphere is inscribed in the round one (its
    // chords up to 0.8 px inside here) and the JPEG's edge pixels are part sphere.
    assert!(
        worst <= 3 && (0.0..=2.5).contains(&mean),
        "left edge off by {offsets:?} px (mean {mean:.2})"
    );
    // Its top: row 41 of the published picture, at columns 461–501.
    let top = (0..height)
        .find(|&y| (461..=501).any(|x| on_sphere(x, y)))
        .unwrap();
    assert!((top as i64 - 41).abs() <= 2, "top at row {top}");
}

/// The other shape scenes of mitsuba-data load, each with its shape on the backdrop.
#[test]
fn the_mitsuba_shape_scenes_load() {
    for (file, shape) in [
        ("shape_rectangle.xml", "rectangle"),
        ("shape_disk.xml", "disk"),
        ("shape_cylinder_onesided.xml", "cylinder"),
    ] {
        let scene = load_file(&mitsuba_data(file)).unwrap();
        assert!(
            scene.notes.sources.iter().any(|(s, n)| s == shape && *n > 0),
            "{file}: {:?}",
            scene.notes
        );
        assert_eq!(scene.notes.size, Some((960, 720)));
    }
}
