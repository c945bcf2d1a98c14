//! Reader of the frames `fields/step_NNNNNN.vtu` that drape writes: VTK XML
//! UnstructuredGrid with raw appended binary data.
//!
//! The XML header is scanned for its `DataArray` tags (name, type,
//! components, `offset`); the appended block starts just after the `_`
//! that follows `<AppendedData encoding="raw">`, and each array there is a
//! byte count (`UInt64`, or `UInt32` with `header_type="UInt32"`) followed by
//! its little-endian values. Every count, offset, index and cell type is
//! checked, so a truncated or foreign file gives an error naming the file and
//! the array, never a panic.

use std::path::{Path, PathBuf};

use crate::error::{RenderError, Result};

/// VTK cell type of the 3-node triangle.
pub const VTK_TRIANGLE: u8 = 5;
/// VTK cell type of the 6-node quadratic triangle.
pub const VTK_QUADRATIC_TRIANGLE: u8 = 22;
/// VTK cell type of the Lagrange triangle (10 nodes: order 3).
pub const VTK_LAGRANGE_TRIANGLE: u8 = 69;

/// One named point or cell array, converted to `f64`, `components` values
/// per tuple, interleaved.
#[derive(Debug, Clone)]
pub struct Array {
    /// The array's name.
    pub name: String,
    /// Values per tuple.
    pub components: usize,
    /// The values.
    pub values: Vec<f64>,
}

/// One frame of the time series.
#[derive(Debug, Clone)]
pub struct Frame {
    /// The file it was read from.
    pub path: PathBuf,
    /// Field data `TIME` (`None` if the file has none).
    pub time: Option<f64>,
    /// Current node positions.
    pub points: Vec<[f64; 3]>,
    /// Node indices of each cell, concatenated; cell `c` is
    /// `connectivity[offsets[c]..offsets[c + 1]]`.
    pub connectivity: Vec<usize>,
    /// Start of each cell in `connectivity`, plus the total length at the end
    /// (`cells + 1` entries, starting with 0).
    pub offsets: Vec<usize>,
    /// VTK cell type of each cell (5, 22 or 69).
    pub types: Vec<u8>,
    /// Arrays with one tuple per point.
    pub point_data: Vec<Array>,
    /// Arrays with one tuple per cell.
    pub cell_data: Vec<Array>,
}

