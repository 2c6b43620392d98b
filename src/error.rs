//! The crate's error type: every failure a user can cause or meet, as one clear line.

use std::path::{Path, PathBuf};

/// Everything that can go wrong between a scene and an image.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A mesh or scene file that cannot be read or makes no sense.
    #[error("{}: {message}", location(path, *line))]
    Input {
        /// The mesh or scene file at fault.
        path: PathBuf,
        /// 1-based line, where the parser knows it.
        line: Option<usize>,
        /// What is wrong, shown after `path:` (or `path:line:`).
        message: String,
    },
    /// A request that cannot be met: a bad camera, resolution or option value.
    #[error("{0}")]
    Invalid(String),
    /// OpenCL trouble: no platform or device, a failed build, out of memory, a lost device.
    #[error("{0}")]
    Device(String),
    /// The output could not be written.
    #[error("{}: {message}", path.display())]
    Output {
        /// The file that could not be written (an image, a hit record, the tuning cache).
        path: PathBuf,
        /// Why, usually the operating system's reason.
        message: String,
    },
    /// Ctrl-C (or `SIGTERM`) came before there was anything to write: nothing was written,
    /// no file replaced.
    #[error("interrupted: nothing written")]
    Interrupted,
}

fn location(path: &Path, line: Option<usize>) -> String {
    match line {
        Some(line) => format!("{}:{line}", path.display()),
        None => path.display().to_string(),
    }
}

impl Error {
    /// Bad input (mesh, scene, camera, options) exits with 2, like a usage error;
    /// failures of the machine (device, output) with 1; an interruption with nothing
    /// written with 130, as a shell reports a process ended by Ctrl-C (128 + `SIGINT`).
    /// (A partial result written after an interruption is not an error: exit status 3,
    /// [`crate::commands::Ending::Partial`].)
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Input { .. } | Error::Invalid(_) => 2,
            Error::Device(_) | Error::Output { .. } => 1,
            Error::Interrupted => 130,
        }
    }

    pub(crate) fn input(path: &Path, message: impl Into<String>) -> Self {
        Error::Input {
            path: path.to_path_buf(),
            line: None,
            message: message.into(),
        }
    }

    pub(crate) fn input_at(path: &Path, line: usize, message: impl Into<String>) -> Self {
        Error::Input {
            path: path.to_path_buf(),
            line: Some(line),
            message: message.into(),
        }
    }

    pub(crate) fn output(path: &Path, message: impl ToString) -> Self {
        Error::Output {
            path: path.to_path_buf(),
            message: message.to_string(),
        }
    }
}

/// The crate's result: [`Error`] unless said otherwise.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// The value among `all` whose `name` is `s`, for the `FromStr` of a named choice (a
/// layout, a method, ...); else an error naming every choice: "`x` is not a `what`: use
/// a, b, c".
pub(crate) fn by_name<T: Copy>(
    s: &str,
    all: &[T],
    name: fn(T) -> &'static str,
    what: &str,
) -> std::result::Result<T, String> {
    all.iter().copied().find(|v| name(*v) == s).ok_or_else(|| {
        let names: Vec<&str> = all.iter().map(|v| name(*v)).collect();
        format!("`{s}` is not a {what}: use {}", names.join(", "))
    })
}
