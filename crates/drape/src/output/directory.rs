//! The output directory as drape's own: one writer at a time, and a fresh
//! run that starts from a clean slate without touching anybody else's
//! files.
//!
//! * **One writer.** A run (or a resumed run) holds an advisory lock on
//!   `DIR/drape.lock` for as long as it writes ([`OutputLock`], the
//!   operating system's `flock` through [`std::fs::File::try_lock`]). A
//!   second process is refused at once, told the holder's process id,
//!   which the holder writes into the file. The lock dies with its
//!   process: a killed run leaves no stale lock behind.
//! * **Only drape's files.** The lock file also marks the directory as
//!   drape's. A fresh run refuses a directory that holds anything but what
//!   drape writes there ([`OWN_FILES`], `fields/step_NNNNNN.vtu` and the
//!   temporary files of [`super::atomic`]) — or a directory with files but
//!   no lock file (not made by this drape) — naming what it found; the
//!   scenario being run may lie there itself. It then removes its own
//!   previous outputs ([`clear_previous_outputs`]), so that a run killed
//!   early never leaves an older run's summary or checkpoint beside a newer
//!   history.

use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The lock file's name.
pub const LOCK_FILE: &str = "drape.lock";

/// The copy of the scenario a run was started with.
pub const SCENARIO_COPY: &str = "scenario.toml";

/// The file naming the scenario a run was started with (its absolute
/// path, in the path's own bytes).
pub const SCENARIO_PATH: &str = "scenario.path";

/// The files drape writes at the top of an output directory (besides the
/// `fields/` folder and temporary files).
pub const OWN_FILES: [&str; 7] = [
    LOCK_FILE,
    SCENARIO_COPY,
    SCENARIO_PATH,
    "history.csv",
    "summary.json",
    "checkpoint.bin",
    "fields.pvd",
];

/// Why an output directory cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DirectoryError {
    /// Another process writes into it, or another run of this process
    /// (two threads calling the library on one directory).
    #[error(
        "{dir} is in use by {}: wait for it to end, or write into another directory (--out; out= from Python)",
        holder(*pid)
    )]
    Busy {
        /// The directory.
        dir: PathBuf,
        /// The holder's process id, when it could be read.
        pid: Option<u32>,
    },
    /// It holds files drape did not write.
    #[error(
        "{dir} holds files drape did not write ({}): a fresh run writes only into an empty directory or one of its own earlier outputs; choose another directory (--out; out= from Python), or move them away",
        entries.join(", ")
    )]
    Foreign {
        /// The directory.
        dir: PathBuf,
        /// What was found (at most a few names).
        entries: Vec<String>,
    },
    /// A resume's directory that is missing, not a directory, or holds no
    /// run; nothing was created or written.
    #[error("cannot resume in {dir}: {what}; name the output directory of a drape run")]
    NotARun {
        /// The directory.
        dir: PathBuf,
        /// What it is instead.
        what: NotARun,
    },
    /// The path is empty: it names no directory (and would put the lock
    /// into the working directory).
    #[error(
        "the output directory \"\" is an empty path: name a directory (--out; out= from Python)"
    )]
    Empty,
    /// It is not a directory, or cannot be created, read or locked.
    #[error("cannot use {path} as the output directory: {error}")]
    Io {
        /// The path.
        path: PathBuf,
        /// The error.
        error: std::io::Error,
    },
}

/// Who holds a directory's lock, from the process id in its lock file:
/// this process itself when the id is its own.
fn holder(pid: Option<u32>) -> String {
    match pid {
        Some(p) if p == std::process::id() => format!("another run in this process (process {p})"),
        Some(p) => format!("another drape process (process {p})"),
        None => "another drape process".into(),
    }
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> DirectoryError + '_ {
    move |error| DirectoryError::Io {
        path: path.to_path_buf(),
        error,
    }
}

/// What a resume's directory is instead of a run's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NotARun {
    /// Nothing is there.
    Missing,
    /// Something other than a directory is there.
    NotADirectory,
    /// A directory without any of [`RUN_FILES`].
    NoRun,
}

impl std::fmt::Display for NotARun {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NotARun::Missing => f.write_str("no such directory"),
            NotARun::NotADirectory => f.write_str("not a directory"),
            NotARun::NoRun => {
                let [a, b, c] = RUN_FILES;
                write!(f, "it holds no drape run (no {a}, {b} or {c})")
            }
        }
    }
}

/// The exclusive lock on an output directory, held until dropped.
#[derive(Debug)]
pub struct OutputLock {
    _file: File,
    /// Whether the lock file was there before: the directory is one drape
    /// wrote into before.
    was_drapes: bool,
}

