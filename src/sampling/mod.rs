//! Sampling: where maps sit on the bounding sphere ([`SpherePoints`]), how a map's texels cover
//! the hemisphere ([`HemisphereLayout`]), orthonormal frames ([`Frame`]) and seeded receiver ray
//! sets ([`rays`]).
//!
//! Sources (stratified sets, seeded sequences) live apart from mappings; each mapping has its
//! forward map, inverse and density side by side.

mod frame;
mod layout;
pub mod rays;
mod sphere;
pub mod warp;

pub use frame::Frame;
pub use layout::{HemisphereLayout, LayoutKind};
pub use sphere::{SphereKind, SpherePoints};

/// Errors from building a sampling pattern with impossible parameters.
#[derive(Debug, thiserror::Error)]
pub enum SamplingError {
    #[error("{0}")]
    Invalid(String),
}
