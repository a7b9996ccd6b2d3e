//! Wavefront OBJ meshes (spec §7), read with `tobj`.
//!
//! Supported: `v x y z [w]` (and `v x y z r g b`, colour ignored), `f` with any number of
//! corners in any of the forms `v`, `v/vt`, `v//vn`, `v/vt/vn`, negative (relative) indices,
//! several objects and groups (merged into one mesh). Polygons are fan-triangulated. Normals,
//! texture coordinates, materials (a missing `.mtl` is fine), points, lines and free-form
//! curves and surfaces are ignored.
//!
//! `tobj` is lenient where we want errors, strict where we don't, and reports no line
//! numbers, so the text goes through [`prepare`] first: it rejects lines that are not OBJ
//! statements and faces with fewer than three corners, and blanks out (byte for byte, so
//! offsets and line numbers stay put) what tobj would misread: `l a b c` becomes a triangle
//! in tobj, a vertex colour on some vertices but not others is an error there, and a
//! relative texture index can overflow. When tobj fails, the line is the one it had just
//! read (the reader's position); face indices are only checked when tobj assembles an object,
//! so an index out of range is located by a second look at the faces ([`locate_bad_face`]).
//! tobj accepts `nan` and `inf` as coordinates: [`locate_non_finite_vertex`] finds the line.

use std::io::Cursor;
use std::path::Path;

use glam::Vec3;

use super::common::{line_of_offset, MeshFile};
use crate::error::{catch_file_panic, Error, Result};
use crate::scene::Mesh;

/// The statements of the OBJ specification; any other first word on a line is an error.
#[rustfmt::skip]
const STATEMENTS: [&str; 37] = [
    "v", "vt", "vn", "vp", "cstype", "deg", "bmat", "step", "p", "l", "f", "curv", "curv2",
    "surf", "parm", "trim", "hole", "scrv", "sp", "end", "con", "g", "s", "mg", "o", "bevel",
    "c_interp", "d_interp", "lod", "usemtl", "mtllib", "shadow_obj", "trace_obj", "ctech",
    "stech", "maplib", "usemap",
];

/// Statements tobj would act on that play no part in H: hidden from it.
const HIDDEN: [&str; 5] = ["vt", "vn", "l", "usemtl", "mtllib"];

