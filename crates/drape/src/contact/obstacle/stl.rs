//! Reader for STL triangle meshes, ASCII and binary.
//!
//! [`read_stl`] reads a file, [`parse_stl`] parses bytes already in memory.
//! Both return a linear [`Mesh`] or a [`MeshReadError`] (the error type of
//! the Gmsh and OBJ readers) naming the file and, in an ASCII file, the
//! 1-based line (in a binary file, the byte offset) of the problem.
//!
//! * **Binary** STL: an 80-byte header, a little-endian `u32` triangle
//!   count `n`, then `n` records of 50 bytes (normal, three vertices, as
//!   twelve little-endian `f32`, and a 2-byte attribute). A file is read as
//!   binary when its size is exactly `84 + 50 n`, whatever its header says
//!   (binary headers often begin with `solid` too). Coordinates are widened
//!   from `f32` to `f64`.
//! * **ASCII** STL: `solid name`, then `facet normal nx ny nz`, `outer
//!   loop`, three `vertex x y z`, `endloop`, `endfacet` per triangle, and
//!   `endsolid name`; several solids in one file are merged. Keywords are
//!   matched without regard to case; line breaks may fall anywhere between
//!   tokens. Coordinates are read in double precision.
//!
//! The stored normals are ignored (the obstacle takes its orientation from
//! the vertex order, counter-clockwise seen from outside). STL has no shared
//! vertices: the mesh has three nodes per triangle, in file order, and
//! [`TriMeshObstacle::new`](super::TriMeshObstacle::new) joins the nodes
//! with equal coordinates. A NaN or infinite coordinate is an error; a file
//! without triangles is an error. The reader does not panic on any input.

#![deny(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

use std::path::Path;

use crate::mesh::gmsh::{Location, MeshReadError};
use crate::mesh::{ElementOrder, Mesh};

/// Reads an STL file (ASCII or binary) into a linear triangle [`Mesh`],
/// three nodes per triangle. Error messages name the file as `path`
/// displays.
pub fn read_stl(path: &Path) -> Result<Mesh, MeshReadError> {
    let (bytes, file) = MeshReadError::read(path)?;
    parse_stl(&bytes, &file)
}

/// Parses the bytes of an STL file; `source` is the file name used in error
/// messages. See the [module documentation](self).
pub fn parse_stl(bytes: &[u8], source: &str) -> Result<Mesh, MeshReadError> {
    let declared = bytes
        .get(80..84)
        .and_then(|b| <[u8; 4]>::try_from(b).ok())
        .map(u32::from_le_bytes);
    let nodes = match declared {
        Some(n) if 84 + 50 * u64::from(n) == bytes.len() as u64 => parse_binary(bytes, source)?,
        _ if is_ascii_stl(bytes) => parse_ascii(bytes, source)?,
        Some(n) => {
            return Err(MeshReadError::Syntax {
                file: source.to_owned(),
                at: Some(Location::Byte(80)),
                message: format!(
                    "not an ASCII STL (it does not begin with 'solid'), and as a binary STL its \
                     {n} triangles need {} bytes, but the file has {}",
                    84 + 50 * u64::from(n),
                    bytes.len()
                ),
            });
        }
        None => {
            return Err(MeshReadError::Syntax {
                file: source.to_owned(),
                at: None,
                message: format!(
                    "not an STL file: it does not begin with 'solid' and is too short ({} bytes) \
                     for a binary STL",
                    bytes.len()
                ),
            });
        }
    };
    if nodes.is_empty() {
        return Err(MeshReadError::NoTriangles {
            file: source.to_owned(),
        });
    }
    let connectivity = (0..nodes.len()).collect();
    Ok(Mesh {
        nodes,
        order: ElementOrder::Linear,
        connectivity,
    })
}

/// Whether the text begins (after white space) with the keyword `solid`.
fn is_ascii_stl(bytes: &[u8]) -> bool {
    let start = bytes
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(bytes.len());
    bytes
        .get(start..start + 5)
        .is_some_and(|w| w.eq_ignore_ascii_case(b"solid"))
}

