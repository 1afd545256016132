//! A second CPU ray caster: Intel Embree 3 (Wald, Woop, Benthin, Johnson, Ernst, "Embree: A
//! Kernel Framework for Efficient CPU Ray Tracing", ACM TOG 33(4), 2014) over the same world
//! triangles as [`super::Tracer`], behind the same [`crate::visibility::Visibility`] interface, so
//! that ray casting by a production kernel can be timed and compared on exactly the rays of our
//! reference and of the field lookups. Built only with the `embree` cargo feature (and the
//! system's `libembree3`, Debian `libembree-dev`).
//!
//! Settings: one triangle geometry (three vertices per triangle, as given, so neighbours share
//! bit-identical edge end points), `RTC_SCENE_FLAG_ROBUST`, build quality high on the scene and
//! the geometry, incoherent intersection context.
//!
//! Watertightness: Embree 3 tests triangles with a modified Plücker test whose edge functions
//! are evaluated on the same two end points for the two triangles sharing an edge ("watertight
//! along the edge for neighbouring triangles", Embree's source), and robust mode makes the BVH
//! traversal conservative and turns off the optimisations that reduce arithmetic accuracy
//! (`rtcSetSceneFlags`). That is not Woop et al.'s watertight test that our [`super::Tracer`]
//! uses: Embree's edge functions are computed in plain f32 (no double-precision fallback at
//! zero), so a ray exactly through a shared vertex, or exactly along an edge, may be reported by
//! neither or both triangles (Embree's issue 387 reports such misses on edges in robust mode),
//! and a hit's `t` may differ from ours by rounding. `tests/embree.rs` counts and characterises
//! the rays on which the two casters disagree.
//!
//! Intervals: rays are filtered as [`super::Tracer`] filters them (`tmin > tmax` or a NaN bound
//! is a miss without a call); within, a hit counts when Embree's test accepts it in
//! `[tnear, tfar]`.

use super::embree_sys as sys;
use super::Hit;
use crate::visibility::{check_batch, check_batch_to, SurfaceHit, Visibility};
use glam::{Vec3, Vec3A};
use std::ffi::c_uint;

/// Embree refused the device, the scene or a geometry.
#[derive(Debug, thiserror::Error)]
#[error("Embree: {what} failed: {code}")]
pub struct EmbreeError {
    /// The call that failed.
    pub what: &'static str,
    /// `RTCError` by name.
    pub code: &'static str,
}

fn error_name(code: c_uint) -> &'static str {
    match code {
        0 => "RTC_ERROR_NONE",
        2 => "RTC_ERROR_INVALID_ARGUMENT",
        3 => "RTC_ERROR_INVALID_OPERATION",
        4 => "RTC_ERROR_OUT_OF_MEMORY",
        5 => "RTC_ERROR_UNSUPPORTED_CPU (Embree needs at least SSE2)",
        6 => "RTC_ERROR_CANCELLED",
        _ => "RTC_ERROR_UNKNOWN",
    }
}

/// The device's pending error, if any, as an [`EmbreeError`] naming `what`.
///
/// # Safety
/// `device` is a valid device.
pub(super) unsafe fn device_error(
    device: sys::RTCDevice,
    what: &'static str,
) -> Result<(), EmbreeError> {
    match sys::rtcGetDeviceError(device) {
        sys::RTC_ERROR_NONE => Ok(()),
        code => Err(EmbreeError {
            what,
            code: error_name(code),
        }),
    }
}

/// A new Embree device with the default configuration.
///
/// # Safety
/// The caller releases the device (`rtcReleaseDevice`) once.
pub(super) unsafe fn new_device() -> Result<sys::RTCDevice, EmbreeError> {
    let device = sys::rtcNewDevice(std::ptr::null());
    if device.is_null() {
        return Err(EmbreeError {
            what: "rtcNewDevice",
            code: error_name(sys::rtcGetDeviceError(std::ptr::null_mut())),
        });
    }
    Ok(device)
}

/// Unit geometric normal of each triangle, `(v1-v0)×(v2-v0)` normalised as [`super::Tracer`]
/// computes it (in Vec3A; its power-of-two scale cancels).
pub(super) fn triangle_normals(triangles: &[[Vec3; 3]]) -> Vec<Vec3> {
    triangles
        .iter()
        .map(|t| {
            let [v0, v1, v2] = t.map(Vec3A::from);
            Vec3::from((v1 - v0).cross(v2 - v0).normalize())
        })
        .collect()
}