pub(super) fn load(path: &Path, bytes: &[u8]) -> Result<MeshFile> {
    let mut text = bytes.to_vec();
    prepare(&mut text).map_err(|(line, message)| Error::file_line(path, line, message))?;

    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let mut reader = Cursor::new(&text[..]);
    let no_materials = |_: &Path| Ok((Vec::new(), Default::default()));
    // tobj 4.0.5 panicked on huge face indices (an overflow); `prepare` guards against that
    // case, and the catch against any other.
    let loaded = catch_file_panic(path, || {
        Ok(tobj::load_obj_buf(&mut reader, &options, no_materials))
    })?;
    let models = match loaded {
        Ok((models, _materials)) => models,
        Err(err) => {
            let end = reader.position() as usize;
            let (line, message) = explain(&text, end, err);
            return Err(Error::file_line(path, line, message));
        }
    };

    let mut mesh = Mesh::new();
    for model in &models {
        let first = mesh.add_vertices(
            model
                .mesh
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        for t in model.mesh.indices.chunks_exact(3) {
            mesh.add_triangle(first + t[0], first + t[1], first + t[2]);
        }
    }
    if mesh.positions.iter().any(|p| !p.is_finite()) {
        if let Some((line, message)) = locate_non_finite_vertex(&text) {
            return Err(Error::file_line(path, line, message));
        }
    }
    Ok(MeshFile {
        mesh,
        camera: None,
        light: None,
    })
}

/// Checks every line's statement and rewrites, in place and byte for byte, what tobj must
/// not see (see the module docs). Errors are (line, message).
fn prepare(text: &mut [u8]) -> std::result::Result<(), (usize, String)> {
    if text.starts_with(b"\xEF\xBB\xBF") {
        text[..3].fill(b' '); // a UTF-8 byte-order mark
    }
    let mut blanks = Vec::new();
    let mut start = 0;
    for (index, raw) in text.split(|&b| b == b'\n').enumerate() {
        let line_number = index + 1;
        let line =
            std::str::from_utf8(raw).map_err(|_| (line_number, "the line is not UTF-8 text".to_string()))?;
        let words: Vec<(usize, &str)> = line
            .split_ascii_whitespace()
            .map(|w| (start + (w.as_ptr() as usize - line.as_ptr() as usize), w))
            .collect();
        start += raw.len() + 1;
        let Some(&(at, keyword)) = words.first() else {
            continue;
        };
        if keyword.starts_with('#') {
            continue;
        }
        if !STATEMENTS.contains(&keyword) {
            let message = format!("'{}' is not an OBJ statement", keyword.escape_debug());
            return Err((line_number, message));
        }
        let arguments = words.len() - 1;
        match keyword {
            "v" if !matches!(arguments, 3 | 4 | 6) => {
                let message = format!(
                    "a vertex has 3 coordinates (and an optional weight or r g b colour), \
                     not {arguments} numbers"
                );
                return Err((line_number, message));
            }
            "v" if arguments == 6 => {
                let (from, _) = words[4];
                let (last, word) = words[6];
                blanks.push((from, last + word.len()));
            }
            "f" if arguments < 3 => {
                let message = format!("a face needs at least 3 corners, this one has {arguments}");
                return Err((line_number, message));
            }
            _ if HIDDEN.contains(&keyword) => blanks.push((at, at + 1)),
            _ => {}
        }
    }
    for (from, to) in blanks {
        // One byte over a keyword makes it a comment word ('#', '#t', ...), over the colour
        // it makes spaces: tobj ignores both.
        let fill = if to - from == 1 { b'#' } else { b' ' };
        text[from..to].fill(fill);
    }
    Ok(())
}

/// The line and message for a tobj error; `end` is how far tobj had read.
fn explain(text: &[u8], end: usize, err: tobj::LoadError) -> (usize, String) {
    use tobj::LoadError as E;
    let line = line_of_offset(text, end.saturating_sub(1));
    let message = match err {
        E::FaceVertexOutOfBounds => match locate_bad_face(text) {
            Some(found) => return found,
            None => "a face refers to a vertex that is not defined".to_string(),
        },
        E::PositionParseError => "cannot read the vertex coordinates as numbers".to_string(),
        E::ScalingByZeroError => "the vertex has weight w = 0".to_string(),
        E::FaceParseError => "cannot read the face's corners: expected vertex numbers \
                              such as '3', '3/1', '3//2' or '3/1/2'"
            .to_string(),
        other => format!("cannot read the OBJ statement ({other})"),
    };
    (line, message)
}

/// The words of every line, with 1-based line numbers.
fn statements(text: &[u8]) -> impl Iterator<Item = (usize, Vec<&str>)> {
    text.split(|&b| b == b'\n').enumerate().map(|(i, raw)| {
        let line = std::str::from_utf8(raw).unwrap_or("");
        (i + 1, line.split_ascii_whitespace().collect())
    })
}

/// The first face corner that names no vertex defined before it, as (line, message).
fn locate_bad_face(text: &[u8]) -> Option<(usize, String)> {
    let mut defined: i64 = 0;
    for (line, words) in statements(text) {
        match words.first() {
            Some(&"v") => defined += 1,
            Some(&"f") => {
                for corner in &words[1..] {
                    let Ok(given) = corner.split('/').next()?.parse::<i64>() else {
                        let message = format!("face corner '{corner}' has no vertex number");
                        return Some((line, message));
                    };
                    let vertex = if given < 0 { defined + 1 + given } else { given };
                    if given == 0 {
                        return Some((line, "vertex numbers start at 1, not 0".to_string()));
                    } else if vertex < 1 || vertex > defined {
                        let message = format!(
                            "face refers to vertex {given} but only {defined} vertices are \
                             defined before it"
                        );
                        return Some((line, message));
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// The first vertex whose coordinates (divided by its weight, if any) are not all finite.
fn locate_non_finite_vertex(text: &[u8]) -> Option<(usize, String)> {
    let mut number = 0;
    for (line, words) in statements(text) {
        if words.first() != Some(&"v") {
            continue;
        }
        number += 1;
        let values: Vec<f32> = words[1..].iter().map(|w| w.parse().unwrap_or(0.0)).collect();
        if values.len() < 3 {
            continue;
        }
        let w = if values.len() == 4 { values[3] } else { 1.0 };
        let p = Vec3::new(values[0], values[1], values[2]) / w;
        if !p.is_finite() {
            let message = format!("vertex {number} is not finite: ({}, {}, {})", p.x, p.y, p.z);
            return Some((line, message));
        }
    }
    None
}
