//! Several instanced fields answering one [`Visibility`] query (2008 Algorithm 2 over all
//! occluders; 2010 §3.2).

use super::lanes::{self, Isa, MayMeetFrom};
use super::lookup::{
    ray_sphere, BlendReads, Crossed, LookupOptions, NearestRead, Reads, SphereOrigin,
};
use super::normals::NormalField;
use super::Selection;
use super::VisibilityField;
use crate::geometry::Similarity;
use crate::visibility::{SurfaceHit, Visibility};
use glam::{Quat, Vec3};
use std::sync::Arc;

/// A field placed in the world by a rigid transform (the same field serves every instance).
///
/// Built by [`FieldInstance::new`], which caches what every lookup needs from `transform`
/// (change the transform through a new instance, not by assigning the field).
#[derive(Clone, Debug)]
pub struct FieldInstance {
    pub field: Arc<VisibilityField>,
    pub transform: Similarity,
    /// World-space bounding sphere (centre transformed, radius scaled).
    pub world_center: Vec3,
    pub world_radius: f32,
    /// The field's normal field, for reflection queries ([`Visibility::surface_hit`]); set by
    /// [`Self::with_normals`].
    pub normals: Option<Arc<NormalField>>,
    /// `transform.rotation.inverse()` (the same value `Similarity::to_local_point` computes).
    pub(super) inv_rotation: Quat,
    /// The part of [`Self::may_meet`]'s margin that does not depend on the ray.
    margin_base: f32,
}

/// Relative slack of [`FieldInstance::may_meet`]: ten times the f32 rounding (a few units of
/// 6e-8 of the coordinates' magnitude) that separates its world-space test from the exact
/// model-space one.
pub(crate) const MAY_MEET_SLACK: f32 = 1e-5;

impl FieldInstance {
    pub fn new(field: Arc<VisibilityField>, transform: Similarity) -> Self {
        let world = transform.to_world_sphere(&field.bounds);
        let max_abs = |v: Vec3| v.abs().max_element();
        FieldInstance {
            inv_rotation: transform.rotation.inverse(),
            margin_base: MAY_MEET_SLACK
                * (max_abs(world.center)
                    + max_abs(transform.translation)
                    + world.radius
                    + transform.scale * max_abs(field.bounds.center)),
            field,
            transform,
            world_center: world.center,
            world_radius: world.radius,
            normals: None,
        }
    }

    /// This instance with the normal field of its field (2010 §4.2), so that it answers
    /// [`Visibility::surface_hit`].
    ///
    /// # Panics
    /// If `normals` does not have the field's map and texel counts.
    pub fn with_normals(mut self, normals: Arc<NormalField>) -> Self {
        let p = &self.field.params;
        assert!(
            normals.texels == p.texels() && normals.data.len() == p.count * p.texels(),
            "with_normals: the normal field is not this field's"
        );
        self.normals = Some(normals);
        self
    }

    /// World-space hit distance and world normal through this instance's field and normal
    /// field.
    ///
    /// # Panics
    /// Without a normal field ([`Self::with_normals`]).
    #[inline]
    pub fn surface_hit(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
        opts: &LookupOptions,
    ) -> Option<SurfaceHit> {
        let normals = self
            .normals
            .as_deref()
            .expect("surface_hit: a reflection query needs the instance's normal field");
        let tr = &self.transform;
        self.field
            .surface_hit(
                normals,
                self.local_origin(origin),
                self.local_dir(dir),
                tr.to_local_distance(tmin),
                tr.to_local_distance(tmax),
                opts,
            )
            .map(|(t, n)| SurfaceHit {
                t: t * tr.scale,
                normal: (tr.rotation * n).normalize(),
            })
    }

    /// A cheap f32 world-space test that is `false` only when [`Self::hit_distance`] is
    /// certainly `None` for a unit `dir`: the ray's line passes farther than the sphere's radius
    /// from its centre, or the whole sphere lies before `tmin`. Both are decided with a margin
    /// of `MAY_MEET_SLACK` times the coordinates' magnitude, far above the rounding that
    /// separates this test from the f64 model-space one, so a ray near the sphere's outline
    /// always takes the exact path.
    #[inline]
    pub fn may_meet(&self, origin: Vec3, dir: Vec3, tmin: f32) -> bool {
        self.may_meet_from(origin).test(dir, tmin)
    }

    /// The terms of [`Self::may_meet`] that depend only on the origin.
    #[inline]
    pub fn may_meet_from(&self, origin: Vec3) -> MayMeetFrom {
        MayMeetFrom {
            f: self.world_center - origin,
            reach: self.world_radius
                + self.margin_base
                + MAY_MEET_SLACK * origin.abs().max_element(),
        }
    }

