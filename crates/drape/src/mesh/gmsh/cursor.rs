//! The byte cursor of the Gmsh reader: lines, records and numbers of the
//! ASCII parts, fixed-size integers and floats of the binary parts, and the
//! checks that keep a corrupt count from reserving memory the file cannot
//! fill.

#![deny(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]

use super::{Location, MeshReadError};

/// Shows a token or line of the file in a message: lossy UTF-8, at most 40
/// characters.
pub(super) fn show(bytes: &[u8]) -> String {
    let text = String::from_utf8_lossy(bytes);
    let mut out: String = text.chars().take(40).collect();
    if text.chars().nth(40).is_some() {
        out.push('…');
    }
    out
}

/// Splits a line into whitespace-separated fields.
pub(super) fn split_fields<'a>(line: &'a [u8], out: &mut Vec<&'a [u8]>) {
    out.clear();
    out.extend(
        line.split(|b| b.is_ascii_whitespace())
            .filter(|t| !t.is_empty()),
    );
}

/// Cursor over the bytes of an MSH file.
pub(super) struct Reader<'a> {
    bytes: &'a [u8],
    /// Offset of the next unread byte.
    pos: usize,
    /// 1-based number of the line that starts at `pos` (text parts).
    line: usize,
    pub(super) file: &'a str,
    pub(super) binary: bool,
    pub(super) big_endian: bool,
    /// Size of `size_t` in a binary 4.1 file.
    pub(super) size_t: usize,
    /// Most nodes `$Nodes` may declare.
    pub(super) max_nodes: usize,
}

impl<'a> Reader<'a> {
    /// A cursor at the start of `bytes`, an ASCII file until `$MeshFormat`
    /// says otherwise; `file` names it in messages.
    pub(super) fn new(bytes: &'a [u8], file: &'a str) -> Self {
        // A UTF-8 byte-order mark, which some editors write, is skipped.
        let start = if bytes.starts_with(b"\xEF\xBB\xBF") {
            3
        } else {
            0
        };
        Self {
            bytes,
            pos: start,
            line: 1,
            file,
            binary: false,
            big_endian: false,
            size_t: 8,
            max_nodes: super::super::MAX_MESH_NODES,
        }
    }

    /// Refuses a `$Nodes` section that declares (at `at`) more than
    /// [`Reader::max_nodes`] nodes, before any is read.
    pub(super) fn check_node_count(&self, count: u64, at: Location) -> Result<(), MeshReadError> {
        super::super::check_node_cap(self.file, at, count, true, self.max_nodes)
    }

    pub(super) fn here(&self) -> Location {
        if self.binary {
            Location::Byte(self.pos)
        } else {
            Location::Line(self.line)
        }
    }

    pub(super) fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    pub(super) fn syntax(&self, at: Location, message: impl Into<String>) -> MeshReadError {
        MeshReadError::Syntax {
            file: self.file.to_owned(),
            at: Some(at),
            message: message.into(),
        }
    }

    pub(super) fn truncated(&self, section: &str) -> MeshReadError {
        MeshReadError::Truncated {
            file: self.file.to_owned(),
            section: section.to_owned(),
        }
    }

    /// The next line without its line end, and where it starts; `None` at
    /// the end of the file.
    pub(super) fn next_line(&mut self) -> Option<(&'a [u8], Location)> {
        let rest = self.bytes.get(self.pos..).filter(|r| !r.is_empty())?;
        let at = self.here();
        let line = rest.split(|&b| b == b'\n').next().unwrap_or(rest);
        self.pos = self
            .pos
            .saturating_add(line.len().saturating_add(1))
            .min(self.bytes.len());
        self.line = self.line.saturating_add(1);
        Some((line.strip_suffix(b"\r").unwrap_or(line), at))
    }

    /// The next line that is not blank, trimmed.
    pub(super) fn next_content_line(&mut self) -> Option<(&'a [u8], Location)> {
        loop {
            let (line, at) = self.next_line()?;
            let line = line.trim_ascii();
            if !line.is_empty() {
                return Some((line, at));
            }
        }
    }

    /// Reads the next record line of a section into `fields`. A line that
    /// starts a new section (`$...`) means the section has fewer records
    /// than it announced.
    pub(super) fn record(
        &mut self,
        section: &str,
        what: impl FnOnce() -> String,
        fields: &mut Vec<&'a [u8]>,
    ) -> Result<Location, MeshReadError> {
        let (line, at) = self
            .next_content_line()
            .ok_or_else(|| self.truncated(section))?;
        if line.starts_with(b"$") {
            return Err(self.syntax(
                at,
                format!(
                    "{section} ends early: expected {}, found '{}'",
                    what(),
                    show(line)
                ),
            ));
        }
        split_fields(line, fields);
        Ok(at)
    }

