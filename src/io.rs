//! File output that never leaves a half-written result behind.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::Path;

/// Writes `bytes` to `path` atomically: into a temporary file in the same directory, flushed
/// and synced, then renamed over `path`. A crash or a full disk leaves the old file (or none).
///
/// A symbolic link is followed: the file it names is replaced and the link kept (a link to
/// nothing is refused). An existing target that is not a regular file (`/dev/null`, a pipe
/// such as `/dev/stdout`, a terminal) is written into directly, as a shell's `>` would, and is
/// never replaced; a directory is refused.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let write_err = |source| Error::Write {
        path: path.to_path_buf(),
        source,
    };
    let resolved;
    let target = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => {
            resolved = std::fs::canonicalize(path).map_err(|_| {
                write_err(std::io::Error::new(
                    std::io::ErrorKind::NotFound,
                    "a dangling symbolic link",
                ))
            })?;
            resolved.as_path()
        }
        _ => path,
    };
    if let Ok(m) = std::fs::metadata(target) {
        if m.is_dir() {
            return Err(write_err(std::io::Error::new(
                std::io::ErrorKind::IsADirectory,
                "is a directory",
            )));
        }
        if !m.is_file() {
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(target)
                .map_err(write_err)?;
            return f
                .write_all(bytes)
                .and_then(|()| f.flush())
                .map_err(write_err);
        }
    }
    let dir = folder_of(target);
    let mut tmp = tempfile::Builder::new()
        .prefix(".kinsynth-")
        .suffix(".tmp")
        .tempfile_in(dir)
        .map_err(write_err)?;
    tmp.write_all(bytes).map_err(write_err)?;
    tmp.as_file().sync_all().map_err(write_err)?;
    // Temporary files are created private (0600); results are ordinary files (0644).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(write_err)?;
    }
    tmp.persist(target).map_err(|e| write_err(e.error))?;
    Ok(())
}

/// The folder a file `path` lies in (`.` for a bare name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Checks, before any work, that `path` can take an output file: it is not a directory and
/// its folder exists. A command that writes several files checks them all first, so that a
/// bad location fails it before anything is written.
pub fn check_output_file(path: &Path) -> Result<()> {
    let refuse = |kind, why: &str| {
        Err(Error::Write {
            path: path.to_path_buf(),
            source: std::io::Error::new(kind, why.to_string()),
        })
    };
    if path.is_dir() {
        return refuse(std::io::ErrorKind::IsADirectory, "is a directory");
    }
    if path.as_os_str().as_encoded_bytes().last() == Some(&b'/') {
        return refuse(
            std::io::ErrorKind::InvalidInput,
            "names a folder (it ends with /), not a file",
        );
    }
    if !folder_of(path).is_dir() {
        return refuse(std::io::ErrorKind::NotFound, "its folder does not exist");
    }
    Ok(())
}

/// Checks, before any work, that `path` can take an output folder: it does not exist as
/// anything but a folder.
pub fn check_output_dir(path: &Path) -> Result<()> {
    if path.exists() && !path.is_dir() {
        return Err(Error::Write {
            path: path.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::AlreadyExists,
                "exists and is not a folder",
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_and_replaces_without_leftovers() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.txt");
        write_atomic(&p, b"first").unwrap();
        write_atomic(&p, b"second").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "second");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode, 0o644, "results are readable by others");
        }
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1, "temporary files must not be left behind");
    }

    #[cfg(unix)]
    #[test]
    fn special_files_are_written_into_and_links_kept() {
        let dir = tempfile::tempdir().unwrap();
        // A pipe (as `/dev/stdout` piped into another program) is written into, never
        // replaced: its reader gets the bytes.
        use std::io::Read;
        use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
        let fifo = dir.path().join("pipe");
        let name = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).unwrap();
        assert_eq!(unsafe { libc::mkfifo(name.as_ptr(), 0o600) }, 0);
        let mut reader = std::fs::OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NONBLOCK)
            .open(&fifo)
            .unwrap();
        write_atomic(&fifo, b"through the pipe").unwrap();
        assert!(std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo());
        let mut got = String::new();
        reader.read_to_string(&mut got).unwrap();
        assert_eq!(got, "through the pipe");
        // A link keeps pointing at its file, which gets the new content.
        let file = dir.path().join("real.txt");
        std::fs::write(&file, "old").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink(&file, &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "new");
        // A dangling link and a directory are refused; nothing is left behind.
        let dangling = dir.path().join("dangling");
        std::os::unix::fs::symlink(dir.path().join("nothing"), &dangling).unwrap();
        let e = write_atomic(&dangling, b"x").unwrap_err().to_string();
        assert!(e.contains("a dangling symbolic link"), "{e}");
        let sub = dir.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        let e = write_atomic(&sub, b"x").unwrap_err().to_string();
        assert!(e.contains("directory"), "{e}");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 5, "no temporary file may be left behind");
    }

    #[test]
    fn missing_directory_is_a_write_error_naming_the_file() {
        let p = Path::new("/nonexistent-dir-kinsynth/out.json");
        let e = write_atomic(p, b"x").unwrap_err();
        assert!(e.to_string().contains("/nonexistent-dir-kinsynth/out.json"));
    }
}
