//! File output that never leaves a half-written result behind.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically: into a temporary file in the same directory, flushed
/// and synced, then renamed over `path`. A crash or a full disk leaves the old file (or none).
///
/// A symbolic link is followed: the file it names is replaced and the link kept (a link to
/// nothing is refused). An existing target that is not a regular file (`/dev/null`, a pipe
/// such as `/dev/stdout`, a terminal) is written into directly, as a shell's `>` would, and is
/// never replaced; a directory is refused.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut staged = Staged::default();
    staged.add(path, bytes)?;
    staged.commit()
}

/// Several output files written together, all or none as far as a file system allows: each
/// regular file is written into a temporary file beside it as it is added ([`Staged::add`]),
/// and [`Staged::commit`] then writes the devices and pipes among the targets and renames the
/// temporary files into place. An error before the renames (a full disk, a device that
/// refuses the bytes) leaves every target as it was: the temporary files are removed. Targets
/// are handled as [`write_atomic`] handles one.
#[derive(Debug, Default)]
pub struct Staged {
    /// Regular-file targets (as given, and with links resolved) with their written temporary
    /// files.
    files: Vec<(PathBuf, PathBuf, tempfile::NamedTempFile)>,
    /// Targets that are neither regular files nor directories, with their bytes.
    devices: Vec<(PathBuf, Vec<u8>)>,
    /// Regular files of an earlier run that this output replaces by nothing, removed once the
    /// others are in place.
    stale: Vec<PathBuf>,
}

impl Staged {
    /// Stages `bytes` for `path`: a regular file's bytes go to a temporary file beside it now,
    /// a device's are kept for [`Staged::commit`].
    pub fn add(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        let write_err = |source| Error::Write {
            path: path.to_path_buf(),
            source,
        };
        // An existing target that is not a regular file is written into, whatever links lead
        // to it: `/dev/stdout` is a link to `/proc/self/fd/1`, whose target (`pipe:[N]` for a
        // pipe) names nothing a path can be resolved to, but opens.
        if let Ok(m) = std::fs::metadata(path) {
            if !m.is_file() && !m.is_dir() {
                self.devices.push((path.to_path_buf(), bytes.to_vec()));
                return Ok(());
            }
        }
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
        if std::fs::metadata(target).is_ok_and(|m| m.is_dir()) {
            return Err(write_err(std::io::Error::new(
                std::io::ErrorKind::IsADirectory,
                "is a directory",
            )));
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
        self.files
            .push((path.to_path_buf(), target.to_path_buf(), tmp));
        Ok(())
    }

    /// Stages the removal of `path` if it is a regular file (an earlier run's output that this
    /// one does not write again), done by [`Staged::commit`] after the renames.
    pub fn remove_stale(&mut self, path: &Path) {
        if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_file()) {
            self.stale.push(path.to_path_buf());
        }
    }

    /// Writes the staged devices and pipes, then renames every temporary file over its
    /// target, then removes the stale files ([`Staged::remove_stale`]). On an error the
    /// temporary files not yet renamed are removed.
    pub fn commit(self) -> Result<()> {
        for (path, bytes) in &self.devices {
            let write_err = |source| Error::Write {
                path: path.clone(),
                source,
            };
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(path)
                .map_err(write_err)?;
            f.write_all(bytes)
                .and_then(|()| f.flush())
                .map_err(write_err)?;
        }
        for (path, target, tmp) in self.files {
            tmp.persist(&target).map_err(|e| Error::Write {
                path,
                source: e.error,
            })?;
        }
        for path in &self.stale {
            match std::fs::remove_file(path) {
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                    return Err(Error::Write {
                        path: path.clone(),
                        source: e,
                    })
                }
                _ => {}
            }
        }
        Ok(())
    }
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

/// True when `a` and `b` name the same existing file or folder, however they are spelt: other
/// relative paths, symbolic links and hard links to it included. A path where nothing exists
/// names no file, so it equals nothing.
pub fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        x.dev() == y.dev() && x.ino() == y.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (x, y);
        matches!(
            (std::fs::canonicalize(a), std::fs::canonicalize(b)),
            (Ok(p), Ok(q)) if p == q
        )
    }
}

/// Checks, before anything is written, that the output file `path` (given as `flag`) is none
/// of the command's `inputs`, each given with what it is (`"the input scenario"`): writing it
/// would replace that input. Only a regular file can be replaced: a device or a pipe such as
/// `/dev/stdout` is written into ([`write_atomic`]) and passes.
pub fn check_not_input(flag: &str, path: &Path, inputs: &[(&Path, &str)]) -> Result<()> {
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return Ok(());
    }
    match inputs.iter().find(|(input, _)| same_file(path, input)) {
        Some((_, what)) => Err(Error::invalid(
            flag,
            path.display(),
            format!("is also {what}"),
        )),
        None => Ok(()),
    }
}

