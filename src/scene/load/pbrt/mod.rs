//! pbrt-v4 scene files (`.pbrt`, and gzipped `.pbrt.gz`): the whole scene, with its camera.
//!
//! Read as pbrt-v4 reads them, for what H depends on:
//! - **The transform stack**: `Identity`, `Translate`, `Scale`, `Rotate`, `LookAt`, `Transform`,
//!   `ConcatTransform`, `CoordinateSystem`, `CoordSysTransform` (with the `camera` and `world`
//!   systems pbrt names itself), `AttributeBegin`/`End` and `TransformBegin`/`End`;
//!   `WorldBegin` resets it. Under `ActiveTransform EndTime` a transform changes only the end
//!   of a motion, so the start (what is read) stays as it was.
//! - **Files**: `Include` and `Import` (as Include), and `plymesh` filenames, relative to the
//!   directory of the file that was loaded (as pbrt resolves them: not of the including
//!   file); any of them gzipped (`.gz`).
//! - **Shapes**: `trianglemesh`, `plymesh` (hmdist's PLY reader; quads split in two),
//!   `bilinearmesh` (two triangles a patch), `loopsubdiv` (Loop subdivision to its `levels`,
//!   pushed to the limit surface, as pbrt does: [`subdiv`]), `sphere`, `disk`, `cylinder`
//!   (tessellated to [`super::assembly::CHORD_ERROR`] of the scene's diagonal, their `zmin`,
//!   `zmax`, `phimax`, `innerradius` honoured). Every other shape is skipped and counted.
//! - **Instances**: `ObjectBegin`/`End` and `ObjectInstance`, flattened into the mesh (the
//!   triangles are copied once per instance; a remark says so).
//! - **The camera**: `perspective`, its field of view `fov` across the picture's shorter
//!   side (pbrt's rule), a centred `screenwindow`, `frameaspectratio`, placed by the transform
//!   at `Camera` time. pbrt's camera space is left-handed, so an unreflected pbrt camera is a
//!   [`crate::scene::Camera::mirrored`] one: the picture is pbrt's, left for left.
//! - **The film**: `xresolution` × `yresolution` (pbrt's defaults 1280 × 720) is the size of a
//!   render that names none.
//! - **The light**: the first `LightSource "spot"` (`from`, `to`, `coneangle`) as hmdist's
//!   spot light; other lights are counted as skipped.
//!
//! Materials, textures, media, the integrator, sampler, filter and colour space are read and
//! not used (H sees geometry only). An unknown directive, a malformed value, a missing file
//! or a shape without its points is an error naming the file and line.

mod subdiv;
mod tokens;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{DMat4, DVec3};

use super::assembly::{camera_from_frame, Assembly, Piece, Quadric};
use super::common::{read_bytes, Failure};
use crate::error::{Error, Result};
use crate::scene::{framing_camera, Scene, SpotLight};
use tokens::{Located, Params, Token, Tokens};

/// Includes nested deeper than this are taken for a file that includes itself.
const MAX_INCLUDE_DEPTH: usize = 32;
/// pbrt's film size where `Film` names none.
const DEFAULT_FILM: (u32, u32) = (1280, 720);
/// The most triangles loop subdivision may make (4^levels times the mesh's).
const MAX_SUBDIVIDED: u64 = 1 << 28;

/// Loads the pbrt-v4 scene at `path`, whose bytes (gzipped where the name ends `.gz`) are
/// `bytes`.
pub(super) fn load(path: &Path, bytes: &[u8]) -> Result<Scene> {
    let text = super::common::gunzip_if_named(path, bytes)?;
    let mut reader = Reader {
        directory: path.parent().unwrap_or(Path::new("")).to_path_buf(),
        ..Reader::default()
    };
    reader.read(path, &text, 0)?;
    reader.finish(path)
}

