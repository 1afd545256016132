//! The harness's one error type: every failure names what it was about (the file, the spec
//! field, the cell, the output path) and keeps its source, so `experiment` prints a chain such
//! as `figure6: cell bunny-slater-290-…-gpu: backend "gpu": device: …`.

use crate::experiment::spec::SpecError;
use crate::field::cache::CacheError;
use crate::field::FieldError;
use crate::geometry::models::ModelError;
use crate::geometry::GeometryError;
use crate::gpu::GpuError;
use std::path::{Path, PathBuf};

/// An error of the experiment harness.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A spec that does not parse or validate (names the file and the field).
    #[error(transparent)]
    Spec(#[from] SpecError),
    /// Reading or writing a file or folder.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A CSV table that cannot be written or read back.
    #[error("{}: {source}", path.display())]
    Csv {
        path: PathBuf,
        #[source]
        source: csv::Error,
    },
    /// A JSON file that cannot be written or read back.
    #[error("{}: {source}", path.display())]
    Json {
        path: PathBuf,
        #[source]
        source: serde_json::Error,
    },
    /// A plot that could not be drawn.
    #[error("{}: {message}", path.display())]
    Plot { path: PathBuf, message: String },
    /// The GPU backend.
    #[error("backend \"gpu\": {0}")]
    Gpu(#[from] GpuError),
    /// A field that cannot be built, sized or loaded.
    #[error("{what}: {source}")]
    Field {
        what: String,
        #[source]
        source: FieldError,
    },
    /// A cache file that cannot be used.
    #[error("{what}: {source}")]
    Cache {
        what: String,
        #[source]
        source: CacheError,
    },
    /// A model from the registry.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// A mesh that fails validation.
    #[error("{what}: {source}")]
    Geometry {
        what: String,
        #[source]
        source: GeometryError,
    },
    /// A value the harness refuses (a command-line flag, a spec name, a size past a limit),
    /// with what it is about.
    #[error("{what}: {message}")]
    Invalid { what: String, message: String },
    /// A failure inside one step, with the step named.
    #[error("{context}: {source}")]
    Context {
        context: String,
        #[source]
        source: Box<Error>,
    },
}

/// Results of the harness.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An I/O error on `path`.
    pub fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
        move |source| Error::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    /// A CSV error on `path`.
    pub fn csv(path: &Path) -> impl Fn(csv::Error) -> Error + '_ {
        move |source| Error::Csv {
            path: path.to_path_buf(),
            source,
        }
    }

    /// A JSON error on `path`.
    pub fn json(path: &Path) -> impl Fn(serde_json::Error) -> Error + '_ {
        move |source| Error::Json {
            path: path.to_path_buf(),
            source,
        }
    }

    /// A refused value.
    pub fn invalid(what: impl Into<String>, message: impl Into<String>) -> Error {
        Error::Invalid {
            what: what.into(),
            message: message.into(),
        }
    }

    /// This error inside `context` (a spec, a cell, a stage).
    pub fn context(self, context: impl Into<String>) -> Error {
        Error::Context {
            context: context.into(),
            source: Box::new(self),
        }
    }
}

/// [`Error::context`] on results.
pub trait ResultExt<T> {
    /// The error, if any, inside `context`.
    fn context(self, context: impl FnOnce() -> String) -> Result<T>;
}

impl<T, E: Into<Error>> ResultExt<T> for std::result::Result<T, E> {
    fn context(self, context: impl FnOnce() -> String) -> Result<T> {
        self.map_err(|e| e.into().context(context()))
    }
}

// TODO(layering-merge): remove once every harness function returns `Result`.
impl From<Error> for String {
    fn from(e: Error) -> String {
        e.to_string()
    }
}

// TODO(layering-merge): remove once every harness function returns `Result`.
impl From<String> for Error {
    fn from(message: String) -> Error {
        Error::invalid("experiment", message)
    }
}
