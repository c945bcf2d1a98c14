//! VTK XML UnstructuredGrid (`.vtu`) writer for one frame of the time series
//! `fields/step_NNNNNN.vtu`.
//!
//! The file is an XML header followed by all arrays as raw binary appended
//! data (`<AppendedData encoding="raw">`, `header_type="UInt64"`,
//! `byte_order="LittleEndian"`): each array is an 8-byte little-endian byte
//! count followed by its values, found at the byte `offset` its `DataArray`
//! gives, counted from just after the `_` that opens the appended block. No
//! text conversion or base64 is involved, so frames of a million elements are
//! written at disk speed. The file is written atomically
//! ([`super::atomic::write_atomic_with`]).
//!
//! Arrays: `Points` (Float64 × 3), `connectivity` and `offsets` (Int64),
//! `types` (UInt8), then the caller's point and cell arrays (Float64 or
//! Int32). The frame's time is stored as the field-data array `TIME` (one
//! Float64, in ASCII so that it is readable with `head`).
//!
//! # Node order
//!
//! Element connectivity is in Gmsh order: the three vertices, then the edge
//! nodes of edges v0–v1, v1–v2, v2–v0 (each edge walked from its first
//! vertex), then the interior node of the 10-node triangle. This is exactly
//! VTK's order for both higher-order cells, so connectivity is written
//! unpermuted:
//!
//! - `VTK_QUADRATIC_TRIANGLE` (22): vertices, then mid-edge nodes of
//!   (0,1), (1,2), (2,0) — reference coordinates (0,0) (1,0) (0,1) (½,0)
//!   (½,½) (0,½), as Gmsh's 6-node triangle.
//! - `VTK_LAGRANGE_TRIANGLE` (69) with 10 points (order 3): vertices, then
//!   per edge in order (0,1), (1,2), (2,0) its two nodes starting next to the
//!   edge's first vertex, then the interior node — reference coordinates
//!   (0,0) (1,0) (0,1) (⅓,0) (⅔,0) (⅔,⅓) (⅓,⅔) (0,⅔) (0,⅓) (⅓,⅓), as Gmsh's
//!   10-node triangle. (Checked against `vtkLagrangeTriangle`'s parametric
//!   coordinates in VTK 9.)

use std::collections::HashSet;
use std::fmt::Write as _;
use std::io::{self, Write};
use std::path::Path;

use super::atomic::write_atomic_with;
use super::history::format_f64;
use super::pvd::escape_xml_attr;

/// VTK cell type of the 3-node linear triangle.
pub const VTK_TRIANGLE: u8 = 5;
/// VTK cell type of the 6-node quadratic triangle.
pub const VTK_QUADRATIC_TRIANGLE: u8 = 22;
/// VTK cell type of the arbitrary-order Lagrange triangle (used for the
/// 10-node cubic triangle).
pub const VTK_LAGRANGE_TRIANGLE: u8 = 69;

/// The VTK cell type for triangles of `nodes_per_element` nodes (3, 6 or 10),
/// or `None` for any other count.
pub fn vtk_cell_type(nodes_per_element: usize) -> Option<u8> {
    match nodes_per_element {
        3 => Some(VTK_TRIANGLE),
        6 => Some(VTK_QUADRATIC_TRIANGLE),
        10 => Some(VTK_LAGRANGE_TRIANGLE),
        _ => None,
    }
}

/// The values of a data array, stored as VTK `Float64` or `Int32`.
#[derive(Debug, Clone, Copy)]
pub enum Values<'a> {
    /// Floating-point values, written as `Float64`.
    F64(&'a [f64]),
    /// Integer values (e.g. flags, region ids), written as `Int32`.
    I32(&'a [i32]),
}

impl Values<'_> {
    /// Number of scalar values (tuples × components).
    pub fn len(&self) -> usize {
        match self {
            Values::F64(v) => v.len(),
            Values::I32(v) => v.len(),
        }
    }

    /// Whether there are no values.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn vtk_type(&self) -> &'static str {
        match self {
            Values::F64(_) => "Float64",
            Values::I32(_) => "Int32",
        }
    }

    fn byte_len(&self) -> u64 {
        match self {
            Values::F64(v) => 8 * v.len() as u64,
            Values::I32(v) => 4 * v.len() as u64,
        }
    }
}