    /// World-space hit distance through this instance's field.
    #[inline]
    pub fn hit_distance(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
        opts: &LookupOptions,
    ) -> Option<f32> {
        let tr = &self.transform;
        self.field
            .hit_distance(
                self.local_origin(origin),
                self.local_dir(dir),
                tr.to_local_distance(tmin),
                tr.to_local_distance(tmax),
                opts,
            )
            .map(|t| t * tr.scale)
    }

    /// Bit-identical to `transform.to_local_point(origin)`.
    #[inline]
    pub(super) fn local_origin(&self, origin: Vec3) -> Vec3 {
        let tr = &self.transform;
        self.inv_rotation * ((origin - tr.translation) / tr.scale)
    }

    /// `transform.to_local_dir(dir)` (bit-identical), renormalised (as
    /// [`lanes::rotate_normalize`] turns the batched lookups' directions).
    #[inline]
    fn local_dir(&self, dir: Vec3) -> Vec3 {
        (self.inv_rotation * dir).normalize()
    }

    /// Whether the segment meets the world sphere (the f32 test that orders several instances).
    #[inline]
    pub(super) fn meets_segment(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
    ) -> Option<f32> {
        let (t0, t1) = ray_sphere(origin, dir, self.world_center, self.world_radius)?;
        (t1 >= tmin && t0 <= tmax).then_some(t0)
    }

    /// [`Self::hit_distance`]`(..).is_some()` of every ray from `origin` along `dirs[i]` that
    /// passes `meet` (this instance's [`Self::may_meet_from`]`(origin)`) and `also(i, dirs[i])`,
    /// ORed into `out[i]`; rays already marked in `out` are skipped.
    ///
    /// The direction-independent work (model-space origin, the sphere crossing's origin terms)
    /// is done once; the cull and the sphere crossings run [`lanes::LANES`] rays at a time
    /// ([`lanes`]); each block of crossings computes its texel addresses and prefetches them
    /// before any is read, so that the storage's cache misses overlap instead of adding up.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn occluded_many(
        &self,
        isa: Isa,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: impl Fn(usize) -> f32,
        opts: &LookupOptions,
        also: impl Fn(usize, Vec3) -> bool,
        out: &mut [bool],
    ) {
        match opts.selection {
            Selection::Nearest => self
                .occluded_many_with::<NearestRead>(isa, origin, dirs, tmin, tmax, opts, also, out),
            Selection::Interpolated => self
                .occluded_many_with::<BlendReads>(isa, origin, dirs, tmin, tmax, opts, also, out),
        }
    }

    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn occluded_many_with<R: Reads>(
        &self,
        isa: Isa,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: impl Fn(usize) -> f32,
        opts: &LookupOptions,
        also: impl Fn(usize, Vec3) -> bool,
        out: &mut [bool],
    ) {
        /// Crossings whose reads are staged together.
        const BLOCK: usize = 16;
        let meet = self.may_meet_from(origin);
        let tr = &self.transform;
        let field = &*self.field;
        let o = self.local_origin(origin);
        let from = SphereOrigin::new(o, field.bounds.center, field.bounds.radius);
        let lmin = tr.to_local_distance(tmin);
        let mut index = [0usize; BLOCK];
        let mut lmaxs = [0.0f32; BLOCK];
        let mut crossed = [Crossed::default(); BLOCK];
        let mut reads = [R::default(); BLOCK];
        let mut n = 0;
        let mut resolve =
            |n: usize, index: &[usize], lmaxs: &[f32], crossed: &[Crossed], out: &mut [bool]| {
                R::of_block(isa, field, &crossed[..n], &mut reads[..n]);
                for k in 0..n {
                    let probe = crossed[k].with_reads(reads[k]);
                    out[index[k]] |= field.finish(&probe, lmin, lmaxs[k], opts).is_some();
                }
            };
        lanes::for_each_crossing(
            isa,
            &meet,
            &from,
            dirs,
            tmin,
            out,
            Some(self.inv_rotation),
            also,
            |out, i, local, hit| {
                let lmax = tr.to_local_distance(tmax(i));
                let Some(c) = field.cross_at(hit, o, local, lmin, lmax) else {
                    return;
                };
                (index[n], lmaxs[n], crossed[n]) = (i, lmax, c);
                n += 1;
                if n == BLOCK {
                    resolve(n, &index, &lmaxs, &crossed, out);
                    n = 0;
                }
            },
        );
        resolve(n, &index, &lmaxs, &crossed, out);
    }
}

/// Every caster's field; a ray tests the instances whose spheres it meets, nearest entry first,
/// and stops at the first occlusion.
#[derive(Clone, Debug, Default)]
pub struct FieldScene {
    pub instances: Vec<FieldInstance>,
    pub options: LookupOptions,
}

