//! Mitsuba's `.serialized` meshes: the triangles of one mesh of the file, by its index.
//!
//! The file is one or more meshes, each a 4-byte header (`u16` 0x041C, `u16` version) and a
//! zlib stream; after the last, a table of where each mesh starts (`u32` offsets in version
//! 3, `u64` in versions 4 and 5) and the number of meshes (`u32`). All little-endian.
//! - **Versions 3 and 4** (Mitsuba 0.4 to 3.6): `u32` flags (0x1 normals, 0x2 texture
//!   coordinates, 0x8 colours, 0x2000 double precision), the mesh's name ending in a NUL
//!   (version 4 only), `u64` vertices V and triangles F, then V positions, V normals, V
//!   texture coordinates (two numbers) and V colours as the flags say, then 3F `u32` indices.
//! - **Version 5** (Mitsuba 3 from 2026): `u32` flags, a name (`u32` length and its bytes),
//!   `u64` V, F and two map sizes, V records of eight `f32` (the position first), then F
//!   records of four `u32` (three indices and a material index); the rest is not needed.
//!
//! Only positions and indices are kept. Every size is checked against what the stream holds
//! before it is trusted, so a corrupt file is refused by name, not read past its end.

use std::io::Read;

use glam::DVec3;

/// The file's first two bytes: Mitsuba's format identifier.
const MAGIC: u16 = 0x041C;
/// The most a mesh's stream may inflate to.
const MAX_STREAM: u64 = crate::scene::load::common::MAX_INFLATED;

/// The positions and triangles of mesh `shape_index` of the `.serialized` file `bytes`.
pub fn read(bytes: &[u8], shape_index: usize) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), String> {
    let (magic, version) = header(bytes, 0).ok_or("the file is too short to be a serialized mesh")?;
    if magic != MAGIC {
        return Err(format!(
            "not a Mitsuba serialized mesh (it begins 0x{magic:04X}, not 0x041C)"
        ));
    }
    if !(3..=5).contains(&version) {
        return Err(format!(
            "serialized version {version}: hmdist reads versions 3, 4 and 5"
        ));
    }
    let start = if shape_index == 0 {
        0
    } else {
        offset(bytes, version, shape_index)?
    };
    match header(bytes, start) {
        Some((MAGIC, v)) if v == version => {}
        _ => {
            return Err(format!(
                "mesh {shape_index} does not start where the file's table says (byte {start})"
            ))
        }
    }
    let mut stream = Stream(flate2::read::ZlibDecoder::new(&bytes[start + 4..]).take(MAX_STREAM));
    if version == 5 {
        read_v5(&mut stream)
    } else {
        read_legacy(&mut stream, version)
    }
    .map_err(|e| format!("mesh {shape_index}: {e}"))
}

/// The (identifier, version) at byte `at`.
fn header(bytes: &[u8], at: usize) -> Option<(u16, u16)> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some((u16::from_le_bytes([b[0], b[1]]), u16::from_le_bytes([b[2], b[3]])))
}

/// Where mesh `index` starts, from the table at the file's end.
fn offset(bytes: &[u8], version: u16, index: usize) -> Result<usize, String> {
    let n = bytes.len();
    let tail = |at: usize, len: usize| {
        bytes
            .get(at..at + len)
            .ok_or_else(|| "the file's table of meshes is cut off".to_string())
    };
    let count = u32::from_le_bytes(tail(n.saturating_sub(4), 4)?.try_into().unwrap()) as usize;
    if index >= count {
        let last = count.saturating_sub(1);
        return Err(format!(
            "shape_index {index} is out of range: the file holds {count} meshes (0 to {last})"
        ));
    }
    let width = if version >= 4 { 8 } else { 4 };
    let from_end = (count - index).checked_mul(width).and_then(|t| t.checked_add(4));
    let at = from_end
        .and_then(|t| n.checked_sub(t))
        .ok_or("the file's table of meshes is cut off")?;
    let raw = tail(at, width)?;
    let start = if width == 8 {
        u64::from_le_bytes(raw.try_into().unwrap())
    } else {
        u32::from_le_bytes(raw.try_into().unwrap()) as u64
    };
    usize::try_from(start).map_err(|_| format!("mesh {index} starts past the file's end"))
}

