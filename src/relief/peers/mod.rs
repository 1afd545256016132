//! Modern peers of the 2005 search, on the same maps, segments `(E, X)` and hit rule: the
//! exact cell walk, maximum mipmaps (Tevs et al., I3D 2008), cone step mapping (Dummer 2006)
//! and relaxed cone stepping (Policarpo and Oliveira, GPU Gems 3, 2007).
//!
//! - [`cellwalk`]: the segment walked cell by cell over the texel-centre grid, the bilinear
//!   patch of each cell intersected exactly: the cost baseline.
//! - [`maxmip`]: a max quadtree over the cells, descended and ascended; exact at the leaves.
//! - [`cone`]: conservative and relaxed cone ratios per texel, and the cone walk.
//! - [`Peer`], [`PeerData`] (the prepared structures with their build time and bytes),
//!   [`PeerData::cast`] and [`render_peer`] (as [`crate::relief::view::render`]).
//!
//! Hit rule: a point on or below the surface (`d = z − M ≤ 0`) is a hit; a segment whose entry
//! lies strictly below the surface is a back face, discarded (a miss), as in
//! [`crate::relief::intersect`].
//!
//! Fetch accounting, as [`crate::relief::Cast`] counts texture reads (one texture read
//! instruction each): one bilinear height sample; one max-mip or cone-ratio texel; one gather
//! of a cell's four texels. Hence the cell walk reads once per cell visited, the max mip once
//! per node visited (leaves: the gather, whose maximum is the leaf's), a cone step twice
//! (height and ratio) and a bisection step once.
//!
//! All peers run in f32 (as their GPU twins in `shaders/relief_peers.wgsl`, operation for
//! operation); [`crate::relief::exact`] (f64) is their reference.

pub mod cellwalk;
pub mod cone;
pub mod grid;
pub mod maxmip;

use super::cast::Cast;
use super::height::HeightMap;
use super::view::{render_with, ReliefFrame, View};
pub use cone::{ConeMaps, CONE_CAP, RELAXED_AZIMUTHS, RELAXED_RINGS};
use glam::Vec3;
pub use maxmip::MaxMip;
use std::time::{Duration, Instant};

/// The most cone steps or bisections accepted (the GPU path loops at most this often per ray,
/// well within lavapipe's 65,535 loop iterations per invocation).
pub const MAX_STEPS: u32 = 16_384;

/// One peer and its settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Peer {
    /// The exact cell walk ([`cellwalk`]).
    CellWalk,
    /// Maximum mipmaps ([`maxmip`]).
    MaxMip,
    /// Cone step mapping with conservative cones ([`cone`]): `steps` cone steps.
    Cone { steps: u32 },
    /// Relaxed cone stepping ([`cone`]): `steps` relaxed steps, then `bisections` bisection
    /// steps of a step that landed at or below the surface.
    RelaxedCone { steps: u32, bisections: u32 },
}

impl Peer {
    /// The name in tables, with the settings.
    pub fn label(&self) -> String {
        match self {
            Peer::CellWalk => "cell walk".into(),
            Peer::MaxMip => "max mip".into(),
            Peer::Cone { steps } => format!("cone {steps}"),
            Peer::RelaxedCone { steps, bisections } => format!("relaxed cone {steps}+{bisections}"),
        }
    }

    /// Checks the settings: `steps` in `1..=MAX_STEPS`, `bisections` in `0..=MAX_STEPS`.
    pub fn validate(&self) -> Result<(), String> {
        let (steps, bisections) = match *self {
            Peer::Cone { steps } => (steps, 0),
            Peer::RelaxedCone { steps, bisections } => (steps, bisections),
            _ => return Ok(()),
        };
        if !(1..=MAX_STEPS).contains(&steps) {
            return Err(format!(
                "{}: steps must be in 1..={MAX_STEPS}, got {steps}",
                self.label()
            ));
        }
        if bisections > MAX_STEPS {
            return Err(format!(
                "{}: bisections must be at most {MAX_STEPS}, got {bisections}",
                self.label()
            ));
        }
        Ok(())
    }
}

