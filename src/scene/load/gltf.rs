//! glTF 2.0 (`.gltf` JSON and `.glb` binary) scenes (spec §7), read with the `gltf` crate.
//!
//! The default scene (else the first; else every root node) is walked from its roots, each
//! node's world matrix applied to its mesh. Supported: `TRIANGLES`, `TRIANGLE_STRIP` and
//! `TRIANGLE_FAN` primitives, indexed or not, with float `VEC3` positions (sparse accessors
//! too); points and lines are skipped. Buffers may be embedded (data URI, GLB chunk) or
//! external files relative to the glTF file. Morph targets and skins are ignored (the rest
//! pose is used); materials and textures are never read.
//!
//! The first perspective camera met in the walk becomes the scene's camera: glTF cameras look
//! along their node's −Z with +Y up, so `eye` is the node's origin in world space, `target`
//! = `eye` + world −Z and `up` = world +Y; `yfov` is the vertical field of view. The first
//! `KHR_lights_punctual` spot light becomes the scene's light: position from its node,
//! direction the node's world −Z, cone half-angle = `outerConeAngle`.

use std::path::Path;

use ::gltf::khr_lights_punctual::Kind as LightKind;
use ::gltf::mesh::Mode;
use ::gltf::{accessor::DataType, accessor::Dimensions, buffer, camera::Projection};
use glam::{Affine3A, Mat4, Vec3};

use super::common::MeshFile;
use crate::error::{catch_file_panic, Error, Result};
use crate::scene::{Camera, Mesh, SpotLight};

pub(super) fn load(path: &Path, bytes: &[u8]) -> Result<MeshFile> {
    // The gltf crate panics on some malformed files, in validation itself (a POSITION naming
    // an accessor that does not exist: checked first, below) and after it (URI decoding,
    // accessor arithmetic with a zero count): the guard turns any other into an error.
    catch_file_panic(path, || {
        let unchecked =
            ::gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| parse_error(path, bytes, e))?;
        check_mesh_accessors(unchecked.document.as_json()).map_err(|m| Error::file(path, m))?;
        let document = ::gltf::Document::from_json(unchecked.document.into_json())
            .map_err(|e| parse_error(path, bytes, e))?;
        let gltf = ::gltf::Gltf {
            document,
            blob: unchecked.blob,
        };
        let buffers = read_buffers(path, &gltf)?;
        walk(&gltf.document, &buffers).map_err(|message| Error::file(path, message))
    })
}

fn parse_error(path: &Path, bytes: &[u8], err: ::gltf::Error) -> Error {
    match err {
        ::gltf::Error::Deserialize(e) if !bytes.starts_with(b"glTF") => {
            Error::file_line(path, e.line(), format!("not valid glTF JSON: {e}"))
        }
        e => Error::file(path, format!("not a valid glTF file: {e}")),
    }
}

/// Refuses a primitive whose attributes or indices name an accessor the file does not have,
/// before the gltf crate's validation looks the POSITION accessor up unchecked (a panic).
fn check_mesh_accessors(root: &::gltf::json::Root) -> std::result::Result<(), String> {
    let count = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let named = primitive.attributes.values().chain(&primitive.indices);
            if let Some(index) = named.map(|i| i.value()).find(|&i| i >= count) {
                return Err(format!(
                    "mesh {m} primitive {p} names accessor {index}, but the file has {count} \
                     accessors"
                ));
            }
        }
    }
    Ok(())
}