impl Frame {
    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.types.len()
    }

    /// Node indices of cell `c`.
    pub fn cell(&self, c: usize) -> &[usize] {
        &self.connectivity[self.offsets[c]..self.offsets[c + 1]]
    }

    /// The point array named `name`.
    pub fn point_array(&self, name: &str) -> Option<&Array> {
        self.point_data.iter().find(|a| a.name == name)
    }

    /// The cell array named `name`.
    pub fn cell_array(&self, name: &str) -> Option<&Array> {
        self.cell_data.iter().find(|a| a.name == name)
    }

    /// Refuses a frame that holds a value that is not finite — a point's
    /// position, or a value of a point array (`displacement`, `velocity`,
    /// ...) or a cell array (`stress`, ...) — naming the file, the array and
    /// the first node or cell. drape writes finite values only (a state
    /// that is not finite is never recorded), so such a frame is damaged;
    /// drawn, it would be blank or coloured on a scale of NaN, and measured,
    /// meaningless.
    ///
    /// # Errors
    /// [`RenderError::Format`] for the first value that is not finite.
    pub fn check_finite(&self) -> Result<()> {
        let damaged = |what: String| {
            Err(RenderError::format(
                &self.path,
                format!("{what}; drape writes finite values only, so the frame is damaged"),
            ))
        };
        if let Some((k, p)) =
            (self.points.iter().enumerate()).find(|(_, p)| !p.iter().all(|x| x.is_finite()))
        {
            return damaged(format!(
                "point {k} (0-based) has no finite position ({p:?})"
            ));
        }
        for (kind, item, arrays) in [
            ("point", "node", &self.point_data),
            ("cell", "cell", &self.cell_data),
        ] {
            for a in arrays {
                if let Some(i) = a.values.iter().position(|v| !v.is_finite()) {
                    let c = a.components.max(1);
                    return damaged(format!(
                        "the {kind} array {:?} holds {} at {item} {} (0-based), component {}",
                        a.name,
                        a.values[i],
                        i / c,
                        i % c
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Reads the frame at `path`.
///
/// # Errors
/// [`RenderError::Io`] if the file cannot be read, [`RenderError::Format`] if
/// it is not a raw-appended little-endian UnstructuredGrid of triangles, or
/// is truncated or inconsistent.
pub fn read_vtu(path: &Path) -> Result<Frame> {
    let bytes = std::fs::read(path).map_err(|e| RenderError::io(path, e))?;
    parse_vtu(path, &bytes)
}

/// Section of the XML header a `DataArray` tag belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Section {
    Field,
    PointData,
    CellData,
    Points,
    Cells,
    Other,
}

#[derive(Debug)]
struct Tag<'a> {
    section: Section,
    attrs: Vec<(&'a str, String)>,
    /// Text between `>` and `</DataArray>` for non-self-closing tags.
    body: Option<&'a str>,
}

impl Tag<'_> {
    fn get(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, v)| v.as_str())
    }
}

/// Parses `key="value"` pairs of one tag's inside (after the tag name).
fn parse_attrs(s: &str) -> Option<Vec<(&str, String)>> {
    let mut out = Vec::new();
    let mut rest = s.trim_start();
    while !rest.is_empty() && !rest.starts_with('/') {
        let eq = rest.find('=')?;
        let key = rest[..eq].trim();
        let after = rest[eq + 1..].trim_start();
        let quote = after.chars().next()?;
        if quote != '"' && quote != '\'' {
            return None;
        }
        let end = after[1..].find(quote)? + 1;
        out.push((key, unescape(&after[1..end])));
        rest = after[end + 1..].trim_start();
    }
    Some(out)
}

fn unescape(s: &str) -> String {
    s.replace("&quot;", "\"")
        .replace("&apos;", "'")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
}

/// The opening tag `<name ...>` that starts at byte `at` of `header`, as its
/// attribute text.
fn tag_attr_text<'a>(header: &'a str, at: usize, name: &str) -> Option<&'a str> {
    let start = at + name.len() + 1;
    let end = header[start..].find('>')? + start;
    Some(&header[start..end])
}

fn section_at(header: &str, pos: usize) -> Section {
    let before = &header[..pos];
    let candidates = [
        ("FieldData", Section::Field),
        ("PointData", Section::PointData),
        ("CellData", Section::CellData),
        ("Points", Section::Points),
        ("Cells", Section::Cells),
    ];
    let mut best: Option<(usize, Section)> = None;
    for (name, section) in candidates {
        let open = format!("<{name}>");
        let open_attr = format!("<{name} ");
        let close = format!("</{name}>");
        let last_open = before
            .rfind(&open)
            .into_iter()
            .chain(before.rfind(&open_attr))
            .max();
        if let Some(o) = last_open {
            let closed = before[o..].contains(&close);
            if !closed && best.is_none_or(|(b, _)| o > b) {
                best = Some((o, section));
            }
        }
    }
    best.map_or(Section::Other, |(_, s)| s)
}

