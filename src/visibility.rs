//! The visibility seam: one interface through which every renderer asks whether a segment is
//! blocked, where it is first blocked, and which surface it meets there, so that ray casting
//! ([`crate::trace::Tracer`], Embree) and field lookup ([`crate::field::scene::FieldScene`])
//! answer exactly the same rays. It sits below every module that implements it (`trace`,
//! `field`) and every module that asks through it (`render`, the harness); each implementation
//! lives beside its type.

use glam::Vec3;

/// The first surface a ray meets: its distance and its unit normal (world space, unoriented:
/// a shader faces it against the ray).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    pub t: f32,
    pub normal: Vec3,
}

/// A visibility oracle. Every renderer is written against this trait so that ray casting and
/// field lookup run on exactly the same rays.
///
/// Both queries cover the segment `origin + t·dir` with `tmin <= t <= tmax` (both ends
/// inclusive), `dir` unit, `tmin >= 0`.
pub trait Visibility: Sync {
    /// Whether the segment origin + t·dir, t in [tmin, tmax], is blocked. `dir` is unit.
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool;

    /// Distance `t` to the first blocker on the segment, `None` when it is free.
    /// `occluded(..) == hit_distance(..).is_some()`.
    fn hit_distance(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<f32>;

    /// The first surface on the segment with its normal, `None` when it is free (reflection
    /// rays). `surface_hit(..).map(|h| h.t) == hit_distance(..)`. Ray casting gives the true
    /// triangle's normal; a field gives its normal field's (which the field must carry).
    fn surface_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit>;

    /// [`Self::occluded`] of every unit direction in `dirs` from one `origin`:
    /// `out[i] = occluded(origin, dirs[i], tmin, tmax)`, bit for bit. Backends override it to
    /// share work between rays with a common origin (receiver rays in AO).
    ///
    /// # Panics
    /// If `dirs` and `out` differ in length.
    fn occluded_many(&self, origin: Vec3, dirs: &[Vec3], tmin: f32, tmax: f32, out: &mut [bool]) {
        check_batch("occluded_many", dirs.len(), out.len());
        for (o, &d) in out.iter_mut().zip(dirs) {
            *o = self.occluded(origin, d, tmin, tmax);
        }
    }

    /// [`Self::occluded`] of every unit direction in `dirs` from one `origin`, ray `i` ending at
    /// `tmaxs[i]` (shadow rays to points on a light): `out[i] = occluded(origin, dirs[i], tmin,
    /// tmaxs[i])`, bit for bit. Backends override it as [`Self::occluded_many`].
    ///
    /// # Panics
    /// If `dirs`, `tmaxs` and `out` differ in length.
    fn occluded_many_to(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmaxs: &[f32],
        out: &mut [bool],
    ) {
        check_batch_to(dirs.len(), tmaxs.len(), out.len());
        for ((o, &d), &t) in out.iter_mut().zip(dirs).zip(tmaxs) {
            *o = self.occluded(origin, d, tmin, t);
        }
    }

    /// [`Self::surface_hit`] of every unit direction in `dirs` from one `origin`:
    /// `out[i] = surface_hit(origin, dirs[i], tmin, tmax)`, bit for bit (reflection rays).
    /// Backends override it as [`Self::occluded_many`].
    ///
    /// # Panics
    /// If `dirs` and `out` differ in length.
    fn surface_hit_many(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: f32,
        out: &mut [Option<SurfaceHit>],
    ) {
        check_batch("surface_hit_many", dirs.len(), out.len());
        for (o, &d) in out.iter_mut().zip(dirs) {
            *o = self.surface_hit(origin, d, tmin, tmax);
        }
    }
}

/// A [`Visibility`] that forwards only the per-ray queries of another, so that
/// [`Visibility::occluded_many`] (and every batched query) takes the trait's per-ray default: the reference that batched
/// implementations are tested and benchmarked against.
pub struct PerRay<'a, V: ?Sized>(pub &'a V);

impl<V: Visibility + ?Sized> Visibility for PerRay<'_, V> {
    #[inline]
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        self.0.occluded(origin, dir, tmin, tmax)
    }

    #[inline]
    fn hit_distance(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        self.0.hit_distance(origin, dir, tmin, tmax)
    }

    #[inline]
    fn surface_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        self.0.surface_hit(origin, dir, tmin, tmax)
    }
}

/// The batched queries' contract ([`Visibility::occluded_many`],
/// [`Visibility::surface_hit_many`]): a result for every direction.
///
/// # Panics
/// If `dirs` and `out` differ.
#[track_caller]
pub fn check_batch(query: &str, dirs: usize, out: usize) {
    assert_eq!(dirs, out, "{query}: dirs and out differ in length");
}

/// [`check_batch`] for [`Visibility::occluded_many_to`]: a far end and a result for every
/// direction.
///
/// # Panics
/// If `dirs`, `tmaxs` and `out` differ.
#[track_caller]
pub fn check_batch_to(dirs: usize, tmaxs: usize, out: usize) {
    assert!(
        dirs == out && dirs == tmaxs,
        "occluded_many_to: dirs, tmaxs and out differ in length"
    );
}