/// A committed scene of one triangle geometry over `triangles` (three vertices per triangle,
/// as given), robust, build quality high on the scene and the geometry.
///
/// # Safety
/// `device` is a valid device; the caller releases the scene once.
///
/// # Panics
/// If a vertex is not finite.
pub(super) unsafe fn triangle_scene(
    device: sys::RTCDevice,
    triangles: &[[Vec3; 3]],
) -> Result<sys::RTCScene, EmbreeError> {
    assert!(
        triangles.iter().flatten().all(|v| v.is_finite()),
        "Embree: triangle vertices must be finite"
    );
    if triangles.len() > (u32::MAX / 3) as usize {
        return Err(EmbreeError {
            what: "rtcSetNewGeometryBuffer (more than u32::MAX / 3 triangles)",
            code: "RTC_ERROR_INVALID_ARGUMENT",
        });
    }
    let scene = sys::rtcNewScene(device);
    if scene.is_null() {
        return Err(EmbreeError {
            what: "rtcNewScene",
            code: error_name(sys::rtcGetDeviceError(device)),
        });
    }
    let built = (|| {
        sys::rtcSetSceneFlags(scene, sys::RTC_SCENE_FLAG_ROBUST);
        sys::rtcSetSceneBuildQuality(scene, sys::RTC_BUILD_QUALITY_HIGH);
        device_error(device, "rtcSetSceneFlags")?;
        if !triangles.is_empty() {
            let n = triangles.len();
            let geom = sys::rtcNewGeometry(device, sys::RTC_GEOMETRY_TYPE_TRIANGLE);
            device_error(device, "rtcNewGeometry")?;
            sys::rtcSetGeometryBuildQuality(geom, sys::RTC_BUILD_QUALITY_HIGH);
            let vb = sys::rtcSetNewGeometryBuffer(
                geom,
                sys::RTC_BUFFER_TYPE_VERTEX,
                0,
                sys::RTC_FORMAT_FLOAT3,
                12,
                3 * n,
            ) as *mut f32;
            let ib = sys::rtcSetNewGeometryBuffer(
                geom,
                sys::RTC_BUFFER_TYPE_INDEX,
                0,
                sys::RTC_FORMAT_UINT3,
                12,
                n,
            ) as *mut u32;
            if vb.is_null() || ib.is_null() {
                sys::rtcReleaseGeometry(geom);
                device_error(device, "rtcSetNewGeometryBuffer")?;
                return Err(EmbreeError {
                    what: "rtcSetNewGeometryBuffer",
                    code: "RTC_ERROR_UNKNOWN",
                });
            }
            // Written within the item counts Embree allocated the buffers with.
            let verts = std::slice::from_raw_parts_mut(vb, 9 * n);
            let index = std::slice::from_raw_parts_mut(ib, 3 * n);
            for (i, tri) in triangles.iter().enumerate() {
                for (k, v) in tri.iter().enumerate() {
                    verts[9 * i + 3 * k..9 * i + 3 * k + 3].copy_from_slice(&v.to_array());
                    index[3 * i + k] = (3 * i + k) as u32;
                }
            }
            sys::rtcCommitGeometry(geom);
            sys::rtcAttachGeometry(scene, geom);
            sys::rtcReleaseGeometry(geom);
            device_error(device, "rtcCommitGeometry")?;
        }
        sys::rtcCommitScene(scene);
        device_error(device, "rtcCommitScene")
    })();
    match built {
        Ok(()) => Ok(scene),
        Err(e) => {
            sys::rtcReleaseScene(scene);
            Err(e)
        }
    }
}

/// How [`Visibility::occluded_many`], [`Visibility::occluded_many_to`] and
/// [`Visibility::surface_hit_many`] cast their rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EmbreeRays {
    /// One `rtcOccluded1` (`rtcIntersect1`) per ray.
    Single,
    /// 8-wide packets (`rtcOccluded8`, `rtcIntersect8`; the last one masked).
    Packet8,
}

/// Embree 3 over a fixed set of world-space triangles: closest hit (`rtcIntersect1`) and any
/// hit (`rtcOccluded1`), and 8-wide packets of either for many rays from one origin.
///
/// Queries as [`super::Tracer`]'s: `origin` finite, `dir` finite and non-zero (`t` in units of
/// its length), `0 <= tmin`; triangles hit from either side.
pub struct EmbreeTracer {
    device: sys::RTCDevice,
    scene: sys::RTCScene,
    /// Unit geometric normal of each triangle, `(v1-v0)×(v2-v0)` normalised as
    /// [`super::Tracer`] computes it.
    normals: Vec<Vec3>,
    rays: EmbreeRays,
}

