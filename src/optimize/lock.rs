//! The output-directory lock of `kinsynth optimize`: one run per directory at a time.
//!
//! The lock is the file [`LOCK_FILE`] in the output directory, held with an exclusive advisory
//! lock (`flock`) for as long as the run lasts and holding the owner's pid, host and command
//! line. The operating system drops the advisory lock when the process ends in any way, so a
//! lock file left by a killed run is stale: the next run takes it over with a warning. On
//! systems without `flock` the file itself is the lock, and a stale one must be removed by
//! hand (the error says so).

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

/// Name of the lock file in the output directory.
pub const LOCK_FILE: &str = ".kinsynth.lock";

/// Most bytes of a lock file read for its owner (a run writes about 200): a longer one names
/// no owner.
const MAX_LOCK_BYTES: u64 = 64 * 1024;

/// Who holds a lock: written into the lock file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Owner {
    /// Process id.
    pub pid: u32,
    /// Host name.
    pub host: String,
    /// Command line.
    pub command: String,
    /// Seconds since the Unix epoch when the lock was taken.
    pub since: u64,
}

impl Owner {
    /// This process.
    pub fn this_process() -> Self {
        Owner {
            pid: std::process::id(),
            host: host_name(),
            command: std::env::args().collect::<Vec<_>>().join(" "),
            since: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs()),
        }
    }

    /// The owner for a message, on one line and of a readable length whatever the lock file
    /// holds (its host and command are shown escaped and shortened, as values in errors are).
    fn describe(&self) -> String {
        crate::error::shorten(&format!(
            "pid {} on host {} ({}), since {} (Unix time)",
            self.pid, self.host, self.command, self.since
        ))
        .into_owned()
    }
}

/// The host name, or `unknown`.
fn host_name() -> String {
    for f in ["/proc/sys/kernel/hostname", "/etc/hostname"] {
        if let Ok(h) = std::fs::read_to_string(f) {
            let h = h.trim();
            if !h.is_empty() {
                return h.to_string();
            }
        }
    }
    std::env::var("HOSTNAME").unwrap_or_else(|_| "unknown".into())
}

/// A held output-directory lock; dropping it removes the lock file and releases the lock, and
/// removes the directory too when acquiring created it and it is still empty (a run refused
/// before it wrote anything leaves nothing behind).
#[derive(Debug)]
pub struct OutputLock {
    path: PathBuf,
    file: Option<File>,
    /// The directories acquiring created (the directory and the missing folders above it),
    /// deepest first.
    created: Vec<PathBuf>,
}

/// What acquiring found besides the lock itself.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Acquired {
    /// The owner of a stale lock that was taken over (its process had ended).
    pub took_over: Option<Owner>,
    /// Temporary files of a killed run (`.kinsynth-*.tmp`) that were removed.
    pub removed: Vec<PathBuf>,
}

fn lock_error(path: &Path, reason: String) -> Error {
    Error::invalid("output directory", path.display(), reason)
}