/// Every file loading the pbrt scene at `path` reads: the file, its includes and the files
/// its parameters name (`"string filename"`), as far as they can be read.
pub(super) fn files_read(path: &Path) -> Vec<PathBuf> {
    let mut files = vec![path.to_path_buf()];
    let directory = path.parent().unwrap_or(Path::new(""));
    scan_files(directory, path, &mut files, 0);
    files
}

fn scan_files(directory: &Path, path: &Path, files: &mut Vec<PathBuf>, depth: usize) {
    let Ok(bytes) = read_bytes(path) else { return };
    let Ok(text) = super::common::gunzip_if_named(path, &bytes) else {
        return;
    };
    let mut tokens = Tokens::new(&text);
    while let Ok(Some((token, _))) = tokens.next() {
        let include = matches!(&token, Token::Word(w) if w == "Include" || w == "Import");
        let named = matches!(&token, Token::Str(s) if s.split_whitespace().eq(["string", "filename"]));
        if !(include || named) {
            continue;
        }
        if named && tokens.peek() == Ok(Some(&Token::Open)) {
            let _ = tokens.next();
        }
        if let Ok(Some((Token::Str(name), _))) = tokens.next() {
            let resolved = directory.join(&name);
            if !files.contains(&resolved) {
                files.push(resolved.clone());
                if include && depth < MAX_INCLUDE_DEPTH {
                    scan_files(directory, &resolved, files, depth + 1);
                }
            }
        }
    }
}

/// Which end of a motion the transform directives change (`ActiveTransform`).
#[derive(Clone, Copy, Default, PartialEq)]
enum Active {
    #[default]
    All,
    Start,
    End,
}

/// The camera as the file declared it, resolved once the film is known.
struct CameraDeclared {
    kind: String,
    params: Params,
    camera_from_world: DMat4,
    file: PathBuf,
    line: usize,
}

#[derive(Default)]
struct Reader {
    /// Where relative file names are resolved: the loaded file's directory.
    directory: PathBuf,
    assembly: Assembly,
    ctm: DMat4,
    active: Active,
    /// AttributeBegin / TransformBegin: the transform and active ends to restore.
    stack: Vec<(DMat4, Active)>,
    named: HashMap<String, DMat4>,
    objects: HashMap<String, Vec<Piece>>,
    /// The object being defined and its pieces.
    defining: Option<(String, Vec<Piece>)>,
    instances: usize,
    camera: Option<CameraDeclared>,
    film: Option<(Params, PathBuf)>,
    light: Option<SpotLight>,
}

impl Reader {
    /// Reads the directives of `text`, the contents of `file`.
    fn read(&mut self, file: &Path, text: &[u8], depth: usize) -> Result<()> {
        let mut tokens = Tokens::new(text);
        let at = |(line, message): Located| Error::file_line(file, line, message);
        while let Some((token, line)) = tokens.next().map_err(at)? {
            let Token::Word(directive) = token else {
                return Err(Error::file_line(
                    file,
                    line,
                    format!("expected a directive, found {}", token.shown()),
                ));
            };
            self.directive(&directive, line, &mut tokens, file, depth)
                .map_err(|e| e.in_file(file))?;
        }
        Ok(())
    }

