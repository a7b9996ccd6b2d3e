//! Stanford PLY meshes (spec §7), read with `ply-rs-bw`.
//!
//! Supported: `ascii`, `binary_little_endian` and `binary_big_endian`; a `vertex` element
//! with scalar `x`, `y`, `z` properties of any numeric type (float and double in practice);
//! a `face` element with a `vertex_indices` (or `vertex_index`) list of any integer type.
//! Polygons are fan-triangulated. Other elements and properties (normals, colours, ...) are
//! skipped. A file without faces (a point cloud) is an error.
//!
//! Errors carry the line for ascii files (header errors always). The element counts in the
//! header must match the data: missing data and data left over after the last element are
//! both errors.

use std::io::Cursor;
use std::path::Path;

use glam::Vec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Encoding, Header, Payload, Property, PropertyAccess, PropertyAccessResult};

use super::common::{line_of_offset, MeshFile};
use crate::error::{catch_file_panic, Error, Result};
use crate::scene::Mesh;

/// The names a face's corner list goes by.
const CORNER_LISTS: [&str; 2] = ["vertex_indices", "vertex_index"];

/// One element of the payload, keeping only what we use: a vertex's position or a face's
/// corners.
#[derive(Default)]
struct Record {
    position: [f32; 3],
    corners: Vec<i64>,
}

impl PropertyAccess for Record {
    fn new() -> Self {
        Self::default()
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let axis = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ if CORNER_LISTS.contains(&name) => return self.set_corners(property),
            _ => return PropertyAccessResult::Ignored,
        };
        match property.to_f32_lossy() {
            Some(value) => {
                self.position[axis] = value;
                PropertyAccessResult::Set
            }
            None => PropertyAccessResult::UnsupportedType,
        }
    }
}

impl Record {
    fn set_corners(&mut self, property: Property) -> PropertyAccessResult {
        fn wide<T: Copy + Into<i64>>(list: Vec<T>) -> Vec<i64> {
            list.into_iter().map(Into::into).collect()
        }
        self.corners = match property {
            Property::ListChar(l) => wide(l),
            Property::ListUChar(l) => wide(l),
            Property::ListShort(l) => wide(l),
            Property::ListUShort(l) => wide(l),
            Property::ListInt(l) => wide(l),
            Property::ListUInt(l) => wide(l),
            _ => return PropertyAccessResult::UnsupportedType,
        };
        PropertyAccessResult::Set
    }
}

/// A parsed file: header, payload and the line of the first payload element (ascii).
struct Parsed {
    header: Header,
    payload: Payload<Record>,
    first_data_line: usize,
}

pub(super) fn load(path: &Path, bytes: &[u8]) -> Result<MeshFile> {
    // ply-rs-bw returned errors for every malformed input we tried (truncations at every
    // byte, thousands of random byte changes); the guard is there because a panic inside a
    // parsing crate must not take the program down.
    let parsed = catch_file_panic(path, || {
        parse(bytes).map_err(|(line, message)| match line {
            Some(line) => Error::file_line(path, line, message),
            None => Error::file(path, message),
        })
    })?;
    let mesh = build_mesh(&parsed).map_err(|(line, message)| match line {
        Some(line) => Error::file_line(path, line, message),
        None => Error::file(path, message),
    })?;
    Ok(MeshFile {
        mesh,
        camera: None,
        light: None,
    })
}

/// An error with its line, where the file has lines there.
type Located = (Option<usize>, String);

fn parse(bytes: &[u8]) -> std::result::Result<Parsed, Located> {
    let parser = Parser::<Record>::new();
    let mut reader = Reader::new(Cursor::new(bytes));
    let header = parser
        .read_header(&mut reader)
        .map_err(|e| (e.line(), tidy(&e.to_string())))?;
    let ascii = header.encoding == Encoding::Ascii;
    let first_data_line = reader.line().max(1);
    let payload = parser.read_payload(&mut reader, &header).map_err(|e| {
        let line = if ascii { e.line() } else { None };
        (line, tidy(&e.to_string()))
    })?;

    let end = reader.get_ref().position() as usize;
    let rest = &bytes[end.min(bytes.len())..];
    if ascii {
        if let Some(extra) = rest.iter().position(|b| !b.is_ascii_whitespace()) {
            let line = line_of_offset(bytes, end + extra);
            let message = "data after the last element: do the element counts in the header \
                           match the data?";
            return Err((Some(line), message.to_string()));
        }
    } else if !rest.is_empty() {
        let message = format!(
            "{} bytes after the last element: do the element counts in the header match the \
             data?",
            rest.len()
        );
        return Err((None, message));
    }
    Ok(Parsed {
        header,
        payload,
        first_data_line,
    })
}

