//! Mitsuba 3 scene files (`.xml`): the whole scene, with its camera.
//!
//! Read as Mitsuba 3 reads them, for what H depends on:
//! - **The file**: a `<scene version="…">` root (a version below 2.0 is Mitsuba 0.6's, whose
//!   camelCase names, `toWorld`, `fovAxis`, `shapeIndex`, are read as Mitsuba 3 upgrades them);
//!   `<default name value>` and `$name` in any attribute (the first default of a name wins, an
//!   undefined name is an error, `\$` is a dollar sign); `<include filename>` (a file whose
//!   root is `<scene>` adds its children, any other root is one element); `<path value>`.
//! - **File names** (`<include>`, and the meshes of `obj`, `ply` and `serialized` shapes) are
//!   looked for in each `<path>` folder (the latest first), then the folder of the file that
//!   names them, then the scene file's folder. Mitsuba also tries the working directory;
//!   hmdist does not, so that a scene loads the same from anywhere.
//! - **Shapes**: `obj` and `ply` (hmdist's readers), `serialized` (Mitsuba's own zlib mesh
//!   format, its `shape_index`: [`serialized`]), `rectangle` (±1 in x and y), `cube` (±1),
//!   `sphere` (`center`, `radius`), `disk` (radius 1), `cylinder` (`p0`, `p1`, `radius`, open
//!   at both ends), the quadrics tessellated to [`super::assembly::CHORD_ERROR`] of the
//!   scene's diagonal; `shapegroup` and `instance` (flattened into the mesh: a remark says
//!   so) and `merge`. Each is placed by its `to_world`. Other shapes are skipped and counted.
//! - **Transforms**: `translate`, `rotate` (an axis by `x`/`y`/`z` or `value`, `angle` in
//!   degrees), `scale` (one number or three), `matrix` (16 or 9 numbers, row by row) and
//!   `lookat` (`origin`, `target`, `up`), each applied after those before it.
//! - **The camera**: the first `<sensor>`, `perspective` (or `thinlens`, as a pinhole), its
//!   `fov` along `fov_axis` (`x` by default, `y`, `diagonal`, `smaller`, `larger`) or its
//!   `focal_length` (`50mm` by default, a diagonal field of view on a 36 × 24 mm frame), placed
//!   by its `to_world`. Mitsuba's camera x points to the picture's left, so a `lookat` camera
//!   is hmdist's unmirrored one; a reflecting `to_world` gives a
//!   [`crate::scene::Camera::mirrored`] camera.
//! - **The film**: `<film>`'s `width` × `height` (Mitsuba's defaults 768 × 576) is the size
//!   of a render that names none.
//! - **The light**: the first `<emitter type="spot">` (`cutoff_angle`, 20° by default, along
//!   +z of its `to_world`); other emitters are counted as skipped.
//!
//! BSDFs, textures, media, the integrator, sampler and reconstruction filter are read and not
//! used (H sees geometry only). A malformed file, an unknown element, an undefined `$name`, a
//! bad value or a missing file is an error naming the file and line.

mod serialized;

pub(super) use serialized::read as serialized;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{DMat3, DMat4, DVec3, DVec4};
use roxmltree::Node;

use super::assembly::{camera_from_frame, Assembly, Piece, Quadric};
use super::common::{read_bytes, Failure, Located};
use crate::error::{Error, Result};
use crate::scene::{framing_camera, Camera, Scene, SpotLight};

/// Includes nested deeper than this are taken for a file that includes itself.
const MAX_INCLUDE_DEPTH: usize = 32;
/// Mitsuba's film size where `<film>` names none.
const DEFAULT_FILM: (u32, u32) = (768, 576);
/// Elements read and not used: they shape the picture's colour, not its geometry.
const NOT_GEOMETRY: [&str; 15] = [
    "bsdf",
    "texture",
    "integrator",
    "sampler",
    "film",
    "rfilter",
    "medium",
    "phase",
    "volume",
    "spectrum",
    "rgb",
    "float",
    "integer",
    "boolean",
    "string",
];

/// Loads the Mitsuba 3 scene at `path`, whose bytes are `bytes`.
pub(super) fn load(path: &Path, bytes: &[u8]) -> Result<Scene> {
    let mut reader = Reader::new(path, false);
    reader.file(path, bytes, 0)?;
    reader.finish(path)
}