fn parse_header<'a>(path: &Path, header: &'a str) -> Result<Vec<Tag<'a>>> {
    let mut tags = Vec::new();
    let mut search = 0;
    while let Some(rel) = header[search..].find("<DataArray") {
        let at = search + rel;
        let inner = tag_attr_text(header, at, "DataArray")
            .ok_or_else(|| RenderError::format(path, "unterminated <DataArray> tag"))?;
        let attrs = parse_attrs(inner).ok_or_else(|| {
            RenderError::format(
                path,
                format!("cannot parse the attributes <DataArray{inner}>"),
            )
        })?;
        let tag_end = at + "<DataArray".len() + inner.len() + 1;
        let body = if inner.trim_end().ends_with('/') {
            None
        } else {
            let close = header[tag_end..]
                .find("</DataArray>")
                .ok_or_else(|| RenderError::format(path, "a <DataArray> tag is never closed"))?;
            Some(&header[tag_end..tag_end + close])
        };
        tags.push(Tag {
            section: section_at(header, at),
            attrs,
            body,
        });
        search = tag_end;
    }
    Ok(tags)
}

/// Byte size of one value of VTK type `ty`.
fn type_size(ty: &str) -> Option<usize> {
    Some(match ty {
        "Float64" | "Int64" | "UInt64" => 8,
        "Float32" | "Int32" | "UInt32" => 4,
        "Int16" | "UInt16" => 2,
        "Int8" | "UInt8" => 1,
        _ => return None,
    })
}

fn decode(ty: &str, bytes: &[u8]) -> Vec<f64> {
    macro_rules! conv {
        ($t:ty, $n:expr) => {
            bytes
                .chunks_exact($n)
                .map(|c| <$t>::from_le_bytes(c.try_into().expect("chunk size")) as f64)
                .collect()
        };
    }
    match ty {
        "Float64" => conv!(f64, 8),
        "Float32" => conv!(f32, 4),
        "Int64" => conv!(i64, 8),
        "UInt64" => conv!(u64, 8),
        "Int32" => conv!(i32, 4),
        "UInt32" => conv!(u32, 4),
        "Int16" => conv!(i16, 2),
        "UInt16" => conv!(u16, 2),
        "Int8" => conv!(i8, 1),
        _ => bytes.iter().map(|&b| b as f64).collect(),
    }
}

/// Parses a whole `.vtu` file already in memory (`path` is for messages).
///
/// # Errors
/// As [`read_vtu`].
pub fn parse_vtu(path: &Path, bytes: &[u8]) -> Result<Frame> {
    let err = |m: String| RenderError::format(path, m);
    let appended = Appended::find(path, bytes)?;
    let (n_points, n_cells) = piece_sizes(path, appended.header)?;
    let arrays = read_arrays(path, &appended)?;
    let (pvals, pcomp) = arrays.points.ok_or_else(|| err("no Points array".into()))?;
    if pcomp != 3 || pvals.len() != 3 * n_points {
        return Err(err(format!(
            "Points: expected {n_points} points of 3 components, got {} values of {pcomp}",
            pvals.len()
        )));
    }
    let points: Vec<[f64; 3]> = pvals.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let conn = arrays
        .connectivity
        .ok_or_else(|| err("no connectivity array".into()))?;
    let offs = arrays
        .offsets
        .ok_or_else(|| err("no offsets array".into()))?;
    let types_f = arrays.types.ok_or_else(|| err("no types array".into()))?;
    if offs.len() != n_cells || types_f.len() != n_cells {
        return Err(err(format!(
            "expected {n_cells} cells, got {} offsets and {} types",
            offs.len(),
            types_f.len()
        )));
    }
    let connectivity = point_indices(path, &conn, n_points)?;
    let (offsets, types) = cells(path, &offs, &types_f, connectivity.len())?;
    for (arrays, count, kind) in [
        (&arrays.point_data, n_points, "point"),
        (&arrays.cell_data, n_cells, "cell"),
    ] {
        for a in arrays {
            if a.values.len() != a.components * count {
                return Err(err(format!(
                    "{kind} array {:?}: {} values for {count} tuples of {} components",
                    a.name,
                    a.values.len(),
                    a.components
                )));
            }
        }
    }
    Ok(Frame {
        path: path.to_owned(),
        time: arrays.time,
        points,
        connectivity,
        offsets,
        types,
        point_data: arrays.point_data,
        cell_data: arrays.cell_data,
    })
}

