//! Building a spec's scenes: meshes loaded (or generated) once each, placed by their transforms.
//!
//! The AO scene's roles follow the 2008 paper: a receiver gets AO at its vertices; occlusion
//! comes from casters only (the reference traces the casters' triangles, the field lookup reads
//! the casters' fields). The corner is a receiver only, so it never occludes itself. An instance
//! that is both (the 2008 Figure 8 multiple-object scene) is occluded by its own field through
//! the intra-object path of the lookup, and by its own triangles in the reference.

use super::spec::{MeshSource, Spec, SpecError, TransformSpec};
use super::user_mesh::{self, FileRecord};
use super::{Error, Result};
use crate::geometry::motion::Pose;
use crate::geometry::procedural::{self, Supershape};
use crate::geometry::rebase::{
    centred_mesh, extent_problem, rebase, rebase_origin, spheres_extent_problem, to_frame,
    PlacedMesh, Placement, Rebased,
};
use crate::geometry::{models, Mesh, Scene, Similarity};
use crate::render::camera::Camera;
use glam::{DVec3, EulerRot, Quat, Vec3};
use std::path::Path;
use std::sync::Arc;

/// The largest world coordinate a placed vertex may have in its scene's frame: differences of
/// two coordinates stay below 2.3e18 and their products, summed three at a time as in a cross
/// product or a squared length, below 1.6e37, inside f32's 3.4e38.
pub const MAX_WORLD_COORDINATE: f32 = 1.152_921_5e18; // 2⁶⁰

/// A mesh used by the spec, with the hash that keys its cached fields.
#[derive(Clone, Debug)]
pub struct LoadedMesh {
    /// Label in tables and the plan (model name or procedural description).
    pub label: String,
    pub mesh: Arc<Mesh>,
    /// sha256 of the model-space positions and triangles (little-endian f32 / u32).
    pub sha256: String,
    /// Where the file's coordinates were moved from ([`centred_mesh`]): zero unless the model
    /// lies far from its file's origin.
    pub model_origin: DVec3,
    /// For a user's mesh file: what `run.json` records of it.
    pub file: Option<FileRecord>,
}

/// One scene of the spec.
#[derive(Clone, Debug)]
pub struct BuiltScene {
    pub name: String,
    /// The scene in its rebased frame ([`crate::geometry::rebase`]): world coordinates are the
    /// spec's minus [`BuiltScene::origin`].
    pub scene: Scene,
    /// The spec-world position of the scene frame's origin (zero for a scene within two
    /// radii of the spec's origin).
    pub origin: DVec3,
    /// Per instance: its mesh's index in [`Scenes::meshes`].
    pub mesh_of: Vec<usize>,
    /// The scene's own camera (spec world), if it has one.
    pub camera: Option<Camera>,
    /// With the spec's `animation`: per frame, its rebasing origin and every instance's
    /// transform in that frame (`scene` and `origin` are frame 0's); empty for a static scene.
    pub frames: Vec<FrameTransforms>,
}

/// One frame of an animated scene: the spec-world position of its frame's origin (each frame
/// rebased on its own instances, [`crate::geometry::rebase`]) and every instance's transform in
/// that frame.
#[derive(Clone, Debug)]
pub struct FrameTransforms {
    pub origin: DVec3,
    pub transforms: Vec<Similarity>,
}

impl BuiltScene {
    /// The scene at frame `f` of its animation, in that frame's rebased frame (itself for a
    /// static scene), with no frames of its own.
    pub fn at_frame(&self, f: usize) -> BuiltScene {
        let mut scene = self.scene.clone();
        let mut origin = self.origin;
        if let Some(frame) = self.frames.get(f) {
            for (inst, &t) in scene.instances.iter_mut().zip(&frame.transforms) {
                inst.transform = t;
            }
            origin = frame.origin;
        }
        BuiltScene {
            name: self.name.clone(),
            scene,
            origin,
            mesh_of: self.mesh_of.clone(),
            camera: self.camera,
            frames: Vec::new(),
        }
    }

    /// Frames of the scene: its animation's, else 1.
    pub fn frame_count(&self) -> usize {
        self.frames.len().max(1)
    }

    /// A spec-world camera in the scene's frame.
    pub fn camera_in_frame(&self, cam: &Camera) -> Camera {
        Camera {
            eye: to_frame(self.origin, cam.eye),
            target: to_frame(self.origin, cam.target),
            ..*cam
        }
    }