/// One named point or cell array: `components` values per point (or cell),
/// interleaved (`x0 y0 z0 x1 y1 z1 …` for a vector).
#[derive(Debug, Clone)]
pub struct DataArray<'a> {
    /// Array name shown in ParaView; must be non-empty and unique among the
    /// point arrays (respectively the cell arrays) of a frame.
    pub name: &'a str,
    /// Values per point (or cell): 1 for a scalar, 3 for a vector, …
    pub components: usize,
    /// The values, `components × count` of them.
    pub values: Values<'a>,
    /// Names of the components (`ComponentName0`, … in the file): either
    /// empty or exactly `components` names.
    pub component_names: &'a [&'a str],
}

/// One frame: the deformed mesh and its fields at one time.
#[derive(Debug, Clone)]
pub struct Frame<'a> {
    /// Node positions.
    pub positions: &'a [[f64; 3]],
    /// Element connectivity, `nodes_per_element` node indices per element in
    /// Gmsh order (see the module doc).
    pub connectivity: &'a [usize],
    /// Nodes per element: 3, 6 or 10.
    pub nodes_per_element: usize,
    /// Arrays with one tuple per node.
    pub point_data: Vec<DataArray<'a>>,
    /// Arrays with one tuple per element.
    pub cell_data: Vec<DataArray<'a>>,
    /// Simulation time of the frame, stored as field data `TIME`.
    pub time: f64,
}

/// Writes `frame` to `path` as a VTK XML UnstructuredGrid with raw appended
/// binary data, atomically (temporary file in the same directory, then
/// rename).
///
/// The frame is fully validated before anything is written.
///
/// # Errors
/// `InvalidInput` if `nodes_per_element` is not 3, 6 or 10; the connectivity
/// length is not a multiple of it; a node index is out of range; `time` is
/// not finite; an array has zero components, a length other than
/// `components × count`, a number of component names other than 0 or
/// `components`, or an empty or duplicate name. Otherwise any I/O error.
pub fn write_vtu(path: &Path, frame: &Frame) -> io::Result<()> {
    let cell_type = validate(frame)?;
    let n_points = frame.positions.len();
    let n_cells = frame.connectivity.len() / frame.nodes_per_element;

    // Appended blocks, in file order, with their byte offsets.
    let mut offset: u64 = 0;
    let mut next = |bytes: u64| {
        let o = offset;
        offset += 8 + bytes;
        o
    };
    let off_points = next(24 * n_points as u64);
    let off_conn = next(8 * frame.connectivity.len() as u64);
    let off_offsets = next(8 * n_cells as u64);
    let off_types = next(n_cells as u64);
    let off_point_data: Vec<u64> = frame
        .point_data
        .iter()
        .map(|a| next(a.values.byte_len()))
        .collect();
    let off_cell_data: Vec<u64> = frame
        .cell_data
        .iter()
        .map(|a| next(a.values.byte_len()))
        .collect();

    let mut xml = String::with_capacity(4096);
    xml.push_str(
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n\
         \x20 <UnstructuredGrid>\n\
         \x20   <FieldData>\n",
    );
    let _ = writeln!(
        xml,
        "      <DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">{}</DataArray>",
        format_f64(frame.time)
    );
    xml.push_str("    </FieldData>\n");
    let _ = writeln!(
        xml,
        "    <Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">"
    );
    xml.push_str("      <PointData>\n");
    for (a, &o) in frame.point_data.iter().zip(&off_point_data) {
        push_array_tag(&mut xml, a, o);
    }
    xml.push_str("      </PointData>\n      <CellData>\n");
    for (a, &o) in frame.cell_data.iter().zip(&off_cell_data) {
        push_array_tag(&mut xml, a, o);
    }
    xml.push_str("      </CellData>\n      <Points>\n");
    let _ = writeln!(
        xml,
        "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" offset=\"{off_points}\"/>"
    );
    xml.push_str("      </Points>\n      <Cells>\n");
    let _ = writeln!(
        xml,
        "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"{off_conn}\"/>\n        \
         <DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"{off_offsets}\"/>\n        \
         <DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"{off_types}\"/>"
    );
    xml.push_str(
        "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _",
    );

    write_atomic_with(path, |w| {
        w.write_all(xml.as_bytes())?;

        write_block(
            w,
            3 * n_points,
            frame.positions.iter().flatten().map(|v| v.to_le_bytes()),
        )?;
        // Node indices were checked to be < n_points <= isize::MAX.
        write_block(
            w,
            frame.connectivity.len(),
            frame.connectivity.iter().map(|&i| (i as i64).to_le_bytes()),
        )?;
        let npe = frame.nodes_per_element as i64;
        write_block(
            w,
            n_cells,
            (1..=n_cells as i64).map(|c| (c * npe).to_le_bytes()),
        )?;
        write_block(w, n_cells, std::iter::repeat_n([cell_type], n_cells))?;
        for a in frame.point_data.iter().chain(&frame.cell_data) {
            match a.values {
                Values::F64(v) => write_block(w, v.len(), v.iter().map(|x| x.to_le_bytes()))?,
                Values::I32(v) => write_block(w, v.len(), v.iter().map(|x| x.to_le_bytes()))?,
            }
        }
        // The newline before the closing tag is what VTK writes too (and
        // what meshio's raw reader expects).
        w.write_all(b"\n  </AppendedData>\n</VTKFile>\n")
    })
}

