//! The photon map file (`hmdist photons build`, `render --photon-map`): `HMDPMAP2`, a header
//! saying which render the map belongs to and what tracing it cost, the tree and every
//! column, little-endian, and a checksum of all of it. Read back with every length checked
//! and the checksum compared: a truncated, foreign or damaged file is an error that names the
//! problem, never a panic and never a different image.

use super::{Payloads, PhotonMap, PhotonMethod, LEAF};

/// What a photon map file says besides the map: which render it belongs to and what tracing
/// it cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MapHeader {
    /// Hash of the scene, the photon parameters, the seed (and the image size, for
    /// camera-sourced photons) and hmdist's version.
    pub fingerprint: u64,
    /// Photons stored.
    pub photons_stored: u64,
    /// Paths traced to store them.
    pub paths_traced: u64,
    /// Stored photons whose continuation escaped.
    pub escaped_photons: u64,
    /// Rays the tracing cast.
    pub rays_cast: u64,
    /// Of those, rays that met nothing.
    pub escaped_rays: u64,
}

/// The first bytes of a photon map file, with its format's version (2: with a checksum).
const MAGIC: &[u8; 8] = b"HMDPMAP2";

/// The checksum a map file ends with: 64-bit FNV-1a of every byte before it.
fn checksum(bytes: &[u8]) -> [u8; 8] {
    crate::scene::stable_hash(bytes).to_le_bytes()
}

impl PhotonMap {
    /// The map as a file: `MAGIC` (`HMDPMAP2`), the header, the tree and every column,
    /// little-endian, then the checksum of all of it.
    pub fn to_bytes(&self, header: &MapHeader) -> Vec<u8> {
        let mut out = MAGIC.to_vec();
        let method = match self.payloads {
            Payloads::StoredDistance { .. } => 1u64,
            Payloads::NextHitPoint { .. } => 2,
        };
        for v in [
            header.fingerprint,
            header.photons_stored,
            header.paths_traced,
            header.escaped_photons,
            header.rays_cast,
            header.escaped_rays,
            method,
            self.depth as u64,
            self.len() as u64,
        ] {
            out.extend(v.to_le_bytes());
        }
        let floats = |out: &mut Vec<u8>, v: &[f32]| out.extend(v.iter().flat_map(|f| f.to_le_bytes()));
        floats(&mut out, &self.planes);
        out.extend(&self.axes);
        for column in [&self.x, &self.y, &self.z] {
            floats(&mut out, column);
        }
        out.extend(self.normals.iter().flatten().flat_map(|n| n.to_le_bytes()));
        match &self.payloads {
            Payloads::StoredDistance { distance } => floats(&mut out, distance),
            Payloads::NextHitPoint { qx, qy, qz } => {
                for column in [qx, qy, qz] {
                    floats(&mut out, column);
                }
            }
        }
        let sum = checksum(&out);
        out.extend(sum);
        out
    }

    /// A map from the bytes of [`PhotonMap::to_bytes`], checked: magic, version, method,
    /// every length and the checksum; the message says what is wrong.
    pub fn from_bytes(
        file: &[u8],
        method: PhotonMethod,
    ) -> std::result::Result<(PhotonMap, MapHeader), String> {
        let (bytes, sum) = file.split_at(file.len().saturating_sub(8));
        let mut r = Reader { bytes, at: 0 };
        if r.take(8)? != MAGIC {
            return Err("is not an hmdist photon map (version 1)".into());
        }
        let mut words = [0u64; 9];
        for w in &mut words {
            *w = u64::from_le_bytes(r.take(8)?.try_into().expect("8 bytes"));
        }
        let [fingerprint, photons_stored, paths_traced, escaped_photons, rays_cast, escaped_rays, kind, depth, n] =
            words;
        let expected = match method {
            PhotonMethod::StoredDistance => 1,
            PhotonMethod::NextHitPoint => 2,
        };
        if kind != expected {
            return Err(format!("is a map for photon{kind}, not {}", method.name()));
        }
        let leaves = usize::try_from(n).unwrap_or(usize::MAX).div_ceil(LEAF).max(1);
        if n > u32::MAX as u64 || depth != leaves.next_power_of_two().trailing_zeros() as u64 {
            return Err("has an inconsistent tree".into());
        }
        let (n, internal) = (n as usize, (1usize << depth) - 1);
        let planes = r.floats(internal)?;
        let axes = r.take(internal)?.to_vec();
        if axes.iter().any(|&a| a > 2) {
            return Err("has an inconsistent tree".into());
        }
        let (x, y, z) = (r.floats(n)?, r.floats(n)?, r.floats(n)?);
        let normals = r
            .take(4 * n)?
            .chunks_exact(4)
            .map(|c| [u16::from_le_bytes([c[0], c[1]]), u16::from_le_bytes([c[2], c[3]])])
            .collect();
        let payloads = match method {
            PhotonMethod::StoredDistance => Payloads::StoredDistance {
                distance: r.floats(n)?,
            },
            PhotonMethod::NextHitPoint => Payloads::NextHitPoint {
                qx: r.floats(n)?,
                qy: r.floats(n)?,
                qz: r.floats(n)?,
            },
        };
        if r.at != bytes.len() {
            return Err("has bytes after its end".into());
        }
        if sum != checksum(bytes) {
            return Err("is damaged: its checksum does not match its contents (build it again with hmdist photons build)".into());
        }
        let header = MapHeader {
            fingerprint,
            photons_stored,
            paths_traced,
            escaped_photons,
            rays_cast,
            escaped_rays,
        };
        let map = PhotonMap {
            planes,
            axes,
            depth: depth as u32,
            x,
            y,
            z,
            normals,
            payloads,
        };
        Ok((map, header))
    }
}

/// Reads a photon map file front to back.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> std::result::Result<&'a [u8], String> {
        let end = self.at.checked_add(n).ok_or("is truncated")?;
        let part = self.bytes.get(self.at..end).ok_or("is truncated")?;
        self.at = end;
        Ok(part)
    }

    fn floats(&mut self, n: usize) -> std::result::Result<Vec<f32>, String> {
        let bytes = self.take(n.checked_mul(4).ok_or("is truncated")?)?;
        Ok(bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
            .collect())
    }
}