/// The structures the peers read besides the map: the max quadtree and both cone-ratio maps,
/// with what each cost to build.
#[derive(Clone, Debug)]
pub struct PeerData {
    pub mip: MaxMip,
    pub cones: ConeMaps,
    /// Build time of the max quadtree.
    pub mip_time: Duration,
    /// Build time of the conservative ratios (the max quadtree's included).
    pub cone_time: Duration,
    /// Build time of the relaxed ratios (given the conservative ones).
    pub relaxed_time: Duration,
}

impl PeerData {
    /// Builds the structures of `map`.
    pub fn new(map: &HeightMap) -> PeerData {
        let t = Instant::now();
        let mip = MaxMip::new(map);
        let mip_time = t.elapsed();
        let t = Instant::now();
        let conservative = cone::conservative_ratios(map, &mip);
        let cone_time = mip_time + t.elapsed();
        let t = Instant::now();
        let relaxed = cone::relaxed_ratios(map, &conservative);
        let relaxed_time = t.elapsed();
        PeerData {
            mip,
            cones: ConeMaps {
                width: map.width,
                height: map.height,
                conservative,
                relaxed,
            },
            mip_time,
            cone_time,
            relaxed_time,
        }
    }

    /// Build time of what `peer` reads besides the map.
    pub fn build_time(&self, peer: &Peer) -> Duration {
        match peer {
            Peer::CellWalk => Duration::ZERO,
            Peer::MaxMip => self.mip_time,
            Peer::Cone { .. } => self.cone_time,
            Peer::RelaxedCone { .. } => self.cone_time + self.relaxed_time,
        }
    }

    /// Bytes `peer` reads besides the map.
    pub fn bytes(&self, peer: &Peer) -> usize {
        match peer {
            Peer::CellWalk => 0,
            Peer::MaxMip => self.mip.bytes(),
            Peer::Cone { .. } | Peer::RelaxedCone { .. } => self.cones.bytes_each(),
        }
    }

    /// `peer` on the segment `E → X` of `map` (the map these structures were built from).
    ///
    /// `peer` is taken as given ([`render_peer`] and the GPU kernel check it with
    /// [`Peer::validate`]).
    ///
    /// # Panics
    /// If `map` is not the size these were built for, or `E` or `X` is not finite or lies
    /// outside the prism `[0, 1]³` by more than [`PRISM_SLACK`] (segments come from
    /// [`View::segment`] or [`crate::relief::view::clip_to_prism`]).
    pub fn cast(&self, map: &HeightMap, peer: &Peer, e: Vec3, x: Vec3) -> Cast {
        assert_eq!(
            (map.width, map.height),
            (self.cones.width, self.cones.height)
        );
        assert!(
            in_prism(e) && in_prism(x),
            "segment ({e}, {x}) leaves the prism [0, 1]³"
        );
        match *peer {
            Peer::CellWalk => cellwalk::cast(map, e, x),
            Peer::MaxMip => self.mip.cast(map, e, x),
            Peer::Cone { steps } => {
                cone::cast(map, &self.cones.conservative, e, x, steps, None).cast
            }
            Peer::RelaxedCone { steps, bisections } => {
                cone::cast(map, &self.cones.relaxed, e, x, steps, Some(bisections)).cast
            }
        }
    }
}

/// How far outside the prism `[0, 1]³` a segment's ends may lie (rounding of the clipping).
pub const PRISM_SLACK: f32 = 1e-4;

/// Whether `p` is finite and in the prism, up to [`PRISM_SLACK`].
pub fn in_prism(p: Vec3) -> bool {
    p.is_finite()
        && p.cmpge(Vec3::splat(-PRISM_SLACK)).all()
        && p.cmple(Vec3::splat(1.0 + PRISM_SLACK)).all()
}

/// Renders `view` with `peer`, as [`crate::relief::view::render`] renders the 2005 search.
pub fn render_peer(
    map: &HeightMap,
    data: &PeerData,
    view: &View,
    peer: &Peer,
) -> Result<ReliefFrame, String> {
    peer.validate()?;
    if (map.width, map.height) != (data.cones.width, data.cones.height) {
        return Err(format!(
            "peer data of {}×{} texels for a {}×{} map",
            data.cones.width, data.cones.height, map.width, map.height
        ));
    }
    Ok(render_with(map, view, |e, x| data.cast(map, peer, e, x)))
}