/// The inflated stream, read in little-endian pieces.
struct Stream<R>(R);

impl<R: Read> Stream<R> {
    fn bytes(&mut self, n: u64, what: &str) -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        (&mut self.0)
            .take(n)
            .read_to_end(&mut out)
            .map_err(|e| format!("the compressed stream is damaged ({e})"))?;
        if (out.len() as u64) < n {
            return Err(format!("the stream ends inside the {what}"));
        }
        Ok(out)
    }

    fn skip(&mut self, n: u64, what: &str) -> Result<(), String> {
        let skipped = std::io::copy(&mut (&mut self.0).take(n), &mut std::io::sink())
            .map_err(|e| format!("the compressed stream is damaged ({e})"))?;
        if skipped < n {
            return Err(format!("the stream ends inside the {what}"));
        }
        Ok(())
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.bytes(4, what)?.try_into().unwrap()))
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.bytes(8, what)?.try_into().unwrap()))
    }
}

/// The vertex and triangle counts, refused where hmdist cannot hold them.
fn counts<R: Read>(stream: &mut Stream<R>) -> Result<(u64, u64), String> {
    let vertices = stream.u64("vertex count")?;
    let triangles = stream.u64("triangle count")?;
    if vertices > u32::MAX as u64 {
        return Err(format!("{vertices} vertices: more than hmdist can hold (2^32)"));
    }
    if triangles > u32::MAX as u64 {
        return Err(format!("{triangles} triangles: more than hmdist can hold (2^32)"));
    }
    Ok((vertices, triangles))
}

fn read_legacy<R: Read>(stream: &mut Stream<R>, version: u16) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), String> {
    let flags = stream.u32("flags")?;
    if version == 4 {
        // The name, up to its NUL (at most 64 KiB).
        let mut length = 0;
        while stream.bytes(1, "mesh's name")?[0] != 0 {
            length += 1;
            if length > 1 << 16 {
                return Err("the mesh's name runs on for more than 64 KiB".into());
            }
        }
    }
    let (vertices, triangles) = counts(stream)?;
    let width = if flags & 0x2000 != 0 { 8 } else { 4 };
    let raw = stream.bytes(3 * vertices * width, "positions")?;
    let positions = raw
        .chunks_exact(3 * width as usize)
        .map(|p| {
            let at = |i: usize| -> f64 {
                let b = &p[i * width as usize..(i + 1) * width as usize];
                if width == 8 {
                    f64::from_le_bytes(b.try_into().unwrap())
                } else {
                    f32::from_le_bytes(b.try_into().unwrap()) as f64
                }
            };
            DVec3::new(at(0), at(1), at(2))
        })
        .collect();
    for (flag, lanes, what) in [
        (0x1, 3, "normals"),
        (0x2, 2, "texture coordinates"),
        (0x8, 3, "colours"),
    ] {
        if flags & flag != 0 {
            stream.skip(lanes * vertices * width, what)?;
        }
    }
    let raw = stream.bytes(12 * triangles, "triangle indices")?;
    let indices = raw
        .chunks_exact(12)
        .map(|t| [0, 1, 2].map(|i| u32::from_le_bytes(t[4 * i..4 * i + 4].try_into().unwrap())))
        .collect();
    checked(positions, indices, vertices)
}

fn read_v5<R: Read>(stream: &mut Stream<R>) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), String> {
    let _flags = stream.u32("flags")?;
    let name_length = stream.u32("name's length")?;
    stream.skip(name_length as u64, "mesh's name")?;
    let (vertices, triangles) = counts(stream)?;
    stream.skip(16, "map sizes")?;
    let raw = stream.bytes(32 * vertices, "vertex records")?;
    let positions = raw
        .chunks_exact(32)
        .map(|r| {
            let at = |i: usize| f32::from_le_bytes(r[4 * i..4 * i + 4].try_into().unwrap()) as f64;
            DVec3::new(at(0), at(1), at(2))
        })
        .collect();
    let raw = stream.bytes(16 * triangles, "face records")?;
    let indices = raw
        .chunks_exact(16)
        .map(|t| [0, 1, 2].map(|i| u32::from_le_bytes(t[4 * i..4 * i + 4].try_into().unwrap())))
        .collect();
    checked(positions, indices, vertices)
}