    fn directive(
        &mut self,
        name: &str,
        line: usize,
        tokens: &mut Tokens,
        file: &Path,
        depth: usize,
    ) -> std::result::Result<(), Failure> {
        let here = |message: String| Failure::Here((line, message));
        match name {
            "AttributeBegin" | "TransformBegin" => self.stack.push((self.ctm, self.active)),
            "AttributeEnd" | "TransformEnd" => {
                let (ctm, active) = self
                    .stack
                    .pop()
                    .ok_or_else(|| here(format!("{name} without a matching begin")))?;
                self.ctm = ctm;
                self.active = active;
            }
            "Identity" => self.transform(|_| DMat4::IDENTITY),
            "Translate" => {
                let v = tokens.numbers(name, 3)?;
                self.transform(|m| m * DMat4::from_translation(DVec3::new(v[0], v[1], v[2])));
            }
            "Scale" => {
                let v = tokens.numbers(name, 3)?;
                self.transform(|m| m * DMat4::from_scale(DVec3::new(v[0], v[1], v[2])));
            }
            "Rotate" => {
                let v = tokens.numbers(name, 4)?;
                let axis = DVec3::new(v[1], v[2], v[3]);
                let axis = axis
                    .try_normalize()
                    .ok_or_else(|| here("Rotate: the axis is zero".into()))?;
                self.transform(|m| m * DMat4::from_axis_angle(axis, v[0].to_radians()));
            }
            "LookAt" => {
                let v = tokens.numbers(name, 9)?;
                let look = look_at(
                    DVec3::new(v[0], v[1], v[2]),
                    DVec3::new(v[3], v[4], v[5]),
                    DVec3::new(v[6], v[7], v[8]),
                )
                .ok_or_else(|| {
                    here(
                        "LookAt: the eye and the point looked at are the same, or up is along the view"
                            .into(),
                    )
                })?;
                self.transform(|m| m * look);
            }
            "Transform" | "ConcatTransform" => {
                let v = tokens.numbers(name, 16)?;
                let matrix = DMat4::from_cols_slice(&v);
                let concat = name == "ConcatTransform";
                self.transform(|m| if concat { m * matrix } else { matrix });
            }
            "CoordinateSystem" => {
                let system = tokens.string(name)?;
                self.named.insert(system, self.ctm);
            }
            "CoordSysTransform" => {
                let system = tokens.string(name)?;
                let m = *self.named.get(&system).ok_or_else(|| {
                    here(format!(
                        "CoordSysTransform: no coordinate system \"{system}\" was named"
                    ))
                })?;
                self.ctm = m;
            }
            "ActiveTransform" => {
                self.active = match tokens.next()? {
                    Some((Token::Word(w), _)) if w == "All" => Active::All,
                    Some((Token::Word(w), _)) if w == "StartTime" => Active::Start,
                    Some((Token::Word(w), _)) if w == "EndTime" => Active::End,
                    _ => return Err(here("ActiveTransform: expected All, StartTime or EndTime".into())),
                };
                if self.active == Active::End {
                    self.assembly
                        .notes
                        .remark("motion: shapes are placed where they are at the start of the frame");
                }
            }
            "TransformTimes" => {
                tokens.numbers(name, 2)?;
            }
            "ReverseOrientation" | "WorldEnd" => {}
            "WorldBegin" => {
                self.ctm = DMat4::IDENTITY;
                self.active = Active::All;
                self.named.insert("world".into(), DMat4::IDENTITY);
            }
            "Option" => {
                let declaration = tokens.string(name)?;
                tokens.parameter(name, &declaration, line)?;
            }
            "ColorSpace" | "NamedMaterial" => {
                tokens.string(name)?;
            }
            "MediumInterface" => {
                tokens.string(name)?;
                if let Some(Token::Str(_)) = tokens.peek()? {
                    tokens.next()?;
                }
            }
            "Texture" => {
                for _ in 0..3 {
                    tokens.string(name)?;
                }
                tokens.parameters(name)?;
            }
            "Film" => {
                tokens.string(name)?;
                self.film = Some((tokens.parameters(name)?, file.to_path_buf()));
            }
            "Camera" => {
                let kind = tokens.string(name)?;
                let params = tokens.parameters(name)?;
                let camera_from_world = self.ctm;
                if camera_from_world.determinant().abs() < 1e-300 {
                    return Err(here("Camera: the transform is singular".into()));
                }
                self.named.insert("camera".into(), camera_from_world.inverse());
                self.camera = Some(CameraDeclared {
                    kind,
                    params,
                    camera_from_world,
                    file: file.to_path_buf(),
                    line,
                });
            }
            "LightSource" => {
                let kind = tokens.string(name)?;
                let params = tokens.parameters(name)?;
                self.light_source(&kind, &params)?;
            }
            "AreaLightSource" => {
                let kind = tokens.string(name)?;
                tokens.parameters(name)?;
                self.assembly
                    .notes
                    .skip(&format!("{kind} area light (emission; its shapes are geometry)"));
            }
            "Sampler" | "Integrator" | "PixelFilter" | "Accelerator" | "Material" | "MakeNamedMaterial"
            | "MakeNamedMedium" | "Attribute" => {
                tokens.string(name)?;
                tokens.parameters(name)?;
            }
            "Shape" => {
                let kind = tokens.string(name)?;
                let params = tokens.parameters(name)?;
                self.shape(&kind, &params, line)?;
            }
            "ObjectBegin" => {
                let object = tokens.string(name)?;
                if self.defining.is_some() {
                    return Err(here("ObjectBegin inside another ObjectBegin".into()));
                }
                self.stack.push((self.ctm, self.active));
                self.defining = Some((object, Vec::new()));
            }
            "ObjectEnd" => {
                let (object, pieces) = self
                    .defining
                    .take()
                    .ok_or_else(|| here("ObjectEnd without ObjectBegin".into()))?;
                self.objects.insert(object, pieces);
                if let Some((ctm, active)) = self.stack.pop() {
                    self.ctm = ctm;
                    self.active = active;
                }
            }
            "ObjectInstance" => {
                let object = tokens.string(name)?;
                if self.defining.is_some() {
                    return Err(here(
                        "ObjectInstance inside ObjectBegin: pbrt does not nest instances".into(),
                    ));
                }
                let pieces = self
                    .objects
                    .get(&object)
                    .ok_or_else(|| here(format!("ObjectInstance: no object \"{object}\" was defined")))?;
                let ctm = self.ctm;
                for piece in pieces {
                    self.assembly.add(piece, &ctm).map_err(Failure::Error)?;
                }
                self.instances += 1;
            }
            "Include" | "Import" => {
                let written = tokens.string(name)?;
                if depth >= MAX_INCLUDE_DEPTH {
                    return Err(here(format!("{name} \"{written}\": includes nested more than {MAX_INCLUDE_DEPTH} deep (does a file include itself?)")));
                }
                let resolved = self.directory.join(&written);
                let bytes = read_bytes(&resolved).map_err(|e| {
                    here(format!(
                        "{name} \"{written}\" (looked for {}): {}",
                        resolved.display(),
                        cause(&e)
                    ))
                })?;
                let text = super::common::gunzip_if_named(&resolved, &bytes).map_err(Failure::Error)?;
                self.read(&resolved, &text, depth + 1).map_err(Failure::Error)?;
            }
            _ => return Err(here(format!("unknown directive '{name}'"))),
        }
        Ok(())
    }