    /// Checks that a record has `n` fields.
    pub(super) fn expect_fields(
        &self,
        fields: &[&[u8]],
        n: usize,
        what: &str,
        at: Location,
    ) -> Result<(), MeshReadError> {
        if fields.len() == n {
            Ok(())
        } else {
            Err(self.syntax(
                at,
                format!(
                    "expected {n} number{} for {what}, found {}",
                    if n == 1 { "" } else { "s" },
                    fields.len()
                ),
            ))
        }
    }

    pub(super) fn field<'f>(
        &self,
        fields: &[&'f [u8]],
        i: usize,
        at: Location,
    ) -> Result<&'f [u8], MeshReadError> {
        fields
            .get(i)
            .copied()
            .ok_or_else(|| self.syntax(at, format!("missing field {}", i + 1)))
    }

    pub(super) fn parse_u64(
        &self,
        tok: &[u8],
        what: &str,
        at: Location,
    ) -> Result<u64, MeshReadError> {
        std::str::from_utf8(tok)
            .ok()
            .and_then(|s| s.parse::<u64>().ok())
            .ok_or_else(|| {
                self.syntax(
                    at,
                    format!(
                        "expected {what} (a non-negative integer), found '{}'",
                        show(tok)
                    ),
                )
            })
    }

    pub(super) fn parse_i64(
        &self,
        tok: &[u8],
        what: &str,
        at: Location,
    ) -> Result<i64, MeshReadError> {
        std::str::from_utf8(tok)
            .ok()
            .and_then(|s| s.parse::<i64>().ok())
            .ok_or_else(|| {
                self.syntax(
                    at,
                    format!("expected {what} (an integer), found '{}'", show(tok)),
                )
            })
    }

    pub(super) fn parse_usize(
        &self,
        tok: &[u8],
        what: &str,
        at: Location,
    ) -> Result<usize, MeshReadError> {
        let v = self.parse_u64(tok, what, at)?;
        usize::try_from(v).map_err(|_| self.syntax(at, format!("{what} {v} is too large")))
    }

    pub(super) fn parse_f64(
        &self,
        tok: &[u8],
        what: &str,
        at: Location,
    ) -> Result<f64, MeshReadError> {
        std::str::from_utf8(tok)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .ok_or_else(|| {
                self.syntax(
                    at,
                    format!("expected {what} (a number), found '{}'", show(tok)),
                )
            })
    }

    /// Parses three coordinates from `fields[first..first + 3]`.
    pub(super) fn parse_xyz(
        &self,
        fields: &[&[u8]],
        first: usize,
        at: Location,
    ) -> Result<[f64; 3], MeshReadError> {
        let mut x = [0.0; 3];
        for (k, (xk, name)) in x.iter_mut().zip(["x", "y", "z"]).enumerate() {
            let tok = self.field(fields, first + k, at)?;
            *xk = self.parse_f64(tok, &format!("coordinate {name}"), at)?;
        }
        Ok(x)
    }

    /// Reads a line holding a single count.
    pub(super) fn count_line(
        &mut self,
        section: &str,
        what: &str,
    ) -> Result<(u64, Location), MeshReadError> {
        let mut fields = Vec::new();
        let at = self.record(section, || what.to_owned(), &mut fields)?;
        self.expect_fields(&fields, 1, what, at)?;
        let tok = self.field(&fields, 0, at)?;
        Ok((self.parse_u64(tok, what, at)?, at))
    }

    /// Reads a line of `N` integers (`N` named in `names`).
    pub(super) fn int_line<const N: usize>(
        &mut self,
        section: &str,
        what: &str,
        names: [&str; N],
    ) -> Result<([i64; N], Location), MeshReadError> {
        let mut fields = Vec::new();
        let at = self.record(section, || what.to_owned(), &mut fields)?;
        self.expect_fields(&fields, N, what, at)?;
        let mut out = [0i64; N];
        for (k, (o, name)) in out.iter_mut().zip(names).enumerate() {
            *o = self.parse_i64(self.field(&fields, k, at)?, name, at)?;
        }
        Ok((out, at))
    }

    /// Skips to the end of section `$name`.
    pub(super) fn skip_section(&mut self, name: &[u8]) -> Result<(), MeshReadError> {
        let end = [b"$End".as_slice(), name].concat();
        loop {
            let Some((line, _)) = self.next_line() else {
                return Err(self.truncated(&format!("${}", show(name))));
            };
            if line.trim_ascii() == end.as_slice() {
                return Ok(());
            }
        }
    }

    /// Reads the `$End{name}` line that closes a section.
    pub(super) fn expect_end(&mut self, name: &str) -> Result<(), MeshReadError> {
        let (line, at) = self
            .next_content_line()
            .ok_or_else(|| self.truncated(&format!("${name}")))?;
        if line.strip_prefix(b"$End") == Some(name.as_bytes()) {
            Ok(())
        } else {
            Err(self.syntax(at, format!("expected $End{name}, found '{}'", show(line))))
        }
    }

    // ----- binary -----

    pub(super) fn take(&mut self, n: usize, section: &str) -> Result<&'a [u8], MeshReadError> {
        let end = self
            .pos
            .checked_add(n)
            .ok_or_else(|| self.truncated(section))?;
        let bytes = self
            .bytes
            .get(self.pos..end)
            .ok_or_else(|| self.truncated(section))?;
        self.pos = end;
        Ok(bytes)
    }

    pub(super) fn take_array<const N: usize>(
        &mut self,
        section: &str,
    ) -> Result<[u8; N], MeshReadError> {
        let bytes = self.take(N, section)?;
        bytes.try_into().map_err(|_| self.truncated(section))
    }

    pub(super) fn read_i32(&mut self, section: &str) -> Result<i32, MeshReadError> {
        let b = self.take_array::<4>(section)?;
        Ok(if self.big_endian {
            i32::from_be_bytes(b)
        } else {
            i32::from_le_bytes(b)
        })
    }

    /// Reads a non-negative `int` (a tag or count).
    pub(super) fn read_int_u64(&mut self, section: &str, what: &str) -> Result<u64, MeshReadError> {
        let at = self.here();
        let v = self.read_i32(section)?;
        u64::try_from(v).map_err(|_| self.syntax(at, format!("{what} is negative ({v})")))
    }

    pub(super) fn read_size_t(&mut self, section: &str) -> Result<u64, MeshReadError> {
        if self.size_t == 4 {
            let b = self.take_array::<4>(section)?;
            Ok(u64::from(if self.big_endian {
                u32::from_be_bytes(b)
            } else {
                u32::from_le_bytes(b)
            }))
        } else {
            let b = self.take_array::<8>(section)?;
            Ok(if self.big_endian {
                u64::from_be_bytes(b)
            } else {
                u64::from_le_bytes(b)
            })
        }
    }

    pub(super) fn read_f64(&mut self, section: &str) -> Result<f64, MeshReadError> {
        let b = self.take_array::<8>(section)?;
        Ok(if self.big_endian {
            f64::from_be_bytes(b)
        } else {
            f64::from_le_bytes(b)
        })
    }

    pub(super) fn read_xyz(&mut self, section: &str) -> Result<[f64; 3], MeshReadError> {
        Ok([
            self.read_f64(section)?,
            self.read_f64(section)?,
            self.read_f64(section)?,
        ])
    }

    /// Checks that `count` records of `record` bytes fit in the rest of the
    /// file, before reading (or reserving memory for) them.
    pub(super) fn check_room(
        &self,
        count: u64,
        record: usize,
        section: &str,
    ) -> Result<(), MeshReadError> {
        let need = u64::try_from(record)
            .ok()
            .and_then(|r| count.checked_mul(r));
        let have = u64::try_from(self.remaining()).unwrap_or(u64::MAX);
        if need.is_none_or(|need| need > have) {
            Err(self.truncated(section))
        } else {
            Ok(())
        }
    }

    /// Capacity to reserve for `count` records of at least `min_record`
    /// bytes each: no more than the rest of the file can hold.
    pub(super) fn capacity(&self, count: u64, min_record: usize) -> usize {
        let fit = self.remaining() / min_record.max(1);
        usize::try_from(count).map_or(fit, |c| c.min(fit))
    }
}

