//! `history.csv`: one row per converged step.
//!
//! The header line is written first (atomically, see
//! [`super::atomic::write_atomic`]); after that the file is opened in append
//! mode and every row is written as one complete line and flushed at once, so
//! that after a crash the file holds the header and every row written before
//! it. A row that cannot be written whole (a full disk, a file-size limit)
//! is cut off again, so that the file never ends in part of a row.
//! Readers can follow the file while the run goes on.
//!
//! Values are formatted with [`format_f64`], which reads back exactly with any
//! correct float parser (Rust's `str::parse::<f64>`, Python's `float`, pandas).

use std::fs::{File, OpenOptions};
use std::io::{self, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use super::atomic::write_atomic;

/// Formats `v` so that it parses back to exactly the same `f64` and stays
/// readable:
///
/// - `0` and magnitudes in `[1e-5, 1e16)` use plain decimal notation with the
///   shortest round-trip digits; integral values print without a fraction
///   (`12`, not `12.0`), so step and iteration counters read as integers;
/// - other magnitudes use the shortest round-trip scientific form
///   (`1.25e-9`, `3e20`);
/// - non-finite values print as `NaN`, `inf` and `-inf`.
pub fn format_f64(v: f64) -> String {
    let a = v.abs();
    if !v.is_finite() || a == 0.0 || (1e-5..1e16).contains(&a) {
        // Rust's Display is the shortest representation that round-trips.
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Appending writer of `history.csv`: a header of column names, then one row
/// of numbers per call to [`HistoryWriter::write_row`], each flushed to the
/// operating system before the call returns.
#[derive(Debug)]
pub struct HistoryWriter {
    path: PathBuf,
    columns: Vec<String>,
    /// The file, appended to one whole line at a time (no buffer: each row
    /// goes to the operating system as it is written).
    file: File,
    /// The file's length after the last complete row.
    len: u64,
    line: String,
}

impl HistoryWriter {
    /// Creates (or replaces) the file at `path` holding only the header
    /// line `columns` joined by commas, then opens it for appending rows.
    ///
    /// The header is written atomically, so a previous file at `path` is
    /// either kept whole or replaced whole.
    ///
    /// # Errors
    /// `InvalidInput` if `columns` is empty or a column name is empty or
    /// contains a comma, a double quote or a line break (names are not
    /// quoted); otherwise any I/O error.
    pub fn create(path: &Path, columns: &[String]) -> io::Result<Self> {
        let header = header_line(columns)?;
        write_atomic(path, header.as_bytes())?;
        Self::open(path, columns)
    }

    /// Opens an existing history file to append more rows, e.g. when a run
    /// resumes from a checkpoint.
    ///
    /// The first line of the file must equal the header that
    /// [`HistoryWriter::create`] would write for `columns`. If the file ends
    /// with an incomplete line (a crash in the middle of writing a row), that
    /// partial line is cut off so that the next row starts on a line of its
    /// own. Rows already in the file are otherwise kept; dropping rows past the
    /// resumed step is the caller's business.
    ///
    /// # Errors
    /// `InvalidInput` for bad column names (see [`HistoryWriter::create`]);
    /// `InvalidData` if the header in the file differs from `columns`;
    /// otherwise any I/O error (`NotFound` if the file does not exist).
    /// Reopens the history of a run resumed from a checkpoint: checks the
    /// header, keeps the first `rows` data rows (those up to the
    /// checkpoint; a crash may have left more) and appends after them.
    pub fn resume(path: &Path, columns: &[String], rows: usize) -> io::Result<Self> {
        let expected = header_line(columns)?;
        let content = std::fs::read(path)?;
        let mut lines = content.split_inclusive(|&b| b == b'\n');
        let header = lines.next().unwrap_or_default();
        if header.strip_suffix(b"\n").unwrap_or(header)
            != expected.trim_end_matches('\n').as_bytes()
        {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                format!(
                    "history file {} does not have the expected header",
                    path.display()
                ),
            ));
        }
        let kept: Vec<&[u8]> = lines.filter(|l| l.ends_with(b"\n")).take(rows).collect();
        if kept.len() < rows {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                format!(
                    "history file {} has {} complete rows, the checkpoint needs {rows}",
                    path.display(),
                    kept.len()
                ),
            ));
        }
        super::atomic::write_atomic_with(path, |w| {
            w.write_all(header)?;
            for l in kept {
                w.write_all(l)?;
            }
            Ok(())
        })?;
        Self::open(path, columns)
    }

    /// Reopens an existing history for appending (see [`HistoryWriter::resume`]
    /// to cut it back to a checkpoint).
    pub fn open_append(path: &Path, columns: &[String]) -> io::Result<Self> {
        let expected = header_line(columns)?;
        let mut file = OpenOptions::new().read(true).write(true).open(path)?;
        let mut content = Vec::new();
        file.read_to_end(&mut content)?;
        let header_end = content
            .iter()
            .position(|&b| b == b'\n')
            .map_or(content.len(), |i| i + 1);
        let found = &content[..header_end];
        let found = found.strip_suffix(b"\n").unwrap_or(found);
        let found = found.strip_suffix(b"\r").unwrap_or(found);
        if found != expected.trim_end_matches('\n').as_bytes() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                format!(
                    "history file {} has header {:?}, expected {:?}",
                    path.display(),
                    String::from_utf8_lossy(found),
                    expected.trim_end_matches('\n'),
                ),
            ));
        }
        if content.last() != Some(&b'\n') {
            // Cut an incomplete last row; keep a header that only lacks its
            // newline by completing it.
            let keep = content
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |i| i + 1);
            if keep == 0 {
                file.set_len(0)?;
                file.seek(SeekFrom::Start(0))?;
                file.write_all(expected.as_bytes())?;
            } else {
                file.set_len(keep as u64)?;
            }
            file.sync_data()?;
        }
        drop(file);
        Self::open(path, columns)
    }

    /// Opens `path` in append mode for rows.
    fn open(path: &Path, columns: &[String]) -> io::Result<Self> {
        let file = OpenOptions::new().append(true).open(path)?;
        let len = file.metadata()?.len();
        Ok(Self {
            path: path.to_path_buf(),
            columns: columns.to_vec(),
            file,
            len,
            line: String::new(),
        })
    }

    /// Appends one row and flushes it to the operating system.
    ///
    /// # Errors
    /// `InvalidInput` (and nothing written) if `values.len()` differs from the
    /// number of columns; otherwise any I/O error, after which the part of
    /// the row that was written is cut off again (as far as the file lets
    /// itself be truncated): the file ends with the last complete row.
    pub fn write_row(&mut self, values: &[f64]) -> io::Result<()> {
        if values.len() != self.columns.len() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "history row has {} values, expected {} ({})",
                    values.len(),
                    self.columns.len(),
                    self.columns.join(","),
                ),
            ));
        }
        self.line.clear();
        for (i, &v) in values.iter().enumerate() {
            if i > 0 {
                self.line.push(',');
            }
            self.line.push_str(&format_f64(v));
        }
        self.line.push('\n');
        match self.file.write_all(self.line.as_bytes()) {
            Ok(()) => {
                self.len += self.line.len() as u64;
                Ok(())
            }
            Err(e) => {
                // Best effort: the write's own error is the one to report.
                let _ = self.file.set_len(self.len);
                Err(e)
            }
        }
    }

    /// Column names, in file order.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }

    /// Path of the history file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The header line (with its newline) for `columns`, after validating them.
