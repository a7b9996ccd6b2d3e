//! Writes meshes as Wavefront OBJ (`hmdist scene export`, spec §7).
//!
//! The file holds a comment line with the counts, then `v x y z` per vertex and `f a b c`
//! per triangle (1-based indices), nothing else. Coordinates are written with Rust's `{}`
//! formatting of `f32`: the shortest decimal that reads back as the same `f32`, so loading
//! the file gives exactly the same triangles. (The OBJ loader numbers vertices in order of
//! first use and drops unused ones, so the vertex list itself comes back identical only when
//! the triangles use the vertices in order.) The file is written beside its destination
//! under a temporary name and renamed into place, so a failed export never leaves half a
//! file.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::scene::Mesh;

/// Writes `mesh` to `path` as OBJ, replacing any file there only once the whole mesh is written
/// (and not at all once an interruption is requested, [`crate::interrupt`]).
pub fn write_obj(mesh: &Mesh, path: &Path) -> Result<()> {
    let temporary = temporary_path(path);
    let written = File::create(&temporary).and_then(|file| {
        let mut out = BufWriter::new(file);
        write_obj_to(mesh, &mut out)?;
        out.into_inner().map_err(|e| e.into_error())?.sync_all()
    });
    let result = written
        .map_err(|e| Error::io(path, "write", e))
        .and_then(|()| crate::interrupt::check())
        .and_then(|()| std::fs::rename(&temporary, path).map_err(|e| Error::io(path, "write", e)));
    result.inspect_err(|_| {
        let _ = std::fs::remove_file(&temporary);
    })
}

/// Writes `mesh` as OBJ text to `out`.
pub fn write_obj_to(mesh: &Mesh, out: &mut impl Write) -> std::io::Result<()> {
    writeln!(
        out,
        "# hmdist mesh: {} triangles, {} vertices",
        mesh.triangle_count(),
        mesh.positions.len()
    )?;
    for p in &mesh.positions {
        writeln!(out, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for [a, b, c] in &mesh.indices {
        writeln!(out, "f {} {} {}", a + 1, b + 1, c + 1)?;
    }
    Ok(())
}

/// A name beside `path` that no other process writing the same file will pick.
fn temporary_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "export".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}