/// A raw appended VTU file taken apart: the XML header before
/// `<AppendedData`, the appended block after its `_`, and the byte size
/// of the block's counts.
struct Appended<'a> {
    header: &'a str,
    data: &'a [u8],
    header_bytes: usize,
}

impl<'a> Appended<'a> {
    /// Checks that `bytes` is a little-endian, uncompressed
    /// UnstructuredGrid with raw appended data, and finds its parts.
    fn find(path: &Path, bytes: &'a [u8]) -> Result<Self> {
        let err = |m: String| RenderError::format(path, m);
        let marker = b"<AppendedData";
        let app = find(bytes, marker).ok_or_else(|| {
            err(
                "no <AppendedData> block (only raw appended VTU files, as drape writes, are read)"
                    .into(),
            )
        })?;
        let header = std::str::from_utf8(&bytes[..app])
            .map_err(|_| err("the XML header is not UTF-8".into()))?;
        if !header.contains("type=\"UnstructuredGrid\"") {
            return Err(err("not a VTK UnstructuredGrid file".into()));
        }
        if header.contains("byte_order=\"BigEndian\"") {
            return Err(err("big-endian files are not supported".into()));
        }
        if header.contains("compressor=") {
            return Err(err("compressed files are not supported".into()));
        }
        let header_bytes = if header.contains("header_type=\"UInt32\"") {
            4
        } else {
            8
        };
        let app_tag_end = bytes[app..]
            .iter()
            .position(|&b| b == b'>')
            .map(|p| app + p)
            .ok_or_else(|| err("unterminated <AppendedData> tag".into()))?;
        let app_tag = String::from_utf8_lossy(&bytes[app..app_tag_end]);
        if !app_tag.contains("encoding=\"raw\"") {
            return Err(err(
                "the appended data is not raw (only encoding=\"raw\" is read)".into(),
            ));
        }
        let underscore = bytes[app_tag_end..]
            .iter()
            .position(|&b| b == b'_')
            .map(|p| app_tag_end + p)
            .ok_or_else(|| err("no '_' marker opening the appended data".into()))?;
        Ok(Self {
            header,
            data: &bytes[underscore + 1..],
            header_bytes,
        })
    }
}

/// `NumberOfPoints` and `NumberOfCells` of the header's `<Piece>`.
fn piece_sizes(path: &Path, header: &str) -> Result<(usize, usize)> {
    let err = |m: String| RenderError::format(path, m);
    let piece_at = header
        .find("<Piece")
        .ok_or_else(|| err("no <Piece> element".into()))?;
    let piece = parse_attrs(
        tag_attr_text(header, piece_at, "Piece").ok_or_else(|| err("bad <Piece> tag".into()))?,
    )
    .ok_or_else(|| err("cannot parse the <Piece> attributes".into()))?;
    let piece_num = |key: &str| -> Result<usize> {
        piece
            .iter()
            .find(|(k, _)| *k == key)
            .and_then(|(_, v)| v.trim().parse().ok())
            .ok_or_else(|| err(format!("<Piece> has no valid {key}")))
    };
    Ok((piece_num("NumberOfPoints")?, piece_num("NumberOfCells")?))
}

/// Every array of a file as read, before the sizes are checked.
#[derive(Default)]
struct Arrays {
    time: Option<f64>,
    /// The values and their components.
    points: Option<(Vec<f64>, usize)>,
    connectivity: Option<Vec<f64>>,
    offsets: Option<Vec<f64>>,
    types: Option<Vec<f64>>,
    point_data: Vec<Array>,
    cell_data: Vec<Array>,
}