impl OutputLock {
    /// Takes the lock of directory `dir` (created if missing), then removes the temporary files
    /// (`.kinsynth-*.tmp`) a killed run left in `dir` and `dir/trajectories`. Refused, with an
    /// error naming the running process, when another process holds it.
    pub fn acquire(dir: &Path) -> Result<(OutputLock, Acquired)> {
        // Only for a plain path: through `..` or a symbolic link an ancestor's name may not
        // be the folder that is created (`new/../keep` creates `new` and names `keep`).
        let plain = dir.components().all(|c| {
            matches!(
                c,
                std::path::Component::Normal(_) | std::path::Component::RootDir
            )
        }) && dir.ancestors().skip(1).all(|d| {
            d.as_os_str().is_empty()
                || std::fs::symlink_metadata(d).map_or(true, |m| !m.file_type().is_symlink())
        });
        let created: Vec<PathBuf> = if plain {
            dir.ancestors()
                .filter(|d| !d.as_os_str().is_empty())
                .take_while(|d| !d.exists())
                .map(Path::to_path_buf)
                .collect()
        } else {
            Vec::new()
        };
        std::fs::create_dir_all(dir).map_err(|source| Error::Write {
            path: dir.to_path_buf(),
            source,
        })?;
        let path = dir.join(LOCK_FILE);
        let write_err = |source| Error::Write {
            path: path.clone(),
            source,
        };
        // A run writes its lock as a regular file: anything else there (a FIFO, which would
        // block the read; a link to /dev/zero, which would never end) is refused, not read.
        if let Ok(m) = std::fs::symlink_metadata(&path) {
            if !m.file_type().is_file() {
                return Err(lock_error(
                    dir,
                    format!(
                        "{} is not a regular file, as a run's lock is: remove it",
                        path.display()
                    ),
                ));
            }
        }
        let (mut file, previous) = loop {
            let mut options = std::fs::OpenOptions::new();
            options.read(true).write(true).create(true).truncate(false);
            #[cfg(unix)]
            {
                // Nor through a link or a FIFO put there since the check above.
                use std::os::unix::fs::OpenOptionsExt;
                options.custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK);
            }
            let file = options.open(&path).map_err(write_err)?;
            let mut text = String::new();
            // A lock file that cannot be read as text, or is longer than an owner's record,
            // is treated as empty (no owner known).
            let _ = (&file).take(MAX_LOCK_BYTES).read_to_string(&mut text);
            let previous: Option<Owner> = serde_json::from_str(&text).ok();
            if !try_lock(&file).map_err(write_err)? {
                let who = previous.map_or_else(
                    || "another process (its details are not written yet)".to_string(),
                    |o| o.describe(),
                );
                return Err(lock_error(
                    dir,
                    format!(
                        "in use by {who}: wait for that run to end, or give another --out; {} is its lock",
                        path.display()
                    ),
                ));
            }
            // The file may have been removed (or replaced) by its owner between our open and
            // our lock; then the lock we hold is on a dead file: start over.
            if same_file(&file, &path) {
                break (file, previous);
            }
        };
        let me = Owner::this_process();
        let took_over = previous;
        let json = serde_json::to_string(&me).expect("an owner serialises");
        file.set_len(0).map_err(write_err)?;
        file.rewind().map_err(write_err)?;
        file.write_all(json.as_bytes()).map_err(write_err)?;
        file.sync_all().map_err(write_err)?;
        let lock = OutputLock {
            path,
            file: Some(file),
            created,
        };
        let mut removed = Vec::new();
        for d in [
            dir.to_path_buf(),
            dir.join(crate::optimize::runner::files::TRAJECTORIES),
        ] {
            let Ok(entries) = std::fs::read_dir(&d) else {
                continue;
            };
            for e in entries.flatten() {
                let name = e.file_name();
                let name = name.to_string_lossy();
                if name.starts_with(".kinsynth-")
                    && name.ends_with(".tmp")
                    && e.file_type().is_ok_and(|t| t.is_file())
                    && std::fs::remove_file(e.path()).is_ok()
                {
                    removed.push(e.path());
                }
            }
        }
        removed.sort();
        Ok((lock, Acquired { took_over, removed }))
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        // Remove the file while holding the lock, then the directory this lock created if
        // nothing else is in it, then release the lock by closing.
        let _ = std::fs::remove_file(&self.path);
        for dir in &self.created {
            if std::fs::remove_dir(dir).is_err() {
                break; // not empty: it (and the folders above it) stay
            }
        }
        drop(self.file.take());
    }
}

#[cfg(unix)]
fn try_lock(file: &File) -> std::io::Result<bool> {
    use std::os::unix::io::AsRawFd;
    // SAFETY: flock on a file descriptor this process owns for the call's duration.
    let r = unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) };
    if r == 0 {
        return Ok(true);
    }
    let e = std::io::Error::last_os_error();
    if e.raw_os_error() == Some(libc::EWOULDBLOCK) {
        Ok(false)
    } else {
        Err(e)
    }
}