/// [`check_not_input`] for the `files` that an output folder `dir` (given as `flag`) receives:
/// none of them may be one of `inputs`. The error names the flag, the folder and the file.
pub fn check_dir_not_input(
    flag: &str,
    dir: &Path,
    files: impl IntoIterator<Item = PathBuf>,
    inputs: &[(&Path, &str)],
) -> Result<()> {
    // Only an input that lies in the folder can be one of its files.
    let within: Vec<&(&Path, &str)> = inputs
        .iter()
        .filter(|(input, _)| {
            std::fs::canonicalize(input)
                .ok()
                .and_then(|p| p.parent().map(|d| same_file(d, dir)))
                .unwrap_or(false)
        })
        .collect();
    if within.is_empty() {
        return Ok(());
    }
    for file in files {
        if !std::fs::metadata(&file).is_ok_and(|m| m.is_file()) {
            continue;
        }
        if let Some((_, what)) = within.iter().find(|(input, _)| same_file(&file, input)) {
            return Err(Error::invalid(
                flag,
                dir.display(),
                format!(
                    "its file {} is also {what}",
                    file.file_name()
                        .map_or(file.display(), |n| Path::new(n).display())
                ),
            ));
        }
    }
    Ok(())
}

/// True when the outputs `a` and `b` would land in the same place: the same location once
/// resolved ([`resolve`], for files not written yet), or the same existing file however spelt
/// ([`same_file`], hard links included).
pub fn same_place(a: &Path, b: &Path) -> bool {
    resolve(a) == resolve(b) || same_file(a, b)
}

/// `path` made absolute with the symbolic links of its existing part resolved, and the `.`
/// and `..` of the part that does not exist yet applied as the file system will: where a
/// folder about to be created will lie.
pub fn resolve(path: &Path) -> PathBuf {
    let absolute = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir()
            .map(|d| d.join(path))
            .unwrap_or_else(|_| path.to_path_buf())
    };
    let mut existing = absolute.as_path();
    let mut rest = Vec::new();
    let mut base = loop {
        if let Ok(p) = std::fs::canonicalize(existing) {
            break p;
        }
        match (existing.parent(), existing.file_name()) {
            (Some(parent), Some(name)) => {
                rest.push(name.to_os_string());
                existing = parent;
            }
            // `..` or the root: nothing more to resolve.
            _ => break existing.to_path_buf(),
        }
    };
    for part in rest.iter().rev() {
        base.push(part);
    }
    // `Path::parent` never yields a `..`, but one may follow a missing folder: apply them.
    let mut out = PathBuf::new();
    for c in base.components() {
        match c {
            std::path::Component::ParentDir => {
                out.pop();
            }
            std::path::Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

/// Checks, before anything is written, that the output folder `dir` (given as `flag`) is not
/// one of the folders `inputs` (each given with what it is) and does not lie inside one: those
/// are only read.
pub fn check_dir_outside(flag: &str, dir: &Path, inputs: &[(&Path, &str)]) -> Result<()> {
    let out = resolve(dir);
    for (input, what) in inputs {
        let input = resolve(input);
        if out == input {
            return Err(Error::invalid(
                flag,
                dir.display(),
                format!("is also {what}"),
            ));
        }
        if out.starts_with(&input) {
            return Err(Error::invalid(
                flag,
                dir.display(),
                format!("lies inside {what}"),
            ));
        }
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
    fn outputs_are_compared_with_inputs_however_spelt() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let input = d.join("s.toml");
        std::fs::write(&input, "x").unwrap();
        std::fs::create_dir(d.join("sub")).unwrap();
        let around = d.join("sub/../s.toml");
        assert!(same_file(&input, &around));
        assert!(!same_file(&input, &d.join("new.toml")), "nothing there yet");
        let inputs = [(input.as_path(), "the input scenario")];
        let e = check_not_input("-o", &around, &inputs)
            .unwrap_err()
            .to_string();
        assert!(e.ends_with("s.toml: is also the input scenario"), "{e}");
        assert!(check_not_input("-o", &d.join("new.toml"), &inputs).is_ok());
        let e = check_dir_not_input("--out", d, [d.join("s.toml")], &inputs)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("its file s.toml is also the input scenario"),
            "{e}"
        );
        // A folder about to be created lies where its `..` put it.
        assert_eq!(resolve(&d.join("sub/new/../x")), resolve(d).join("sub/x"));
        let slices = [(d.join("sub"), "the slice")];
        let slices: Vec<(&Path, &str)> = slices.iter().map(|(p, w)| (p.as_path(), *w)).collect();
        for (out, ok) in [
            ("sub", false),
            ("sub/new", false),
            ("x/../sub", false),
            ("x", true),
        ] {
            assert_eq!(
                check_dir_outside("--out", &d.join(out), &slices).is_ok(),
                ok,
                "{out}"
            );
        }
        assert!(
            check_dir_outside("--out", d, &slices).is_ok(),
            "a folder holding it"
        );
    }

    #[test]
    fn missing_directory_is_a_write_error_naming_the_file() {
        let p = Path::new("/nonexistent-dir-kinsynth/out.json");
        let e = write_atomic(p, b"x").unwrap_err();
        assert!(e.to_string().contains("/nonexistent-dir-kinsynth/out.json"));
    }
}