/// The vertices of a binary STL whose size has been checked.
fn parse_binary(bytes: &[u8], file: &str) -> Result<Vec<[f64; 3]>, MeshReadError> {
    let records = bytes.get(84..).unwrap_or_default().chunks_exact(50);
    let mut nodes = Vec::with_capacity(3 * records.len());
    for (t, record) in records.enumerate() {
        let offset = 84 + 50 * t;
        // Skip the normal (12 bytes); read three vertices of 12 bytes.
        let coordinates = record.get(12..48).unwrap_or_default().chunks_exact(4);
        let mut vertex = [0.0; 3];
        for (i, word) in coordinates.enumerate() {
            let value = <[u8; 4]>::try_from(word).map_or(f32::NAN, f32::from_le_bytes);
            if !value.is_finite() {
                return Err(MeshReadError::NonFiniteCoordinate {
                    file: file.to_owned(),
                    at: Some(Location::Byte(offset + 12 + 4 * i)),
                    node: (3 * t + i / 3 + 1) as u64,
                    value: f64::from(value),
                });
            }
            if let Some(v) = vertex.get_mut(i % 3) {
                *v = f64::from(value);
            }
            if i % 3 == 2 {
                nodes.push(vertex);
            }
        }
    }
    Ok(nodes)
}

/// Whitespace-separated tokens with their 1-based line numbers.
struct Tokens<'a> {
    bytes: &'a [u8],
    at: usize,
    line: usize,
}

impl<'a> Tokens<'a> {
    /// The next token and its line, or `None` at the end.
    fn next_token(&mut self) -> Option<(&'a [u8], usize)> {
        while let Some(&b) = self.bytes.get(self.at) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.at += 1;
        }
        let start = self.at;
        while self
            .bytes
            .get(self.at)
            .is_some_and(|b| !b.is_ascii_whitespace())
        {
            self.at += 1;
        }
        let token = self.bytes.get(start..self.at)?;
        (!token.is_empty()).then_some((token, self.line))
    }

    /// Skips the rest of the current line (a solid's name).
    fn skip_line(&mut self) {
        while let Some(&b) = self.bytes.get(self.at) {
            if b == b'\n' {
                break;
            }
            self.at += 1;
        }
    }
}

/// A token of the file in a message: lossy UTF-8, at most 40 characters.
fn show(token: &[u8]) -> String {
    let text = String::from_utf8_lossy(token);
    let mut out: String = text.chars().take(40).collect();
    if text.chars().nth(40).is_some() {
        out.push('…');
    }
    out
}