/// Every file loading the Mitsuba scene at `path` reads: the file, its includes and its
/// shapes' meshes, as far as the files can be read.
pub(super) fn files_read(path: &Path) -> Vec<PathBuf> {
    let mut reader = Reader::new(path, true);
    if let Ok(bytes) = read_bytes(path) {
        let _ = reader.file(path, &bytes, 0);
    }
    let mut files = vec![path.to_path_buf()];
    for file in reader.files {
        if !files.contains(&file) {
            files.push(file);
        }
    }
    files
}

/// The file being read: its path, its document, and whether it is Mitsuba 0.6's.
struct Context<'a, 'input> {
    file: &'a Path,
    doc: &'a roxmltree::Document<'input>,
    old: bool,
}

impl Context<'_, '_> {
    fn line(&self, node: Node) -> usize {
        self.doc.text_pos_at(node.range().start).row as usize
    }

    /// The folder of the file, where the names it gives are looked for.
    fn folder(&self) -> &Path {
        self.file.parent().unwrap_or(Path::new(""))
    }
}

/// One property of an object (`<float name="radius" value="2"/>`), substitutions made; a
/// point or vector as "x y z".
struct Property {
    tag: String,
    value: String,
    line: usize,
}

/// An object's properties by name, and its transforms.
#[derive(Default)]
struct Properties {
    values: HashMap<String, Property>,
    transforms: HashMap<String, DMat4>,
    /// The object's line, for properties it lacks.
    line: usize,
}

impl Properties {
    fn line_of(&self, name: &str) -> usize {
        self.values.get(name).map_or(self.line, |p| p.line)
    }

    fn string(&self, name: &str) -> Option<&str> {
        self.values.get(name).map(|p| p.value.as_str())
    }

    fn number(&self, name: &str, default: f64) -> std::result::Result<f64, Located> {
        let Some(p) = self.values.get(name) else {
            return Ok(default);
        };
        number(&p.value).map_err(|m| (p.line, format!("<{} name=\"{name}\">: {m}", p.tag)))
    }

    fn point(&self, name: &str, default: DVec3) -> std::result::Result<DVec3, Located> {
        let Some(p) = self.values.get(name) else {
            return Ok(default);
        };
        vector(&p.value).map_err(|m| (p.line, format!("<{} name=\"{name}\">: {m}", p.tag)))
    }

    fn to_world(&self) -> DMat4 {
        self.transforms
            .get("to_world")
            .copied()
            .unwrap_or(DMat4::IDENTITY)
    }
}

/// A number as Mitsuba writes one.
fn number(text: &str) -> std::result::Result<f64, String> {
    let t = text.trim();
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("\"{t}\" is not a finite number")),
    }
}

/// Numbers separated by spaces or commas.
fn numbers(text: &str) -> std::result::Result<Vec<f64>, String> {
    text.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .map(number)
        .collect()
}

fn vector(text: &str) -> std::result::Result<DVec3, String> {
    match numbers(text)?[..] {
        [x, y, z] => Ok(DVec3::new(x, y, z)),
        ref v => Err(format!("expected 3 numbers, not {}", v.len())),
    }
}

/// Mitsuba 0.6's camelCase name in Mitsuba 3's spelling (`toWorld` → `to_world`).
fn snake_case(name: &str) -> String {
    let mut out = String::with_capacity(name.len() + 4);
    for c in name.chars() {
        if c.is_ascii_uppercase() {
            out.push('_');
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(c);
        }
    }
    out
}