/// Appends the `<DataArray …/>` tag of `a` at appended offset `offset`.
fn push_array_tag(xml: &mut String, a: &DataArray, offset: u64) {
    let _ = write!(
        xml,
        "        <DataArray type=\"{}\" Name=\"{}\"",
        a.values.vtk_type(),
        escape_xml_attr(a.name),
    );
    // Like VTK's own writer, leave out the default of one component (readers
    // such as meshio then return scalars as 1-D arrays).
    if a.components != 1 {
        let _ = write!(xml, " NumberOfComponents=\"{}\"", a.components);
    }
    for (i, c) in a.component_names.iter().enumerate() {
        let _ = write!(xml, " ComponentName{i}=\"{}\"", escape_xml_attr(c));
    }
    let _ = writeln!(xml, " format=\"appended\" offset=\"{offset}\"/>");
}

/// Writes one appended block: the UInt64 byte count of `count` items, then
/// the items' bytes. Items are packed into a local chunk so that the
/// underlying writer sees large writes.
fn write_block<const N: usize>(
    w: &mut impl Write,
    count: usize,
    items: impl Iterator<Item = [u8; N]>,
) -> io::Result<()> {
    const CHUNK: usize = 1 << 16;
    w.write_all(&((count * N) as u64).to_le_bytes())?;
    let mut buf = Vec::with_capacity(CHUNK);
    let mut written = 0usize;
    for item in items {
        buf.extend_from_slice(&item);
        written += 1;
        if buf.len() + N > CHUNK {
            w.write_all(&buf)?;
            buf.clear();
        }
    }
    w.write_all(&buf)?;
    if written != count {
        // Internal consistency guard: the header would not match the data.
        return Err(io::Error::other(format!(
            "vtu: block announced {count} items but {written} were written"
        )));
    }
    Ok(())
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

/// Checks the frame and returns its VTK cell type.
fn validate(frame: &Frame) -> io::Result<u8> {
    let npe = frame.nodes_per_element;
    let cell_type = vtk_cell_type(npe).ok_or_else(|| {
        invalid(format!(
            "vtu: nodes_per_element must be 3, 6 or 10, got {npe}"
        ))
    })?;
    if !frame.connectivity.len().is_multiple_of(npe) {
        return Err(invalid(format!(
            "vtu: connectivity length {} is not a multiple of {npe}",
            frame.connectivity.len()
        )));
    }
    let n_points = frame.positions.len();
    if let Some(pos) = frame.connectivity.iter().position(|&i| i >= n_points) {
        return Err(invalid(format!(
            "vtu: element {} refers to node {} but there are {n_points} nodes",
            pos / npe,
            frame.connectivity[pos]
        )));
    }
    if !frame.time.is_finite() {
        return Err(invalid(format!("vtu: time {} is not finite", frame.time)));
    }
    let n_cells = frame.connectivity.len() / npe;
    validate_arrays(&frame.point_data, n_points, "point")?;
    validate_arrays(&frame.cell_data, n_cells, "cell")?;
    Ok(cell_type)
}

fn validate_arrays(arrays: &[DataArray], count: usize, kind: &str) -> io::Result<()> {
    let mut names = HashSet::new();
    for a in arrays {
        if a.name.is_empty() {
            return Err(invalid(format!("vtu: {kind} array with an empty name")));
        }
        if !names.insert(a.name) {
            return Err(invalid(format!(
                "vtu: two {kind} arrays are named {:?}",
                a.name
            )));
        }
        if a.components == 0 {
            return Err(invalid(format!(
                "vtu: {kind} array {:?} has zero components",
                a.name
            )));
        }
        let expected = a.components.checked_mul(count);
        if expected != Some(a.values.len()) {
            return Err(invalid(format!(
                "vtu: {kind} array {:?} has {} values, expected {} components x {count} {kind}s",
                a.name,
                a.values.len(),
                a.components
            )));
        }
        if !a.component_names.is_empty() && a.component_names.len() != a.components {
            return Err(invalid(format!(
                "vtu: {kind} array {:?} has {} component names for {} components",
                a.name,
                a.component_names.len(),
                a.components
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;
    use std::path::PathBuf;

    fn test_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("drape-output-vtu-{}-{}", name, std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// Minimal reader of our own files: the XML header as text and the raw
    /// appended block as bytes.
    struct Parsed {
        header: String,
        data: Vec<u8>,
    }

    impl Parsed {
        fn read(path: &Path) -> Parsed {
            let bytes = fs::read(path).unwrap();
            let tag = b"<AppendedData encoding=\"raw\">";
            let tag_pos = find(&bytes, tag).expect("AppendedData tag");
            let underscore = tag_pos
                + tag.len()
                + bytes[tag_pos + tag.len()..]
                    .iter()
                    .position(|&b| b == b'_')
                    .expect("underscore");
            // Everything before the tag must be text.
            let header = String::from_utf8(bytes[..tag_pos + tag.len()].to_vec()).unwrap();
            let tail = b"\n  </AppendedData>\n</VTKFile>\n";
            assert!(bytes.ends_with(tail));
            let data = bytes[underscore + 1..bytes.len() - tail.len()].to_vec();
            Parsed { header, data }
        }

        /// The `<DataArray …>` tag text of the array called `name`.
        fn tag(&self, name: &str) -> &str {
            let key = format!("Name=\"{name}\"");
            let at = self.header.find(&key).unwrap_or_else(|| panic!("{name}"));
            let start = self.header[..at].rfind('<').unwrap();
            let end = at + self.header[at..].find('>').unwrap();
            &self.header[start..=end]
        }

        fn attr(&self, name: &str, attr: &str) -> String {
            let tag = self.tag(name);
            let key = format!(" {attr}=\"");
            let s = tag.find(&key).unwrap_or_else(|| panic!("{name}.{attr}")) + key.len();
            let e = s + tag[s..].find('"').unwrap();
            tag[s..e].to_string()
        }

        /// The raw bytes of the appended array called `name`.
        fn block(&self, name: &str) -> &[u8] {
            let offset: usize = self.attr(name, "offset").parse().unwrap();
            let len = u64::from_le_bytes(self.data[offset..offset + 8].try_into().unwrap());
            &self.data[offset + 8..offset + 8 + len as usize]
        }

        fn f64s(&self, name: &str) -> Vec<f64> {
            assert_eq!(self.attr(name, "type"), "Float64");
            self.block(name)
                .chunks_exact(8)
                .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
                .collect()
        }

        fn i64s(&self, name: &str) -> Vec<i64> {
            assert_eq!(self.attr(name, "type"), "Int64");
            self.block(name)
                .chunks_exact(8)
                .map(|c| i64::from_le_bytes(c.try_into().unwrap()))
                .collect()
        }

        fn i32s(&self, name: &str) -> Vec<i32> {
            assert_eq!(self.attr(name, "type"), "Int32");
            self.block(name)
                .chunks_exact(4)
                .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
                .collect()
        }

        fn u8s(&self, name: &str) -> Vec<u8> {
            assert_eq!(self.attr(name, "type"), "UInt8");
            self.block(name).to_vec()
        }

        /// Sum of all block sizes must cover the appended data exactly.
        fn check_blocks_tile_data(&self, names: &[&str]) {
            let mut spans: Vec<(usize, usize)> = names
                .iter()
                .map(|n| {
                    let o: usize = self.attr(n, "offset").parse().unwrap();
                    (o, 8 + self.block(n).len())
                })
                .collect();
            spans.sort();
            let mut at = 0;
            for (o, len) in spans {
                assert_eq!(o, at);
                at += len;
            }
            assert_eq!(at, self.data.len());
        }
    }

    fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
        hay.windows(needle.len()).position(|w| w == needle)
    }

    /// A structured triangulation of an `n × n` grid of squares, with
    /// higher-order nodes placed at their Gmsh reference positions.
    /// Returns (positions, connectivity).
    fn mesh(n: usize, npe: usize) -> (Vec<[f64; 3]>, Vec<usize>) {
        // Lattice with `order` subdivisions per square side; every triangle
        // node is a lattice point, so nodes are shared between elements.
        let order = match npe {
            3 => 1,
            6 => 2,
            10 => 3,
            _ => unreachable!(),
        };
        let m = n * order + 1;
        let id = |i: usize, j: usize| j * m + i;
        let mut pos = Vec::new();
        for j in 0..m {
            for i in 0..m {
                let (x, y) = (i as f64 / (m - 1) as f64, j as f64 / (m - 1) as f64);
                pos.push([x, y, 0.1 * x * y + 1.0 / 3.0]);
            }
        }
        // Reference (a, b) lattice coordinates of the Gmsh node order.
        let refs: &[(usize, usize)] = match order {
            1 => &[(0, 0), (1, 0), (0, 1)],
            2 => &[(0, 0), (2, 0), (0, 2), (1, 0), (1, 1), (0, 1)],
            _ => &[
                (0, 0),
                (3, 0),
                (0, 3),
                (1, 0),
                (2, 0),
                (2, 1),
                (1, 2),
                (0, 2),
                (0, 1),
                (1, 1),
            ],
        };
        let mut conn = Vec::new();
        for cj in 0..n {
            for ci in 0..n {
                let (i0, j0) = (ci * order, cj * order);
                // Lower-left triangle: origin (i0, j0), axes +x, +y.
                for &(a, b) in refs {
                    conn.push(id(i0 + a, j0 + b));
                }
                // Upper-right triangle: origin (i0+o, j0+o), axes -x, -y.
                for &(a, b) in refs {
                    conn.push(id(i0 + order - a, j0 + order - b));
                }
            }
        }
        (pos, conn)
    }

    fn check_frame(npe: usize, expected_type: u8) {
        let dir = test_dir(&format!("t{npe}"));
        let path = dir.join("step_000003.vtu");
        let (pos, conn) = mesh(3, npe);
        let n_points = pos.len();
        let n_cells = conn.len() / npe;
        let disp: Vec<f64> = (0..3 * n_points)
            .map(|k| (k as f64).sin() * 1e-3 + 0.1)
            .collect();
        let stress: Vec<f64> = (0..3 * n_cells).map(|k| k as f64 / 7.0 - 1.0).collect();
        let region: Vec<i32> = (0..n_cells as i32).map(|c| c % 3 - 1).collect();
        let contact: Vec<i32> = (0..n_points as i32).map(|p| p % 2).collect();
        let frame = Frame {
            positions: &pos,
            connectivity: &conn,
            nodes_per_element: npe,
            point_data: vec![
                DataArray {
                    name: "displacement",
                    components: 3,
                    values: Values::F64(&disp),
                    component_names: &["x", "y", "z"],
                },
                DataArray {
                    name: "contact",
                    components: 1,
                    values: Values::I32(&contact),
                    component_names: &[],
                },
            ],
            cell_data: vec![
                DataArray {
                    name: "stress",
                    components: 3,
                    values: Values::F64(&stress),
                    component_names: &["xx", "yy", "xy"],
                },
                DataArray {
                    name: "region",
                    components: 1,
                    values: Values::I32(&region),
                    component_names: &[],
                },
            ],
            time: 0.30000000000000004,
        };
        write_vtu(&path, &frame).unwrap();

        // Nothing but the file in the directory (atomic write cleaned up).
        let names: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert_eq!(names, vec!["step_000003.vtu"]);

        let p = Parsed::read(&path);
        let h = &p.header;
        assert!(h.starts_with("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\""));
        assert!(h.contains("version=\"1.0\""));
        assert!(h.contains("byte_order=\"LittleEndian\""));
        assert!(h.contains("header_type=\"UInt64\""));
        assert!(h.contains(&format!(
            "<Piece NumberOfPoints=\"{n_points}\" NumberOfCells=\"{n_cells}\">"
        )));
        assert!(h.contains(
            "<DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">0.30000000000000004</DataArray>"
        ));
        for tag in [
            "UnstructuredGrid",
            "FieldData",
            "Piece",
            "PointData",
            "CellData",
            "Points",
            "Cells",
        ] {
            assert_eq!(
                h.matches(&format!("<{tag}>")).count() + h.matches(&format!("<{tag} ")).count(),
                1,
                "{tag}"
            );
            assert_eq!(h.matches(&format!("</{tag}>")).count(), 1, "{tag}");
        }
        assert_eq!(p.attr("Points", "NumberOfComponents"), "3");
        assert_eq!(p.attr("displacement", "NumberOfComponents"), "3");
        assert_eq!(p.attr("displacement", "ComponentName0"), "x");
        assert_eq!(p.attr("displacement", "ComponentName2"), "z");
        assert_eq!(p.attr("stress", "ComponentName2"), "xy");
        assert!(!p.tag("contact").contains("ComponentName"));
        assert!(!p.tag("contact").contains("NumberOfComponents"));
        assert!(!p.tag("region").contains("NumberOfComponents"));
        // Point arrays inside <PointData>, cell arrays inside <CellData>.
        let pd = h.find("<PointData>").unwrap()..h.find("</PointData>").unwrap();
        let cd = h.find("<CellData>").unwrap()..h.find("</CellData>").unwrap();
        assert!(pd.contains(&h.find("Name=\"displacement\"").unwrap()));
        assert!(pd.contains(&h.find("Name=\"contact\"").unwrap()));
        assert!(cd.contains(&h.find("Name=\"stress\"").unwrap()));
        assert!(cd.contains(&h.find("Name=\"region\"").unwrap()));

        p.check_blocks_tile_data(&[
            "Points",
            "connectivity",
            "offsets",
            "types",
            "displacement",
            "contact",
            "stress",
            "region",
        ]);

        let flat: Vec<f64> = pos.iter().flatten().copied().collect();
        assert_eq!(bits(&p.f64s("Points")), bits(&flat));
        let conn64: Vec<i64> = conn.iter().map(|&i| i as i64).collect();
        assert_eq!(p.i64s("connectivity"), conn64);
        let offsets: Vec<i64> = (1..=n_cells as i64).map(|c| c * npe as i64).collect();
        assert_eq!(p.i64s("offsets"), offsets);
        assert_eq!(p.u8s("types"), vec![expected_type; n_cells]);
        assert_eq!(bits(&p.f64s("displacement")), bits(&disp));
        assert_eq!(p.i32s("contact"), contact);
        assert_eq!(bits(&p.f64s("stress")), bits(&stress));
        assert_eq!(p.i32s("region"), region);
        fs::remove_dir_all(&dir).unwrap();
    }

    fn bits(v: &[f64]) -> Vec<u64> {
        v.iter().map(|x| x.to_bits()).collect()
    }

    #[test]
    fn cell_types() {
        assert_eq!(vtk_cell_type(3), Some(5));
        assert_eq!(vtk_cell_type(6), Some(22));
        assert_eq!(vtk_cell_type(10), Some(69));
        assert_eq!(vtk_cell_type(4), None);
    }

    #[test]
    fn t3_frame_round_trips() {
        check_frame(3, VTK_TRIANGLE);
    }

    #[test]
    fn t6_frame_round_trips() {
        check_frame(6, VTK_QUADRATIC_TRIANGLE);
    }

    #[test]
    fn t10_frame_round_trips() {
        check_frame(10, VTK_LAGRANGE_TRIANGLE);
    }

    #[test]
    fn empty_frame_is_valid() {
        let dir = test_dir("empty");
        let path = dir.join("e.vtu");
        let frame = Frame {
            positions: &[],
            connectivity: &[],
            nodes_per_element: 3,
            point_data: vec![],
            cell_data: vec![],
            time: 0.0,
        };
        write_vtu(&path, &frame).unwrap();
        let p = Parsed::read(&path);
        assert!(
            p.header
                .contains("NumberOfPoints=\"0\" NumberOfCells=\"0\"")
        );
        assert!(p.f64s("Points").is_empty());
        assert!(p.i64s("connectivity").is_empty());
        p.check_blocks_tile_data(&["Points", "connectivity", "offsets", "types"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn names_are_xml_escaped() {
        let dir = test_dir("escape");
        let path = dir.join("e.vtu");
        let (pos, conn) = mesh(1, 3);
        let v = vec![1.0; pos.len()];
        let frame = Frame {
            positions: &pos,
            connectivity: &conn,
            nodes_per_element: 3,
            point_data: vec![DataArray {
                name: "a<b>&\"c\"",
                components: 1,
                values: Values::F64(&v),
                component_names: &["q&"],
            }],
            cell_data: vec![],
            time: 1.0,
        };
        write_vtu(&path, &frame).unwrap();
        let p = Parsed::read(&path);
        assert!(p.header.contains("Name=\"a&lt;b&gt;&amp;&quot;c&quot;\""));
        assert!(p.header.contains("ComponentName0=\"q&amp;\""));
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn invalid_frames_are_rejected_without_writing() {
        let dir = test_dir("invalid");
        let path = dir.join("bad.vtu");
        let (pos, conn) = mesh(1, 3);
        let np = pos.len();
        let nc = conn.len() / 3;
        let good_p = vec![0.0; np];
        let short_p = vec![0.0; np - 1];
        let good_c = vec![0i32; 2 * nc];
        let bad_conn: Vec<usize> = vec![0, 1, np];
        let base = || Frame {
            positions: &pos,
            connectivity: &conn,
            nodes_per_element: 3,
            point_data: vec![],
            cell_data: vec![],
            time: 0.0,
        };
        let arr = |name: &'static str, components, values, component_names| DataArray {
            name,
            components,
            values,
            component_names,
        };

        let cases: Vec<Frame> = vec![
            Frame {
                nodes_per_element: 4,
                ..base()
            },
            Frame {
                connectivity: &conn[..5],
                ..base()
            },
            Frame {
                connectivity: &bad_conn,
                ..base()
            },
            Frame {
                time: f64::NAN,
                ..base()
            },
            Frame {
                point_data: vec![arr("p", 1, Values::F64(&short_p), &[])],
                ..base()
            },
            Frame {
                point_data: vec![arr("p", 2, Values::F64(&good_p), &[])],
                ..base()
            },
            Frame {
                point_data: vec![arr("p", 0, Values::F64(&[]), &[])],
                ..base()
            },
            Frame {
                point_data: vec![arr("", 1, Values::F64(&good_p), &[])],
                ..base()
            },
            Frame {
                point_data: vec![
                    arr("p", 1, Values::F64(&good_p), &[]),
                    arr("p", 1, Values::F64(&good_p), &[]),
                ],
                ..base()
            },
            Frame {
                point_data: vec![arr("p", 1, Values::F64(&good_p), &["a", "b"])],
                ..base()
            },
            Frame {
                cell_data: vec![arr("c", 1, Values::I32(&good_c), &[])],
                ..base()
            },
        ];
        for (k, frame) in cases.iter().enumerate() {
            let e = write_vtu(&path, frame).unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput, "case {k}: {e}");
        }
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 0);

        // The same names in point and cell data are fine, and so is a good
        // cell array.
        let frame = Frame {
            point_data: vec![arr("p", 1, Values::F64(&good_p), &[])],
            cell_data: vec![arr("p", 2, Values::I32(&good_c), &["a", "b"])],
            ..base()
        };
        write_vtu(&path, &frame).unwrap();
        fs::remove_dir_all(&dir).unwrap();
    }

    /// Checks that meshio (Python) reads our T3, T6 and T10 files: point
    /// count, cell type, cell count and field data. Needs `python3` with
    /// `meshio` (`pip install meshio`); skipped with a notice when it is
    /// missing, unless `DRAPE_REQUIRE_MESHIO=1` (set by CI), then it fails.
    #[test]
    fn meshio_reads_our_files() {
        let available = std::process::Command::new("python3")
            .args(["-c", "import meshio"])
            .output()
            .is_ok_and(|o| o.status.success());
        if !available {
            assert!(
                std::env::var("DRAPE_REQUIRE_MESHIO").as_deref() != Ok("1"),
                "DRAPE_REQUIRE_MESHIO=1 but python3 cannot import meshio"
            );
            eprintln!("skipped: python3 cannot import meshio (pip install meshio)");
            return;
        }
        let dir = test_dir("meshio");
        for (npe, meshio_type) in [
            (3, "triangle"),
            (6, "triangle6"),
            (10, "VTK_LAGRANGE_TRIANGLE"),
        ] {
            let path = dir.join(format!("t{npe}.vtu"));
            let (pos, conn) = mesh(2, npe);
            let n_cells = conn.len() / npe;
            let u: Vec<f64> = (0..3 * pos.len()).map(|k| k as f64 * 0.5).collect();
            let s: Vec<f64> = (0..n_cells).map(|k| k as f64).collect();
            let frame = Frame {
                positions: &pos,
                connectivity: &conn,
                nodes_per_element: npe,
                point_data: vec![DataArray {
                    name: "u",
                    components: 3,
                    values: Values::F64(&u),
                    component_names: &[],
                }],
                cell_data: vec![DataArray {
                    name: "s",
                    components: 1,
                    values: Values::F64(&s),
                    component_names: &[],
                }],
                time: 2.5,
            };
            write_vtu(&path, &frame).unwrap();
            let script = format!(
                r#"
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
assert m.points.shape == ({np}, 3), m.points.shape
assert len(m.cells) == 1, m.cells
c = m.cells[0]
assert c.type == "{ty}", c.type
assert c.data.shape == ({nc}, {npe}), c.data.shape
assert m.point_data["u"].shape == ({np}, 3)
assert m.point_data["u"][1, 0] == 1.5
assert m.cell_data["s"][0].shape == ({nc},)
assert float(m.field_data["TIME"][0]) == 2.5
print("ok", c.type, m.points.shape[0], c.data.shape)
"#,
                np = pos.len(),
                nc = n_cells,
                ty = meshio_type,
            );
            let out = std::process::Command::new("python3")
                .arg("-c")
                .arg(&script)
                .arg(&path)
                .output()
                .expect("run python3");
            assert!(
                out.status.success(),
                "meshio failed on T{npe}:\n{}\n{}",
                String::from_utf8_lossy(&out.stdout),
                String::from_utf8_lossy(&out.stderr)
            );
            println!("T{npe}: {}", String::from_utf8_lossy(&out.stdout).trim());
        }
        fs::remove_dir_all(&dir).unwrap();
    }
}