    /// Applies a transform directive to the start of the motion unless only its end is active.
    fn transform(&mut self, f: impl FnOnce(DMat4) -> DMat4) {
        if self.active != Active::End {
            self.ctm = f(self.ctm);
        }
    }

    fn light_source(&mut self, kind: &str, params: &Params) -> std::result::Result<(), Failure> {
        if kind != "spot" {
            self.assembly.notes.skip(&format!("{kind} light"));
            return Ok(());
        }
        if self.light.is_some() {
            self.assembly.notes.skip("spot light (only the first is used)");
            return Ok(());
        }
        let point = |name: &str, default: DVec3| -> std::result::Result<DVec3, Failure> {
            Ok(match params.points(name)? {
                Some(p) if p.len() == 1 => p[0],
                Some(_) => {
                    return Err(Failure::Here((
                        params.line_of(name, 0),
                        format!("LightSource \"spot\": \"{name}\" must be one point"),
                    )))
                }
                None => default,
            })
        };
        let from = point("from", DVec3::ZERO)?;
        let to = point("to", DVec3::Z)?;
        let angle = params.number("coneangle", 30.0)?;
        let position = self.ctm.transform_point3(from);
        let direction = self.ctm.transform_vector3(to - from).try_normalize();
        let line = params.line_of("to", params.line_of("from", 0));
        let direction = direction.ok_or_else(|| {
            Failure::Here((
                line,
                "LightSource \"spot\": \"from\" and \"to\" are the same point".into(),
            ))
        })?;
        if !(angle > 0.0 && angle <= 180.0) {
            return Err(Failure::Here((
                params.line_of("coneangle", line),
                format!("LightSource \"spot\": coneangle must be in (0, 180], not {angle}"),
            )));
        }
        self.light = Some(SpotLight {
            position: position.as_vec3(),
            direction: direction.as_vec3(),
            cone_half_angle_deg: angle as f32,
        });
        Ok(())
    }