/// The vertices of an ASCII STL.
fn parse_ascii(bytes: &[u8], file: &str) -> Result<Vec<[f64; 3]>, MeshReadError> {
    let mut tokens = Tokens {
        bytes,
        at: 0,
        line: 1,
    };
    let syntax = |line: usize, message: String| MeshReadError::Syntax {
        file: file.to_owned(),
        at: Some(Location::Line(line)),
        message,
    };
    let truncated = || MeshReadError::Truncated {
        file: file.to_owned(),
        section: "a solid (no 'endsolid')".to_owned(),
    };
    let expect = |tokens: &mut Tokens, keyword: &str| -> Result<usize, MeshReadError> {
        let (token, line) = tokens.next_token().ok_or_else(truncated)?;
        if token.eq_ignore_ascii_case(keyword.as_bytes()) {
            Ok(line)
        } else {
            Err(syntax(
                line,
                format!("expected '{keyword}', found '{}'", show(token)),
            ))
        }
    };
    let number = |tokens: &mut Tokens, what: &str| -> Result<(f64, usize), MeshReadError> {
        let (token, line) = tokens.next_token().ok_or_else(truncated)?;
        std::str::from_utf8(token)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .map(|v| (v, line))
            .ok_or_else(|| {
                syntax(
                    line,
                    format!("expected {what} (a number), found '{}'", show(token)),
                )
            })
    };

    let mut nodes = Vec::new();
    expect(&mut tokens, "solid")?;
    tokens.skip_line();
    loop {
        let (token, line) = tokens.next_token().ok_or_else(truncated)?;
        if token.eq_ignore_ascii_case(b"endsolid") {
            tokens.skip_line();
            match tokens.next_token() {
                None => break,
                Some((t, _)) if t.eq_ignore_ascii_case(b"solid") => {
                    tokens.skip_line();
                    continue;
                }
                Some((t, line)) => {
                    return Err(syntax(
                        line,
                        format!(
                            "expected 'solid' or the end of the file, found '{}'",
                            show(t)
                        ),
                    ));
                }
            }
        }
        if !token.eq_ignore_ascii_case(b"facet") {
            return Err(syntax(
                line,
                format!("expected 'facet' or 'endsolid', found '{}'", show(token)),
            ));
        }
        expect(&mut tokens, "normal")?;
        for name in ["the normal's x", "the normal's y", "the normal's z"] {
            number(&mut tokens, name)?;
        }
        expect(&mut tokens, "outer")?;
        expect(&mut tokens, "loop")?;
        for _ in 0..3 {
            expect(&mut tokens, "vertex")?;
            let mut vertex = [0.0; 3];
            for (v, name) in vertex.iter_mut().zip(["x", "y", "z"]) {
                let (value, line) = number(&mut tokens, &format!("coordinate {name}"))?;
                if !value.is_finite() {
                    return Err(MeshReadError::NonFiniteCoordinate {
                        file: file.to_owned(),
                        at: Some(Location::Line(line)),
                        node: nodes.len() as u64 + 1,
                        value,
                    });
                }
                *v = value;
            }
            nodes.push(vertex);
        }
        expect(&mut tokens, "endloop")?;
        expect(&mut tokens, "endfacet")?;
    }
    Ok(nodes)
}

#[cfg(test)]
#[allow(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]
pub(super) mod tests {
    use super::*;

    const TETRA: &str = "solid tetra made by hand\n\
        facet normal 0 0 -1\n outer loop\n  vertex 0 0 0\n  vertex 0 1 0\n  vertex 1 0 0\n endloop\nendfacet\n\
        facet normal 0 -1 0\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 0 1\n endloop\nendfacet\n\
        facet normal -1 0 0\n outer loop\n  vertex 0 0 0\n  vertex 0 0 1\n  vertex 0 1 0\n endloop\nendfacet\n\
        facet normal 1 1 1\n outer loop\n  vertex 1 0 0\n  vertex 0 1 0\n  vertex 0 0 1\n endloop\nendfacet\n\
        endsolid tetra made by hand\n";

    /// The binary STL of the given triangles.
    pub(crate) fn binary(header: &[u8], triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
        let mut out = vec![0u8; 80];
        out[..header.len()].copy_from_slice(header);
        out.extend_from_slice(&(triangles.len() as u32).to_le_bytes());
        for t in triangles {
            out.extend_from_slice(&[0u8; 12]);
            for v in t {
                for c in v {
                    out.extend_from_slice(&c.to_le_bytes());
                }
            }
            out.extend_from_slice(&[0u8; 2]);
        }
        out
    }

    #[test]
    fn ascii_tetrahedron() {
        let m = parse_stl(TETRA.as_bytes(), "t.stl").unwrap();
        assert_eq!(m.nodes.len(), 12);
        assert_eq!(m.element_count(), 4);
        assert_eq!(m.nodes[1], [0.0, 1.0, 0.0]);
        assert_eq!(m.nodes[11], [0.0, 0.0, 1.0]);
        // Upper case, two solids, everything on one line, CRLF line ends.
        let text = "SOLID a\r\nFACET NORMAL 0 0 0 OUTER LOOP VERTEX 0 0 0 VERTEX 1 0 0 VERTEX 0 1 0 \
                    ENDLOOP ENDFACET ENDSOLID a\r\nsolid b\r\nendsolid\r\n";
        let m = parse_stl(text.as_bytes(), "u.stl").unwrap();
        assert_eq!(m.element_count(), 1);
        // Precision: ASCII numbers are read as f64.
        let text = TETRA.replacen("vertex 0 1 0", "vertex 0.1 1 0", 1);
        assert_eq!(
            parse_stl(text.as_bytes(), "t.stl").unwrap().nodes[1][0],
            0.1
        );
    }