    /// The camera of the view of `image` in the scene's frame: the scene's own camera, else the
    /// image's, else [`Camera::corner`].
    pub fn view_camera(&self, image: &super::spec::ImageSpec) -> Camera {
        let cam = self.camera.or(image.camera).unwrap_or_else(Camera::corner);
        self.camera_in_frame(&cam)
    }

    /// Indices of the distinct meshes of the casters, in first-use order.
    pub fn caster_meshes(&self) -> Vec<usize> {
        let mut out = Vec::new();
        for (i, _) in self.scene.casters() {
            if !out.contains(&self.mesh_of[i]) {
                out.push(self.mesh_of[i]);
            }
        }
        out
    }

    /// Receiver vertices (the vertex-AO points).
    pub fn receiver_vertices(&self) -> usize {
        self.scene
            .receivers()
            .map(|(_, i)| i.mesh.vertex_count())
            .sum()
    }

    /// Triangles of every caster.
    pub fn caster_triangles(&self) -> usize {
        self.scene
            .casters()
            .map(|(_, i)| i.mesh.triangle_count())
            .sum()
    }

    /// Radius of the minimal sphere around every instance (the scale of the ray offset).
    pub fn radius(&self) -> f32 {
        self.bounds().radius
    }

    /// The minimal bounding sphere of every instance's world vertices.
    pub fn bounds(&self) -> crate::geometry::Sphere {
        self.scene.bounding_sphere()
    }
}

/// Every scene of a spec profile, with its meshes deduplicated.
#[derive(Clone, Debug, Default)]
pub struct Scenes {
    pub meshes: Vec<LoadedMesh>,
    pub scenes: Vec<BuiltScene>,
}

impl Scenes {
    /// Loads and places the meshes of `spec`'s scenes; `path` is where the scenes live in the
    /// file (`scenes` or `quick.scenes`), for error messages. Mesh files must fit half the
    /// machine's memory ([`Scenes::build_within`]).
    pub fn build(spec: &Spec, file: &Path, path: &str) -> Result<Scenes, SpecError> {
        Scenes::build_within(spec, file, path, crate::field::default_memory_limit())
    }