#[cfg(test)]
#[allow(
    clippy::indexing_slicing,
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic
)]
mod tests {
    use crate::mesh::gmsh::fixtures::*;
    use crate::mesh::gmsh::{Location, MeshReadError, parse_msh, parse_msh_at_most};

    #[test]
    fn error_truncated_file() {
        let cut = &V22_T3[..V22_T3.find("3 1 1 0").unwrap()];
        let err = parse(cut).unwrap_err();
        assert!(
            matches!(&err, MeshReadError::Truncated { section, .. } if section == "$Nodes"),
            "{err}"
        );
        assert_eq!(
            err.to_string(),
            "test.msh: the file ends inside $Nodes, which is incomplete"
        );
        let bytes = v41_binary_t6_bytes(None);
        let err = parse_msh(&bytes[..bytes.len() - 40], "bin.msh").unwrap_err();
        assert!(
            matches!(&err, MeshReadError::Truncated { section, .. } if section == "$Elements"),
            "{err}"
        );
        let err = parse("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Elements\n1\n").unwrap_err();
        assert!(matches!(err, MeshReadError::Truncated { .. }), "{err}");
    }

    #[test]
    fn error_garbage_bytes() {
        let garbage: Vec<u8> = (0..4096u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
            .collect();
        let err = parse_msh(&garbage, "junk.msh").unwrap_err();
        assert!(matches!(err, MeshReadError::Syntax { .. }), "{err}");
        assert!(err.to_string().starts_with("junk.msh"));
        let err = parse_msh(b"", "empty.msh").unwrap_err();
        assert!(
            matches!(err, MeshReadError::Syntax { at: None, .. }),
            "{err}"
        );
        let err = parse("$MeshFormat\n4.1 0 8\n$EndMeshFormat\nhello\n").unwrap_err();
        assert_eq!(
            err.to_string(),
            "test.msh, line 4: expected a section header such as $Nodes, found 'hello'"
        );
        let err = parse("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 zero 0\n$EndNodes\n")
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "test.msh, line 6: expected coordinate y (a number), found 'zero'"
        );
    }

