//! Reading the files a scenario names (the scenario itself, meshes,
//! obstacle meshes): regular files only.
//!
//! Opening a FIFO blocks until something writes into it, and a device
//! such as `/dev/zero` never ends; a directory is no input either. Every
//! input is therefore checked to be a regular file (after symbolic links)
//! before it is opened, and refused by its path otherwise.

use std::io;
use std::path::Path;

/// Refuses `path` unless it is a regular file, saying what it is.
///
/// # Errors
/// The operating system's error when `path` cannot be examined (missing,
/// no permission), or `InvalidInput` naming the kind of file.
pub fn check_regular(path: &Path) -> io::Result<()> {
    let file_type = std::fs::metadata(path)?.file_type();
    if file_type.is_file() {
        return Ok(());
    }
    let kind = if file_type.is_dir() {
        "a directory"
    } else {
        kind_of_special(&file_type)
    };
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("it is {kind}, not a regular file (drape reads its inputs from files)"),
    ))
}

#[cfg(unix)]
fn kind_of_special(t: &std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

#[cfg(not(unix))]
fn kind_of_special(_: &std::fs::FileType) -> &'static str {
    "a special file"
}

/// The bytes of the regular file at `path` (see [`check_regular`]).
///
/// # Errors
/// As [`check_regular`], and any error reading the file.
pub fn read(path: &Path) -> io::Result<Vec<u8>> {
    check_regular(path)?;
    std::fs::read(path)
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    /// A FIFO and a device are refused by kind without blocking; a
    /// directory too; a regular file is read.
    #[test]
    fn only_regular_files_are_read() {
        let dir = std::env::temp_dir().join(format!("drape-input-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let fifo = dir.join("pipe");
        let status = std::process::Command::new("mkfifo").arg(&fifo).status();
        if status.is_ok_and(|s| s.success()) {
            let e = read(&fifo).unwrap_err();
            assert!(e.to_string().contains("a FIFO"), "{e}");
        }
        let e = read(Path::new("/dev/zero")).unwrap_err();
        assert!(e.to_string().contains("a device"), "{e}");
        assert!(read(&dir).unwrap_err().to_string().contains("a directory"));
        std::fs::write(dir.join("f"), "x").unwrap();
        assert_eq!(read(&dir.join("f")).unwrap(), b"x");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
