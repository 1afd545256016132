//! Embree 3 with instance geometries: one committed triangle scene per mesh, built once (robust,
//! high quality, as [`super::embree::EmbreeTracer`]'s), and a top scene of one instance
//! geometry per rigid object whose transforms are set and which is committed again every frame
//! ([`EmbreeInstances::update`]). This is how Embree is meant to serve scenes of moving rigid
//! objects (Wald et al., "Embree: A Kernel Framework for Efficient CPU Ray Tracing", ACM TOG
//! 33(4), 2014, §5.3, instancing): the motion costs the top level's rebuild over the instances,
//! not the triangles'. The top scene is flagged dynamic and built at low quality (Embree's advice
//! for a scene rebuilt every frame); the instanced scenes keep the robust flag.
//!
//! Embree moves each ray into the instance's space with the inverse of the 3 × 4 matrix given
//! here (f32), as our [`super::two_level::TwoLevel`] does with the similarity's inverse: the
//! two agree away from edges and grazing rays, and `tests/embree_instances.rs` counts where
//! they differ.

use super::embree::{
    device_error, new_device, triangle_normals, triangle_scene, Committed, EmbreeError, EmbreeRays,
};
use super::embree_sys as sys;
use crate::geometry::Similarity;
use crate::visibility::{check_batch, check_batch_to, SurfaceHit, Visibility};
use glam::Vec3;

/// Meshes, each a committed Embree scene, instanced by rigid transforms under a top scene.
///
/// Queries as [`super::embree::EmbreeTracer`]'s (`origin` finite, `dir` finite and non-zero,
/// `0 <= tmin`; triangles hit from either side); `t` is in units of the world ray's `dir`.
pub struct EmbreeInstances {
    device: sys::RTCDevice,
    /// Per mesh, its scene (model space) and its triangles' unit normals.
    meshes: Vec<(sys::RTCScene, Vec<Vec3>)>,
    /// The top scene over `instances`; null before the first [`Self::update`].
    top: sys::RTCScene,
    /// Per instance: its mesh and transform, as the last [`Self::update`] placed them.
    instances: Vec<(usize, Similarity)>,
    /// The instance geometries of `top`, one per entry of `instances`.
    geometries: Vec<sys::RTCGeometry>,
    rays: EmbreeRays,
}

// SAFETY: as `EmbreeTracer`: queries only read committed scenes, which Embree documents as
// thread-safe; every mutation (`update`, `drop`) takes `&mut self`.
unsafe impl Send for EmbreeInstances {}
unsafe impl Sync for EmbreeInstances {}

impl Drop for EmbreeInstances {
    fn drop(&mut self) {
        // SAFETY: each handle was created here and is released once.
        unsafe {
            self.release_top();
            for &(scene, _) in &self.meshes {
                sys::rtcReleaseScene(scene);
            }
            sys::rtcReleaseDevice(self.device);
        }
    }
}

/// `t` as Embree's column-major 3 × 4 matrix: the columns of `rotation · scale`, then the
/// translation.
fn matrix(t: &Similarity) -> [f32; 12] {
    let m = glam::Mat3::from_quat(t.rotation) * t.scale;
    let mut out = [0.0; 12];
    out[0..3].copy_from_slice(&m.x_axis.to_array());
    out[3..6].copy_from_slice(&m.y_axis.to_array());
    out[6..9].copy_from_slice(&m.z_axis.to_array());
    out[9..12].copy_from_slice(&t.translation.to_array());
    out
}

impl EmbreeInstances {
    /// Builds each mesh's scene over its model-space triangles; no instance yet (every query
    /// misses until [`Self::update`]).
    ///
    /// # Errors
    /// When Embree refuses the device or a scene.
    ///
    /// # Panics
    /// If a vertex is not finite.
    pub fn new(meshes: &[Vec<[Vec3; 3]>]) -> Result<EmbreeInstances, EmbreeError> {
        // SAFETY: every handle is checked by the helpers; `out` releases what was made if a
        // later mesh fails.
        unsafe {
            let device = new_device()?;
            let mut out = EmbreeInstances {
                device,
                meshes: Vec::with_capacity(meshes.len()),
                top: std::ptr::null_mut(),
                instances: Vec::new(),
                geometries: Vec::new(),
                rays: super::embree::EmbreeTracer::DEFAULT_RAYS,
            };
            for tris in meshes {
                let scene = triangle_scene(device, tris)?;
                out.meshes.push((scene, triangle_normals(tris)));
            }
            Ok(out)
        }
    }