    fn shape(&mut self, kind: &str, params: &Params, line: usize) -> std::result::Result<(), Failure> {
        let to_world = self.ctm;
        let here = |message: String| Failure::Here((line, message));
        if params.has("alpha") {
            self.assembly
                .notes
                .remark("alpha textures are not applied: cut-out surfaces are solid");
        }
        let degrees = |name: &str| -> std::result::Result<f64, Failure> {
            Ok(params.number(name, 360.0)?.clamp(0.0, 360.0).to_radians())
        };
        let quadric_piece = |quadric| Piece::Quadric {
            source: kind.to_string(),
            quadric,
            to_world,
        };
        let piece = match kind {
            "trianglemesh" | "bilinearmesh" | "loopsubdiv" => {
                let positions = params
                    .points("P")?
                    .ok_or_else(|| here(format!("Shape \"{kind}\": no \"point3 P\"")))?;
                let corners = if kind == "bilinearmesh" { 4 } else { 3 };
                let indices = match params.integers("indices")? {
                    Some(i) => i,
                    None if positions.len() == corners => (0..corners as u64).collect(),
                    None => {
                        return Err(here(format!(
                        "Shape \"{kind}\": no \"integer indices\" (needed for more than {corners} points)"
                    )))
                    }
                };
                let iline = params.line_of("indices", line);
                if indices.len() % corners != 0 {
                    return Err(Failure::Here((
                        iline,
                        format!(
                            "Shape \"{kind}\": {} indices, not a multiple of {corners}",
                            indices.len()
                        ),
                    )));
                }
                if let Some(bad) = indices.iter().find(|&&i| i >= positions.len() as u64) {
                    return Err(Failure::Here((
                        iline,
                        format!(
                            "Shape \"{kind}\": index {bad}, but there are {} points",
                            positions.len()
                        ),
                    )));
                }
                let indices: Vec<u32> = indices.iter().map(|&i| i as u32).collect();
                let (positions, triangles) = match kind {
                    "bilinearmesh" => {
                        // p(u, v) over corners 0, 1, 2, 3 at (0,0), (1,0), (0,1), (1,1).
                        let t = indices
                            .chunks_exact(4)
                            .flat_map(|q| [[q[0], q[1], q[3]], [q[0], q[3], q[2]]])
                            .collect();
                        (positions, t)
                    }
                    "loopsubdiv" => {
                        let levels = params.number("levels", 3.0)?;
                        let count = indices.len() as u64 / 3;
                        if !(0.0..=16.0).contains(&levels)
                            || levels.fract() != 0.0
                            || count.saturating_mul(1 << (2 * levels as u64)) > MAX_SUBDIVIDED
                        {
                            return Err(Failure::Here((params.line_of("levels", line), format!("Shape \"loopsubdiv\": {levels} levels of {count} triangles is more than hmdist subdivides (at most {MAX_SUBDIVIDED} triangles)"))));
                        }
                        let t: Vec<[u32; 3]> = indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
                        subdiv::subdivide(positions, t, levels as u32)
                    }
                    _ => (
                        positions,
                        indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
                    ),
                };
                Piece::Triangles {
                    source: kind.to_string(),
                    positions,
                    indices: triangles,
                    to_world,
                }
            }
            "plymesh" => {
                let written = params
                    .string("filename")?
                    .ok_or_else(|| here("Shape \"plymesh\": no \"string filename\"".into()))?;
                if params.has("displacement") {
                    self.assembly.notes.remark("plymesh displacement is not applied");
                }
                let resolved = self.directory.join(&written);
                let fline = params.line_of("filename", line);
                let bytes = read_bytes(&resolved).map_err(|e| {
                    Failure::Here((
                        fline,
                        format!(
                            "Shape \"plymesh\" \"{written}\" (looked for {}): {}",
                            resolved.display(),
                            cause(&e)
                        ),
                    ))
                })?;
                let bytes = super::common::gunzip_if_named(&resolved, &bytes).map_err(Failure::Error)?;
                let mesh = super::ply::load(&resolved, &bytes).map_err(Failure::Error)?.mesh;
                let positions = mesh.positions.iter().map(|p| p.as_dvec3()).collect();
                Piece::Triangles {
                    source: format!("plymesh {written}"),
                    positions,
                    indices: mesh.indices,
                    to_world,
                }
            }
            "sphere" => {
                let radius = params.number("radius", 1.0)?;
                let quadric = Quadric::Sphere {
                    radius,
                    z_min: params.number("zmin", -radius)?,
                    z_max: params.number("zmax", radius)?,
                    phi_max: degrees("phimax")?,
                };
                quadric_piece(quadric)
            }
            "disk" => {
                let quadric = Quadric::Disk {
                    height: params.number("height", 0.0)?,
                    radius: params.number("radius", 1.0)?,
                    inner: params.number("innerradius", 0.0)?,
                    phi_max: degrees("phimax")?,
                };
                quadric_piece(quadric)
            }
            "cylinder" => {
                let quadric = Quadric::Cylinder {
                    radius: params.number("radius", 1.0)?,
                    z_min: params.number("zmin", -1.0)?,
                    z_max: params.number("zmax", 1.0)?,
                    phi_max: degrees("phimax")?,
                };
                quadric_piece(quadric)
            }
            _ => {
                self.assembly.notes.skip(&format!("{kind} shape"));
                return Ok(());
            }
        };
        if let Piece::Quadric { quadric, .. } = &piece {
            quadric.check().map_err(here)?;
        }
        match &mut self.defining {
            Some((_, pieces)) => pieces.push(piece),
            None => self
                .assembly
                .add(&piece, &DMat4::IDENTITY)
                .map_err(Failure::Error)?,
        }
        Ok(())
    }