    #[test]
    fn error_message_names_file_line_and_counts() {
        let text = V22_T3.replace("2 1 0 0\n", "2 1 0\n");
        let err = parse_msh(text.as_bytes(), "fabric.msh").unwrap_err();
        assert_eq!(
            err.to_string(),
            "fabric.msh, line 12: expected 4 numbers for node, found 3"
        );
        assert_eq!(err.location(), Some(Location::Line(12)));
        let text = V22_T3.replace("4\n1 15", "5\n1 15");
        let err = parse(&text).unwrap_err();
        assert_eq!(
            err.to_string(),
            "test.msh, line 22: $Elements ends early: expected element 5 of 5, found '$EndElements'"
        );
    }

    /// Counts past the file's size fail fast, without reserving memory
    /// for them; read without a node cap (which would refuse the node
    /// counts first), so that the bound by the file's size is what is
    /// tested.
    #[test]
    fn error_huge_counts_fail_fast_without_allocating() {
        let uncapped = |bytes: &[u8]| parse_msh_at_most(bytes, "bin.msh", usize::MAX);
        let parse = |text: &str| uncapped(text.as_bytes());
        let start = std::time::Instant::now();
        // ASCII 2.2.
        let text = V22_T3.replace("$Nodes\n4\n", "$Nodes\n1000000000000\n");
        assert!(parse(&text).is_err());
        let text = V22_T3.replace("$Elements\n4\n", "$Elements\n1000000000000\n");
        assert!(parse(&text).is_err());
        // ASCII 4.1, in the header and in a block.
        let text = V41_T3.replace("$Nodes\n3 4 1 4\n", "$Nodes\n3 1000000000000 1 4\n");
        assert!(parse(&text).is_err());
        let text = V41_T3.replace("0 1 0 2\n", "0 1 0 1000000000000\n");
        assert!(parse(&text).is_err());
        // Binary 2.2: the count line.
        let bytes = v22_binary_t3(false);
        let text = String::from_utf8_lossy(&bytes).into_owned();
        assert!(text.contains("$Nodes\n4\n"));
        let mut bytes2 = Vec::new();
        let at = bytes.windows(9).position(|w| w == b"$Nodes\n4\n").unwrap();
        bytes2.extend_from_slice(&bytes[..at]);
        bytes2.extend_from_slice(b"$Nodes\n1000000000000\n");
        bytes2.extend_from_slice(&bytes[at + 9..]);
        let err = uncapped(&bytes2).unwrap_err();
        assert!(matches!(err, MeshReadError::Truncated { .. }), "{err}");
        // Binary 4.1: the header and a block.
        let err = uncapped(&v41_binary_t6_bytes(Some(1_000_000_000_000))).unwrap_err();
        assert!(matches!(err, MeshReadError::Truncated { .. }), "{err}");
        let mut b = Bin::new();
        b.s("$MeshFormat\n4.1 1 8\n")
            .i(1)
            .s("\n$EndMeshFormat\n$Nodes\n");
        b.z(1)
            .z(u64::MAX)
            .z(1)
            .z(u64::MAX)
            .i(2)
            .i(1)
            .i(0)
            .z(u64::MAX);
        let err = uncapped(&b.v).unwrap_err();
        assert!(matches!(err, MeshReadError::Truncated { .. }), "{err}");
        assert!(start.elapsed() < std::time::Duration::from_secs(2));
    }
}
