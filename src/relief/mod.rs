//! Per-pixel displacement mapping with empty-space skipping: A. Kolb, C. Rezk-Salama,
//! "Efficient Empty Space Skipping for Per-Pixel Displacement Mapping", VMV 2005.
//!
//! - [`height`]: displacement maps M : [0, 1]² → [0, 1] (bilinear) and the procedural datasets.
//! - [`zones`]: the dilation / erosion safety-zone maps, up to four box sizes (§3.2, §3.4),
//!   δ as the paper's (the box size) or half of it.
//! - [`cast`]: linear search, bisection and forward / backward skips (§3.1, §3.3), and the
//!   exact intersection with the bilinear surface, cell by cell, as the reference.
//! - [`view`]: images of a displaced square seen at an angle, CPU (rayon), with per-pixel
//!   texture-fetch counts.
//!
//! Deviation from the paper: the paper renders the bounding prisms of a GPU base mesh and
//! runs the search in a fragment program; here the base is one square (the paper's tests use
//! two triangles, i.e. one square, too), its prism is the box `[0, 1]² × [0, 1]`, and the
//! search runs on the CPU, so its cost is reported as texture fetches per pixel and CPU time
//! rather than frame rates.

pub mod cast;
pub mod height;
pub mod peers;
pub mod view;
pub mod zones;

pub use cast::{exact, intersect, Cast, CastParams};
pub use height::{Dataset, HeightMap};
pub use zones::{DeltaRule, SafetyZones, PAPER_BOXES};
