//! The 2010 paper's other rays in `experiment performance` (Gaitatzes et al., WSCG 2010, §4.1
//! and §4.2): shadow rays to spherical lights and glossy reflection rays, on the AO sweeps'
//! casters, fields and receivers, so that each kind of ray is timed beside the AO lookup on the
//! same caster and field.
//!
//! - Shadow rays: three sphere lights of radius 0.3 over the corner's open side, 4 × 4
//!   stratified rays per light at each receiver vertex ([`shadow_at_points`]: one
//!   `occluded_many_to` call per receiver, a far end per ray on the light's near side), the
//!   2010 Figures 7 and 8's 16 rays a light.
//! - Reflection rays: a Phong lobe of exponent 50 about the mirror direction from an eye over
//!   the corner, 4 × 4 rays at each receiver vertex ([`reflect_at_points`]: one
//!   `surface_hit_many` call per receiver, the hit's distance and normal), the field answering
//!   through its 16-bit normal field.
//! - Their `entering` sweeps take the AO sweep's rays (a set share entering the caster's
//!   sphere): shadow rays with a far end past the sphere (a light behind the caster), reflection
//!   rays unbounded.
//!
//! The rays are the same for every backend: they depend on the receivers and the options only.

use super::Rays;
use crate::render::ao::AoOptions;
use crate::render::reflect::{reflect_at_points, Gloss, ReflectOptions};
use crate::render::shadow::{shadow_at_points, ShadowOptions, SphereLight};
use crate::sampling::rays::RaySet;
use crate::visibility::{SurfaceHit, Visibility};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// The kinds of ray a sweep times.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// Vertex AO: 256 cosine rays a receiver, `occluded_many` (the original sweeps).
    Ao,
    /// Shadow rays to sphere lights, `occluded_many_to`.
    Shadow,
    /// Glossy reflection rays, `surface_hit_many`.
    Reflection,
}

impl RayKind {
    /// The sweep's name in `backend_times.csv` for the base sweep `base` (`triangles`, `field_size`,
    /// `entering`): the AO sweeps keep their names, the others are prefixed by the ray.
    pub fn sweep(self, base: &str) -> &'static str {
        match (self, base) {
            (RayKind::Ao, "triangles") => "triangles",
            (RayKind::Ao, "field_size") => "field_size",
            (RayKind::Ao, _) => "entering",
            (RayKind::Shadow, "triangles") => "shadow_triangles",
            (RayKind::Shadow, "field_size") => "shadow_field_size",
            (RayKind::Shadow, _) => "shadow_entering",
            (RayKind::Reflection, "triangles") => "reflection_triangles",
            (RayKind::Reflection, "field_size") => "reflection_field_size",
            (RayKind::Reflection, _) => "reflection_entering",
        }
    }
}

/// Three lights over the corner's open side (radius 0.3; also `examples/ray_cost.rs`'s).
pub fn lights() -> Vec<SphereLight> {
    [
        Vec3::new(1.8, 2.0, 1.2),
        Vec3::new(1.2, 1.9, 2.0),
        Vec3::new(2.2, 1.5, 2.2),
    ]
    .map(|center| SphereLight {
        center,
        radius: 0.3,
        intensity: 1.0,
    })
    .to_vec()
}

/// The options and ray sets of the shadow and reflection passes (also `examples/ray_cost.rs`'s).
pub struct Secondary {
    pub shadow: ShadowOptions,
    pub reflect: ReflectOptions,
    /// 4 × 4 stratified rays (per light for shadows, per receiver for reflections).
    pub set: RaySet,
}

impl Secondary {
    /// The passes' options, their ray origins offset as `ao`'s.
    pub fn new(ao: &AoOptions) -> Secondary {
        Secondary {
            shadow: ShadowOptions {
                offset: ao.offset,
                lights: lights(),
            },
            reflect: ReflectOptions {
                offset: ao.offset,
                eye: Vec3::new(2.5, 1.6, 2.2),
                gloss: Gloss::Phong { exponent: 50.0 },
                lights: lights(),
                albedo: 0.8,
                sky: 0.2,
            },
            set: RaySet::new(4, 1),
        }
    }