    /// [`Scenes::build`] with the memory limit that every mesh file's sizes are checked against
    /// before any mesh is loaded ([`user_mesh::precheck`]).
    pub fn build_within(
        spec: &Spec,
        file: &Path,
        path: &str,
        memory_limit: u64,
    ) -> Result<Scenes, SpecError> {
        user_mesh::precheck(spec, file, path, memory_limit)?;
        let invalid = |field: String, message: String| SpecError::Invalid {
            file: file.to_path_buf(),
            field,
            message,
        };
        let mut out = Scenes::default();
        let mut sources: Vec<MeshSource> = Vec::new();
        for (si, sc) in spec.scenes.iter().enumerate() {
            let mut instances = Vec::new();
            let mut mesh_of = Vec::new();
            for (ii, inst) in sc.instances.iter().enumerate() {
                let at = format!("{path}[{si}].instances[{ii}].mesh");
                let m = match sources.iter().position(|s| s == &inst.mesh) {
                    Some(m) => m,
                    None => {
                        let (mesh, record) = build_mesh(&inst.mesh, file)
                            .map_err(|e| invalid(at.clone(), e.chain()))?;
                        let (mesh, model_origin) = centred_mesh(mesh);
                        sources.push(inst.mesh.clone());
                        out.meshes.push(LoadedMesh {
                            label: inst.mesh.label(),
                            sha256: mesh_sha256(&mesh),
                            mesh: Arc::new(mesh),
                            model_origin,
                            file: record,
                        });
                        out.meshes.len() - 1
                    }
                };
                let mesh = out.meshes[m].mesh.clone();
                instances.push(PlacedMesh {
                    placement: placement(&inst.transform, &mesh, out.meshes[m].model_origin),
                    mesh,
                    caster: inst.caster,
                    receiver: inst.receiver,
                });
                mesh_of.push(m);
            }
            let motion = spec.animation.as_ref().map(|a| {
                let motions: Vec<_> = sc.instances.iter().map(|i| i.motion.as_ref()).collect();
                frame_placements(&instances, &motions, a.frames, a.time_step)
            });
            let (Rebased { scene, origin }, frames) = match &motion {
                None => {
                    if let Some(message) = extent_problem(&instances) {
                        return Err(invalid(format!("{path}[{si}].instances"), message));
                    }
                    (rebase(&instances), Vec::new())
                }
                Some(m) => {
                    let at =
                        |field: String, message| invalid(format!("{path}[{si}].{field}"), message);
                    m.rebased(&instances, &sc.instances, at)?
                }
            };
            // Placements past what f32 geometry can hold (a translation of 1e39, a scale of
            // 3e38) would reach the tracer as infinities, or overflow in its squares and cross
            // products: refused here, naming the instance, before any BVH is built.
            for (ii, inst) in scene.instances.iter().enumerate() {
                let too_far =
                    |p: &Vec3| !p.is_finite() || p.abs().max_element() > MAX_WORLD_COORDINATE;
                if let Some(bad) = inst.world_triangles().flatten().find(too_far) {
                    return Err(invalid(
                        format!("{path}[{si}].instances[{ii}].transform"),
                        format!(
                            "places a vertex at {bad}, outside ±{MAX_WORLD_COORDINATE:e}, the \
                             f32 range in which the geometry's squares and cross products stay \
                             finite (coordinates in the scene's frame, centred on its instances)"
                        ),
                    ));
                }
            }
            // The BVH builders order triangles by Morton codes over the scene's box, 2²¹
            // cells a side: an instance below that resolution puts all its triangles in a few
            // cells, and the build degrades towards quadratic time (a 500,000-triangle corner
            // scaled to 1e-7 beside a caster 65,536 away stalled it for minutes).
            let scene_radius = scene.bounding_sphere().radius;
            for (ii, inst) in scene.instances.iter().enumerate() {
                let r = inst.world_bounding_sphere().radius;
                if r < scene_radius * MIN_INSTANCE_TO_SCENE {
                    return Err(invalid(
                        format!("{path}[{si}].instances[{ii}].transform"),
                        format!(
                            "an instance of radius {r:e} in a scene of radius {scene_radius:e}: \
                             below 2⁻²¹ of the scene, the resolution at which the ray casters' \
                             BVH builders order triangles"
                        ),
                    ));
                }
            }
            out.scenes.push(BuiltScene {
                name: sc.name.clone(),
                scene,
                origin,
                mesh_of,
                camera: sc.camera,
                frames,
            });
        }
        Ok(out)
    }
}

/// Every frame's placements of a scene's instances, and their bounding spheres.
struct FramePlacements {
    /// Frame-major: frame f's instance i at `f · instances + i`.
    placed: Vec<Placement>,
    /// The world bounding sphere of each, in the same order.
    spheres: Vec<(DVec3, f64)>,
    instances: usize,
}

/// The placements of `instances` at every frame of `frames` of `dt` seconds, each moved by its
/// motion ([`crate::geometry::motion::Motion::pose`]; none: where it is placed).
fn frame_placements(
    instances: &[PlacedMesh],
    motions: &[Option<&crate::geometry::motion::Motion>],
    frames: u32,
    dt: f64,
) -> FramePlacements {
    let model: Vec<crate::geometry::Sphere> =
        instances.iter().map(|p| p.mesh.bounding_sphere()).collect();
    // Each moving instance's poses over the run, in one pass (a walk steps once a frame).
    let poses: Vec<Option<Vec<Pose>>> = instances
        .iter()
        .zip(motions)
        .zip(&model)
        .map(|((p, m), s)| m.map(|m| m.poses(frames, dt, &p.placement, s.center)))
        .collect();
    let mut placed = Vec::with_capacity(frames as usize * instances.len());
    let mut spheres = Vec::with_capacity(placed.capacity());
    for f in 0..frames as usize {
        for ((p, poses), s) in instances.iter().zip(&poses).zip(&model) {
            let q = match poses {
                Some(poses) => poses[f].apply(&p.placement, s.center),
                None => p.placement,
            };
            spheres.push((q.to_world_point(s.center), s.radius as f64 * q.scale as f64));
            placed.push(q);
        }
    }
    FramePlacements {
        placed,
        spheres,
        instances: instances.len(),
    }
}

