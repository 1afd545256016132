//! Sampling: where maps sit on the bounding sphere ([`SpherePoints`]), how a map's texels cover
//! the hemisphere ([`HemisphereLayout`]), orthonormal frames ([`Frame`]) and seeded receiver ray
//! sets ([`rays`]).
//!
//! Sources (stratified sets, seeded sequences) live apart from mappings; each mapping has its
//! forward map, inverse and density side by side.
//!
//! Files: `sphere` (the public point-set type) over `cube_grid` (a cube-map grid of per-cell
//! candidate points and triangles: the query path of `nearest` and `surrounding`) with
//! `owner_grid` (a finer grid of cells with a single nearest point, read first by `nearest`),
//! `rings` (Slater and lat-long: ring sets with an exact O(1) analytic nearest query) and
//! `fibonacci`
//! (Keinert et al.'s inverse plus a certificate), which build the grid; `mesh` (spherical
//! triangulations: interpolation triangles, Delaunay spacing); `layout` with `layout_fast`
//! (libm-free square coordinates with a certificate), `texel_table` (a certified
//! concentric texel table over the disk) and `texel_measure` (closed-form texel
//! solid angles); `warp` (square/disk/hemisphere maps); `frame`; `rays`; `approx` (cheap
//! atan/floor with stated error bounds).
//!
//! Every `nearest` is exact — the grid's answer is the brute-force search's index itself, the
//! analytic queries equal it up to exact ties — and every used layout texel round-trips
//! exactly: `to_texel(to_direction(t)) == t`; `to_texel` equals the libm inverse's texel for
//! every direction.

mod approx;
mod cube_grid;
mod fibonacci;
mod frame;
mod layout;
mod layout_fast;
mod mesh;
mod owner_grid;
pub mod rays;
mod rings;
mod sphere;
mod texel_measure;
mod texel_table;
pub mod warp;

/// The concentric layout's fast texel path, for `field::lanes`'s eight-lane copy of it.
pub(crate) use approx::ATAN_F32_COEFFS;
pub use frame::Frame;
pub use layout::{HemisphereLayout, LayoutKind};
pub(crate) use layout_fast::{certificate_margin, FOUR_OVER_PI};
pub use sphere::{OwnerCell, Spacing, SphereKind, SpherePoints, MAX_FIBONACCI, MIN_FIBONACCI};
pub use texel_table::{TexelCell, TexelTable};

/// Errors from building a sampling pattern with impossible parameters.
#[derive(Debug, thiserror::Error)]
pub enum SamplingError {
    #[error("{0}")]
    Invalid(String),
}
