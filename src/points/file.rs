//! Point files for `hmdist points` (spec §8): rows `x y z nx ny nz` in, H per row out, as
//! `.npy` (read: float32 or float64 of shape [n, 6], C or Fortran order; written: float32 of
//! shape `[n]`) or CSV (six numbers per line, commas or spaces; a header line, blank lines and
//! `#` comments are skipped; written: one value per line), by extension. `.npy` needs the
//! `npy` feature (on with `cli`).

use std::path::Path;

use crate::error::{catch_file_panic, Error, Result};

/// The formats of a point file, by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointFormat {
    /// NumPy's `.npy`.
    Npy,
    /// Comma- (or space-) separated text.
    Csv,
}

impl PointFormat {
    /// The format of `path` by its extension (case-insensitive): `.npy` or `.csv`.
    pub fn of(path: &Path) -> Result<PointFormat> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
        {
            Some(e) if e == "npy" => Ok(PointFormat::Npy),
            Some(e) if e == "csv" => Ok(PointFormat::Csv),
            _ => Err(Error::file(path, "is neither .npy nor .csv")),
        }
    }
}

/// The rows of the point file at `path`.
pub fn read_rows(path: &Path) -> Result<Vec<[f32; 6]>> {
    PointFormat::of(path)?;
    let bytes = crate::files::read_regular(path)?;
    parse_rows(path, &bytes)
}

/// [`read_rows`] of the file at `path` whose bytes are `bytes`. At least one row; the values
/// are not checked (a [`super::SurfacePoint`] checks its own).
pub fn parse_rows(path: &Path, bytes: &[u8]) -> Result<Vec<[f32; 6]>> {
    match PointFormat::of(path)? {
        // npyz arithmetic on a header's shape is not ours to check: a panic there is caught.
        PointFormat::Npy => catch_file_panic(path, || parse_npy(path, bytes)),
        PointFormat::Csv => parse_csv(path, bytes),
    }
}

/// The bytes of the file `path` holding `hmd`, one value per row, in its format.
pub fn encode_values(path: &Path, hmd: &[f32]) -> Result<Vec<u8>> {
    Ok(match PointFormat::of(path)? {
        PointFormat::Npy => npy_bytes(path, hmd)?,
        PointFormat::Csv => hmd
            .iter()
            .map(|h| format!("{h}\n"))
            .collect::<String>()
            .into_bytes(),
    })
}

/// Rows of an `.npy` file of shape [n, 6], float32 or float64, in C or Fortran order.
#[cfg(feature = "npy")]
fn parse_npy(path: &Path, bytes: &[u8]) -> Result<Vec<[f32; 6]>> {
    check_header_nesting(path, bytes)?;
    let npy = npyz::NpyFile::new(bytes).map_err(|e| {
        // The parser's message spans lines (the header, a caret): one line.
        let message = e.to_string().split_whitespace().collect::<Vec<_>>().join(" ");
        Error::file(path, format!("is not an .npy file: {message}"))
    })?;
    let shape = npy.shape().to_vec();
    let fortran = npy.order() == npyz::Order::Fortran;
    let dtype = npy.dtype().descr();
    let [n, 6] = shape[..] else {
        return Err(Error::file(path, format!("has shape {shape:?}: expected [n, 6]")));
    };
    // The values must be in the file: a header claiming more rows than the bytes hold is
    // refused before anything is allocated for them.
    let most = bytes.len() as u64 / 6 / 4;
    if n > most {
        let message = format!("has shape [{n}, 6] but only {} bytes", bytes.len());
        return Err(Error::file(path, message));
    }
    let n = n as usize;
    let bad = |e: std::io::Error| Error::file(path, format!("cannot read its values: {e}"));
    let values: Vec<f32> = match npy.try_data::<f32>() {
        Ok(data) => data.collect::<std::io::Result<_>>().map_err(bad)?,
        Err(npy) => match npy.try_data::<f64>() {
            Ok(data) => {
                let values: Vec<f64> = data.collect::<std::io::Result<_>>().map_err(bad)?;
                values.into_iter().map(|v| v as f32).collect()
            }
            Err(_) => {
                let message = format!("holds {dtype}: expected float32 or float64");
                return Err(Error::file(path, message));
            }
        },
    };
    if values.len() != n * 6 {
        let message = format!("holds {} values for shape [{n}, 6]", values.len());
        return Err(Error::file(path, message));
    }
    rows(path, n, |r, c| {
        values[if fortran { c * n + r } else { r * 6 + c }]
    })
}

