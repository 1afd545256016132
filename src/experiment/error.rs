//! The harness's one error type: every failure names what it was about (the file, the spec
//! field, the cell, the output path) and keeps its source, so `experiment` prints a chain such
//! as `figure6: cell bunny-slater-290-…-gpu: backend "gpu": device: …`.

use crate::field::FieldError;
use crate::geometry::models::ModelError;
use crate::geometry::GeometryError;
use crate::gpu::GpuError;
use crate::io::CacheError;
use crate::sampling::SamplingError;
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
    /// An image (PNG) that cannot be encoded or read back.
    #[error("{}: {source}", path.display())]
    Image {
        path: PathBuf,
        #[source]
        source: image::ImageError,
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
    /// A sampling pattern (sphere set, hemisphere layout) with impossible parameters.
    #[error("{what}: {source}")]
    Sampling {
        what: String,
        #[source]
        source: SamplingError,
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

    /// An image error on `path`.
    pub fn image(path: &Path) -> impl Fn(image::ImageError) -> Error + '_ {
        move |source| Error::Image {
            path: path.to_path_buf(),
            source,
        }
    }

    /// A plot of `path` that could not be drawn (plotters' errors carry no common type).
    pub fn plot<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> Error + '_ {
        move |e| Error::Plot {
            path: path.to_path_buf(),
            message: e.to_string(),
        }
    }

    /// A field error about `what` (a mesh and its parameters).
    pub fn field(what: impl Into<String>) -> impl FnOnce(FieldError) -> Error {
        move |source| Error::Field {
            what: what.into(),
            source,
        }
    }

    /// A cache error about `what` (a cache file).
    pub fn cache(what: impl Into<String>) -> impl FnOnce(CacheError) -> Error {
        move |source| Error::Cache {
            what: what.into(),
            source,
        }
    }

    /// A geometry error about `what` (a mesh).
    pub fn geometry(what: impl Into<String>) -> impl FnOnce(GeometryError) -> Error {
        move |source| Error::Geometry {
            what: what.into(),
            source,
        }
    }

    /// A sampling error about `what` (a sphere set or layout).
    pub fn sampling(what: impl Into<String>) -> impl FnOnce(SamplingError) -> Error {
        move |source| Error::Sampling {
            what: what.into(),
            source,
        }
    }

    /// The message with every source not already part of it, joined by `: `. The variants
    /// that wrap a source print it in their own message, so for them this is the message;
    /// a source whose text is missing (an opaque wrapper) is appended.
    pub fn chain(&self) -> String {
        let mut text = self.to_string();
        let mut source = std::error::Error::source(self);
        while let Some(s) = source {
            let t = s.to_string();
            if !text.contains(&t) {
                text.push_str(": ");
                text.push_str(&t);
            }
            source = s.source();
        }
        text
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

/// A spec error, naming the file and the field.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    #[error("{}: {source}", file.display())]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: at `{path}`: {message}", file.display())]
    Parse {
        file: PathBuf,
        path: String,
        message: String,
    },
    #[error("{}: field `{field}`: {message}", file.display())]
    Invalid {
        file: PathBuf,
        field: String,
        message: String,
    },
}
