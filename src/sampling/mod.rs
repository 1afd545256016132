//! Sampling: where maps sit on the bounding sphere ([`SpherePoints`]), how a map's texels cover
//! the hemisphere ([`HemisphereLayout`]), orthonormal frames ([`Frame`]) and seeded receiver ray
//! sets ([`rays`]).
//!
//! Sources (stratified sets, seeded sequences) live apart from mappings; each mapping has its
//! forward map, inverse and density side by side.

mod approx;
mod fibonacci;
mod frame;
mod layout;
mod mesh;
pub mod rays;
pub mod report;
mod report_plots;
mod rings;
mod sphere;
mod texel_measure;
pub mod warp;

pub use frame::Frame;
pub use layout::{HemisphereLayout, LayoutKind};
pub use sphere::{Spacing, SphereKind, SpherePoints};

/// Errors from building a sampling pattern with impossible parameters.
#[derive(Debug, thiserror::Error)]
pub enum SamplingError {
    #[error("{0}")]
    Invalid(String),
}