#[cfg(unix)]
fn same_file(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// Without `flock`, a non-empty lock file means the directory is in use.
#[cfg(not(unix))]
fn try_lock(file: &File) -> std::io::Result<bool> {
    Ok(file.metadata()?.len() == 0)
}

#[cfg(not(unix))]
fn same_file(_: &File, path: &Path) -> bool {
    path.exists()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_held_lock_refuses_a_second_holder_and_is_removed_on_drop() {
        let dir = tempfile::tempdir().unwrap();
        let (lock, first) = OutputLock::acquire(dir.path()).unwrap();
        assert_eq!(first, Acquired::default());
        let e = OutputLock::acquire(dir.path()).unwrap_err().to_string();
        assert!(e.contains(&format!("pid {}", std::process::id())), "{e}");
        assert!(e.contains(LOCK_FILE), "{e}");
        let path = lock.path().to_path_buf();
        drop(lock);
        assert!(!path.exists(), "the lock file goes with the lock");
        let (_again, second) = OutputLock::acquire(dir.path()).unwrap();
        assert_eq!(second.took_over, None);
    }

    #[test]
    fn a_stale_lock_is_taken_over_and_temporary_files_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        let dead = Owner {
            pid: 999_999,
            host: "elsewhere".into(),
            command: "kinsynth optimize x.toml --out y".into(),
            since: 1,
        };
        std::fs::write(
            dir.path().join(LOCK_FILE),
            serde_json::to_string(&dead).unwrap(),
        )
        .unwrap();
        std::fs::create_dir(dir.path().join("trajectories")).unwrap();
        for f in [
            ".kinsynth-abc.tmp",
            "trajectories/.kinsynth-def.tmp",
            "keep.tmp",
        ] {
            std::fs::write(dir.path().join(f), "x").unwrap();
        }
        let (_lock, got) = OutputLock::acquire(dir.path()).unwrap();
        assert_eq!(got.took_over, Some(dead));
        assert_eq!(got.removed.len(), 2, "{:?}", got.removed);
        assert!(dir.path().join("keep.tmp").exists());
    }

    /// What is not a run's lock file is refused without being read: a FIFO (whose read would
    /// block) and a link to /dev/zero (whose read would never end); a huge lock file is read
    /// only as far as an owner's record goes (its owner is then unknown); and an owner with a
    /// line break and a long command is described on one line of a readable length.
    #[cfg(unix)]
    #[test]
    fn what_is_not_a_lock_file_is_refused_unread_and_owners_are_shown_on_one_line() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(LOCK_FILE);
        let name = std::ffi::CString::new(path.as_os_str().as_encoded_bytes()).unwrap();
        assert_eq!(unsafe { libc::mkfifo(name.as_ptr(), 0o600) }, 0);
        let e = OutputLock::acquire(dir.path()).unwrap_err().to_string();
        assert!(
            e.contains("is not a regular file, as a run's lock is: remove it"),
            "{e}"
        );
        std::fs::remove_file(&path).unwrap();
        std::os::unix::fs::symlink("/dev/zero", &path).unwrap();
        let e = OutputLock::acquire(dir.path()).unwrap_err().to_string();
        assert!(e.contains("is not a regular file"), "{e}");
        std::fs::remove_file(&path).unwrap();
        // 1 GiB of zeros, sparse: read only as far as the limit, no owner known.
        std::fs::File::create(&path)
            .unwrap()
            .set_len(1 << 30)
            .unwrap();
        let (lock, got) = OutputLock::acquire(dir.path()).unwrap();
        assert_eq!(got.took_over, None);
        drop(lock);
        let forged = Owner {
            pid: 1,
            host: "vm\nerror: forged line".into(),
            command: "x".repeat(20_000),
            since: 1,
        };
        let shown = forged.describe();
        assert_eq!(shown.lines().count(), 1, "{shown}");
        assert!(shown.contains("vm\\nerror: forged line"), "{shown}");
        assert!(shown.len() < 400, "{} bytes", shown.len());
    }
}
