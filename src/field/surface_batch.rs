//! Reflection rays in batches (Gaitatzes et al., WSCG 2010, §4.2: a reflection ray is one field
//! lookup for the hit distance and one normal-field read for the hit's normal):
//! [`FieldScene::surface_hit_many_on`], the batched form of [`Visibility::surface_hit`] for the
//! rays of one origin.
//!
//! The rays go through the steps of the batched occlusion query ([`FieldInstance`]'s
//! `occluded_many`): the bounding-sphere cull, the f64 sphere crossing and the rotation into
//! model space eight rays at a time ([`lanes::for_each_crossing`]), the owner-table cell, map
//! frame and texel in staged blocks ([`Reads::of_block`]); then, per block, each hit's
//! normal-field texel is requested before any is read, and the hits' normals are turned back
//! to the world eight at a time ([`lanes::rotate_normalize`]). Answers are those of
//! `surface_hit` bit for bit (`tests/reflect_batch.rs`, every instruction set).
//!
//! With several instances a ray's hit is the nearest over the instances, found exactly as
//! [`FieldScene::nearest_among`] finds it one ray at a time: each instance's hits are found
//! without a far limit, with the entry distance that orders the instance for the ray, and then
//! each ray walks its instances in that order, each limited to the nearest hit so far (a hit
//! within a limit is a hit without one whose model-space distance is within it, because a
//! lookup's distance never precedes its sphere entry).
//!
//! [`Visibility::surface_hit`]: crate::visibility::Visibility::surface_hit

use super::lanes::{self, Isa, LANES};
use super::lookup::{BlendReads, Crossed, LookupOptions, NearestRead, Reads, SphereOrigin};
use super::scene::{FieldInstance, FieldScene};
use super::Selection;
use crate::visibility::SurfaceHit;
use glam::Vec3;
use std::cell::RefCell;

/// Crossings whose reads are staged together (as in the occlusion query).
const BLOCK: usize = 16;

/// Rays per call of [`lanes::for_each_crossing`]: its window.
const CHUNK: usize = 8 * LANES;

impl FieldInstance {
    /// The hit of every ray from `origin` along `dirs[i]` within [tmin, tmax] that passes this
    /// instance's cull and `keep(i, dirs[i])`: `visit(i, t, hit)` with the model-space distance
    /// `t` and the world-space hit of [`Self::surface_hit`], bit for bit.
    ///
    /// # Panics
    /// Without a normal field ([`Self::with_normals`]), once a ray reaches the sphere.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn surface_hits(
        &self,
        isa: Isa,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: f32,
        opts: &LookupOptions,
        keep: impl FnMut(usize, Vec3) -> bool,
        visit: impl FnMut(usize, f32, SurfaceHit),
    ) {
        match opts.selection {
            Selection::Nearest => self
                .surface_hits_with::<NearestRead>(isa, origin, dirs, tmin, tmax, opts, keep, visit),
            Selection::Interpolated => self
                .surface_hits_with::<BlendReads>(isa, origin, dirs, tmin, tmax, opts, keep, visit),
        }
    }

    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn surface_hits_with<R: Reads>(
        &self,
        isa: Isa,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: f32,
        opts: &LookupOptions,
        mut keep: impl FnMut(usize, Vec3) -> bool,
        mut visit: impl FnMut(usize, f32, SurfaceHit),
    ) {
        let meet = self.may_meet_from(origin);
        let tr = &self.transform;
        let field = &*self.field;
        let o = self.local_origin(origin);
        let from = SphereOrigin::new(o, field.bounds.center, field.bounds.radius);
        let (lmin, lmax) = (tr.to_local_distance(tmin), tr.to_local_distance(tmax));
        let mut index = [0usize; BLOCK];
        let mut crossed = [Crossed::default(); BLOCK];
        let mut reads = [R::default(); BLOCK];
        let mut nearest = [NearestRead::default(); BLOCK];
        let mut n = 0;
        let mut resolve = |n: usize, index: &[usize], crossed: &[Crossed]| {
            if n == 0 {
                return;
            }
            let normals = self
                .normals
                .as_deref()
                .expect("surface_hit: a reflection query needs the instance's normal field");
            R::of_block(isa, field, &crossed[..n], &mut reads[..n]);
            // The normal's texel is the nearest selection's, also when the distance blends.
            let nearest = match R::nearest_block(&reads[..n]) {
                Some(same) => same,
                None => {
                    NearestRead::of_block(isa, field, &crossed[..n], &mut nearest[..n]);
                    &nearest[..n]
                }
            };
            let (mut at, mut ts, mut normal) =
                ([0usize; BLOCK], [0.0f32; BLOCK], [Vec3::ZERO; BLOCK]);
            let mut hits = 0;
            for k in 0..n {
                let probe = crossed[k].with_reads(reads[k]);
                if let Some(t) = field.finish(&probe, lmin, lmax, opts) {
                    let r = nearest[k];
                    let cell = normals.cell(r.map as usize, r.texel as usize);
                    crate::hint::prefetch_value(cell);
                    (at[hits], ts[hits]) = (k, t);
                    hits += 1;
                }
            }
            for h in 0..hits {
                let r = nearest[at[h]];
                normal[h] = normals.get(r.map as usize, r.texel as usize);
            }
            // (rotation · n).normalize(), eight at a time.
            lanes::rotate_normalize(isa, tr.rotation, &mut normal[..hits]);
            for h in 0..hits {
                let hit = SurfaceHit {
                    t: ts[h] * tr.scale,
                    normal: normal[h],
                };
                visit(index[at[h]], ts[h], hit);
            }
        };
        for (c, chunk) in dirs.chunks(CHUNK).enumerate() {
            let base = c * CHUNK;
            // No ray is marked in advance: every one is looked up.
            let mut none = [false; CHUNK];
            lanes::for_each_crossing(
                isa,
                &meet,
                &from,
                chunk,
                tmin,
                &mut none[..chunk.len()],
                Some(self.inv_rotation),
                |i, d| keep(base + i, d),
                |_, i, local, hit| {
                    let Some(c) = field.cross_at(hit, o, local, lmin, lmax) else {
                        return;
                    };
                    (index[n], crossed[n]) = (base + i, c);
                    n += 1;
                    if n == BLOCK {
                        resolve(n, &index, &crossed);
                        n = 0;
                    }
                },
            );
        }
        resolve(n, &index, &crossed);
    }
}

