//! Cost floors for the lookup-versus-ray-casting comparison (`experiment performance`,
//! `benches/field.rs`, `examples/ao_cost.rs`; tested by `tests/floor.rs`): two [`Visibility`]
//! backends that do strictly less work than any field lookup must do on the same rays, so that
//! "ray casting time / floor time" bounds the speed-up that any field lookup can reach there.
//!
//! - [`NoQuery`]: every ray free. What remains is the caller's own cost: building the rays and
//!   reducing the answers (the AO loop).
//! - [`SphereCull`]: occluded wherever the segment meets a caster's bounding sphere. Every field
//!   lookup decides this first (2008 Algorithm 2 starts from the ray's entry into the sphere):
//!   the same cheap cull ([`FieldInstance::may_meet`]) and the same exact f64 crossing
//!   ([`SphereOrigin`]), shared per origin and eight rays at a time as in the batched lookup
//!   ([`lanes`]), taken in world space (the
//!   lookup also moves each ray into the field's model space), without choosing a map or a
//!   texel and without reading the field.
//!
//! Neither answers visibility; they exist to be timed, which is why they live in the harness
//! and not in the core.

use crate::field::lanes::{self, Isa};
use crate::field::lookup::SphereOrigin;
use crate::field::scene::{FieldInstance, FieldScene};
use crate::visibility::{SurfaceHit, Visibility};
use glam::Vec3;

/// Every ray free, at no cost ([module docs](self)).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoQuery;

impl Visibility for NoQuery {
    fn occluded(&self, _: Vec3, _: Vec3, _: f32, _: f32) -> bool {
        false
    }

    fn hit_distance(&self, _: Vec3, _: Vec3, _: f32, _: f32) -> Option<f32> {
        None
    }

    fn surface_hit(&self, _: Vec3, _: Vec3, _: f32, _: f32) -> Option<SurfaceHit> {
        None
    }

    fn occluded_many(&self, _: Vec3, dirs: &[Vec3], _: f32, _: f32, out: &mut [bool]) {
        crate::visibility::check_batch("occluded_many", dirs.len(), out.len());
        // The caller must still build the rays, although nothing reads them.
        std::hint::black_box(dirs);
        out.fill(false);
    }
}

/// Occluded where the segment meets a caster's bounding sphere ([module docs](self)).
#[derive(Clone, Copy, Debug)]
pub struct SphereCull<'a>(pub &'a FieldScene);

impl SphereCull<'_> {
    /// The distance at which the segment enters `inst`'s world sphere (`tmin` when it starts
    /// inside), if it meets it within [tmin, tmax].
    #[inline]
    fn entry(
        inst: &FieldInstance,
        from: &SphereOrigin,
        o: Vec3,
        d: Vec3,
        tmin: f32,
        tmax: f32,
    ) -> Option<f32> {
        if !inst.may_meet(o, d, tmin) {
            return None;
        }
        let c = from.crossing(d)?;
        (c.t1 >= tmin && c.t0 <= tmax).then_some(c.t0.max(tmin))
    }
}

impl Visibility for SphereCull<'_> {
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        self.hit_distance(origin, dir, tmin, tmax).is_some()
    }

    fn hit_distance(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        self.0
            .instances
            .iter()
            .filter_map(|inst| {
                let from = SphereOrigin::new(origin, inst.world_center, inst.world_radius);
                Self::entry(inst, &from, origin, dir, tmin, tmax)
            })
            .min_by(f32::total_cmp)
    }

    /// The entry point with the sphere's outward normal there.
    fn surface_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        let t = self.hit_distance(origin, dir, tmin, tmax)?;
        let p = origin + t * dir;
        let inst = self
            .0
            .instances
            .iter()
            .min_by(|a, b| {
                (a.world_center.distance(p) - a.world_radius)
                    .abs()
                    .total_cmp(&(b.world_center.distance(p) - b.world_radius).abs())
            })
            .expect("a hit has an instance");
        Some(SurfaceHit {
            t,
            normal: (p - inst.world_center).normalize_or_zero(),
        })
    }

    /// The lookup's own batched cull and crossing ([`lanes::for_each_crossing`]).
    fn occluded_many(&self, origin: Vec3, dirs: &[Vec3], tmin: f32, tmax: f32, out: &mut [bool]) {
        crate::visibility::check_batch("occluded_many", dirs.len(), out.len());
        self.cull_and_cross(origin, dirs, tmin, |_| tmax, out);
    }

    /// As [`Self::occluded_many`], each ray with its own far end (shadow rays).
    fn occluded_many_to(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmaxs: &[f32],
        out: &mut [bool],
    ) {
        crate::visibility::check_batch_to(dirs.len(), tmaxs.len(), out.len());
        self.cull_and_cross(origin, dirs, tmin, |i| tmaxs[i], out);
    }
}

impl SphereCull<'_> {
    /// The batched floor from one origin, ray i ending at `tmax(i)`.
    fn cull_and_cross(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: impl Fn(usize) -> f32,
        out: &mut [bool],
    ) {
        out.fill(false);
        let isa = Isa::detect();
        for inst in &self.0.instances {
            let meet = inst.may_meet_from(origin);
            let from = SphereOrigin::new(origin, inst.world_center, inst.world_radius);
            lanes::for_each_crossing(
                isa,
                &meet,
                &from,
                dirs,
                tmin,
                out,
                None,
                |_, _| true,
                |out, i, _, c| out[i] = c.t1 >= tmin && c.t0 <= tmax(i),
            );
        }
    }
}