    /// The scene: the mesh, the camera resolved against the film, the light.
    fn finish(self, path: &Path) -> Result<Scene> {
        let film = match &self.film {
            Some((params, file)) => {
                let size = |name: &str, default: u32| -> Result<u32> {
                    let v = params
                        .number(name, default as f64)
                        .map_err(|(l, m)| Error::file_line(file, l, format!("Film: {m}")))?;
                    if (1.0..=1e6).contains(&v) && v.fract() == 0.0 {
                        Ok(v as u32)
                    } else {
                        Err(Error::file_line(
                            file,
                            params.line_of(name, 0),
                            format!("Film: \"{name}\" must be a whole number from 1 to 10^6, not {v}"),
                        ))
                    }
                };
                (
                    size("xresolution", DEFAULT_FILM.0)?,
                    size("yresolution", DEFAULT_FILM.1)?,
                )
            }
            None => DEFAULT_FILM,
        };
        let cropped = self
            .film
            .as_ref()
            .is_some_and(|(p, _)| p.has("cropwindow") || p.has("pixelbounds"));
        let Reader {
            mut assembly,
            camera,
            light,
            instances,
            ..
        } = self;
        let bounds = assembly.bounds();
        if cropped {
            assembly
                .notes
                .remark("the film's cropwindow/pixelbounds is not applied: the whole picture is rendered");
        }
        if instances > 0 {
            let s = if instances == 1 { "" } else { "s" };
            assembly
                .notes
                .remark(format!("{instances} object instance{s} flattened into the mesh"));
        }
        let camera = match camera {
            None => {
                assembly
                    .notes
                    .remark("no Camera: a camera framing the scene is used");
                framing_camera(bounds)
            }
            Some(c) if c.kind != "perspective" => {
                assembly.notes.remark(format!(
                    "a \"{}\" camera is not a pinhole: a camera framing the scene is used",
                    c.kind
                ));
                framing_camera(bounds)
            }
            Some(c) => {
                if c.params.number("lensradius", 0.0).unwrap_or(0.0) > 0.0 {
                    assembly
                        .notes
                        .remark("depth of field (lensradius) is not applied: the camera is a pinhole");
                }
                perspective(&c, film)
                    .map_err(|(l, m)| Error::file_line(&c.file, l, format!("Camera \"perspective\": {m}")))?
            }
        };
        assembly.into_scene(path, camera, light, Some(film))
    }
}