/// Creates `dir` if needed and takes its lock; refuses at once if another
/// process holds it.
pub fn lock(dir: &Path) -> Result<OutputLock, DirectoryError> {
    if dir.as_os_str().is_empty() {
        return Err(DirectoryError::Empty);
    }
    if dir.exists() && !dir.is_dir() {
        return Err(DirectoryError::Io {
            path: dir.to_path_buf(),
            error: std::io::Error::other("it exists and is not a directory"),
        });
    }
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let path = dir.join(LOCK_FILE);
    let was_drapes = path.is_file();
    let mut file = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(io(&path))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(std::fs::TryLockError::WouldBlock) => {
            let mut text = String::new();
            let pid = file
                .read_to_string(&mut text)
                .ok()
                .and_then(|_| text.trim().parse().ok());
            return Err(DirectoryError::Busy {
                dir: dir.to_path_buf(),
                pid,
            });
        }
        Err(std::fs::TryLockError::Error(e)) => return Err(io(&path)(e)),
    }
    file.set_len(0)
        .and_then(|()| file.seek(SeekFrom::Start(0)))
        .and_then(|_| writeln!(file, "{}", std::process::id()))
        .and_then(|()| file.flush())
        .map_err(io(&path))?;
    Ok(OutputLock {
        _file: file,
        was_drapes,
    })
}

/// The files of which one marks a directory as holding a run, for a
/// resume: the checkpoint, the summary, the scenario's path.
pub const RUN_FILES: [&str; 3] = ["checkpoint.bin", "summary.json", SCENARIO_PATH];

/// Takes the lock of the directory a resume continues in, which must exist
/// and hold a run (one of [`RUN_FILES`]): nothing is created in a
/// directory that does not. A resume holds its directory before it reads
/// anything, so that a refusal can be recorded in the summary without
/// racing another writer.
pub fn lock_resume(dir: &Path) -> Result<OutputLock, DirectoryError> {
    if dir.as_os_str().is_empty() {
        return Err(DirectoryError::Empty);
    }
    let not_a_run = |what| {
        Err(DirectoryError::NotARun {
            dir: dir.to_path_buf(),
            what,
        })
    };
    if !dir.is_dir() {
        return not_a_run(if dir.exists() {
            NotARun::NotADirectory
        } else {
            NotARun::Missing
        });
    }
    if !RUN_FILES.iter().any(|f| dir.join(f).is_file()) {
        return not_a_run(NotARun::NoRun);
    }
    lock(dir)
}

/// Whether `name` (an entry of `fields/`) is a frame drape writes.
fn is_frame(name: &str) -> bool {
    name.strip_prefix("step_")
        .and_then(|s| s.strip_suffix(".vtu"))
        .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
}

/// Whether `name` is a temporary file of [`super::atomic`] (`.NAME.tmp-PID`).
fn is_temporary(name: &str) -> bool {
    name.starts_with('.') && name.contains(".tmp-")
}

/// Checks that `dir`, locked by `lock`, holds only drape's outputs —
/// `scenario`, the file being run, may lie there too — and removes the
/// previous run's outputs: summary, checkpoint, history, collection and
/// frames (not the scenario copy, which the caller rewrites).
///
/// A refused directory that had no lock file before `lock` made one is
/// left as it was found: the lock file goes again (the directory is not
/// drape's, and the next run into it must not take it for drape's).
pub fn clear_previous_outputs(
    lock: &OutputLock,
    dir: &Path,
    scenario: Option<&Path>,
) -> Result<(), DirectoryError> {
    let cleared = clear(lock, dir, scenario);
    if cleared.is_err() && !lock.was_drapes {
        // Nothing else was touched: without an earlier lock file every
        // file of drape's name counts as foreign, so nothing was removed.
        let _ = std::fs::remove_file(dir.join(LOCK_FILE));
    }
    cleared
}

