//! Reading the files a scenario names (the scenario itself, meshes,
//! obstacle meshes): regular files only.
//!
//! Opening a FIFO blocks until something writes into it, and a device
//! such as `/dev/zero` never ends; a directory is no input either. Every
//! input is therefore checked to be a regular file (after symbolic links)
//! before it is opened, and refused by its path otherwise.
//!
//! Each file read is recorded with the hash of its bytes ([`InputFile`],
//! [`fnv1a`]): a resumed run refuses a changed one.

use std::io;
use std::path::{Path, PathBuf};

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

/// FNV-1a's initial state (its offset basis).
const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;

/// 64-bit FNV-1a of `bytes`: stable across platforms and Rust versions.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    fnv1a_extend(FNV_OFFSET, bytes)
}

/// FNV-1a continued from the state `h` over `bytes`: hashing a file in
/// pieces gives [`fnv1a`] of the whole (see [`InputFile::hash_file`]).
pub(crate) fn fnv1a_extend(mut h: u64, bytes: &[u8]) -> u64 {
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// A file a scenario reads, as it was when the setup was built.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputFile {
    /// The scenario key that names it: `mesh.path`, `obstacle[1].path`.
    pub key: String,
    /// Its path (absolute when it could be resolved).
    pub path: PathBuf,
    /// [`fnv1a`] of its bytes.
    pub hash: u64,
}

impl InputFile {
    /// The input read from `path` under `key`, whose bytes were `bytes`.
    pub(crate) fn new(key: String, path: &Path, bytes: &[u8]) -> Self {
        Self {
            key,
            path: std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()),
            hash: fnv1a(bytes),
        }
    }

    /// [`fnv1a`] of the file at `path` now, read in pieces (a mesh may be
    /// large). Anything but a regular file is refused before it is opened
    /// (a FIFO would block).
    pub fn hash_file(path: &Path) -> std::io::Result<u64> {
        use std::io::Read;
        check_regular(path)?;
        let mut file = std::fs::File::open(path)?;
        let mut buffer = vec![0u8; 1 << 16];
        let mut h = FNV_OFFSET;
        loop {
            match file.read(&mut buffer) {
                Ok(0) => return Ok(h),
                Ok(n) => h = fnv1a_extend(h, &buffer[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
    }
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