    /// Releases the top scene and its instance geometries.
    ///
    /// # Safety
    /// Only from `update` and `drop` (`&mut self`).
    unsafe fn release_top(&mut self) {
        for &g in &self.geometries {
            sys::rtcReleaseGeometry(g);
        }
        self.geometries.clear();
        if !self.top.is_null() {
            sys::rtcReleaseScene(self.top);
            self.top = std::ptr::null_mut();
        }
    }

    /// Places the instances (mesh index, transform) for this frame: with the same meshes in
    /// the same order as the last frame, each instance's transform is set and the top scene
    /// committed again; otherwise the top scene is made anew.
    ///
    /// # Errors
    /// When Embree refuses a geometry or the commit.
    ///
    /// # Panics
    /// If an instance names a mesh that does not exist, or a transform is not finite.
    pub fn update(&mut self, instances: &[(usize, Similarity)]) -> Result<(), EmbreeError> {
        assert!(
            instances.iter().all(|&(m, t)| m < self.meshes.len()
                && t.translation.is_finite()
                && t.rotation.is_finite()
                && t.scale.is_finite()),
            "EmbreeInstances::update: an instance names no mesh or has a non-finite transform"
        );
        let same = self.instances.len() == instances.len()
            && self
                .instances
                .iter()
                .zip(instances)
                .all(|(a, b)| a.0 == b.0)
            && !self.top.is_null();
        // SAFETY: handles are checked as they are made; geometries are attached to `top`, which
        // retains them, and released with it.
        unsafe {
            if !same {
                self.release_top();
                self.instances.clear();
                let top = sys::rtcNewScene(self.device);
                if top.is_null() {
                    device_error(self.device, "rtcNewScene (instances)")?;
                    return Err(EmbreeError {
                        what: "rtcNewScene (instances)",
                        code: "RTC_ERROR_UNKNOWN",
                    });
                }
                self.top = top;
                sys::rtcSetSceneFlags(top, sys::RTC_SCENE_FLAG_DYNAMIC);
                sys::rtcSetSceneBuildQuality(top, sys::RTC_BUILD_QUALITY_LOW);
                for &(m, _) in instances {
                    let g = sys::rtcNewGeometry(self.device, sys::RTC_GEOMETRY_TYPE_INSTANCE);
                    device_error(self.device, "rtcNewGeometry (instance)")?;
                    sys::rtcSetGeometryInstancedScene(g, self.meshes[m].0);
                    sys::rtcAttachGeometry(top, g);
                    self.geometries.push(g);
                }
            }
            for (&g, (_, t)) in self.geometries.iter().zip(instances) {
                let xfm = matrix(t);
                sys::rtcSetGeometryTransform(
                    g,
                    0,
                    sys::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR,
                    xfm.as_ptr().cast(),
                );
                sys::rtcCommitGeometry(g);
            }
            device_error(self.device, "rtcCommitGeometry (instance)")?;
            sys::rtcCommitScene(self.top);
            device_error(self.device, "rtcCommitScene (instances)")?;
        }
        self.instances = instances.to_vec();
        Ok(())
    }

    #[inline]
    fn q(&self) -> Committed {
        Committed {
            scene: self.top,
            empty: self.top.is_null() || self.instances.is_empty(),
        }
    }
}

impl Visibility for EmbreeInstances {
    #[inline]
    fn occluded(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> bool {
        self.q().any_hit(origin, dir, tmin, tmax)
    }

    #[inline]
    fn hit_distance(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<f32> {
        self.q()
            .intersect(origin, dir, tmin, tmax)
            .map(|rh| rh.ray.tfar)
    }

    /// The hit triangle's model-space normal (as [`super::Tracer`] computes it) turned by the
    /// instance's rotation.
    fn surface_hit(&self, origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Option<SurfaceHit> {
        let rh = self.q().intersect(origin, dir, tmin, tmax)?;
        let (m, t) = self.instances[rh.hit.instID[0] as usize];
        Some(SurfaceHit {
            t: rh.ray.tfar,
            normal: (t.rotation * self.meshes[m].1[rh.hit.primID as usize]).normalize(),
        })
    }

    fn occluded_many(&self, origin: Vec3, dirs: &[Vec3], tmin: f32, tmax: f32, out: &mut [bool]) {
        check_batch("occluded_many", dirs.len(), out.len());
        self.q()
            .any_hits(self.rays, origin, dirs, tmin, |_| tmax, out);
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