/// A frame around unit `n` (Duff et al.'s, as Mitsuba's `coordinate_system`).
fn frame_around(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

struct Reader {
    /// The scene file's folder, where names are looked for last.
    main_folder: PathBuf,
    /// `<path>` folders, the latest first.
    paths: Vec<PathBuf>,
    /// `<default>` values by name.
    params: Vec<(String, String)>,
    assembly: Assembly,
    /// Shape groups by id, for instances.
    groups: HashMap<String, Vec<Piece>>,
    instances: usize,
    /// The first sensor's camera (`None` where it is not a pinhole) and film size.
    sensor: Option<(Option<Camera>, (u32, u32))>,
    light: Option<SpotLight>,
    /// Only list the files a load would read: no meshes are read.
    listing: bool,
    /// Every file read (or, when listing, that would be).
    files: Vec<PathBuf>,
}

impl Reader {
    fn new(path: &Path, listing: bool) -> Reader {
        Reader {
            main_folder: path.parent().unwrap_or(Path::new("")).to_path_buf(),
            paths: Vec::new(),
            params: Vec::new(),
            assembly: Assembly::default(),
            groups: HashMap::new(),
            instances: 0,
            sensor: None,
            light: None,
            listing,
            files: Vec::new(),
        }
    }

    /// Reads the scene file (or included file) `file`, whose bytes are `bytes`.
    fn file(&mut self, file: &Path, bytes: &[u8], depth: usize) -> Result<()> {
        let text = std::str::from_utf8(bytes).map_err(|e| {
            let line = super::common::line_of_offset(bytes, e.valid_up_to());
            Error::file_line(file, line, "not UTF-8 text: a Mitsuba scene is an XML file")
        })?;
        let options = roxmltree::ParsingOptions {
            allow_dtd: true,
            ..Default::default()
        };
        let doc = roxmltree::Document::parse_with_options(text, options)
            .map_err(|e| Error::file_line(file, e.pos().row as usize, format!("not well-formed XML: {e}")))?;
        let root = doc.root_element();
        let mut cx = Context {
            file,
            doc: &doc,
            old: false,
        };
        let at = |(line, message): Located| Error::file_line(file, line, message);
        let is_scene = root.tag_name().name() == "scene";
        if depth == 0 && !is_scene {
            let tag = root.tag_name().name();
            return Err(at((
                cx.line(root),
                format!("the root element is <{tag}>, not <scene>"),
            )));
        }
        if is_scene {
            let version = self.attribute(&cx, root, "version").map_err(at)?.ok_or_else(|| {
                at((
                    cx.line(root),
                    "<scene> has no version (Mitsuba requires one)".into(),
                ))
            })?;
            let major = version
                .split('.')
                .next()
                .and_then(|m| m.trim().parse::<u32>().ok());
            let Some(major) = major else {
                return Err(at((
                    cx.line(root),
                    format!("<scene version=\"{version}\">: not a version number"),
                )));
            };
            cx.old = major < 2;
        }
        let result = if is_scene {
            root.children()
                .filter(|n| n.is_element())
                .try_for_each(|node| self.element(&cx, node, depth))
        } else {
            self.element(&cx, root, depth)
        };
        result.map_err(|f| f.in_file(file))
    }

    /// The attribute `name` of `node`, `$name`s replaced by their defaults.
    fn attribute(
        &self,
        cx: &Context,
        node: Node,
        name: &str,
    ) -> std::result::Result<Option<String>, Located> {
        let Some(value) = node.attribute(name) else {
            return Ok(None);
        };
        self.substitute(value).map(Some).map_err(|m| (cx.line(node), m))
    }

    /// A required attribute.
    fn required(&self, cx: &Context, node: Node, name: &str) -> std::result::Result<String, Located> {
        let tag = node.tag_name().name();
        self.attribute(cx, node, name)?
            .ok_or_else(|| (cx.line(node), format!("<{tag}> has no \"{name}\" attribute")))
    }

    /// `value` with each `$name` replaced by its default (the longest name first, as Mitsuba
    /// does), `\$` kept as a dollar sign.
    fn substitute(&self, value: &str) -> std::result::Result<String, String> {
        if !value.contains('$') {
            return Ok(value.to_string());
        }
        let mut params: Vec<&(String, String)> = self.params.iter().collect();
        params.sort_by_key(|(name, _)| std::cmp::Reverse(name.len()));
        let mut out = String::new();
        let mut rest = value;
        while let Some(i) = rest.find('$') {
            let escaped = rest[..i].ends_with('\\');
            out.push_str(&rest[..if escaped { i - 1 } else { i }]);
            rest = &rest[i + 1..];
            if escaped {
                out.push('$');
                continue;
            }
            match params.iter().find(|(name, _)| rest.starts_with(name.as_str())) {
                Some((name, v)) => {
                    out.push_str(v);
                    rest = &rest[name.len()..];
                }
                None => {
                    let name: String = rest
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    return Err(format!("${name} is not defined (no <default name=\"{name}\">)"));
                }
            }
        }
        out.push_str(rest);
        Ok(out)
    }

    /// Where the name `written` (given in `cx`'s file) is found: each `<path>` folder, the
    /// file's folder, the scene's folder; or the error naming where it was looked for.
    fn resolve(&self, cx: &Context, written: &str, what: &str) -> std::result::Result<PathBuf, String> {
        let mut places: Vec<PathBuf> = self.paths.clone();
        places.push(cx.folder().to_path_buf());
        places.push(self.main_folder.clone());
        places.dedup();
        let candidates: Vec<PathBuf> = places.iter().map(|p| p.join(written)).collect();
        if let Some(found) = candidates.iter().find(|c| c.is_file()) {
            return Ok(found.clone());
        }
        let looked: Vec<String> = candidates.iter().map(|c| c.display().to_string()).collect();
        Err(format!(
            "{what} \"{written}\" not found (looked for {})",
            looked.join(", ")
        ))
    }

    /// A child of `<scene>`.
    fn element(&mut self, cx: &Context, node: Node, depth: usize) -> std::result::Result<(), Failure> {
        let line = cx.line(node);
        match node.tag_name().name() {
            "default" => {
                let name = self.required(cx, node, "name")?;
                let value = self.required(cx, node, "value")?;
                if name.is_empty() {
                    return Err((line, "<default> has an empty name".into()).into());
                }
                if !self.params.iter().any(|(n, _)| *n == name) {
                    self.params.push((name, value));
                }
            }
            "path" => {
                let value = self.required(cx, node, "value")?;
                let folder = cx.folder().join(&value);
                if !folder.is_dir() {
                    let shown = folder.display();
                    return Err((line, format!("<path value=\"{value}\">: no folder {shown}")).into());
                }
                self.paths.insert(0, folder);
            }
            "include" => {
                let written = self.required(cx, node, "filename")?;
                let resolved = self.resolve(cx, &written, "<include>").map_err(|m| (line, m))?;
                if depth + 1 >= MAX_INCLUDE_DEPTH {
                    let message = format!(
                        "<include> nested more than {MAX_INCLUDE_DEPTH} deep: does a file include itself?"
                    );
                    return Err((line, message).into());
                }
                self.files.push(resolved.clone());
                let bytes = read_bytes(&resolved).map_err(Failure::Error)?;
                let paths = self.paths.clone();
                self.file(&resolved, &bytes, depth + 1).map_err(Failure::Error)?;
                self.paths = paths;
            }
            "shape" => {
                for piece in self.shape(cx, node)? {
                    self.assembly
                        .add(&piece, &DMat4::IDENTITY)
                        .map_err(Failure::Error)?;
                }
            }
            "sensor" => self.sensor(cx, node)?,
            "emitter" => self.emitter(cx, node)?,
            "ref" => {}
            tag if NOT_GEOMETRY.contains(&tag) => {}
            tag => return Err((line, format!("<{tag}> is not a Mitsuba 3 scene element")).into()),
        }
        Ok(())
    }

    /// An object's properties, and its child objects (shapes, emitters, a film, ...).
    fn properties<'a, 'input>(
        &self,
        cx: &Context,
        node: Node<'a, 'input>,
    ) -> std::result::Result<(Properties, Vec<Node<'a, 'input>>), Located> {
        let mut props = Properties {
            line: cx.line(node),
            ..Properties::default()
        };
        let mut objects = Vec::new();
        for child in node.children().filter(|n| n.is_element()) {
            let tag = child.tag_name().name();
            let line = cx.line(child);
            let name = || -> std::result::Result<String, Located> {
                let name = self.required(cx, child, "name")?;
                Ok(if cx.old { snake_case(&name) } else { name })
            };
            let value = match tag {
                "float" | "integer" | "string" | "boolean" | "rgb" => {
                    self.attribute(cx, child, "value")?.unwrap_or_default()
                }
                "spectrum" => String::new(),
                "point" | "vector" => self
                    .xyz(cx, child, 0.0)?
                    .map(|v| format!("{} {} {}", v.x, v.y, v.z))
                    .unwrap_or_default(),
                "transform" => {
                    let matrix = self.transform(cx, child)?;
                    props.transforms.insert(name()?, matrix);
                    continue;
                }
                _ => {
                    objects.push(child);
                    continue;
                }
            };
            let property = Property {
                tag: tag.to_string(),
                value,
                line,
            };
            props.values.insert(name()?, property);
        }
        Ok((props, objects))
    }

    /// A `value="x y z"` (or one number for all three) or `x`/`y`/`z` attributes (each
    /// `default` where missing); `None` where the element has none of them.
    fn xyz(&self, cx: &Context, node: Node, default: f64) -> std::result::Result<Option<DVec3>, Located> {
        let line = cx.line(node);
        let tag = node.tag_name().name();
        let bad = |m: String| (line, format!("<{tag}>: {m}"));
        if let Some(value) = self.attribute(cx, node, "value")? {
            if ["x", "y", "z"].iter().any(|a| node.attribute(*a).is_some()) {
                return Err(bad("\"value\" and \"x\"/\"y\"/\"z\" cannot be mixed".into()));
            }
            return match numbers(&value).map_err(bad)?[..] {
                [v] => Ok(Some(DVec3::splat(v))),
                [x, y, z] => Ok(Some(DVec3::new(x, y, z))),
                ref v => Err(bad(format!("\"value\" must be 1 or 3 numbers, not {}", v.len()))),
            };
        }
        let mut v = [default; 3];
        let mut any = false;
        for (i, axis) in ["x", "y", "z"].iter().enumerate() {
            if let Some(text) = self.attribute(cx, node, axis)? {
                v[i] = number(&text).map_err(|m| bad(format!("{axis}: {m}")))?;
                any = true;
            }
        }
        Ok(any.then(|| DVec3::from_array(v)))
    }

    /// A `<transform>`: its operations, each applied after those before it.
    fn transform(&self, cx: &Context, node: Node) -> std::result::Result<DMat4, Located> {
        let mut m = DMat4::IDENTITY;
        for op in node.children().filter(|n| n.is_element()) {
            let line = cx.line(op);
            let tag = op.tag_name().name();
            let bad = |m: String| (line, format!("<{tag}>: {m}"));
            let step = match tag {
                "translate" => DMat4::from_translation(self.xyz(cx, op, 0.0)?.unwrap_or(DVec3::ZERO)),
                "scale" => DMat4::from_scale(self.xyz(cx, op, 1.0)?.unwrap_or(DVec3::ONE)),
                "rotate" => {
                    let axis = self.xyz(cx, op, 0.0)?.unwrap_or(DVec3::ZERO);
                    let angle = number(&self.required(cx, op, "angle")?).map_err(bad)?;
                    let axis = axis
                        .try_normalize()
                        .ok_or_else(|| bad("the rotation axis is zero".into()))?;
                    DMat4::from_axis_angle(axis, angle.to_radians())
                }
                "matrix" => {
                    let v = numbers(&self.required(cx, op, "value")?).map_err(bad)?;
                    match v.len() {
                        16 => DMat4::from_cols_array(&v.try_into().unwrap()).transpose(),
                        9 => DMat4::from_mat3(DMat3::from_cols_array(&v.try_into().unwrap()).transpose()),
                        n => return Err(bad(format!("a matrix is 16 or 9 numbers (row by row), not {n}"))),
                    }
                }
                "lookat" | "lookAt" => {
                    let origin =
                        vector(&self.required(cx, op, "origin")?).map_err(|m| bad(format!("origin: {m}")))?;
                    let target =
                        vector(&self.required(cx, op, "target")?).map_err(|m| bad(format!("target: {m}")))?;
                    let up = match self.attribute(cx, op, "up")? {
                        Some(up) => vector(&up).map_err(|m| bad(format!("up: {m}")))?,
                        None => DVec3::ZERO,
                    };
                    look_at(origin, target, up).ok_or_else(|| {
                        bad("origin and target are the same point, or up is along the view".into())
                    })?
                }
                _ => return Err((line, format!("<{tag}> is not a transform operation"))),
            };
            m = step * m;
        }
        if !m.is_finite() {
            return Err((cx.line(node), "the transform is not finite".into()));
        }
        Ok(m)
    }

    /// A `<shape>`: its placed pieces (none where it is skipped or a shape group).
    fn shape(&mut self, cx: &Context, node: Node) -> std::result::Result<Vec<Piece>, Failure> {
        let line = cx.line(node);
        let kind = self.required(cx, node, "type")?;
        let (props, objects) = self.properties(cx, node)?;
        let to_world = props.to_world();
        let here = |m: String| Failure::Here((line, format!("<shape type=\"{kind}\">: {m}")));
        for object in &objects {
            if object.tag_name().name() == "emitter" {
                self.assembly
                    .notes
                    .skip("area emitter (emission; its shapes are geometry)");
            }
        }
        let children = |reader: &mut Reader| -> std::result::Result<Vec<Piece>, Failure> {
            let mut pieces = Vec::new();
            for object in objects.iter().filter(|o| o.tag_name().name() == "shape") {
                pieces.extend(reader.shape(cx, *object)?);
            }
            Ok(pieces)
        };
        let quadric =
            |source: &str, quadric: Quadric, to_world: DMat4| -> std::result::Result<Vec<Piece>, Failure> {
                quadric.check().map_err(here)?;
                Ok(vec![Piece::Quadric {
                    source: source.to_string(),
                    quadric,
                    to_world,
                }])
            };
        let triangles = |source: String, positions: Vec<DVec3>, indices: Vec<[u32; 3]>| {
            vec![Piece::Triangles {
                source,
                positions,
                indices,
                to_world,
            }]
        };
        let full = std::f64::consts::TAU;
        Ok(match kind.as_str() {
            "obj" | "ply" | "serialized" => {
                let written = props
                    .string("filename")
                    .ok_or_else(|| here("no <string name=\"filename\">".into()))?;
                let fline = props.line_of("filename");
                let resolved = self
                    .resolve(cx, written, &format!("<shape type=\"{kind}\">"))
                    .map_err(|m| Failure::Here((fline, m)))?;
                self.files.push(resolved.clone());
                if self.listing {
                    return Ok(Vec::new());
                }
                let bytes = read_bytes(&resolved).map_err(Failure::Error)?;
                match kind.as_str() {
                    "serialized" => {
                        let index = props.number("shape_index", 0.0)?;
                        if !(index >= 0.0 && index.fract() == 0.0 && index <= u32::MAX as f64) {
                            let iline = props.line_of("shape_index");
                            return Err(Failure::Here((
                                iline,
                                format!("shape_index must be a whole number ≥ 0, not {index}"),
                            )));
                        }
                        let index = index as usize;
                        let (positions, indices) = serialized::read(&bytes, index)
                            .map_err(|m| Failure::Error(Error::file(&resolved, m)))?;
                        triangles(format!("serialized {written} (mesh {index})"), positions, indices)
                    }
                    _ => {
                        let file = if kind == "obj" {
                            super::obj::load(&resolved, &bytes)
                        } else {
                            super::ply::load(&resolved, &bytes)
                        };
                        let mesh = file.map_err(Failure::Error)?.mesh;
                        let positions = mesh.positions.iter().map(|p| p.as_dvec3()).collect();
                        triangles(format!("{kind} {written}"), positions, mesh.indices)
                    }
                }
            }
            "rectangle" => {
                let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
                let positions = corners.iter().map(|&(x, y)| DVec3::new(x, y, 0.0)).collect();
                triangles(kind.clone(), positions, vec![[0, 1, 2], [0, 2, 3]])
            }
            "cube" => {
                let positions = (0..8)
                    .map(|i| {
                        DVec3::new(
                            [-1.0, 1.0][i & 1],
                            [-1.0, 1.0][i >> 1 & 1],
                            [-1.0, 1.0][i >> 2 & 1],
                        )
                    })
                    .collect();
                // Two triangles a face, corners by bits (x, y, z).
                let faces = [
                    [0, 2, 3, 1],
                    [4, 5, 7, 6],
                    [0, 1, 5, 4],
                    [2, 6, 7, 3],
                    [0, 4, 6, 2],
                    [1, 3, 7, 5],
                ];
                let indices = faces
                    .iter()
                    .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
                    .collect();
                triangles(kind.clone(), positions, indices)
            }
            "sphere" => {
                let radius = props.number("radius", 1.0)?;
                let center = props.point("center", DVec3::ZERO)?;
                let sphere = Quadric::Sphere {
                    radius,
                    z_min: -radius,
                    z_max: radius,
                    phi_max: full,
                };
                quadric("sphere", sphere, to_world * DMat4::from_translation(center))?
            }
            "disk" => {
                let disk = Quadric::Disk {
                    height: 0.0,
                    radius: 1.0,
                    inner: 0.0,
                    phi_max: full,
                };
                quadric("disk", disk, to_world)?
            }
            "cylinder" => {
                let radius = props.number("radius", 1.0)?;
                let p0 = props.point("p0", DVec3::ZERO)?;
                let p1 = props.point("p1", DVec3::Z)?;
                let length = (p1 - p0).length();
                let axis = (p1 - p0)
                    .try_normalize()
                    .ok_or_else(|| here("p0 and p1 are the same point".into()))?;
                let (s, t) = frame_around(axis);
                let frame = DMat4::from_cols(s.extend(0.0), t.extend(0.0), axis.extend(0.0), p0.extend(1.0));
                let cylinder = Quadric::Cylinder {
                    radius,
                    z_min: 0.0,
                    z_max: length,
                    phi_max: full,
                };
                quadric("cylinder", cylinder, to_world * frame)?
            }
            "shapegroup" => {
                let id = self
                    .attribute(cx, node, "id")?
                    .ok_or_else(|| here("a shape group needs an id for instances to name".into()))?;
                let pieces = children(self)?;
                self.groups.insert(id, pieces);
                Vec::new()
            }
            "instance" => {
                let reference = objects
                    .iter()
                    .find(|o| o.tag_name().name() == "ref")
                    .ok_or_else(|| here("no <ref id=\"…\"> to a shape group".into()))?;
                let id = self.required(cx, *reference, "id")?;
                let group = self
                    .groups
                    .get(&id)
                    .ok_or_else(|| here(format!("no shape group \"{id}\" is defined before it")))?;
                self.instances += 1;
                group.iter().map(|piece| piece.placed(&to_world)).collect()
            }
            "merge" => children(self)?,
            _ => {
                self.assembly.notes.skip(&format!("{kind} shape"));
                Vec::new()
            }
        })
    }

    /// A `<sensor>`: the first is the camera, with its film.
    fn sensor(&mut self, cx: &Context, node: Node) -> std::result::Result<(), Failure> {
        if self.sensor.is_some() {
            self.assembly.notes.skip("sensor (only the first is used)");
            return Ok(());
        }
        let line = cx.line(node);
        let kind = self.required(cx, node, "type")?;
        let (props, objects) = self.properties(cx, node)?;
        let mut film = DEFAULT_FILM;
        if let Some(f) = objects.iter().find(|o| o.tag_name().name() == "film") {
            let (fp, _) = self.properties(cx, *f)?;
            let size = |name: &str, default: u32| -> std::result::Result<u32, Located> {
                let v = fp.number(name, default as f64)?;
                if !((1.0..=1e6).contains(&v) && v.fract() == 0.0) {
                    return Err((
                        fp.line_of(name),
                        format!("<film>: {name} must be a whole number from 1 to 10^6, not {v}"),
                    ));
                }
                Ok(v as u32)
            };
            film = (size("width", DEFAULT_FILM.0)?, size("height", DEFAULT_FILM.1)?);
            if ["crop_width", "crop_height", "crop_offset_x", "crop_offset_y"]
                .iter()
                .any(|k| fp.values.contains_key(*k))
            {
                self.assembly
                    .notes
                    .remark("the film's crop window is not applied: the whole picture is rendered");
            }
        }
        let camera = match kind.as_str() {
            "perspective" | "thinlens" => {
                if kind == "thinlens" {
                    self.assembly
                        .notes
                        .remark("depth of field (thinlens) is not applied: the camera is a pinhole");
                }
                let camera = perspective(&props, film)
                    .map_err(|(l, m)| (l, format!("<sensor type=\"{kind}\">: {m}")))?;
                camera.validate().map_err(|e| {
                    (
                        line,
                        format!("<sensor>: {}", e.to_string().replacen("bad scene: ", "", 1)),
                    )
                })?;
                Some(camera)
            }
            _ => {
                self.assembly.notes.remark(format!(
                    "a \"{kind}\" sensor is not a pinhole camera: a camera framing the scene is used"
                ));
                None
            }
        };
        self.sensor = Some((camera, film));
        Ok(())
    }

    /// An `<emitter>`: the first spot is the light.
    fn emitter(&mut self, cx: &Context, node: Node) -> std::result::Result<(), Failure> {
        let kind = self.required(cx, node, "type")?;
        if kind != "spot" {
            self.assembly.notes.skip(&format!("{kind} emitter"));
            return Ok(());
        }
        if self.light.is_some() {
            self.assembly.notes.skip("spot emitter (only the first is used)");
            return Ok(());
        }
        let (props, _) = self.properties(cx, node)?;
        let angle = props.number("cutoff_angle", 20.0)?;
        if !(angle > 0.0 && angle <= 180.0) {
            let line = props.line_of("cutoff_angle");
            return Err(Failure::Here((
                line,
                format!("<emitter type=\"spot\">: cutoff_angle must be in (0, 180], not {angle}"),
            )));
        }
        let m = props.to_world();
        let direction = m.transform_vector3(DVec3::Z).try_normalize().ok_or_else(|| {
            (
                props.line,
                "<emitter type=\"spot\">: its to_world collapses its axis".to_string(),
            )
        })?;
        self.light = Some(SpotLight {
            position: m.transform_point3(DVec3::ZERO).as_vec3(),
            direction: direction.as_vec3(),
            cone_half_angle_deg: angle as f32,
        });
        Ok(())
    }

    /// The scene: the mesh, the camera, the light, the notes.
    fn finish(self, path: &Path) -> Result<Scene> {
        let Reader {
            mut assembly,
            sensor,
            light,
            instances,
            ..
        } = self;
        if instances > 0 {
            let s = if instances == 1 { "" } else { "s" };
            assembly
                .notes
                .remark(format!("{instances} shape instance{s} flattened into the mesh"));
        }
        let bounds = assembly.bounds();
        let (camera, size) = match sensor {
            Some((Some(camera), size)) => (camera, Some(size)),
            Some((None, size)) => (framing_camera(bounds), Some(size)),
            None => {
                assembly
                    .notes
                    .remark("no <sensor>: a camera framing the scene is used");
                (framing_camera(bounds), None)
            }
        };
        assembly.into_scene(path, camera, light, size)
    }
}

/// Mitsuba's `lookat`: world from local, local x = up × dir (the picture's left for a
/// camera), y the new up, z the view direction. A zero `up` is chosen around the view.
fn look_at(origin: DVec3, target: DVec3, up: DVec3) -> Option<DMat4> {
    let dir = (target - origin).try_normalize()?;
    let up = if up == DVec3::ZERO {
        frame_around(dir).0
    } else {
        up
    };
    let left = up.cross(dir).try_normalize()?;
    let new_up = dir.cross(left);
    Some(DMat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    ))
}