// SAFETY: after `rtcCommitScene` an Embree scene is read-only and Embree documents ray queries
// on it as thread-safe from any number of threads; the device and the scene are released only
// in `drop`, which takes `&mut self`.
unsafe impl Send for EmbreeTracer {}
unsafe impl Sync for EmbreeTracer {}

impl Drop for EmbreeTracer {
    fn drop(&mut self) {
        // SAFETY: both handles were created by `new` and are released once.
        unsafe {
            sys::rtcReleaseScene(self.scene);
            sys::rtcReleaseDevice(self.device);
        }
    }
}

impl EmbreeTracer {
    /// The rays of [`Visibility::occluded_many`] by default: the faster mode measured on the
    /// Figure 6 AO rays (`examples/embree_cost.rs`, docs/performance.md).
    pub const DEFAULT_RAYS: EmbreeRays = EmbreeRays::Packet8;

    /// Builds Embree's BVH over `triangles` (robust, high quality). An empty list gives a
    /// tracer that always misses.
    ///
    /// # Errors
    /// When Embree refuses the device (an unsupported CPU) or the scene (out of memory), or
    /// there are more than `u32::MAX / 3` triangles.
    ///
    /// # Panics
    /// If a vertex is not finite (as [`super::Tracer::new`]).
    pub fn new(triangles: &[[Vec3; 3]]) -> Result<EmbreeTracer, EmbreeError> {
        // SAFETY: `new_device` and `triangle_scene` check every handle; the scene and the
        // device are released once, by `drop`.
        unsafe {
            let device = new_device()?;
            let scene = match triangle_scene(device, triangles) {
                Ok(scene) => scene,
                Err(e) => {
                    sys::rtcReleaseDevice(device);
                    return Err(e);
                }
            };
            Ok(EmbreeTracer {
                device,
                scene,
                normals: triangle_normals(triangles),
                rays: Self::DEFAULT_RAYS,
            })
        }
    }

    /// The same tracer with `occluded_many(_to)` casting `rays`.
    pub fn with_rays(mut self, rays: EmbreeRays) -> EmbreeTracer {
        self.rays = rays;
        self
    }

    /// How `occluded_many(_to)` casts.
    pub fn rays(&self) -> EmbreeRays {
        self.rays
    }

    /// Embree's version, e.g. "3.13.5".
    pub fn version(&self) -> String {
        // SAFETY: a valid device; the property is an integer.
        let v = unsafe { sys::rtcGetDeviceProperty(self.device, sys::RTC_DEVICE_PROPERTY_VERSION) };
        format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100)
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.normals.len()
    }

    pub fn is_empty(&self) -> bool {
        self.normals.is_empty()
    }

    /// Queries on the committed scene.
    #[inline]
    fn q(&self) -> Committed {
        Committed {
            scene: self.scene,
            empty: self.normals.is_empty(),
        }
    }

    /// Closest hit with `tmin <= t <= tmax`, as Embree's `rtcIntersect1` reports it; the
    /// normal is the hit triangle's (as [`super::Tracer`] computes it, so equal bit for bit
    /// where both hit the same triangle).
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<Hit> {
        self.closest_hit_raw(origin, dir, tmin, tmax)
            .map(|(hit, _)| hit)
    }

    /// [`Self::closest_hit`] and Embree's own unnormalised geometric normal `Ng`.
    pub fn closest_hit_raw(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
    ) -> Option<(Hit, Vec3)> {
        let rh = self.q().intersect(origin, dir, tmin, tmax)?;
        let triangle = rh.hit.primID;
        Some((
            Hit {
                t: rh.ray.tfar,
                triangle,
                u: rh.hit.u,
                v: rh.hit.v,
                normal: self.normals[triangle as usize],
            },
            Vec3::new(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z),
        ))
    }

    /// Whether any triangle is hit with `tmin <= t <= tmax` (`rtcOccluded1`).
    pub fn any_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        self.q().any_hit(origin, dir, tmin, tmax)
    }
}

