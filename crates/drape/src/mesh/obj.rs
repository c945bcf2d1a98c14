//! Reader for Wavefront OBJ surface meshes, through the `tobj` crate.
//!
//! [`read_obj`] reads a file, [`parse_obj`] parses bytes already in memory.
//! Both return a linear ([`ElementOrder::Linear`]) [`Mesh`] or a
//! [`MeshReadError`] (the same error type as the Gmsh reader) naming the
//! file and, for most problems, the 1-based line.
//!
//! What is read:
//!
//! * `v x y z` vertices, with an optional `w` (the coordinates are divided by
//!   it) or vertex colour `r g b` (ignored). A vertex with a NaN or infinite
//!   coordinate is an error, even if no face uses it, and so is a vertex
//!   past [`MAX_MESH_NODES`] (or the cap given to [`parse_obj_at_most`]).
//! * `f` faces, `v`, `v/vt`, `v//vn` or `v/vt/vn` per corner, with absolute
//!   (1-based) or relative (negative) vertex indices. A face with more than
//!   three corners is cut into triangles by ear clipping
//!   ([`super::polygon`]): a convex one into the fan about its first corner
//!   (a quad `a b c d` gives `a b c` and `a c d`), a concave one into
//!   triangles that do not overlap; a face that is not planar, has no area
//!   or intersects itself is refused, naming its line and number. A face
//!   with fewer than three corners, or
//!   a corner that refers to a vertex that does not exist, is an error.
//! * Objects (`o`) and groups (`g`), and material changes (`usemtl`), are
//!   merged into one mesh. OBJ vertex indices are global to the file, so a
//!   vertex used by faces of several objects or groups is one node of the
//!   mesh, shared by their triangles.
//! * Everything else (texture coordinates, normals, lines `l`, points `p`,
//!   smoothing groups, materials and `mtllib` files, free-form geometry) is
//!   ignored; no other file is opened.
//!
//! The mesh holds only the vertices used by faces, numbered in the order in
//! which the faces first use them.
//!
//! Precision: `tobj` is built with its `use_f64` feature, so coordinates
//! are read in double precision.
//!
//! Before handing the file to `tobj`, the reader checks it line by line and
//! keeps only vertex positions and face corners, so that errors can name
//! their line and no malformed index reaches `tobj`. Errors `tobj` still
//! raises come back as [`MeshReadError::Obj`].

#![deny(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

use std::path::Path;

use super::{ElementOrder, MAX_MESH_NODES, Mesh, check_node_cap};

pub use super::{Location, MeshReadError};

/// Reads a Wavefront OBJ file into a linear triangle [`Mesh`].
///
/// Error messages name the file as `path` displays. See the
/// [module documentation](self) for what is read.
pub fn read_obj(path: &Path) -> Result<Mesh, MeshReadError> {
    let (bytes, file) = MeshReadError::read(path)?;
    parse_obj(&bytes, &file)
}

/// Parses the bytes of a Wavefront OBJ file into a linear triangle
/// [`Mesh`]; `source` is the file name used in error messages. A file of
/// more than [`MAX_MESH_NODES`] vertices is refused at the first vertex
/// past it ([`MeshReadError::TooManyNodes`]).
///
/// All objects and groups are merged; faces with more than three corners
/// are split into triangle fans. See the [module documentation](self).
pub fn parse_obj(bytes: &[u8], source: &str) -> Result<Mesh, MeshReadError> {
    parse_obj_at_most(bytes, source, MAX_MESH_NODES)
}