/// The mesh, once every position is finite and every index names a vertex.
fn checked(
    positions: Vec<DVec3>,
    indices: Vec<[u32; 3]>,
    vertices: u64,
) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), String> {
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {i} is not a finite point ({})", positions[i]));
    }
    for (i, t) in indices.iter().enumerate() {
        if let Some(v) = t.iter().find(|&&v| v as u64 >= vertices) {
            return Err(format!(
                "triangle {i} names vertex {v}, but the mesh has {vertices}"
            ));
        }
    }
    Ok((positions, indices))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// A version-3 or -4 mesh of `positions` and `indices` with normals, as Mitsuba writes it.
    fn legacy(version: u16, positions: &[[f32; 3]], indices: &[[u32; 3]]) -> Vec<u8> {
        let mut raw = Vec::new();
        raw.extend(0x1001u32.to_le_bytes());
        if version == 4 {
            raw.extend(b"mesh\0");
        }
        raw.extend((positions.len() as u64).to_le_bytes());
        raw.extend((indices.len() as u64).to_le_bytes());
        for p in positions.iter().flatten() {
            raw.extend(p.to_le_bytes());
        }
        for _ in 0..positions.len() * 3 {
            raw.extend(0.5f32.to_le_bytes());
        }
        for i in indices.iter().flatten() {
            raw.extend(i.to_le_bytes());
        }
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&raw).unwrap();
        let mut out = MAGIC.to_le_bytes().to_vec();
        out.extend(version.to_le_bytes());
        out.extend(z.finish().unwrap());
        out
    }

    fn two_meshes(version: u16) -> Vec<u8> {
        let a = legacy(
            version,
            &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &[[0, 1, 2]],
        );
        let b = legacy(
            version,
            &[[0.0, 0.0, 5.0], [1.0, 0.0, 5.0], [0.0, 1.0, 5.0], [1.0, 1.0, 5.0]],
            &[[0, 1, 2], [1, 3, 2]],
        );
        let mut file = a.clone();
        file.extend(&b);
        if version >= 4 {
            file.extend(0u64.to_le_bytes());
            file.extend((a.len() as u64).to_le_bytes());
        } else {
            file.extend(0u32.to_le_bytes());
            file.extend((a.len() as u32).to_le_bytes());
        }
        file.extend(2u32.to_le_bytes());
        file
    }

    #[test]
    fn each_mesh_of_a_file_is_read_by_its_index() {
        for version in [3, 4] {
            let file = two_meshes(version);
            let (p, t) = read(&file, 0).unwrap();
            assert_eq!((p.len(), t), (3, vec![[0, 1, 2]]));
            let (p, t) = read(&file, 1).unwrap();
            assert_eq!(p[3], DVec3::new(1.0, 1.0, 5.0));
            assert_eq!(t, vec![[0, 1, 2], [1, 3, 2]]);
            assert!(
                read(&file, 2).unwrap_err().contains("holds 2 meshes"),
                "v{version}"
            );
        }
    }

    #[test]
    fn damaged_files_are_refused_by_name() {
        let file = two_meshes(4);
        assert!(read(&file[..2], 0).unwrap_err().contains("too short"));
        assert!(read(&[0, 0, 4, 0], 0)
            .unwrap_err()
            .contains("not a Mitsuba serialized mesh"));
        let mut v9 = file.clone();
        v9[2] = 9;
        assert!(read(&v9, 0).unwrap_err().contains("version 9"));
        assert!(read(&file[..40], 0).unwrap_err().contains("stream"));
        let bad = legacy(3, &[[0.0; 3]; 3], &[[0, 1, 7]]);
        assert!(read(&bad, 0).unwrap_err().contains("names vertex 7"));
        let nan = legacy(3, &[[f32::NAN, 0.0, 0.0]; 3], &[[0, 1, 2]]);
        assert!(read(&nan, 0).unwrap_err().contains("not a finite point"));
    }
}
