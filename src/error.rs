//! The crate's error type: every failure names what was wrong, where, and with which value.

use std::path::PathBuf;

/// Result alias used throughout the crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong while reading, validating or using a scenario or a design.
///
/// Variants carry named fields so callers can react to them; their `Display` is a one-line
/// message fit for a command line: file, field path, value and what is wrong with it.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A file could not be written (or its temporary file renamed into place).
    #[error("{}: cannot write: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A file is not well-formed: syntax, an unknown key, a missing key or a value of the wrong
    /// type. The message names the field path and, where known, the line.
    #[error("{}: {}", file.display(), one_line(message))]
    Parse {
        /// The file.
        file: PathBuf,
        /// What the parser reported, with the field path.
        message: String,
    },
    /// A value is out of its domain (a negative radius, `min > max`, a NaN, …).
    #[error("{field} = {}: {}", one_line(value), one_line(reason))]
    InvalidValue {
        /// Field path, e.g. `obstacle[3].radius`.
        field: String,
        /// The offending value as written.
        value: String,
        /// What the value must be.
        reason: String,
    },
    /// A task point lies inside an obstacle (paper Eq. 4 requires every task point outside).
    #[error("task[{task}] = {point} lies inside obstacle[{obstacle}] ({name})")]
    TaskInsideObstacle {
        /// Index of the task point.
        task: usize,
        /// The task point, formatted.
        point: String,
        /// Index of the obstacle.
        obstacle: usize,
        /// Name (or shape) of the obstacle.
        name: String,
    },
    /// A mesh file referenced by a field could not be used.
    #[error("{field}: {source}")]
    Mesh {
        /// Field path, e.g. `obstacle[2].file`.
        field: String,
        /// What is wrong with the mesh (names the mesh file).
        #[source]
        source: crate::world::mesh::MeshError,
    },
    /// A URDF robot cannot be used as a serial chain: an unsupported joint type, a branch or a
    /// cycle between base and tip, a missing frame, a bad limit.
    #[error("{element}: {}", one_line(reason))]
    Urdf {
        /// The joint or link concerned, e.g. `joint 'elbow' (parent 'upper_arm', child 'forearm')`.
        element: String,
        /// What is wrong with it.
        reason: String,
    },
    /// An island job over MPI could not go on: a rank refused the job, or the messages between
    /// ranks were not what the protocol expects.
    #[error("island job, rank {rank}: {}", one_line(message))]
    Island {
        /// The rank that reports it.
        rank: usize,
        /// What happened.
        message: String,
    },
    /// An error found while processing a particular file.
    #[error("{}: {source}", file.display())]
    InFile {
        /// The file being processed.
        file: PathBuf,
        /// What went wrong in it.
        #[source]
        source: Box<Error>,
    },
}

/// `text` on one line: every run of line breaks (and the spaces around them) becomes one space,
/// so that a parser's multi-line message, or a value quoted from the input, keeps every error
/// on a single line.
pub fn one_line(text: &str) -> std::borrow::Cow<'_, str> {
    if !text.contains(['\n', '\r']) {
        return std::borrow::Cow::Borrowed(text);
    }
    let parts: Vec<&str> = text
        .split(['\n', '\r'])
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .collect();
    std::borrow::Cow::Owned(parts.join(" "))
}

/// Longest word (run without spaces) an error message shows whole; longer ones, such as a long
/// value quoted from the input, keep their ends ([`shorten`]).
pub const MESSAGE_WORD: usize = 120;
/// Longest error message shown whole ([`shorten`]).
pub const MESSAGE_LENGTH: usize = 2_000;