    /// The mean light fraction over the receivers (the pass's answer).
    pub(super) fn shadow_pass(&self, vis: &dyn Visibility, rays: &Rays) -> f64 {
        mean(&shadow_at_points(
            vis,
            &rays.points,
            &rays.normals,
            &self.set,
            &self.shadow,
        ))
    }

    /// The mean reflected radiance over the receivers.
    pub(super) fn reflection_pass(&self, vis: &dyn Visibility, rays: &Rays) -> f64 {
        mean(&reflect_at_points(
            vis,
            &rays.points,
            &rays.normals,
            &self.set,
            &self.reflect,
        ))
    }

    /// The rays each pass casts (the same for every backend), counted through [`Counted`].
    pub(super) fn count(&self, kind: RayKind, rays: &Rays) -> u64 {
        let counted = Counted::new(&super::floor::NoQuery);
        match kind {
            RayKind::Ao => return rays.count(),
            RayKind::Shadow => self.shadow_pass(&counted, rays),
            RayKind::Reflection => self.reflection_pass(&counted, rays),
        };
        counted.rays()
    }
}

fn mean(v: &[f32]) -> f64 {
    v.iter().map(|&x| x as f64).sum::<f64>() / v.len().max(1) as f64
}

/// The `entering` sweep's rays through `kind`'s query: the share of rays answered free
/// (unoccluded, or without a hit), over all receivers in parallel. Shadow rays end at
/// `far(origin)`.
pub(super) fn entering_pass(
    kind: RayKind,
    vis: &dyn Visibility,
    dirs: &[(Vec3, Vec<Vec3>)],
    ao_tmax: f32,
    far: impl Fn(Vec3) -> f32 + Sync,
) -> f64 {
    let free: usize = dirs
        .par_iter()
        .map(|(o, d)| match kind {
            RayKind::Ao | RayKind::Shadow => {
                let mut out = vec![false; d.len()];
                if kind == RayKind::Ao {
                    vis.occluded_many(*o, d, 0.0, ao_tmax, &mut out);
                } else {
                    let tmaxs = vec![far(*o); d.len()];
                    vis.occluded_many_to(*o, d, 0.0, &tmaxs, &mut out);
                }
                out.iter().filter(|&&b| !b).count()
            }
            RayKind::Reflection => {
                let mut out = vec![None; d.len()];
                vis.surface_hit_many(*o, d, 0.0, f32::INFINITY, &mut out);
                out.iter().filter(|h| h.is_none()).count()
            }
        })
        .sum();
    let total: usize = dirs.iter().map(|d| d.1.len()).sum();
    free as f64 / total.max(1) as f64
}

/// `V` counting the rays asked of it (also `examples/ray_cost.rs`'s).
pub struct Counted<'a, V: ?Sized>(&'a V, AtomicU64);

impl<'a, V: Visibility + ?Sized> Counted<'a, V> {
    pub fn new(vis: &'a V) -> Self {
        Counted(vis, AtomicU64::new(0))
    }

    /// The rays asked so far.
    pub fn rays(&self) -> u64 {
        self.1.load(Relaxed)
    }
}

impl<V: Visibility + ?Sized> Visibility for Counted<'_, V> {
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        self.1.fetch_add(1, Relaxed);
        self.0.occluded(origin, dir, tmin, tmax)
    }

    fn hit_distance(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        self.1.fetch_add(1, Relaxed);
        self.0.hit_distance(origin, dir, tmin, tmax)
    }

    fn surface_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        self.1.fetch_add(1, Relaxed);
        self.0.surface_hit(origin, dir, tmin, tmax)
    }

    fn occluded_many_to(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmaxs: &[f32],
        out: &mut [bool],
    ) {
        self.1.fetch_add(dirs.len() as u64, Relaxed);
        self.0.occluded_many_to(origin, dirs, tmin, tmaxs, out)
    }

    fn surface_hit_many(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: f32,
        out: &mut [Option<SurfaceHit>],
    ) {
        self.1.fetch_add(dirs.len() as u64, Relaxed);
        self.0.surface_hit_many(origin, dirs, tmin, tmax, out)
    }
}