/// Ray queries on a committed Embree scene: a triangle scene ([`EmbreeTracer`]) or a scene of
/// instances ([`super::embree_instances::EmbreeInstances`]).
#[derive(Clone, Copy)]
pub(super) struct Committed {
    pub scene: sys::RTCScene,
    /// Nothing to hit: every query misses without a call.
    pub empty: bool,
}

impl Committed {
    /// Whether a query can hit anything (the checks [`super::Tracer`] makes).
    #[inline]
    fn live(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        debug_assert!(origin.is_finite() && dir.is_finite() && dir != Vec3::ZERO);
        debug_assert!(
            tmin.is_nan() || tmin >= 0.0,
            "tmin must be >= 0, got {tmin}"
        );
        !(self.empty || tmin.is_nan() || tmax.is_nan() || tmin > tmax)
    }

    #[inline]
    fn ray(origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> sys::RTCRay {
        sys::RTCRay {
            org_x: origin.x,
            org_y: origin.y,
            org_z: origin.z,
            tnear: tmin,
            dir_x: dir.x,
            dir_y: dir.y,
            dir_z: dir.z,
            time: 0.0,
            tfar: tmax,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        }
    }

    /// `rtcIntersect1`'s closest hit with `tmin <= t <= tmax`, if any.
    pub fn intersect(
        &self,
        origin: Vec3,
        dir: Vec3,
        tmin: f32,
        tmax: f32,
    ) -> Option<sys::RTCRayHit> {
        if !self.live(origin, dir, tmin, tmax) {
            return None;
        }
        let mut rh = sys::RTCRayHit {
            ray: Self::ray(origin, dir, tmin, tmax),
            hit: sys::RTCHit {
                geomID: sys::RTC_INVALID_GEOMETRY_ID,
                instID: [sys::RTC_INVALID_GEOMETRY_ID],
                ..Default::default()
            },
        };
        let mut ctx = sys::RTCIntersectContext::new(sys::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
        // SAFETY: a committed scene, a valid context and ray-hit.
        unsafe { sys::rtcIntersect1(self.scene, &mut ctx, &mut rh) };
        (rh.hit.geomID != sys::RTC_INVALID_GEOMETRY_ID).then_some(rh)
    }

    /// Whether anything is hit with `tmin <= t <= tmax` (`rtcOccluded1`).
    pub fn any_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        if !self.live(origin, dir, tmin, tmax) {
            return false;
        }
        let mut ray = Self::ray(origin, dir, tmin, tmax);
        let mut ctx = sys::RTCIntersectContext::new(sys::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
        // SAFETY: a committed scene, a valid context and ray.
        unsafe { sys::rtcOccluded1(self.scene, &mut ctx, &mut ray) };
        // Embree marks an occluded ray by tfar = -inf.
        ray.tfar == f32::NEG_INFINITY
    }

    /// The closest hit of each ray from `origin` along `dirs[i]` within [tmin, tmax]:
    /// `found(i, t, primID)`, one `rtcIntersect1` per ray or through 8-wide `rtcIntersect8`
    /// packets as `rays` says; rays without a hit are not reported.
    pub fn closest_hits(
        &self,
        rays: EmbreeRays,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: f32,
        mut found: impl FnMut(usize, f32, u32),
    ) {
        if rays == EmbreeRays::Single {
            for (i, &d) in dirs.iter().enumerate() {
                if let Some(rh) = self.intersect(origin, d, tmin, tmax) {
                    found(i, rh.ray.tfar, rh.hit.primID);
                }
            }
            return;
        }
        for (c, dirs) in dirs.chunks(8).enumerate() {
            let (ray, valid) = self.packet8(origin, dirs, tmin, |_| tmax);
            let mut packet = sys::RTCRayHit8 {
                ray,
                hit: sys::RTCHit8 {
                    geomID: [sys::RTC_INVALID_GEOMETRY_ID; 8],
                    instID: [[sys::RTC_INVALID_GEOMETRY_ID; 8]],
                    ..Default::default()
                },
            };
            if valid.0.iter().all(|&v| v == 0) {
                continue;
            }
            let mut ctx = sys::RTCIntersectContext::new(sys::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
            // SAFETY: a committed scene, an aligned valid mask and packet.
            unsafe { sys::rtcIntersect8(valid.0.as_ptr(), self.scene, &mut ctx, &mut packet) };
            for j in 0..dirs.len() {
                if valid.0[j] != 0 && packet.hit.geomID[j] != sys::RTC_INVALID_GEOMETRY_ID {
                    found(8 * c + j, packet.ray.tfar[j], packet.hit.primID[j]);
                }
            }
        }
    }

    /// The 8-wide packet of the rays from `origin` along `dirs` (at most eight), ray j over
    /// [tmin, tmax(j)], and its valid mask: the lanes whose query can hit ([`Self::live`]).
    fn packet8(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: impl Fn(usize) -> f32,
    ) -> (sys::RTCRay8, sys::Valid8) {
        let mut ray = sys::RTCRay8 {
            mask: [u32::MAX; 8],
            ..Default::default()
        };
        let mut valid = sys::Valid8([0; 8]);
        for (j, &d) in dirs.iter().enumerate() {
            let tm = tmax(j);
            if !self.live(origin, d, tmin, tm) {
                continue;
            }
            valid.0[j] = -1;
            (ray.org_x[j], ray.org_y[j], ray.org_z[j]) = (origin.x, origin.y, origin.z);
            (ray.dir_x[j], ray.dir_y[j], ray.dir_z[j]) = (d.x, d.y, d.z);
            (ray.tnear[j], ray.tfar[j]) = (tmin, tm);
        }
        (ray, valid)
    }

    /// `out[i] = any_hit(origin, dirs[i], tmin, tmax(i))`, one call per ray or through 8-wide
    /// packets as `rays` says.
    pub fn any_hits(
        &self,
        rays: EmbreeRays,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: impl Fn(usize) -> f32,
        out: &mut [bool],
    ) {
        if rays == EmbreeRays::Single {
            for (i, (o, &d)) in out.iter_mut().zip(dirs).enumerate() {
                *o = self.any_hit(origin, d, tmin, tmax(i));
            }
            return;
        }
        for (c, (dirs, out)) in dirs.chunks(8).zip(out.chunks_mut(8)).enumerate() {
            let (mut packet, valid) = self.packet8(origin, dirs, tmin, |j| tmax(8 * c + j));
            if valid.0.iter().any(|&v| v != 0) {
                let mut ctx =
                    sys::RTCIntersectContext::new(sys::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
                // SAFETY: a committed scene, an aligned valid mask and packet.
                unsafe { sys::rtcOccluded8(valid.0.as_ptr(), self.scene, &mut ctx, &mut packet) };
            }
            for (j, o) in out.iter_mut().enumerate() {
                *o = valid.0[j] != 0 && packet.tfar[j] == f32::NEG_INFINITY;
            }
        }
    }
}

/// The second ray-cast backend. `occluded_many(_to)` and `surface_hit_many` cast per
/// [`EmbreeTracer::rays`]; in packet mode the answers are Embree's packet kernels', which
/// `tests/embree.rs` checks equal to its single-ray kernels' on the test rays.
impl Visibility for EmbreeTracer {
    #[inline]
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        self.any_hit(origin, dir, tmin, tmax)
    }

    #[inline]
    fn hit_distance(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        self.closest_hit(origin, dir, tmin, tmax).map(|h| h.t)
    }

    #[inline]
    fn surface_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        self.closest_hit(origin, dir, tmin, tmax)
            .map(|h| SurfaceHit {
                t: h.t,
                normal: h.normal,
            })
    }

    fn occluded_many(&self, origin: Vec3, dirs: &[Vec3], tmin: f32, tmax: f32, out: &mut [bool]) {
        check_batch("occluded_many", dirs.len(), out.len());
        self.q()
            .any_hits(self.rays, origin, dirs, tmin, |_| tmax, out);
    }

    /// Reflection rays: 8-wide `rtcIntersect8` packets in packet mode, the hit triangle's
    /// normal as [`Self::surface_hit`]'s.
    fn surface_hit_many(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmax: f32,
        out: &mut [Option<SurfaceHit>],
    ) {
        check_batch("surface_hit_many", dirs.len(), out.len());
        out.fill(None);
        self.q()
            .closest_hits(self.rays, origin, dirs, tmin, tmax, |i, t, triangle| {
                out[i] = Some(SurfaceHit {
                    t,
                    normal: self.normals[triangle as usize],
                });
            });
    }

    fn occluded_many_to(
        &self,
        origin: Vec3,
        dirs: &[Vec3],
        tmin: f32,
        tmaxs: &[f32],
        out: &mut [bool],
    ) {
        check_batch_to(dirs.len(), tmaxs.len(), out.len());
        self.q()
            .any_hits(self.rays, origin, dirs, tmin, |i| tmaxs[i], out);
    }
}