/// Every buffer's bytes: the GLB chunk, a data URI, or a file beside the glTF file.
fn read_buffers(path: &Path, gltf: &::gltf::Gltf) -> Result<Vec<buffer::Data>> {
    let base = path.parent().unwrap_or(Path::new("."));
    let mut blob = gltf.blob.clone();
    let mut buffers = Vec::new();
    for buffer in gltf.buffers() {
        let what = match buffer.source() {
            buffer::Source::Uri(uri) if uri.starts_with("file:") => {
                format!("buffer {} ('{uri}')", buffer.index())
            }
            buffer::Source::Uri(uri) if !uri.starts_with("data:") => {
                format!("buffer {} ('{}')", buffer.index(), base.join(uri).display())
            }
            _ => format!("buffer {}", buffer.index()),
        };
        if let buffer::Source::Uri(uri) = buffer.source() {
            check_external_buffer(base, uri).map_err(|m| Error::file(path, format!("{what}: {m}")))?;
        }
        let data = buffer::Data::from_source_and_blob(buffer.source(), Some(base), &mut blob);
        let data = data.map_err(|e| Error::file(path, format!("cannot read {what}: {e}")))?;
        if data.len() < buffer.length() {
            let message = format!(
                "{what} holds {} bytes but the file says {}",
                data.len(),
                buffer.length()
            );
            return Err(Error::file(path, message));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// Refuses, before the gltf crate reads it, a buffer URI it would mishandle: a relative path
/// whose percent-decoding is not UTF-8 (decoded there with a panic), or one naming something
/// other than a regular file (`/dev/zero` would be read until memory runs out). Data URIs
/// and other schemes are the crate's to check.
fn check_external_buffer(base: &Path, uri: &str) -> std::result::Result<(), String> {
    let file = match uri.strip_prefix("file://").or(uri.strip_prefix("file:")) {
        Some(file) => Path::new(file).to_path_buf(),
        None if uri.contains(':') => return Ok(()),
        None => base.join(percent_decoded(uri).ok_or("its URI is not percent-encoded UTF-8")?),
    };
    match std::fs::metadata(&file) {
        Ok(metadata) if !metadata.is_file() => Err("it names something other than a file".into()),
        _ => Ok(()), // a missing file is the crate's error, with the OS's words
    }
}

/// `text` with each `%XX` replaced by the byte it stands for, if the result is UTF-8.
fn percent_decoded(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    let digit = |b: u8| (b as char).to_digit(16);
    while i < bytes.len() {
        let escape = bytes.get(i + 1..i + 3).filter(|_| bytes[i] == b'%');
        match escape.and_then(|h| Some((digit(h[0])?, digit(h[1])?))) {
            Some((high, low)) => {
                out.push((high * 16 + low) as u8);
                i += 3;
            }
            None => {
                out.push(bytes[i]);
                i += 1;
            }
        }
    }
    String::from_utf8(out).ok()
}

/// Walks the scene's node trees depth first, parents before children, in file order.
fn walk(document: &::gltf::Document, buffers: &[buffer::Data]) -> std::result::Result<MeshFile, String> {
    let scene = document.default_scene().or_else(|| document.scenes().next());
    let roots: Vec<::gltf::Node> = match scene {
        Some(scene) => scene.nodes().collect(),
        None => {
            let children: Vec<usize> = document
                .nodes()
                .flat_map(|n| n.children().map(|c| c.index()).collect::<Vec<_>>())
                .collect();
            document
                .nodes()
                .filter(|n| !children.contains(&n.index()))
                .collect()
        }
    };
    let mut visited = vec![false; document.nodes().len()];
    let mut stack: Vec<(::gltf::Node, Mat4)> = roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut found = MeshFile::default();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(format!(
                "node {} is reached twice: the node hierarchy must be a tree",
                node.index()
            ));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        visit(&node, world, buffers, &mut found)?;
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    Ok(found)
}

fn visit(
    node: &::gltf::Node,
    world: Mat4,
    buffers: &[buffer::Data],
    found: &mut MeshFile,
) -> std::result::Result<(), String> {
    let origin = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    if let Some(mesh) = node.mesh() {
        let transform = Affine3A::from_mat4(world);
        for primitive in mesh.primitives() {
            let local = read_primitive(&primitive, buffers).map_err(|message| {
                format!("mesh {} primitive {}: {message}", mesh.index(), primitive.index())
            })?;
            found.mesh.append_transformed(&local, transform);
        }
    }
    if let (None, Some(camera)) = (found.camera, node.camera()) {
        if let Projection::Perspective(perspective) = camera.projection() {
            found.camera = Some(Camera {
                eye: origin,
                target: origin + forward,
                up: world.transform_vector3(Vec3::Y).normalize_or_zero(),
                fov_y_deg: perspective.yfov().to_degrees(),
                mirrored: false,
            });
        }
    }
    if let (None, Some(light)) = (found.light, node.light()) {
        if let LightKind::Spot { outer_cone_angle, .. } = light.kind() {
            found.light = Some(SpotLight {
                position: origin,
                direction: forward,
                cone_half_angle_deg: outer_cone_angle.to_degrees(),
            });
        }
    }
    Ok(())
}

/// The triangles of one primitive in its node's local space; empty for points and lines.
fn read_primitive(
    primitive: &::gltf::Primitive,
    buffers: &[buffer::Data],
) -> std::result::Result<Mesh, String> {
    let mut mesh = Mesh::new();
    if matches!(
        primitive.mode(),
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip
    ) {
        return Ok(mesh);
    }
    let accessor = primitive
        .get(&::gltf::Semantic::Positions)
        .ok_or("it has no POSITION attribute")?;
    if accessor.dimensions() != Dimensions::Vec3 || accessor.data_type() != DataType::F32 {
        return Err(
            "POSITION must be a float VEC3 accessor (quantised positions are not \
                    supported)"
                .to_string(),
        );
    }
    if accessor.count() == 0 {
        return Ok(mesh);
    }
    let reader = primitive.reader(|b| buffers.get(b.index()).map(|d| d.0.as_slice()));
    let outside = "its data lies outside its buffer";
    mesh.add_vertices(reader.read_positions().ok_or(outside)?.map(Vec3::from));

    let corners: Vec<u32> = match primitive.indices() {
        Some(indices) => {
            let integer = matches!(indices.data_type(), DataType::U8 | DataType::U16 | DataType::U32);
            if indices.dimensions() != Dimensions::Scalar || !integer {
                return Err("indices must be unsigned integer scalars".to_string());
            }
            if indices.count() == 0 {
                return Ok(Mesh::new());
            }
            reader.read_indices().ok_or(outside)?.into_u32().collect()
        }
        None => (0..mesh.positions.len() as u32).collect(),
    };
    let n = mesh.positions.len();
    if let Some(&c) = corners.iter().find(|&&c| c as usize >= n) {
        return Err(format!("index {c} is out of range: there are {n} vertices"));
    }
    match primitive.mode() {
        Mode::TriangleStrip => {
            // glTF 2.0 §3.7.2.1: triangle i is (i, i+1+i%2, i+2-i%2), keeping the winding.
            for (i, w) in corners.windows(3).enumerate() {
                let (b, c) = if i % 2 == 0 { (w[1], w[2]) } else { (w[2], w[1]) };
                mesh.add_triangle(w[0], b, c);
            }
        }
        Mode::TriangleFan => {
            for w in corners.get(1..).unwrap_or(&[]).windows(2) {
                mesh.add_triangle(w[0], w[1], corners[0]);
            }
        }
        _ => {
            if !corners.len().is_multiple_of(3) {
                return Err(format!(
                    "{} corners is not a whole number of triangles",
                    corners.len()
                ));
            }
            for t in corners.chunks_exact(3) {
                mesh.add_triangle(t[0], t[1], t[2]);
            }
        }
    }
    Ok(mesh)
}