fn header_line(columns: &[String]) -> io::Result<String> {
    if columns.is_empty() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "history needs at least one column",
        ));
    }
    for c in columns {
        if c.is_empty() || c.contains([',', '"', '\n', '\r']) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "history column name {c:?} must be non-empty without commas, quotes or line breaks"
                ),
            ));
        }
    }
    let mut line = columns.join(",");
    line.push('\n');
    Ok(line)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    fn test_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "drape-output-history-{}-{}",
            name,
            std::process::id()
        ));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn cols(names: &[&str]) -> Vec<String> {
        names.iter().map(|s| s.to_string()).collect()
    }

    fn parse_rows(text: &str) -> Vec<Vec<f64>> {
        text.lines()
            .skip(1)
            .map(|l| l.split(',').map(|s| s.parse::<f64>().unwrap()).collect())
            .collect()
    }

    #[test]
    fn format_is_readable_and_round_trips() {
        assert_eq!(format_f64(12.0), "12");
        assert_eq!(format_f64(0.0), "0");
        assert_eq!(format_f64(-0.0), "-0");
        assert_eq!(format_f64(0.5), "0.5");
        assert_eq!(format_f64(-3.25), "-3.25");
        assert_eq!(format_f64(1e15), "1000000000000000");
        assert_eq!(format_f64(1e-5), "0.00001");
        assert_eq!(format_f64(1.5e-9), "1.5e-9");
        assert_eq!(format_f64(2e20), "2e20");
        assert_eq!(format_f64(f64::NAN), "NaN");
        assert_eq!(format_f64(f64::INFINITY), "inf");
        assert_eq!(format_f64(f64::NEG_INFINITY), "-inf");
        let samples = [
            0.1 + 0.2,
            std::f64::consts::PI,
            1.0 / 3.0,
            -2.0 / 3.0 * 1e-7,
            123456.789e10,
            f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            -0.0,
            9_007_199_254_740_993.0,
            1e16,
            0.999_999_999_999_999_9,
            12_345.678_901_234_567,
        ];
        for v in samples {
            let s = format_f64(v);
            let back: f64 = s.parse().unwrap();
            assert_eq!(back.to_bits(), v.to_bits(), "{v} -> {s}");
        }
        // A cheap deterministic sweep over many bit patterns.
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        for _ in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x);
            if v.is_nan() {
                continue;
            }
            let back: f64 = format_f64(v).parse().unwrap();
            assert_eq!(back.to_bits(), v.to_bits());
        }
    }

    #[test]
    fn header_rows_round_trip_and_flush_per_row() {
        let dir = test_dir("rows");
        let path = dir.join("history.csv");
        let columns = cols(&["step", "time", "iterations", "residual", "energy"]);
        let mut h = HistoryWriter::create(&path, &columns).unwrap();
        assert_eq!(h.columns(), &columns[..]);
        assert_eq!(h.path(), path.as_path());
        assert_eq!(
            fs::read_to_string(&path).unwrap(),
            "step,time,iterations,residual,energy\n"
        );

        let rows = vec![
            vec![1.0, 0.1, 4.0, 1.234_567_890_123_456_7e-11, -0.1 - 0.2],
            vec![2.0, 0.2, 3.0, 9.876e-13, std::f64::consts::E * 1e7],
            vec![3.0, 0.30000000000000004, 12.0, 0.0, 1e300],
        ];
        for (i, row) in rows.iter().enumerate() {
            h.write_row(row).unwrap();
            // Read between writes: the row must already be in the file.
            let text = fs::read_to_string(&path).unwrap();
            assert_eq!(text.lines().count(), i + 2);
            assert!(text.ends_with('\n'));
            let parsed = parse_rows(&text);
            assert_eq!(parsed.len(), i + 1);
            for (p, r) in parsed.iter().zip(&rows) {
                let pb: Vec<u64> = p.iter().map(|v| v.to_bits()).collect();
                let rb: Vec<u64> = r.iter().map(|v| v.to_bits()).collect();
                assert_eq!(pb, rb);
            }
        }
        let text = fs::read_to_string(&path).unwrap();
        let third = text.lines().nth(3).unwrap();
        assert!(
            third.starts_with("3,0.30000000000000004,12,0,1e300"),
            "{third}"
        );
        drop(h);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn wrong_row_length_is_an_error_and_writes_nothing() {
        let dir = test_dir("len");
        let path = dir.join("history.csv");
        let mut h = HistoryWriter::create(&path, &cols(&["a", "b"])).unwrap();
        let e = h.write_row(&[1.0]).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        let e = h.write_row(&[1.0, 2.0, 3.0]).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert_eq!(fs::read_to_string(&path).unwrap(), "a,b\n");
        h.write_row(&[1.0, 2.0]).unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "a,b\n1,2\n");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_column_names_are_rejected() {
        let dir = test_dir("names");
        let path = dir.join("history.csv");
        for bad in [vec![], cols(&["a,b"]), cols(&["x", ""]), cols(&["q\""])] {
            let e = HistoryWriter::create(&path, &bad).unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        }
        assert!(!path.exists());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn create_replaces_an_old_file() {
        let dir = test_dir("replace");
        let path = dir.join("history.csv");
        fs::write(&path, "old,header\n1,2\n").unwrap();
        let mut h = HistoryWriter::create(&path, &cols(&["step"])).unwrap();
        h.write_row(&[7.0]).unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "step\n7\n");
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn open_append_resumes_and_checks_header() {
        let dir = test_dir("append");
        let path = dir.join("history.csv");
        let columns = cols(&["step", "time"]);
        {
            let mut h = HistoryWriter::create(&path, &columns).unwrap();
            h.write_row(&[1.0, 0.5]).unwrap();
        }
        {
            let mut h = HistoryWriter::open_append(&path, &columns).unwrap();
            h.write_row(&[2.0, 1.0]).unwrap();
        }
        assert_eq!(
            fs::read_to_string(&path).unwrap(),
            "step,time\n1,0.5\n2,1\n"
        );

        let e = HistoryWriter::open_append(&path, &cols(&["step", "t"])).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
        let e = HistoryWriter::open_append(&path, &cols(&["step"])).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidData);
        let e = HistoryWriter::open_append(&dir.join("missing.csv"), &columns).unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::NotFound);
        // Failed opens leave the file alone.
        assert_eq!(
            fs::read_to_string(&path).unwrap(),
            "step,time\n1,0.5\n2,1\n"
        );
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn open_append_cuts_a_partial_last_row() {
        let dir = test_dir("partial");
        let path = dir.join("history.csv");
        let columns = cols(&["step", "time"]);
        fs::write(&path, "step,time\n1,0.5\n2,0.7").unwrap();
        let mut h = HistoryWriter::open_append(&path, &columns).unwrap();
        h.write_row(&[2.0, 0.75]).unwrap();
        assert_eq!(
            fs::read_to_string(&path).unwrap(),
            "step,time\n1,0.5\n2,0.75\n"
        );

        // A header that lost only its newline is completed.
        fs::write(&path, "step,time").unwrap();
        let mut h = HistoryWriter::open_append(&path, &columns).unwrap();
        h.write_row(&[1.0, 0.5]).unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), "step,time\n1,0.5\n");

        // CRLF header (edited on another system) is accepted.
        fs::write(&path, "step,time\r\n1,0.5\r\n").unwrap();
        let mut h = HistoryWriter::open_append(&path, &columns).unwrap();
        h.write_row(&[2.0, 1.0]).unwrap();
        assert_eq!(
            fs::read_to_string(&path).unwrap(),
            "step,time\r\n1,0.5\r\n2,1\n"
        );
        fs::remove_dir_all(&dir).unwrap();
    }
}