/// The header's `DataArray`s, their values read from the appended block
/// (and the field data `TIME` from the header).
fn read_arrays(path: &Path, appended: &Appended) -> Result<Arrays> {
    let err = |m: String| RenderError::format(path, m);
    let mut arrays = Arrays::default();
    for tag in &parse_header(path, appended.header)? {
        let name = tag.get("Name").unwrap_or("").to_owned();
        let ty = tag
            .get("type")
            .ok_or_else(|| err(format!("array {name:?} has no type")))?;
        let size =
            type_size(ty).ok_or_else(|| err(format!("array {name:?}: unsupported type {ty}")))?;
        let components: usize = match tag.get("NumberOfComponents") {
            Some(c) => c
                .trim()
                .parse()
                .ok()
                .filter(|&c| c > 0)
                .ok_or_else(|| err(format!("array {name:?}: bad NumberOfComponents {c:?}")))?,
            None => 1,
        };
        if tag.section == Section::Field {
            if name == "TIME" {
                let text = tag.body.unwrap_or("").trim();
                let t: f64 = text
                    .split_whitespace()
                    .next()
                    .and_then(|s| s.parse().ok())
                    .ok_or_else(|| err(format!("field data TIME {text:?} is not a number")))?;
                arrays.time = Some(t);
            }
            continue;
        }
        let format = tag.get("format").unwrap_or("");
        if format != "appended" {
            return Err(err(format!(
                "array {name:?} has format {format:?} (only \"appended\" is read)"
            )));
        }
        let offset: usize = tag
            .get("offset")
            .and_then(|o| o.trim().parse().ok())
            .ok_or_else(|| err(format!("array {name:?} has no valid offset")))?;
        let (data, header_bytes) = (appended.data, appended.header_bytes);
        let values = read_block(path, data, offset, header_bytes, size, ty, &name)?;
        match (tag.section, name.as_str()) {
            (Section::Points, _) => arrays.points = Some((values, components)),
            (Section::Cells, "connectivity") => arrays.connectivity = Some(values),
            (Section::Cells, "offsets") => arrays.offsets = Some(values),
            (Section::Cells, "types") => arrays.types = Some(values),
            (Section::PointData, _) => arrays.point_data.push(Array {
                name,
                components,
                values,
            }),
            (Section::CellData, _) => arrays.cell_data.push(Array {
                name,
                components,
                values,
            }),
            _ => {}
        }
    }
    Ok(arrays)
}

/// The connectivity as indices: each a whole number below `n_points`.
fn point_indices(path: &Path, conn: &[f64], n_points: usize) -> Result<Vec<usize>> {
    let mut connectivity = Vec::with_capacity(conn.len());
    for &v in conn {
        if !(v >= 0.0 && v < n_points as f64 && v.fract() == 0.0) {
            return Err(RenderError::format(
                path,
                format!("connectivity holds {v}, not a point index below {n_points}"),
            ));
        }
        connectivity.push(v as usize);
    }
    Ok(connectivity)
}

/// The cells' offsets (from 0, ending at the connectivity's `length`)
/// and types: each a triangle of order 1, 2 or 3 with its number of
/// nodes.
fn cells(
    path: &Path,
    offs: &[f64],
    types_f: &[f64],
    length: usize,
) -> Result<(Vec<usize>, Vec<u8>)> {
    let err = |m: String| RenderError::format(path, m);
    let mut offsets = Vec::with_capacity(offs.len() + 1);
    offsets.push(0usize);
    let mut types = Vec::with_capacity(offs.len());
    for (c, (&o, &t)) in offs.iter().zip(types_f).enumerate() {
        let prev = *offsets.last().expect("non-empty");
        if !(o >= prev as f64 && o <= length as f64) {
            return Err(err(format!("cell {c}: offset {o} out of order or range")));
        }
        let o = o as usize;
        let t = t as u8;
        let expected = match t {
            VTK_TRIANGLE => 3,
            VTK_QUADRATIC_TRIANGLE => 6,
            VTK_LAGRANGE_TRIANGLE => 10,
            _ => {
                return Err(err(format!(
                    "cell {c}: VTK type {t} is not a triangle of order 1, 2 or 3"
                )));
            }
        };
        if o - prev != expected {
            return Err(err(format!(
                "cell {c}: type {t} needs {expected} nodes, has {}",
                o - prev
            )));
        }
        offsets.push(o);
        types.push(t);
    }
    if offsets.last() != Some(&length) {
        return Err(err(format!(
            "the offsets end at {}, the connectivity has {length} entries",
            offsets.last().unwrap_or(&0),
        )));
    }
    Ok((offsets, types))
}