/// [`parse_obj`] with a cap of `max_nodes` vertices, refused at the line
/// of the first vertex past it.
pub fn parse_obj_at_most(
    bytes: &[u8],
    source: &str,
    max_nodes: usize,
) -> Result<Mesh, MeshReadError> {
    let clean = normalize(bytes, source, max_nodes)?;
    // `..Default::default()` covers the fields that `tobj`'s optional
    // features (`merging`, `reordering`) add, should another crate enable them.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj_buf(&mut clean.as_slice(), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|source_error| MeshReadError::Obj {
        file: source.to_owned(),
        source: source_error,
    })?;

    let internal = |message: String| MeshReadError::Syntax {
        file: source.to_owned(),
        at: None,
        message,
    };
    let mut nodes: Vec<[f64; 3]> = Vec::new();
    let mut connectivity = Vec::new();
    for model in &models {
        let mesh = &model.mesh;
        let base = nodes.len();
        for p in mesh.positions.chunks_exact(3) {
            if let &[x, y, z] = p {
                nodes.push([x, y, z]);
            }
        }
        let count = nodes.len() - base;
        for &i in &mesh.indices {
            let i = usize::try_from(i).unwrap_or(usize::MAX);
            if i >= count {
                return Err(internal(format!(
                    "tobj returned vertex index {i} out of range"
                )));
            }
            connectivity.push(base + i);
        }
    }
    if connectivity.is_empty() {
        return Err(MeshReadError::NoTriangles {
            file: source.to_owned(),
        });
    }
    if connectivity.len() % 3 != 0 {
        return Err(internal(
            "tobj returned a face that is not a triangle".to_owned(),
        ));
    }
    for (i, x) in nodes.iter().enumerate() {
        if let Some(&value) = x.iter().find(|v| !v.is_finite()) {
            return Err(MeshReadError::NonFiniteCoordinate {
                file: source.to_owned(),
                at: None,
                node: i as u64 + 1,
                value,
            });
        }
    }
    Ok(Mesh {
        nodes,
        order: ElementOrder::Linear,
        connectivity,
    })
}

/// Shows a token of the file in a message: lossy UTF-8, at most 40
/// characters.
fn show(bytes: &[u8]) -> String {
    let text = String::from_utf8_lossy(bytes);
    let mut out: String = text.chars().take(40).collect();
    if text.chars().nth(40).is_some() {
        out.push('…');
    }
    out
}

/// Lines of the file with their 1-based numbers, without line ends, split
/// into whitespace-separated fields.
fn lines(bytes: &[u8]) -> impl Iterator<Item = (usize, Vec<&[u8]>)> {
    bytes.split(|&b| b == b'\n').enumerate().map(|(i, line)| {
        let fields = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|t| !t.is_empty())
            .collect();
        (i + 1, fields)
    })
}

/// Checks the file and rewrites it for `tobj` as plain `v x y z [w]` and
/// `f i j k ...` lines (absolute 1-based indices), dropping everything else.
fn normalize(bytes: &[u8], file: &str, max_nodes: usize) -> Result<Vec<u8>, MeshReadError> {
    // A UTF-8 byte-order mark, which some editors write, is skipped.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut out = Vec::with_capacity(bytes.len());
    // Pass 1: vertices (their positions kept for the polygons of pass 2).
    let positions = write_vertices(bytes, file, max_nodes, &mut out)?;
    // Pass 2: faces, with the vertex indices made absolute.
    write_faces(bytes, file, &positions, &mut out)?;
    Ok(out)
}

/// A syntax error at `line` of `file`.
fn syntax(file: &str, line: usize, message: String) -> MeshReadError {
    MeshReadError::Syntax {
        file: file.to_owned(),
        at: Some(Location::Line(line)),
        message,
    }
}

/// The number in `tok`, which is `what`, at `line` of `file`.
fn parse_f64(tok: &[u8], what: &str, file: &str, line: usize) -> Result<f64, MeshReadError> {
    std::str::from_utf8(tok)
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .ok_or_else(|| {
            syntax(
                file,
                line,
                format!("expected {what} (a number), found '{}'", show(tok)),
            )
        })
}

/// Writes the file's vertices as `v x y z [w]` lines into `out`, and
/// returns their positions (divided by `w`), each checked finite; the
/// first vertex past `max_nodes` is refused at its line.
fn write_vertices(
    bytes: &[u8],
    file: &str,
    max_nodes: usize,
    out: &mut Vec<u8>,
) -> Result<Vec<[f64; 3]>, MeshReadError> {
    let mut vertices: u64 = 0;
    let mut positions: Vec<[f64; 3]> = Vec::new();
    for (line, fields) in lines(bytes) {
        let [b"v", values @ ..] = fields.as_slice() else {
            continue;
        };
        vertices += 1;
        check_node_cap(file, Location::Line(line), vertices, false, max_nodes)?;
        let (xyz, w) = match values {
            [x, y, z] | [x, y, z, _, _, _] => ([*x, *y, *z], None),
            [x, y, z, w] => ([*x, *y, *z], Some(*w)),
            _ => {
                return Err(syntax(
                    file,
                    line,
                    format!(
                        "expected 3 coordinates for vertex {vertices} (optionally followed by w \
                         or by r g b), found {} numbers",
                        values.len()
                    ),
                ));
            }
        };
        let mut x = [0f64; 3];
        for ((xk, tok), name) in x.iter_mut().zip(xyz).zip(["x", "y", "z"]) {
            *xk = parse_f64(tok, &format!("coordinate {name}"), file, line)?;
        }
        if let Some(w) = w {
            let w = parse_f64(w, "the weight w", file, line)?;
            if w == 0.0 {
                return Err(syntax(
                    file,
                    line,
                    format!("vertex {vertices} has the weight w = 0"),
                ));
            }
            for xk in &mut x {
                *xk /= w;
            }
        }
        if let Some(&value) = x.iter().find(|v| !v.is_finite()) {
            return Err(MeshReadError::NonFiniteCoordinate {
                file: file.to_owned(),
                at: Some(Location::Line(line)),
                node: vertices,
                value,
            });
        }
        positions.push(x);
        out.extend_from_slice(b"v");
        for tok in xyz.iter().chain(&w) {
            out.push(b' ');
            out.extend_from_slice(tok);
        }
        out.push(b'\n');
    }
    Ok(positions)
}