/// One instance's hit of one ray, with what orders the instance for the ray.
#[derive(Clone, Copy, Debug)]
struct Found {
    ray: u32,
    /// Where the ray enters the instance's world sphere (at least tmin).
    entry: f32,
    instance: u32,
    /// The hit's model-space distance.
    local_t: f32,
    hit: SurfaceHit,
}

thread_local! {
    /// The hits of several instances and the entries of one, reused across calls.
    static FOUND: RefCell<(Vec<Found>, Vec<f32>)> = const { RefCell::new((Vec::new(), Vec::new())) };
}

impl FieldScene {
    /// [`crate::visibility::Visibility::surface_hit_many`] with the eight-lane steps of `isa`
    /// ([`lanes`]): the same bits on every instruction set, and those of
    /// [`crate::visibility::Visibility::surface_hit`] ray by ray (the module's docs).
    ///
    /// # Panics
    /// If `dirs` and `out` differ in length; when an instance a ray reaches has no normal
    /// field.
    pub fn surface_hit_many_on(
        &self,
        isa: Isa,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: f32,
        out: &mut [Option<SurfaceHit>],
    ) {
        crate::visibility::check_batch("surface_hit_many", dirs.len(), out.len());
        if dirs.len() < LANES {
            // Fewer rays than one step of lanes: one at a time costs less than the batch's
            // setup per instance (`examples/ray_cost.rs reflect4`: four rays a point, two
            // casters), with the same answers.
            for (o, &d) in out.iter_mut().zip(dirs) {
                *o = crate::visibility::Visibility::surface_hit(self, origin, d, tmin, tmax);
            }
            return;
        }
        out.fill(None);
        let opts = &self.options;
        match self.instances.as_slice() {
            [] => {}
            [only] => only.surface_hits(
                isa,
                origin,
                dirs,
                tmin,
                tmax,
                opts,
                |_, _| true,
                |i, _, hit| out[i] = Some(hit),
            ),
            several => FOUND.with_borrow_mut(|(found, entries)| {
                found.clear();
                entries.clear();
                entries.resize(dirs.len(), 0.0);
                for (j, inst) in several.iter().enumerate() {
                    let start = found.len();
                    // Unlimited: the walk below applies each ray's limit.
                    inst.surface_hits(
                        isa,
                        origin,
                        dirs,
                        tmin,
                        f32::INFINITY,
                        opts,
                        |i, d| match inst.meets_segment(origin, d, tmin, tmax) {
                            Some(t0) => {
                                entries[i] = t0.max(tmin);
                                true
                            }
                            None => false,
                        },
                        |i, local_t, hit| {
                            found.push(Found {
                                ray: i as u32,
                                entry: 0.0,
                                instance: j as u32,
                                local_t,
                                hit,
                            })
                        },
                    );
                    for f in &mut found[start..] {
                        f.entry = entries[f.ray as usize];
                    }
                }
                found.sort_unstable_by(|a, b| {
                    (a.ray.cmp(&b.ray))
                        .then(a.entry.total_cmp(&b.entry))
                        .then(a.instance.cmp(&b.instance))
                });
                for ray in found.chunk_by(|a, b| a.ray == b.ray) {
                    out[ray[0].ray as usize] = self.nearest_of(ray, tmax);
                }
            }),
        }
    }

    /// [`FieldScene::nearest_among`]'s walk over one ray's instances in entry order: each
    /// asked up to the nearest hit so far (its hit counts when its model-space distance is
    /// within that limit), stopping once an instance starts beyond it. Instances the ray
    /// reaches without a hit are left out: they change nothing, and neither does stopping at
    /// them, since every instance after them starts no sooner.
    fn nearest_of(&self, ray: &[Found], tmax: f32) -> Option<SurfaceHit> {
        let mut best: Option<SurfaceHit> = None;
        for f in ray {
            let limit = best.map_or(tmax, |h| h.t);
            if best.is_some() && f.entry > limit {
                break;
            }
            let tr = &self.instances[f.instance as usize].transform;
            if f.local_t <= tr.to_local_distance(limit) && (best.is_none() || f.hit.t < limit) {
                best = Some(f.hit);
            }
        }
        best
    }
}