fn clear(lock: &OutputLock, dir: &Path, scenario: Option<&Path>) -> Result<(), DirectoryError> {
    let scenario = scenario.and_then(|p| std::fs::canonicalize(p).ok());
    let had_lock = lock.was_drapes;
    let mut foreign = Vec::new();
    let mut own = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(io(dir))? {
        let entry = entry.map_err(io(dir))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let path = entry.path();
        if scenario.is_some() && std::fs::canonicalize(&path).ok() == scenario {
            continue;
        }
        if name == "fields" && path.is_dir() {
            for frame in std::fs::read_dir(&path).map_err(io(&path))? {
                let frame = frame.map_err(io(&path))?;
                let n = frame.file_name().to_string_lossy().into_owned();
                if is_frame(&n) || is_temporary(&n) {
                    own.push(frame.path());
                } else {
                    foreign.push(format!("fields/{n}"));
                }
            }
        } else if OWN_FILES.contains(&name.as_str()) || is_temporary(&name) {
            own.push(path);
        } else {
            foreign.push(name);
        }
    }
    // A directory drape never wrote into (no lock file from an earlier
    // run of this drape) is not drape's, whatever its files are called:
    // it may be the user's own `scenario.toml`.
    if !had_lock {
        foreign.extend(
            own.iter()
                .filter(|p| p.file_name().is_some_and(|n| n != LOCK_FILE))
                .map(|p| p.strip_prefix(dir).unwrap_or(p).display().to_string()),
        );
    }
    if !foreign.is_empty() {
        foreign.sort();
        if foreign.len() > 5 {
            let more = foreign.len() - 5;
            foreign.truncate(5);
            foreign.push(format!("and {more} more"));
        }
        return Err(DirectoryError::Foreign {
            dir: dir.to_path_buf(),
            entries: foreign,
        });
    }
    for path in own {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
        if matches!(
            name.as_deref(),
            Some(LOCK_FILE | SCENARIO_COPY | SCENARIO_PATH)
        ) {
            continue;
        }
        std::fs::remove_file(&path).map_err(io(&path))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("drape-dir-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    /// One lock at a time, even within one process (a second open file
    /// description); free again once the first is dropped.
    #[test]
    fn a_second_writer_is_refused_with_the_holders_pid() {
        let dir = scratch("lock");
        let held = lock(&dir).expect("free");
        match lock(&dir) {
            Err(e @ DirectoryError::Busy { pid, .. }) => {
                assert_eq!(pid, Some(std::process::id()));
                assert!(e.to_string().contains("another run in this process"), "{e}");
            }
            other => panic!("{other:?}"),
        }
        drop(held);
        lock(&dir).expect("free again");
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A resume's directory must be there and hold a run: refused
    /// otherwise with nothing created; taken (its lock) when it does.
    #[test]
    fn a_resume_needs_a_directory_holding_a_run() {
        let dir = scratch("resume");
        for (setup, said) in [
            (None, "no such directory"),
            (Some(false), "not a directory"),
            (Some(true), "holds no drape run"),
        ] {
            let _ = std::fs::remove_dir_all(&dir);
            let _ = std::fs::remove_file(&dir);
            match setup {
                Some(true) => std::fs::create_dir_all(&dir).unwrap(),
                Some(false) => std::fs::write(&dir, "a file").unwrap(),
                None => {}
            }
            match lock_resume(&dir) {
                Err(e @ DirectoryError::NotARun { .. }) => {
                    assert!(e.to_string().contains(said), "{e}")
                }
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "created");
        std::fs::write(dir.join("summary.json"), "{}").unwrap();
        let held = lock_resume(&dir).expect("a run");
        assert!(matches!(
            lock_resume(&dir),
            Err(DirectoryError::Busy { .. })
        ));
        drop(held);
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// A fresh run removes its own previous outputs and keeps nothing
    /// else; a file of the user's, or drape's names in a directory drape
    /// never wrote into, are refused by name.
    #[test]
    fn only_drapes_own_outputs_are_cleared() {
        let dir = scratch("clear");
        // An earlier run's directory: its lock file is there.
        drop(lock(&dir).expect("free"));
        let held = lock(&dir).expect("free");
        std::fs::create_dir_all(dir.join("fields")).unwrap();
        for f in [
            "summary.json",
            "checkpoint.bin",
            "history.csv",
            "fields.pvd",
            "fields/step_000010.vtu",
            "scenario.toml",
        ] {
            std::fs::write(dir.join(f), "x").unwrap();
        }
        clear_previous_outputs(&held, &dir, None).expect("all drape's");
        for f in [
            "summary.json",
            "checkpoint.bin",
            "history.csv",
            "fields.pvd",
            "fields/step_000010.vtu",
        ] {
            assert!(!dir.join(f).exists(), "{f} left");
        }
        assert!(dir.join("scenario.toml").exists() && dir.join(LOCK_FILE).exists());
        std::fs::write(dir.join("notes.txt"), "mine").unwrap();
        std::fs::write(dir.join("summary.json"), "x").unwrap();
        match clear_previous_outputs(&held, &dir, None) {
            Err(DirectoryError::Foreign { entries, .. }) => assert_eq!(entries, ["notes.txt"]),
            other => panic!("{other:?}"),
        }
        // Nothing was removed when refusing.
        assert!(dir.join("summary.json").exists());
        let _ = std::fs::remove_dir_all(&dir);

        let user = scratch("user");
        std::fs::create_dir_all(&user).unwrap();
        std::fs::write(user.join("scenario.toml"), "mine").unwrap();
        std::fs::write(user.join("variant.toml"), "run me").unwrap();
        let held = lock(&user).expect("free");
        match clear_previous_outputs(&held, &user, Some(&user.join("variant.toml"))) {
            Err(DirectoryError::Foreign { entries, .. }) => assert_eq!(entries, ["scenario.toml"]),
            other => panic!("{other:?}"),
        }
        // Refused, the directory is left as it was found: no lock file.
        assert!(!user.join(LOCK_FILE).exists());
        // The scenario being run may lie in the directory.
        std::fs::remove_file(user.join("scenario.toml")).unwrap();
        clear_previous_outputs(&held, &user, Some(&user.join("variant.toml")))
            .expect("only the scenario");
        let _ = std::fs::remove_dir_all(&user);
    }
}