/// The instances a single-ray query considers: each named at most once. With several
/// instances, a superset of those whose spheres the segment meets gives the same answers as
/// all of them ([`FieldScene::for_each_of`] tests each named one's sphere).
pub(super) type Candidates<'a> = &'a dyn Fn(&mut dyn FnMut(usize));

impl FieldScene {
    /// Every instance, as [`Candidates`].
    fn all(&self, visit: &mut dyn FnMut(usize)) {
        (0..self.instances.len()).for_each(visit)
    }

    /// Calls `f` on the instances of `candidates` whose world spheres the segment meets, in
    /// order of entry distance, until it returns `false`. No allocation for up to 16
    /// instances. A scene of one instance skips the sphere test: its own lookup does the exact
    /// one, after a cheap rejection.
    fn for_each_of(
        &self,
        candidates: Candidates,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
        mut f: impl FnMut(f32, &FieldInstance) -> bool,
    ) {
        if let [only] = self.instances.as_slice() {
            if only.may_meet(origin, dir, tmin) {
                f(tmin, only);
            }
            return;
        }
        let mut stack = [(0.0f32, 0usize); 16];
        let mut heap = Vec::new();
        let mut n = 0;
        candidates(&mut |i| {
            let inst = &self.instances[i];
            if !inst.may_meet(origin, dir, tmin) {
                return;
            }
            if let Some(t0) = inst.meets_segment(origin, dir, tmin, tmax) {
                if n < stack.len() {
                    stack[n] = (t0.max(tmin), i);
                } else {
                    if heap.is_empty() {
                        heap.extend_from_slice(&stack);
                    }
                    heap.push((t0.max(tmin), i));
                }
                n += 1;
            }
        });
        let order = if heap.is_empty() {
            &mut stack[..n]
        } else {
            &mut heap[..]
        };
        order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for &(t, i) in order.iter() {
            if !f(t, &self.instances[i]) {
                return;
            }
        }
    }

    /// [`Visibility::occluded`] over the instances `candidates` names.
    pub(super) fn occluded_among(
        &self,
        candidates: Candidates,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
    ) -> bool {
        let mut hit = false;
        self.for_each_of(candidates, origin, dir, tmin, tmax, |_, inst| {
            hit = inst
                .hit_distance(origin, dir, tmin, tmax, &self.options)
                .is_some();
            !hit
        });
        hit
    }
}

impl FieldScene {
    /// [`Visibility::occluded_many_to`] with the eight-lane steps of `isa` ([`lanes`]): the same
    /// bits on every instruction set (tested), so that tests can compare them.
    ///
    /// # Panics
    /// If `dirs`, `tmaxs` and `out` differ in length.
    pub fn occluded_many_to_on(
        &self,
        isa: Isa,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmaxs: &[f32],
        out: &mut [bool],
    ) {
        crate::visibility::check_batch_to(dirs.len(), tmaxs.len(), out.len());
        self.occluded_from(isa, origin, dirs, tmin, |i| tmaxs[i], out);
    }

    /// The batched queries from one origin, ray i ending at `tmax(i)` (see
    /// [`Visibility::occluded_many`]).
    pub(super) fn occluded_from(
        &self,
        isa: Isa,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: impl Fn(usize) -> f32 + Copy,
        out: &mut [bool],
    ) {
        out.fill(false);
        let several = self.instances.len() > 1;
        for inst in &self.instances {
            let also = |i: usize, dir: Vec3| {
                !several || inst.meets_segment(origin, dir, tmin, tmax(i)).is_some()
            };
            inst.occluded_many(isa, origin, dirs, tmin, tmax, &self.options, also, out);
        }
    }
}

impl Visibility for FieldScene {
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        self.occluded_among(&|v| self.all(v), origin, dir, tmin, tmax)
    }

    /// Bit-identical to [`Self::occluded`] per ray: a ray is occluded when any instance that
    /// `occluded` would consider (its `may_meet`, and with several instances the world sphere
    /// test) reports a hit, which does not depend on the order instances are tried in. So the
    /// instances are taken one at a time, each over all rays not yet occluded.
    fn occluded_many(&self, origin: Vec3, dirs: &[Vec3], tmin: f32, tmax: f32, out: &mut [bool]) {
        crate::visibility::check_batch("occluded_many", dirs.len(), out.len());
        self.occluded_from(Isa::detect(), origin, dirs, tmin, |_| tmax, out);
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
        self.occluded_many_to_on(Isa::detect(), origin, dirs, tmin, tmaxs, out);
    }

    /// Batched per origin ([`FieldScene::surface_hit_many_on`]), bit-identical to
    /// [`Self::surface_hit`] per ray.
    fn surface_hit_many(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: f32,
        out: &mut [Option<SurfaceHit>],
    ) {
        self.surface_hit_many_on(Isa::detect(), origin, dirs, tmin, tmax, out);
    }

    /// As [`Self::hit_distance`], with the hit instance's normal field's normal.
    ///
    /// # Panics
    /// When an instance the ray reaches has no normal field.
    fn surface_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        self.nearest_among(
            &|v| self.all(v),
            origin,
            dir,
            tmin,
            tmax,
            |h: &SurfaceHit| h.t,
            |inst, limit| inst.surface_hit(origin, dir, tmin, limit, &self.options),
        )
    }

    fn hit_distance(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        self.nearest_among(
            &|v| self.all(v),
            origin,
            dir,
            tmin,
            tmax,
            |&t| t,
            |inst, limit| inst.hit_distance(origin, dir, tmin, limit, &self.options),
        )
    }
}