impl FramePlacements {
    /// Frame 0 as a scene and every frame's origin and transforms, each frame rebased on its own
    /// instances ([`rebase_origin`] of its spheres, so that a scene moved as a whole by a
    /// multiple of the rebasing step keeps its coordinates bit for bit). Each frame is checked as
    /// a static scene is in [`Scenes::build`], on its bounding spheres: its distance from the
    /// spec's origin over its extent ([`spheres_extent_problem`]), every sphere within
    /// ±[`MAX_WORLD_COORDINATE`] of the frame's origin, each instance at least
    /// [`MIN_INSTANCE_TO_SCENE`] of the frame's extent; refused naming the frame and the
    /// instance's motion (or transform), or, where a still instance fails only because another
    /// moved (a caster flying away leaves the receiver small in a wide frame, or out of range
    /// of the frame's origin), the motion of the instance moved farthest from its placement,
    /// naming the failing instance in the message (`at(field, message)`).
    fn rebased(
        &self,
        instances: &[PlacedMesh],
        specs: &[super::spec::InstanceSpec],
        at: impl Fn(String, String) -> SpecError,
    ) -> Result<(Rebased, Vec<FrameTransforms>), SpecError> {
        let n = self.instances;
        let field = |i: usize| {
            let moving = specs[i].motion.is_some();
            format!(
                "instances[{i}].{}",
                if moving { "motion" } else { "transform" }
            )
        };
        // Where each instance's placement puts its centre, unmoved.
        let unmoved: Vec<DVec3> = instances
            .iter()
            .map(|p| p.placement.to_world_point(p.mesh.bounding_sphere().center))
            .collect();
        let moved = |i: usize, spheres: &[(DVec3, f64)]| (spheres[i].0 - unmoved[i]).length();
        // The instance to blame for instance `i`'s failure at a frame of `spheres`: `i` itself
        // where it moves or nothing else has, else the instance moved farthest.
        let blame = |i: usize, spheres: &[(DVec3, f64)]| -> Option<usize> {
            let j = (0..n)
                .filter(|&j| specs[j].motion.is_some())
                .max_by(|&a, &b| moved(a, spheres).total_cmp(&moved(b, spheres)))?;
            (j != i && specs[i].motion.is_none() && moved(j, spheres) > 0.0).then_some(j)
        };
        let mut frames = Vec::new();
        for (f, (placed, spheres)) in self
            .placed
            .chunks(n)
            .zip(self.spheres.chunks(n))
            .enumerate()
        {
            if let Some(message) = spheres_extent_problem(spheres) {
                return Err(at("instances".into(), format!("at frame {f}: {message}")));
            }
            let origin = rebase_origin(spheres);
            let rel: Vec<(DVec3, f64)> = spheres.iter().map(|&(c, r)| (c - origin, r)).collect();
            let (lo, hi) = rel.iter().fold(
                (DVec3::INFINITY, DVec3::NEG_INFINITY),
                |(lo, hi), &(c, r)| (lo.min(c - r), hi.max(c + r)),
            );
            let half = 0.5 * (hi - lo).length();
            for (i, &(c, r)) in rel.iter().enumerate() {
                let reach = c.abs().max_element() + r;
                if reach.is_nan() || reach > MAX_WORLD_COORDINATE as f64 {
                    let range = format!(
                        "past ±{MAX_WORLD_COORDINATE:e}, the f32 range in which the geometry's \
                         squares and cross products stay finite (coordinates in the frame's \
                         rebased frame)"
                    );
                    return Err(match blame(i, spheres) {
                        None => at(
                            field(i),
                            format!(
                                "at frame {f} puts its bounding sphere (centre {c}, radius \
                                 {r:e}) {range}"
                            ),
                        ),
                        Some(j) => at(
                            field(j),
                            format!(
                                "at frame {f} moves it {:e} from its placement, which puts the \
                                 bounding sphere of instances[{i}] (centre {c}, radius {r:e}) \
                                 {range}",
                                moved(j, spheres)
                            ),
                        ),
                    });
                }
            }
            for (i, &(_, r)) in rel.iter().enumerate() {
                if r < half * MIN_INSTANCE_TO_SCENE as f64 {
                    let resolution = "below 2⁻²¹ of it, the resolution at which the ray casters' \
                                      BVH builders order triangles";
                    return Err(match blame(i, spheres) {
                        None => at(
                            field(i),
                            format!(
                                "at frame {f}: an instance of radius {r:e} in a frame of \
                                 half-extent {half:e}: {resolution}"
                            ),
                        ),
                        Some(j) => at(
                            field(j),
                            format!(
                                "at frame {f} moves it {:e} from its placement, spreading the \
                                 frame to a half-extent of {half:e}: instances[{i}], of radius \
                                 {r:e}, is {resolution}",
                                moved(j, spheres)
                            ),
                        ),
                    });
                }
            }
            frames.push(FrameTransforms {
                origin,
                transforms: placed.iter().map(|p| p.relative_to(origin)).collect(),
            });
        }
        let scene = Scene {
            instances: instances
                .iter()
                .zip(&frames[0].transforms)
                .map(|(p, &transform)| crate::geometry::Instance {
                    mesh: p.mesh.clone(),
                    transform,
                    caster: p.caster,
                    receiver: p.receiver,
                })
                .collect(),
        };
        let origin = frames[0].origin;
        Ok((Rebased { scene, origin }, frames))
    }
}

