//! Crash-safe whole-file writes.
//!
//! A file is first written to a temporary name in the same directory
//! (`.<name>.tmp-<pid>`), flushed and synced to disk, then renamed over the
//! destination. A rename within one directory is atomic on POSIX file
//! systems, so readers (and a restarted run after a crash) see either the old
//! complete file or the new complete file, never a half-written one.
//!
//! The temporary name includes the process id, so two processes writing the
//! same path do not clobber each other's temporary file; two threads of one
//! process must not write the same path at the same time.

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Buffer size of the [`BufWriter`] handed to [`write_atomic_with`] (1 MiB):
/// large enough that multi-hundred-megabyte frames are written in few system
/// calls.
const BUFFER_SIZE: usize = 1 << 20;

/// Writes `bytes` to `path` atomically: temporary file in the same directory,
/// write, flush, `sync_data`, rename over `path`.
///
/// On error the temporary file is removed (best effort) and `path` is left
/// untouched.
///
/// # Errors
/// `InvalidInput` if `path` has no file name; otherwise any I/O error from
/// creating, writing, syncing or renaming the file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Streams a file to `path` atomically: `f` writes the content into a
/// buffered temporary file in the same directory; if it returns `Ok` the
/// buffer is flushed, the data synced to disk and the temporary file renamed
/// over `path`.
///
/// If `f` (or any later step) fails, the temporary file is removed (best
/// effort), `path` is left untouched and the error is returned.
///
/// # Errors
/// `InvalidInput` if `path` has no file name; the error returned by `f`; or
/// any I/O error from creating, flushing, syncing or renaming the file.
pub fn write_atomic_with(
    path: &Path,
    f: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> io::Result<()> {
    let tmp = temp_path(path)?;
    let result = write_then_rename(path, &tmp, f);
    if result.is_err() {
        // Best effort: the temporary may not exist (creation failed) or may
        // already have been renamed.
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// The temporary path used for `path`: `.<name>.tmp-<pid>` in the same
/// directory.
fn temp_path(path: &Path) -> io::Result<PathBuf> {
    let name = path.file_name().ok_or_else(|| {
        io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("atomic write: path {} has no file name", path.display()),
        )
    })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".tmp-{}", std::process::id()));
    Ok(path.with_file_name(tmp_name))
}

fn write_then_rename(
    path: &Path,
    tmp: &Path,
    f: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> io::Result<()> {
    let file = OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .open(tmp)?;
    let mut writer = BufWriter::with_capacity(BUFFER_SIZE, file);
    f(&mut writer)?;
    writer.flush()?;
    let file = writer.into_inner().map_err(|e| e.into_error())?;
    file.sync_data()?;
    drop(file);
    fs::rename(tmp, path)?;
    sync_parent_dir(path);
    Ok(())
}

/// Best-effort sync of the directory holding `path`, so that the rename itself
/// survives a power loss. Failures are ignored: the data is already complete
/// under one name or the other.
fn sync_parent_dir(path: &Path) {
    #[cfg(unix)]
    {
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
    }
    #[cfg(not(unix))]
    {
        let _ = path;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh, empty directory under the system temp dir.
    fn test_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "drape-output-atomic-{}-{}",
            name,
            std::process::id()
        ));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn temp_name_is_hidden_in_same_dir() {
        let tmp = temp_path(Path::new("/a/b/summary.json")).unwrap();
        assert_eq!(
            tmp,
            PathBuf::from(format!("/a/b/.summary.json.tmp-{}", std::process::id()))
        );
        let tmp = temp_path(Path::new("x.csv")).unwrap();
        assert_eq!(
            tmp,
            PathBuf::from(format!(".x.csv.tmp-{}", std::process::id()))
        );
    }

    #[test]
    fn writes_and_replaces_without_leaving_temp() {
        let dir = test_dir("replace");
        let path = dir.join("summary.json");
        write_atomic(&path, b"{\"a\": 1}").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"{\"a\": 1}");
        assert_eq!(entries(&dir), vec!["summary.json"]);

        // Shorter content fully replaces the longer one (no stale tail).
        write_atomic(&path, b"{}").unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"{}");
        assert_eq!(entries(&dir), vec!["summary.json"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn streaming_writer() {
        let dir = test_dir("stream");
        let path = dir.join("big.bin");
        write_atomic_with(&path, |w| {
            for i in 0..100_000u32 {
                w.write_all(&i.to_le_bytes())?;
            }
            Ok(())
        })
        .unwrap();
        let bytes = fs::read(&path).unwrap();
        assert_eq!(bytes.len(), 400_000);
        assert_eq!(&bytes[4 * 99_999..], &99_999u32.to_le_bytes());
        assert_eq!(entries(&dir), vec!["big.bin"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn failed_writer_keeps_old_file_and_removes_temp() {
        let dir = test_dir("fail");
        let path = dir.join("fields.pvd");
        write_atomic(&path, b"old").unwrap();
        let err = write_atomic_with(&path, |w| {
            w.write_all(b"partial new content")?;
            Err(io::Error::other("simulated failure"))
        })
        .unwrap_err();
        assert_eq!(err.to_string(), "simulated failure");
        assert_eq!(fs::read(&path).unwrap(), b"old");
        assert_eq!(entries(&dir), vec!["fields.pvd"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_directory_is_an_error() {
        let dir = test_dir("missing");
        let path = dir.join("no-such-dir").join("x.json");
        let err = write_atomic(&path, b"x").unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::NotFound);
        assert_eq!(entries(&dir), Vec::<String>::new());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn path_without_file_name_is_invalid_input() {
        let err = write_atomic(Path::new("/"), b"x").unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
    }
}