impl FieldScene {
    /// The nearest hit on the segment over the instances `candidates` names,
    /// `hit(instance, limit)` answering for one instance within [tmin, limit] and `t_of` giving
    /// a hit's distance. Spheres may overlap, so a later entry can still hold a nearer surface:
    /// every instance is asked, each up to the nearest hit so far, stopping once no remaining
    /// sphere starts before it.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn nearest_among<H: Copy>(
        &self,
        candidates: Candidates,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
        t_of: impl Fn(&H) -> f32,
        hit: impl Fn(&FieldInstance, f32) -> Option<H>,
    ) -> Option<H> {
        let mut best: Option<H> = None;
        self.for_each_of(candidates, origin, dir, tmin, tmax, |t_entry, inst| {
            let limit = best.as_ref().map_or(tmax, &t_of);
            if best.is_some() && t_entry > limit {
                return false;
            }
            if let Some(h) = hit(inst, limit) {
                if best.is_none() || t_of(&h) < limit {
                    best = Some(h);
                }
            }
            true
        });
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Sphere;
    use crate::sampling::rays::seeded_sphere_direction;

    /// A field whose every texel stores a hit halfway across: a ray entering the sphere from
    /// outside always reports a hit, so `hit_distance` is `Some` for every ray that meets the
    /// sphere ahead.
    fn solid_field() -> Arc<VisibilityField> {
        let bounds = Sphere {
            center: Vec3::new(0.1, -0.2, 0.3),
            radius: 0.8,
        };
        Arc::new(crate::field::constant_field(0.5, bounds))
    }

    #[test]
    fn may_meet_never_rejects_a_ray_that_hits() {
        let field = solid_field();
        let transforms = [
            Similarity::default(),
            Similarity::new(
                Quat::from_euler(glam::EulerRot::YXZ, 0.7, -0.3, 1.1),
                Vec3::new(1e3, -2e3, 5e2),
                0.01,
            ),
            Similarity::new(Quat::from_rotation_z(2.0), Vec3::new(0.5, 0.5, 0.5), 3.0),
        ];
        for tr in transforms {
            let inst = FieldInstance::new(field.clone(), tr);
            let (c, r) = (inst.world_center, inst.world_radius);
            let (mut hits, mut rejected, mut total) = (0, 0, 0);
            for i in 0..100_000u64 {
                // Origins from 1.01 R to 10⁴ R away; targets across the sphere's outline
                // (radii 1 ± 1e-4 in steps of 1e-6), inside it, or anywhere.
                let dist = r * 10f32.powf(4.0 * (i % 1000) as f32 / 1000.0) * 1.01;
                let origin = c + dist * seeded_sphere_direction(i, 31);
                let toward = (c - origin).normalize();
                let side = seeded_sphere_direction(i, 32).reject_from_normalized(toward);
                let side = side.normalize_or(toward.any_orthonormal_vector());
                let target = match i % 3 {
                    0 => c + r * (1.0 + 1e-6 * ((i / 3 % 201) as f32 - 100.0)) * side,
                    1 => c + 0.9 * r * seeded_sphere_direction(i, 33),
                    _ => origin + seeded_sphere_direction(i, 34),
                };
                let dir = (target - origin).normalize();
                let hit = inst
                    .hit_distance(origin, dir, 0.0, f32::INFINITY, &LookupOptions::default())
                    .is_some();
                let meet = inst.may_meet(origin, dir, 0.0);
                assert!(meet || !hit, "{tr:?}: rejected a hit, {origin} {dir}");
                hits += hit as u32;
                rejected += !meet as u32;
                total += 1;
            }
            // Both sides are exercised: many hits, and most of the clear misses rejected.
            assert!(
                hits > total / 4 && rejected > total / 5,
                "{hits} {rejected}"
            );
        }
    }
}