/// The reason in a file error, without its path (the message names the path itself).
fn cause(error: &Error) -> String {
    match error {
        Error::File { message, .. } => message.clone(),
        other => other.to_string(),
    }
}

/// pbrt's `LookAt`: camera from world, for a camera at `eye` looking at `look`.
fn look_at(eye: DVec3, look: DVec3, up: DVec3) -> Option<DMat4> {
    let dir = (look - eye).try_normalize()?;
    let right = up.try_normalize()?.cross(dir).try_normalize()?;
    let new_up = dir.cross(right);
    let world_from_camera = DMat4::from_cols(
        right.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        eye.extend(1.0),
    );
    Some(world_from_camera.inverse())
}

/// A perspective camera as hmdist's, for a film `film` (width, height) in pixels.
fn perspective(c: &CameraDeclared, film: (u32, u32)) -> std::result::Result<crate::scene::Camera, Located> {
    let fov = c.params.number("fov", 90.0)?;
    if !(fov > 0.0 && fov < 180.0) {
        return Err((
            c.params.line_of("fov", c.line),
            format!("fov must be in (0, 180), not {fov}"),
        ));
    }
    let aspect = match c.params.numbers("frameaspectratio")? {
        Some(v) if v.len() == 1 && v[0] > 0.0 => v[0],
        Some(_) => {
            return Err((
                c.params.line_of("frameaspectratio", c.line),
                "frameaspectratio must be one positive number".into(),
            ))
        }
        None => film.0 as f64 / film.1 as f64,
    };
    // The screen window: by default the shorter side spans [-1, 1].
    let half_height = match c.params.numbers("screenwindow")? {
        None if aspect >= 1.0 => 1.0,
        None => 1.0 / aspect,
        Some(w) => {
            let line = c.params.line_of("screenwindow", c.line);
            let [x0, x1, y0, y1] = w[..] else {
                return Err((line, format!("screenwindow must be 4 numbers, not {}", w.len())));
            };
            let centred = (x0 + x1).abs() <= 1e-9 * x1.abs() && (y0 + y1).abs() <= 1e-9 * y1.abs();
            // Within 0.1 %: a hand-written 1.333 for a 4:3 film is the film's shape.
            let shaped =
                x1 > 0.0 && y1 > 0.0 && ((x1 / y1) / (film.0 as f64 / film.1 as f64) - 1.0).abs() < 1e-3;
            if !(centred && shaped) {
                return Err((line, format!("screenwindow [{x0} {x1} {y0} {y1}] is off the view axis or not the film's shape: hmdist's pinhole camera cannot take it")));
            }
            y1
        }
    };
    let fov_y = 2.0 * (half_height * (0.5 * fov.to_radians()).tan()).atan().to_degrees();
    let world_from_camera = c.camera_from_world.inverse();
    let eye = world_from_camera.transform_point3(DVec3::ZERO);
    let right = world_from_camera.transform_vector3(DVec3::X);
    let up = world_from_camera.transform_vector3(DVec3::Y);
    let forward = world_from_camera.transform_vector3(DVec3::Z);
    let camera = camera_from_frame(eye, right, up, forward, fov_y);
    camera
        .validate()
        .map_err(|e| (c.line, e.to_string().replacen("bad scene: ", "", 1)))?;
    Ok(camera)
}