    #[test]
    fn binary_even_with_a_solid_header() {
        let tri = [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]]];
        for header in [&b"binary"[..], &b"solid but binary"[..]] {
            let m = parse_stl(&binary(header, &tri), "b.stl").unwrap();
            assert_eq!(m.nodes, vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]]);
            assert_eq!(m.connectivity, vec![0, 1, 2]);
        }
    }

    #[test]
    fn errors_name_line_or_byte() {
        let text = TETRA.replacen("vertex 0 1 0", "vertex 0 one 0", 1);
        let e = parse_stl(text.as_bytes(), "t.stl").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.stl, line 5: expected coordinate y (a number), found 'one'"
        );
        let text = TETRA.replacen("endloop", "endlop", 1);
        let e = parse_stl(text.as_bytes(), "t.stl").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.stl, line 7: expected 'endloop', found 'endlop'"
        );
        let text = TETRA.replacen("vertex 1 0 0", "vertex 1 0 nan", 1);
        let e = parse_stl(text.as_bytes(), "t.stl").unwrap_err();
        assert!(
            matches!(
                e,
                MeshReadError::NonFiniteCoordinate {
                    node: 3,
                    at: Some(Location::Line(6)),
                    ..
                }
            ),
            "{e}"
        );
        let cut = &TETRA[..TETRA.len() - "endsolid tetra made by hand\n".len()];
        let e = parse_stl(cut.as_bytes(), "t.stl").unwrap_err();
        assert!(matches!(e, MeshReadError::Truncated { .. }), "{e}");
        let e = parse_stl(b"solid x\nendsolid x\n", "e.stl").unwrap_err();
        assert_eq!(e.to_string(), "e.stl: the file holds no triangles");
        let e = parse_stl(b"hello", "h.stl").unwrap_err();
        assert!(e.to_string().starts_with("h.stl: not an STL file"), "{e}");
        let mut b = binary(b"", &[[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]]);
        b.pop();
        let e = parse_stl(&b, "b.stl").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("b.stl, byte 80: not an ASCII STL"),
            "{e}"
        );
        let b = binary(
            b"",
            &[[[0.0; 3], [1.0, 0.0, 0.0], [0.0, f32::INFINITY, 0.0]]],
        );
        let e = parse_stl(&b, "b.stl").unwrap_err();
        assert!(
            matches!(
                e,
                MeshReadError::NonFiniteCoordinate {
                    node: 3,
                    at: Some(Location::Byte(124)),
                    ..
                }
            ),
            "{e}"
        );
        let e = parse_stl(&binary(b"", &[]), "z.stl").unwrap_err();
        assert!(matches!(e, MeshReadError::NoTriangles { .. }), "{e}");
    }

    #[test]
    fn no_panic_on_damaged_input() {
        let text = TETRA.as_bytes();
        for n in 0..text.len() {
            let _ = parse_stl(&text[..n], "cut.stl");
        }
        let bin = binary(b"solid", &[[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]; 3]);
        let mut state: u64 = 5;
        for source in [text, &bin[..]] {
            for _ in 0..2000 {
                let mut copy = source.to_vec();
                for _ in 0..3 {
                    state = state
                        .wrapping_mul(6_364_136_223_846_793_005)
                        .wrapping_add(1_442_695_040_888_963_407);
                    let i = (state >> 33) as usize % copy.len();
                    copy[i] = (state >> 17) as u8;
                }
                let _ = parse_stl(&copy, "damaged.stl");
            }
        }
    }

    #[test]
    fn reads_a_file_and_names_it_in_io_errors() {
        let dir = std::env::temp_dir().join(format!("drape-stl-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("tetra.stl");
        std::fs::write(&path, TETRA).unwrap();
        assert_eq!(read_stl(&path).unwrap().element_count(), 4);
        let missing = dir.join("missing.stl");
        let e = read_stl(&missing).unwrap_err();
        assert!(matches!(e, MeshReadError::Io { .. }));
        assert_eq!(e.file(), missing.display().to_string());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