fn read_block(
    path: &Path,
    data: &[u8],
    offset: usize,
    header_bytes: usize,
    size: usize,
    ty: &str,
    name: &str,
) -> Result<Vec<f64>> {
    let truncated = || {
        RenderError::format(
            path,
            format!("array {name:?} at appended offset {offset}: the file is truncated"),
        )
    };
    let head = data
        .get(offset..offset.checked_add(header_bytes).ok_or_else(truncated)?)
        .ok_or_else(truncated)?;
    let n = if header_bytes == 8 {
        u64::from_le_bytes(head.try_into().expect("8 bytes"))
    } else {
        u32::from_le_bytes(head.try_into().expect("4 bytes")) as u64
    };
    let n = usize::try_from(n).map_err(|_| truncated())?;
    if n % size != 0 {
        return Err(RenderError::format(
            path,
            format!("array {name:?}: {n} bytes is not a whole number of {ty} values"),
        ));
    }
    let start = offset + header_bytes;
    let body = data
        .get(start..start.checked_add(n).ok_or_else(truncated)?)
        .ok_or_else(truncated)?;
    Ok(decode(ty, body))
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attrs() {
        let a = parse_attrs(r#" type="Float64" Name="a&amp;b" offset='12'/"#).unwrap();
        assert_eq!(a[0], ("type", "Float64".to_owned()));
        assert_eq!(a[1], ("Name", "a&b".to_owned()));
        assert_eq!(a[2], ("offset", "12".to_owned()));
    }

    /// The first value that is not finite is named by its array, its node
    /// or cell and its component; positions come first, then point arrays,
    /// then cell arrays.
    #[test]
    fn check_finite_names_the_first_value_that_is_not() {
        let array = |name: &str, values: Vec<f64>| Array {
            name: name.into(),
            components: 3,
            values,
        };
        let mut frame = Frame {
            path: "f.vtu".into(),
            time: None,
            points: vec![[0.0; 3]; 3],
            connectivity: vec![0, 1, 2],
            offsets: vec![0, 3],
            types: vec![VTK_TRIANGLE],
            point_data: vec![array("velocity", vec![0.0; 9])],
            cell_data: vec![array("stress", vec![0.0; 3])],
        };
        assert!(frame.check_finite().is_ok());
        frame.cell_data[0].values[1] = f64::NAN;
        let e = frame.check_finite().unwrap_err().to_string();
        assert!(
            e.starts_with(
                "f.vtu: the cell array \"stress\" holds NaN at cell 0 (0-based), component 1"
            ),
            "{e}"
        );
        frame.point_data[0].values[7] = f64::INFINITY;
        let e = frame.check_finite().unwrap_err().to_string();
        assert!(
            e.contains("point array \"velocity\" holds inf at node 2 (0-based), component 1"),
            "{e}"
        );
        frame.points[1][2] = f64::NAN;
        let e = frame.check_finite().unwrap_err().to_string();
        assert!(
            e.contains("point 1 (0-based) has no finite position"),
            "{e}"
        );
        assert!(e.ends_with("the frame is damaged"), "{e}");
    }

    #[test]
    fn garbage_is_an_error() {
        let p = Path::new("x.vtu");
        assert!(parse_vtu(p, b"").is_err());
        assert!(parse_vtu(p, b"<VTKFile><AppendedData encoding=\"raw\">_").is_err());
        assert!(parse_vtu(p, &[0xff; 100]).is_err());
    }
}