/// Writes the file's faces into `out` as `f i j k` triangles of absolute
/// vertex indices into `positions` (a polygon cut into its ears).
fn write_faces(
    bytes: &[u8],
    file: &str,
    positions: &[[f64; 3]],
    out: &mut Vec<u8>,
) -> Result<(), MeshReadError> {
    let mut seen: u64 = 0;
    let mut faces: u64 = 0;
    for (line, fields) in lines(bytes) {
        match fields.as_slice() {
            [b"v", ..] => seen += 1,
            [b"f", corners @ ..] => {
                faces += 1;
                let at = FaceAt {
                    file,
                    line,
                    face: faces,
                    seen,
                    vertices: positions.len() as u64,
                };
                let face = at.indices(corners)?;
                for triangle in triangles(&face, positions).map_err(|e| {
                    syntax(
                        file,
                        line,
                        format!("face {faces} ({} corners): {e}", face.len()),
                    )
                })? {
                    out.push(b'f');
                    for corner in triangle {
                        out.extend_from_slice(format!(" {corner}").as_bytes());
                    }
                    out.push(b'\n');
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// Where a face is read: its file, line and number, after `seen` of the
/// file's `vertices` vertices.
struct FaceAt<'a> {
    file: &'a str,
    line: usize,
    face: u64,
    seen: u64,
    vertices: u64,
}

impl FaceAt<'_> {
    /// The absolute (1-based) vertex index of each of the face's
    /// `corners` (`v`, `v/vt`, `v//vn` or `v/vt/vn`, absolute or relative);
    /// at least three, each naming a vertex of the file.
    fn indices(&self, corners: &[&[u8]]) -> Result<Vec<u64>, MeshReadError> {
        let (file, line, faces) = (self.file, self.line, self.face);
        if corners.len() < 3 {
            return Err(syntax(
                file,
                line,
                format!(
                    "face {faces} has {} corner{}; a face needs at least 3",
                    corners.len(),
                    if corners.len() == 1 { "" } else { "s" }
                ),
            ));
        }
        let mut face: Vec<u64> = Vec::with_capacity(corners.len());
        for corner in corners {
            let v = corner.split(|&b| b == b'/').next().unwrap_or(corner);
            let index = std::str::from_utf8(v)
                .ok()
                .and_then(|s| s.parse::<i64>().ok())
                .ok_or_else(|| {
                    syntax(
                        file,
                        line,
                        format!(
                            "expected a vertex index in face {faces}, found '{}'",
                            show(corner)
                        ),
                    )
                })?;
            let absolute = self.absolute(index)?;
            if absolute > self.vertices {
                return Err(MeshReadError::UnknownNode {
                    file: file.to_owned(),
                    at: Some(Location::Line(line)),
                    element: faces,
                    node_tag: absolute,
                });
            }
            face.push(absolute);
        }
        Ok(face)
    }

    /// The 1-based index of vertex `index`: itself when positive, counted
    /// back from the last vertex seen when negative; 0 is refused.
    fn absolute(&self, index: i64) -> Result<u64, MeshReadError> {
        let (file, line, faces, seen) = (self.file, self.line, self.face, self.seen);
        match index {
            0 => Err(syntax(
                file,
                line,
                format!("face {faces} uses vertex index 0; OBJ indices start at 1"),
            )),
            i if i > 0 => Ok(i.unsigned_abs()),
            i => {
                let back = i.unsigned_abs();
                if back > seen {
                    return Err(syntax(
                        file,
                        line,
                        format!(
                            "face {faces} uses relative vertex index {i}, but only \
                             {seen} vertices precede it"
                        ),
                    ));
                }
                Ok(seen - back + 1)
            }
        }
    }
}

/// The triangles of the face `face` (1-based vertex indices into
/// `positions`): itself when it has three corners; a polygon's ears
/// ([`super::polygon`]), or why it has none. A polygon that repeats a
/// vertex is passed on whole, for the mesh's check to name the repeat.
fn triangles(
    face: &[u64],
    positions: &[[f64; 3]],
) -> Result<Vec<Vec<u64>>, super::polygon::PolygonError> {
    let repeats = face
        .iter()
        .enumerate()
        .any(|(i, v)| face.iter().skip(i + 1).any(|w| w == v));
    if face.len() == 3 || repeats {
        return Ok(vec![face.to_vec()]);
    }
    let x: Vec<[f64; 3]> = face
        .iter()
        .map(|&v| {
            usize::try_from(v)
                .ok()
                .and_then(|v| positions.get(v.wrapping_sub(1)))
                .copied()
                .unwrap_or([f64::NAN; 3])
        })
        .collect();
    Ok(super::polygon::triangulate(&x)?
        .into_iter()
        .map(|t| t.iter().filter_map(|&k| face.get(k).copied()).collect())
        .collect())
}

#[cfg(test)]
#[allow(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Mesh, MeshReadError> {
        parse_obj(text.as_bytes(), "test.obj")
    }

    #[test]
    fn quad_is_split_into_two_triangles() {
        let m = parse("# a square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
        assert_eq!(m.order, ElementOrder::Linear);
        assert_eq!(
            m.nodes,
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0]
            ]
        );
        assert_eq!(m.connectivity, vec![0, 1, 2, 0, 2, 3]);
    }

    #[test]
    fn skips_a_byte_order_mark() {
        let m = parse("\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(m.nodes[0], [0.0, 0.0, 0.0]);
        assert_eq!(m.connectivity, vec![0, 1, 2]);
    }

    #[test]
    fn polygon_is_a_fan_and_nodes_follow_first_use() {
        let m =
            parse("v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nv 9 9 9\nf 2 3 4 5 1\n").unwrap();
        // Vertex 6 is unused; nodes are numbered by first use: 2 3 4 5 1.
        assert_eq!(
            m.nodes,
            vec![
                [1.0, 0.0, 0.0],
                [2.0, 1.0, 0.0],
                [1.0, 2.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 0.0]
            ]
        );
        assert_eq!(m.connectivity, vec![0, 1, 2, 0, 2, 3, 0, 3, 4]);
    }

    #[test]
    fn two_objects_are_merged() {
        let text = "mtllib cloth.mtl\no first\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n\
                    o second\nv 0 0 1\nv 1 0 1\nv 0 1 1\nusemtl blue\nf 4 5 6\n";
        let m = parse(text).unwrap();
        assert_eq!(
            m.nodes,
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 1.0],
                [0.0, 1.0, 1.0]
            ]
        );
        assert_eq!(m.connectivity, vec![0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn groups_share_their_common_vertices() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng front\nf 1 2 3\ng back\nf 1 3 4\n";
        let m = parse(text).unwrap();
        assert_eq!(m.node_count(), 4);
        assert_eq!(m.connectivity, vec![0, 1, 2, 0, 2, 3]);
    }

    #[test]
    fn relative_indices_texcoords_normals_weights_and_colors() {
        let text = "v 0 0 0\nv 2 0 0 2\nv 1 1 0 0.5 0.5 0.5\nvt 0 0\nvt 1 0\nvn 0 0 1\n\
                    f -3/1/1 -2//1 -1/2\nl 1 2\n";
        let m = parse(text).unwrap();
        assert_eq!(
            m.nodes,
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]
        );
        assert_eq!(m.connectivity, vec![0, 1, 2]);
    }

    #[test]
    fn coordinates_are_read_in_double_precision() {
        let m = parse("v 0.1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(m.nodes[0][0], 0.1);
    }

    #[test]
    fn error_face_with_missing_vertex() {
        let err = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 5\n").unwrap_err();
        assert!(
            matches!(
                err,
                MeshReadError::UnknownNode {
                    element: 2,
                    node_tag: 5,
                    at: Some(Location::Line(5)),
                    ..
                }
            ),
            "{err}"
        );
        assert_eq!(
            err.to_string(),
            "test.obj, line 5: element 2 refers to node 5, which is not defined"
        );
        let err = parse("v 0 0 0\nv 1 0 0\nf 1 2 -3\nv 0 1 0\n").unwrap_err();
        assert!(matches!(err, MeshReadError::Syntax { .. }), "{err}");
        let err = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").unwrap_err();
        assert!(err.to_string().contains("index 0"), "{err}");
    }

    #[test]
    fn error_empty_file() {
        for text in [
            "",
            "\n\n",
            "# only a comment\n",
            "v 0 0 0\nv 1 0 0\nl 1 2\n",
        ] {
            let err = parse(text).unwrap_err();
            assert!(matches!(err, MeshReadError::NoTriangles { .. }), "{err}");
            assert_eq!(err.to_string(), "test.obj: the file holds no triangles");
        }
    }

    #[test]
    fn error_nan_or_infinite_coordinate() {
        let err = parse("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n").unwrap_err();
        assert!(
            matches!(
                err,
                MeshReadError::NonFiniteCoordinate {
                    node: 2,
                    at: Some(Location::Line(2)),
                    ..
                }
            ),
            "{err}"
        );
        assert_eq!(
            err.to_string(),
            "test.obj, line 2: node 2 has a non-finite coordinate (NaN)"
        );
        // Overflows f64.
        let err = parse("v 0 0 0\nv 1 0 0\nv 0 1e309 0\nf 1 2 3\n").unwrap_err();
        assert!(
            matches!(err, MeshReadError::NonFiniteCoordinate { node: 3, .. }),
            "{err}"
        );
    }

    #[test]
    fn error_malformed_lines() {
        let err = parse("v 0 0\n").unwrap_err();
        assert!(
            err.to_string()
                .starts_with("test.obj, line 1: expected 3 coordinates"),
            "{err}"
        );
        let err = parse("v 0 0 0\nv 1 0 x\n").unwrap_err();
        assert_eq!(
            err.to_string(),
            "test.obj, line 2: expected coordinate z (a number), found 'x'"
        );
        let err = parse("v 0 0 0\nv 1 0 0\nf 1 2\n").unwrap_err();
        assert_eq!(
            err.to_string(),
            "test.obj, line 3: face 1 has 2 corners; a face needs at least 3"
        );
        let err = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 a 3\n").unwrap_err();
        assert!(matches!(err, MeshReadError::Syntax { .. }), "{err}");
        let err = parse("v 0 0 0 0\n").unwrap_err();
        assert!(err.to_string().contains("w = 0"), "{err}");
    }

    #[test]
    fn no_panic_on_damaged_input() {
        let text = b"o a\nv 0 0 0\nv 1 0 0 1\nv 1 1 0\nvt 0 0\nvn 0 0 1\nv 0 1 0\nf 1/1/1 2//1 3 4\ng b\nf -1 -2 -3\n";
        for n in 0..text.len() {
            let _ = parse_obj(&text[..n], "cut.obj");
        }
        let mut state: u64 = 12345;
        for _ in 0..3000 {
            let mut copy = text.to_vec();
            for _ in 0..3 {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                let i = (state >> 33) as usize % copy.len();
                copy[i] = (state >> 17) as u8;
            }
            let _ = parse_obj(&copy, "damaged.obj");
        }
        let garbage: Vec<u8> = (0..4096u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
            .collect();
        assert!(parse_obj(&garbage, "junk.obj").is_err());
    }

    #[test]
    fn reads_a_file_and_reports_io_errors_with_the_name() {
        let dir = std::env::temp_dir().join(format!("drape-obj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("tri.obj");
        std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(read_obj(&path).unwrap().element_count(), 1);
        let missing = dir.join("missing.obj");
        let err = read_obj(&missing).unwrap_err();
        assert!(matches!(err, MeshReadError::Io { .. }));
        assert_eq!(err.file(), missing.display().to_string());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The cap on nodes, given small: a file of up to that many vertices
    /// is read, the first vertex past it is refused at its line.
    #[test]
    fn a_vertex_past_the_cap_is_refused_at_its_line() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\n# more\nv 0 1 0\nf 1 2 3 4\n";
        let m = parse_obj_at_most(text.as_bytes(), "cap.obj", 4).unwrap();
        assert_eq!(m.node_count(), 4);
        let err = parse_obj_at_most(text.as_bytes(), "cap.obj", 3).unwrap_err();
        assert_eq!(
            err.to_string(),
            "cap.obj, line 5: vertex 4, more than the 3 nodes a mesh may have; use a coarser mesh"
        );
        assert_eq!(err.location(), Some(Location::Line(5)));
    }
}