/// Brackets a `.npy` header may nest: numpy's own nest at most 4 deep (a structured dtype's
/// list of tuples with a sub-array shape, inside the dictionary).
#[cfg(feature = "npy")]
const MAX_HEADER_NESTING: usize = 8;

/// Refuses a header whose brackets nest deeper than [`MAX_HEADER_NESTING`], before npyz
/// parses it: its parser of Python literals backtracks, doubling its time with each unclosed
/// bracket (a 181-byte file opening 51 lists ran for more than 14 minutes under the fuzzer;
/// 8 take a few milliseconds, 20 five seconds). A header that cannot be found is left to
/// npyz to refuse.
#[cfg(feature = "npy")]
fn check_header_nesting(path: &Path, bytes: &[u8]) -> Result<()> {
    let header = match bytes.get(6) {
        Some(1) => bytes
            .get(8..10)
            .map(|n| (10, u16::from_le_bytes([n[0], n[1]]) as usize)),
        Some(2 | 3) => bytes
            .get(8..12)
            .map(|n| (12, u32::from_le_bytes([n[0], n[1], n[2], n[3]]) as usize)),
        _ => None,
    };
    let Some((start, length)) = header else {
        return Ok(());
    };
    let text = &bytes[start.min(bytes.len())..start.saturating_add(length).min(bytes.len())];
    let (mut depth, mut deepest) = (0usize, 0usize);
    for b in text {
        match b {
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
        deepest = deepest.max(depth);
    }
    if deepest > MAX_HEADER_NESTING {
        let message =
            format!("is not an .npy file: its header nests brackets {deepest} deep (numpy's nest at most 4)");
        return Err(Error::file(path, message));
    }
    Ok(())
}

#[cfg(not(feature = "npy"))]
fn parse_npy(path: &Path, _: &[u8]) -> Result<Vec<[f32; 6]>> {
    Err(without_npy(path))
}

#[cfg(not(feature = "npy"))]
fn without_npy(path: &Path) -> Error {
    Error::file(
        path,
        "this build of hmdist reads and writes no .npy files (feature npy)",
    )
}

/// H as an `.npy` file: float32, shape [n].
#[cfg(feature = "npy")]
fn npy_bytes(_: &Path, hmd: &[f32]) -> Result<Vec<u8>> {
    use npyz::WriterBuilder;
    let mut bytes = vec![];
    let mut writer = npyz::WriteOptions::new()
        .default_dtype()
        .shape(&[hmd.len() as u64])
        .writer(&mut bytes)
        .begin_nd()
        .expect("writing to memory");
    writer.extend(hmd.iter().copied()).expect("writing to memory");
    writer.finish().expect("writing to memory");
    Ok(bytes)
}

#[cfg(not(feature = "npy"))]
fn npy_bytes(path: &Path, _: &[f32]) -> Result<Vec<u8>> {
    Err(without_npy(path))
}

/// Rows of a CSV file: six numbers per line, separated by commas (or spaces); a header (the
/// first line with text, if none of its fields is a number), blank lines, `#` comments (whole
/// lines or the end of one) and a UTF-8 byte-order mark are skipped. A first line with some
/// numbers and some text is a bad row, not a header.
fn parse_csv(path: &Path, bytes: &[u8]) -> Result<Vec<[f32; 6]>> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count();
        Error::file_line(path, line, "not UTF-8 text")
    })?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut out = vec![];
    let mut first = true;
    for (i, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split([',', ' ', '\t']).filter(|f| !f.is_empty()).collect();
        let numbers: Vec<f32> = fields.iter().filter_map(|f| f.trim().parse().ok()).collect();
        let header = std::mem::take(&mut first) && numbers.is_empty();
        if header {
            continue;
        }
        if numbers.len() != 6 || fields.len() != 6 {
            let message = format!("expected 6 numbers (x y z nx ny nz), found '{line}'");
            return Err(Error::file_line(path, i + 1, message));
        }
        out.push([
            numbers[0], numbers[1], numbers[2], numbers[3], numbers[4], numbers[5],
        ]);
    }
    rows(path, out.len(), |r, c| out[r][c])
}

/// `n` rows from `value(row, column)`; none is refused.
fn rows(path: &Path, n: usize, value: impl Fn(usize, usize) -> f32) -> Result<Vec<[f32; 6]>> {
    if n == 0 {
        return Err(Error::file(path, "holds no points"));
    }
    Ok((0..n).map(|r| std::array::from_fn(|c| value(r, c))).collect())
}
