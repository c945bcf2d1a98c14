//! `fields.pvd`: the ParaView collection file that ties the frames
//! `fields/step_NNNNNN.vtu` into a time series.
//!
//! The whole collection is rewritten atomically after each frame is added,
//! so the file on disk is always complete, valid XML and lists only frames
//! that were fully written before it (write the `.vtu` first, then
//! [`PvdWriter::push`] it).

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use super::atomic::write_atomic_with;
use super::history::format_f64;

/// Path of the frame of step `step` relative to the output directory (and so
/// to `fields.pvd`): `fields/step_NNNNNN.vtu`, with the step number
/// zero-padded to 6 digits (more digits past 999999).
pub fn frame_relative_path(step: u64) -> String {
    format!("fields/step_{step:06}.vtu")
}

/// Writer of a ParaView `.pvd` collection: a list of `(time, file)` pairs,
/// rewritten whole and atomically on every [`PvdWriter::push`].
#[derive(Debug, Clone)]
pub struct PvdWriter {
    path: PathBuf,
    entries: Vec<(f64, String)>,
}

impl PvdWriter {
    /// A writer for the collection file at `path` with no entries yet.
    /// Nothing is written until the first [`PvdWriter::push`].
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            entries: Vec::new(),
        }
    }

    /// A collection resumed from a checkpoint: exactly `entries` (the
    /// frames written up to the checkpoint), written at once.
    pub fn resume(path: impl Into<PathBuf>, entries: Vec<(f64, String)>) -> io::Result<Self> {
        let writer = Self {
            path: path.into(),
            entries,
        };
        writer.write()?;
        Ok(writer)
    }

    /// Adds the frame `relative_file` (relative to the directory of the
    /// collection file, `/`-separated, e.g. from [`frame_relative_path`]) at
    /// `time`, then rewrites the collection file atomically.
    ///
    /// If writing fails the entry is not kept, so the in-memory list matches
    /// the file on disk.
    ///
    /// # Errors
    /// `InvalidInput` if `time` is not finite; otherwise any I/O error.
    pub fn push(&mut self, time: f64, relative_file: &str) -> io::Result<()> {
        if !time.is_finite() {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("pvd entry {relative_file:?}: time {time} is not finite"),
            ));
        }
        self.entries.push((time, relative_file.to_owned()));
        let result = self.write();
        if result.is_err() {
            self.entries.pop();
        }
        result
    }

    /// The `(time, relative_file)` entries written so far, in push order.
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }

    /// Path of the collection file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn write(&self) -> io::Result<()> {
        write_atomic_with(&self.path, |w| {
            w.write_all(
                b"<?xml version=\"1.0\"?>\n\
                  <VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n\
                  \x20 <Collection>\n",
            )?;
            for (time, file) in &self.entries {
                writeln!(
                    w,
                    "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>",
                    format_f64(*time),
                    escape_xml_attr(file)
                )?;
            }
            w.write_all(b"  </Collection>\n</VTKFile>\n")
        })
    }
}

/// Escapes `s` for use inside a double-quoted XML attribute.
pub(crate) fn escape_xml_attr(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            '\t' => out.push_str("&#9;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    fn test_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("drape-output-pvd-{}-{}", name, std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// Checks the XML-ish shape of a collection file and returns its
    /// `(timestep, file)` attributes in order.
    fn parse_collection(text: &str) -> Vec<(f64, String)> {
        assert!(text.starts_with("<?xml version=\"1.0\"?>\n"));
        assert!(text.contains("<VTKFile type=\"Collection\""));
        assert!(text.ends_with("  </Collection>\n</VTKFile>\n"));
        assert_eq!(text.matches("<Collection>").count(), 1);
        assert_eq!(text.matches("</Collection>").count(), 1);
        assert_eq!(text.matches('<').count(), text.matches('>').count());
        text.lines()
            .filter(|l| l.trim_start().starts_with("<DataSet "))
            .map(|l| {
                assert!(l.trim_end().ends_with("/>"), "{l}");
                (attr(l, "timestep").parse().unwrap(), attr(l, "file"))
            })
            .collect()
    }

    fn attr(line: &str, name: &str) -> String {
        let key = format!(" {name}=\"");
        let start = line.find(&key).unwrap() + key.len();
        let len = line[start..].find('"').unwrap();
        line[start..start + len].to_string()
    }

    #[test]
    fn frame_paths_are_zero_padded() {
        assert_eq!(frame_relative_path(0), "fields/step_000000.vtu");
        assert_eq!(frame_relative_path(42), "fields/step_000042.vtu");
        assert_eq!(frame_relative_path(1_234_567), "fields/step_1234567.vtu");
    }

    #[test]
    fn lists_entries_in_order_and_is_valid_after_every_push() {
        let dir = test_dir("order");
        let path = dir.join("fields.pvd");
        let mut pvd = PvdWriter::new(&path);
        assert!(pvd.entries().is_empty());
        assert!(!path.exists());
        let times = [0.0, 0.1, 0.30000000000000004, 1.5e-9 + 1.0, 12.0];
        for (i, &t) in times.iter().enumerate() {
            let file = frame_relative_path(i as u64 * 10);
            pvd.push(t, &file).unwrap();
            let parsed = parse_collection(&fs::read_to_string(&path).unwrap());
            assert_eq!(parsed.len(), i + 1);
            for (k, (pt, pf)) in parsed.iter().enumerate() {
                assert_eq!(pt.to_bits(), times[k].to_bits());
                assert_eq!(pf, &frame_relative_path(k as u64 * 10));
            }
            assert_eq!(pvd.entries(), &parsed[..]);
        }
        let names: Vec<_> = fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        assert_eq!(names, vec!["fields.pvd"]);
        let text = fs::read_to_string(&path).unwrap();
        assert!(text.contains(
            "<DataSet timestep=\"0.1\" group=\"\" part=\"0\" file=\"fields/step_000010.vtu\"/>"
        ));
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn escapes_file_names_and_rejects_non_finite_time() {
        let dir = test_dir("escape");
        let path = dir.join("fields.pvd");
        let mut pvd = PvdWriter::new(path.clone());
        pvd.push(1.0, "a&b\"<c>.vtu").unwrap();
        let text = fs::read_to_string(&path).unwrap();
        assert!(text.contains("file=\"a&amp;b&quot;&lt;c&gt;.vtu\""));
        let e = pvd.push(f64::NAN, "x.vtu").unwrap_err();
        assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
        assert_eq!(pvd.entries().len(), 1);
        assert_eq!(fs::read_to_string(&path).unwrap(), text);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failed_write_does_not_keep_entry() {
        let dir = test_dir("fail");
        let mut pvd = PvdWriter::new(dir.join("missing-dir").join("fields.pvd"));
        assert!(pvd.push(0.0, "a.vtu").is_err());
        assert!(pvd.entries().is_empty());
        fs::remove_dir_all(&dir).unwrap();
    }
}