/// The smallest instance radius a scene accepts, as a fraction of the scene's radius: 2⁻²¹, the
/// Morton-code resolution of the BVH builders (see `Scenes::build`).
pub const MIN_INSTANCE_TO_SCENE: f32 = 1.0 / 2_097_152.0;

/// Loads or generates a mesh; a mesh file (relative to the folder of `spec_file`) comes with
/// its record.
pub fn build_mesh(src: &MeshSource, spec_file: &Path) -> Result<(Mesh, Option<FileRecord>)> {
    let r = match src {
        MeshSource::Model(name) => return Ok((models::load_model(name)?, None)),
        MeshSource::File(f) => {
            let (mesh, record) = user_mesh::load(spec_file, f)?;
            return Ok((mesh, Some(record)));
        }
        MeshSource::Corner { n } => procedural::corner(*n),
        MeshSource::CubeWithHole { size, hole } => procedural::cube_with_hole(*size, *hole),
        MeshSource::Supershape { triangles } => {
            procedural::supershape(&Supershape::default(), *triangles)
        }
        MeshSource::Sphere {
            radius,
            stacks,
            slices,
        } => procedural::uv_sphere(*radius, *stacks, *slices),
        MeshSource::Plane { size, n } => procedural::plane(*size, *n),
        MeshSource::Ellipsoid {
            radii,
            stacks,
            slices,
        } => procedural::ellipsoid(*radii, *stacks, *slices),
    };
    r.map(|m| (m, None)).map_err(Error::geometry(src.label()))
}

/// The placement described by `t` (see [`TransformSpec`]) of `mesh`, whose model-space points
/// were moved by `−model_origin` ([`centred_mesh`]); the translation in f64.
pub fn placement(t: &TransformSpec, mesh: &Mesh, model_origin: DVec3) -> Placement {
    let rotation = t
        .rotate_deg
        .map(|d| {
            Quat::from_euler(
                EulerRot::YXZ,
                d.y.to_radians(),
                d.x.to_radians(),
                d.z.to_radians(),
            )
            .normalize()
        })
        .unwrap_or(Quat::IDENTITY);
    // A fit places the mesh's sphere, wherever the model's coordinates were: the offset only
    // matters without one.
    let (inner, offset) = match &t.fit {
        Some(f) => {
            let s = mesh.bounding_sphere();
            let k = f.radius / s.radius;
            let fit = Similarity::new(rotation, f.center - k * (rotation * s.center), k);
            (fit, DVec3::ZERO)
        }
        None => (Similarity::new(rotation, Vec3::ZERO, 1.0), model_origin),
    };
    let outer = Placement::new(
        Quat::IDENTITY,
        t.translate.unwrap_or(DVec3::ZERO),
        t.scale.unwrap_or(1.0),
    );
    outer.compose(&inner).after_model_offset(offset)
}

/// sha256 of a mesh's model-space positions and triangles.
pub fn mesh_sha256(mesh: &Mesh) -> String {
    let mut bytes: Vec<u8> = bytemuck::cast_slice(&mesh.positions).to_vec();
    bytes.extend_from_slice(bytemuck::cast_slice(&mesh.triangles));
    crate::io::sha256_hex(&bytes)
}