/// ply-rs-bw's messages span several lines and nest ("Line 7: Couldn't read element line.\n\t
/// String: '...'\n\tError: Couldn't parse ...\n\tError: expected ..."): one line, without the
/// line number (we report it ourselves), the outer context and the innermost cause.
fn tidy(message: &str) -> String {
    let message = match message.strip_prefix("Line ") {
        Some(rest) => rest.split_once(": ").map_or(rest, |(_, m)| m),
        None => message,
    };
    let message = message.split_whitespace().collect::<Vec<_>>().join(" ");
    match (message.split_once(" Error: "), message.rsplit_once("Error: ")) {
        (Some((context, _)), Some((_, cause))) => {
            format!("{}: {cause}", context.trim_end_matches('.'))
        }
        _ => message,
    }
}

fn build_mesh(parsed: &Parsed) -> std::result::Result<Mesh, Located> {
    let elements = &parsed.header.elements;
    let ascii = parsed.header.encoding == Encoding::Ascii;
    // The line of element `index` of `name` (ascii files: one element per line).
    let line_of = |name: &str, index: usize| -> Option<usize> {
        let before: usize = elements
            .iter()
            .take_while(|(n, _)| n.as_str() != name)
            .map(|(_, e)| e.count)
            .sum();
        ascii.then_some(parsed.first_data_line + before + index)
    };

    let vertex = elements
        .get("vertex")
        .ok_or((None, "the file has no 'vertex' element".to_string()))?;
    if let Some(axis) = ["x", "y", "z"]
        .into_iter()
        .find(|a| !vertex.properties.contains_key(*a))
    {
        let message = format!("the 'vertex' element has no '{axis}' property");
        return Err((None, message));
    }
    let Some(face) = elements.get("face") else {
        return Err((None, "the file has no faces (no 'face' element)".to_string()));
    };
    if !CORNER_LISTS.iter().any(|l| face.properties.contains_key(*l)) {
        let message = "the 'face' element has no 'vertex_indices' list";
        return Err((None, message.to_string()));
    }

    let empty = Vec::new();
    let vertices = parsed.payload.get("vertex").unwrap_or(&empty);
    let faces = parsed.payload.get("face").unwrap_or(&empty);
    let mut mesh = Mesh::new();
    mesh.add_vertices(vertices.iter().map(|v| Vec3::from(v.position)));
    let n = vertices.len();
    for (i, f) in faces.iter().enumerate() {
        if f.corners.len() < 3 {
            let message = format!(
                "face {i} has {} corners: a face needs at least 3",
                f.corners.len()
            );
            return Err((line_of("face", i), message));
        }
        if let Some(&c) = f.corners.iter().find(|&&c| c < 0 || c as usize >= n) {
            let message = format!("face {i} refers to vertex {c} but the file has only {n} vertices");
            return Err((line_of("face", i), message));
        }
        let c = |k: usize| f.corners[k] as u32;
        for k in 1..f.corners.len() - 1 {
            mesh.add_triangle(c(0), c(k), c(k + 1));
        }
    }
    let non_finite = mesh
        .indices
        .iter()
        .flatten()
        .find(|&&v| !mesh.positions[v as usize].is_finite());
    if let Some(&v) = non_finite {
        let p = mesh.positions[v as usize];
        let message = format!("vertex {v} is not finite: ({}, {}, {})", p.x, p.y, p.z);
        return Err((line_of("vertex", v as usize), message));
    }
    Ok(mesh)
}