/// `text` short enough to read: every word longer than [`MESSAGE_WORD`] characters keeps its
/// first 60 and last 20 with the number left out between them, and a message still longer than
/// [`MESSAGE_LENGTH`] keeps its start (file and field) and its end (the reason). A 3 MB value in
/// a scenario otherwise made a 3 MB error line. Control characters (a newline in a file name,
/// say) are shown escaped, as `\n`, so that the text stays on one line.
pub fn shorten(text: &str) -> std::borrow::Cow<'_, str> {
    if text.chars().any(char::is_control) {
        let mut escaped = String::with_capacity(text.len() + 8);
        for c in text.chars() {
            match c.is_control() {
                true => escaped.extend(c.escape_default()),
                false => escaped.push(c),
            }
        }
        return std::borrow::Cow::Owned(shorten(&escaped).into_owned());
    }
    let long = |w: &str| w.chars().count() > MESSAGE_WORD;
    if text.chars().count() <= MESSAGE_LENGTH && !text.split(' ').any(long) {
        return std::borrow::Cow::Borrowed(text);
    }
    let words: Vec<String> = text
        .split(' ')
        .map(|w| {
            if !long(w) {
                return w.to_string();
            }
            let chars: Vec<char> = w.chars().collect();
            let (head, tail) = (&chars[..60], &chars[chars.len() - 20..]);
            format!(
                "{}…[{} characters]…{}",
                head.iter().collect::<String>(),
                chars.len() - 80,
                tail.iter().collect::<String>()
            )
        })
        .collect();
    let joined = words.join(" ");
    let chars: Vec<char> = joined.chars().collect();
    if chars.len() <= MESSAGE_LENGTH {
        return std::borrow::Cow::Owned(joined);
    }
    let head: String = chars[..1_200].iter().collect();
    let tail: String = chars[chars.len() - 600..].iter().collect();
    std::borrow::Cow::Owned(format!(
        "{head} …[{} characters]… {tail}",
        chars.len() - 1_800
    ))
}

/// A number for messages: as Rust writes it for ordinary magnitudes (`0.25`, `-3`), in exponent
/// form for very large or very small ones (`1e308` rather than 309 digits).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Num(pub f64);

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = self.0;
        if v.is_finite() && v != 0.0 && !(1e-5..1e16).contains(&v.abs()) {
            write!(f, "{v:e}")
        } else {
            write!(f, "{v}")
        }
    }
}

/// Numbers as `[a, b, …]`, each written as [`Num`].
pub fn fmt_list(values: &[f64]) -> String {
    let parts: Vec<String> = values.iter().map(|&v| Num(v).to_string()).collect();
    format!("[{}]", parts.join(", "))
}

impl Error {
    /// An [`Error::InvalidValue`] from displayable parts.
    pub fn invalid(
        field: impl Into<String>,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> Self {
        Error::InvalidValue {
            field: field.into(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }

    /// Prefixes the field path of an [`Error::InvalidValue`] or [`Error::Mesh`] with `prefix`
    /// (`radius` under `obstacle[3]` → `obstacle[3].radius`); other errors pass unchanged.
    pub fn under(self, prefix: &str) -> Self {
        match self {
            Error::InvalidValue {
                field,
                value,
                reason,
            } => Error::InvalidValue {
                field: format!("{prefix}.{field}"),
                value,
                reason,
            },
            Error::Mesh { field, source } => Error::Mesh {
                field: format!("{prefix}.{field}"),
                source,
            },
            other => other,
        }
    }

    /// Attaches the file being processed, unless the error already names a file (a parse error
    /// with an empty file name gets this one).
    pub fn in_file(self, file: impl Into<PathBuf>) -> Self {
        match self {
            Error::Parse { file: f, message } if f.as_os_str().is_empty() => Error::Parse {
                file: file.into(),
                message,
            },
            e @ (Error::Read { .. }
            | Error::Write { .. }
            | Error::Parse { .. }
            | Error::InFile { .. }) => e,
            other => Error::InFile {
                file: file.into(),
                source: Box::new(other),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_values_are_shortened_keeping_field_and_reason() {
        let short = "s.toml: robot.links = 3: must be at most 64";
        assert_eq!(shorten(short), short);
        let value = "a".repeat(1_000_000);
        let text = format!("s.toml: robot.links = \"{value}\": expected a whole number");
        let out = shorten(&text);
        assert!(out.len() < 300, "{} bytes", out.len());
        assert!(out.starts_with("s.toml: robot.links = \"aaa"), "{out}");
        assert!(out.ends_with(": expected a whole number"), "{out}");
        assert!(out.contains("[999923 characters]"), "{out}");
        let spaced = format!("f.json: x = \"{}\": too long", "ab ".repeat(100_000));
        let out = shorten(&spaced);
        assert!(out.chars().count() < 2_000, "{}", out.chars().count());
        assert!(
            out.starts_with("f.json: x = ") && out.ends_with(": too long"),
            "{out}"
        );
        let broken = "a\nb.toml\r\t: cannot read";
        assert_eq!(shorten(broken), "a\\nb.toml\\r\\t: cannot read");
    }
}