/// A perspective sensor as hmdist's camera, for a film (width, height) in pixels: Mitsuba's
/// field of view rules (`parse_fov`), its frame from `to_world`.
fn perspective(props: &Properties, film: (u32, u32)) -> std::result::Result<Camera, Located> {
    let aspect = film.0 as f64 / film.1 as f64;
    let half_tan = |degrees: f64| (0.5 * degrees.to_radians()).tan();
    if props.values.contains_key("fov") && props.values.contains_key("focal_length") {
        return Err((props.line_of("fov"), "give fov or focal_length, not both".into()));
    }
    // tan(fov_x / 2), by the axis the fov is given along.
    let tan_x = if props.values.contains_key("fov") {
        let fov = props.number("fov", 0.0)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err((
                props.line_of("fov"),
                format!("fov must be in (0, 180), not {fov}"),
            ));
        }
        let axis = props.string("fov_axis").unwrap_or("x").to_ascii_lowercase();
        let axis = match axis.as_str() {
            "smaller" if aspect > 1.0 => "y",
            "smaller" => "x",
            "larger" if aspect > 1.0 => "x",
            "larger" => "y",
            other => other,
        };
        match axis {
            "x" => half_tan(fov),
            "y" => half_tan(fov) * aspect,
            "diagonal" => half_tan(fov) * aspect / (aspect * aspect + 1.0).sqrt(),
            _ => {
                let line = props.line_of("fov_axis");
                return Err((
                    line,
                    format!("fov_axis \"{axis}\": expected x, y, diagonal, smaller or larger"),
                ));
            }
        }
    } else {
        let written = props.string("focal_length").unwrap_or("50mm");
        let f = written.trim().strip_suffix("mm").unwrap_or(written.trim());
        let f = match f.parse::<f64>() {
            Ok(f) if f > 0.0 && f.is_finite() => f,
            _ => {
                let line = props.line_of("focal_length");
                return Err((
                    line,
                    format!("focal_length \"{written}\": expected a length in mm, as \"50mm\""),
                ));
            }
        };
        // A diagonal field of view on a 36 × 24 mm frame.
        let tan_diagonal = (36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * f);
        tan_diagonal * aspect / (aspect * aspect + 1.0).sqrt()
    };
    for offset in ["principal_point_offset_x", "principal_point_offset_y"] {
        if props.number(offset, 0.0)? != 0.0 {
            return Err((
                props.line_of(offset),
                format!("{offset} moves the view off its axis: hmdist's pinhole camera cannot take it"),
            ));
        }
    }
    let fov_y = 2.0 * (tan_x / aspect).atan().to_degrees();
    let m = props.to_world();
    let columns = [m.x_axis, m.y_axis, m.z_axis].map(|c: DVec4| c.truncate());
    let unit = columns.iter().all(|c| (c.length() - 1.0).abs() < 1e-4);
    let orthogonal = (columns[0].dot(columns[1]).abs()
        + columns[1].dot(columns[2]).abs()
        + columns[0].dot(columns[2]).abs())
        < 1e-4;
    if !(unit && orthogonal) {
        let line = props.line;
        return Err((
            line,
            "its to_world scales or shears (Mitsuba refuses that too)".into(),
        ));
    }
    let eye = m.transform_point3(DVec3::ZERO);
    Ok(camera_from_frame(eye, -columns[0], columns[1], columns[2], fov_y))
}
