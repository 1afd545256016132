//! The crowd: N rigid casters over a receiver plane, each orbiting its grid cell's centre and
//! tumbling, every method answering vertex AO at the plane's vertices frame after frame.

use super::FrameRow;
use crate::experiment::fields::FieldSupply;
use crate::experiment::methods::field::MeshFields;
use crate::experiment::methods::motion::{self, FrameCasters, Mover, MoverInputs};
use crate::experiment::methods::Method;
use crate::experiment::metrics::{self, rms_unquantised};
use crate::experiment::scenes::{mesh_sha256, LoadedMesh};
use crate::experiment::truth_cache::{load_or_compute, TruthInputs};
use crate::experiment::{Error, Result};
use crate::field::lookup::LookupOptions;
use crate::field::{FieldParams, Precision};
use crate::geometry::procedural::{supershape, Supershape};
use crate::geometry::{models, procedural, Mesh, Similarity};
use crate::render::ao::AoOptions;
use crate::render::estimator::{AoEstimator, Points};
use crate::render::truth::TruthOptions;
use crate::sampling::rays::RaySet;
use crate::sampling::{LayoutKind, SphereKind};
use glam::{Quat, Vec3};
use std::sync::Arc;

/// Grid cell side (world units); the plane is √N cells wide.
const CELL: f32 = 1.0;
/// Each caster's bounding sphere radius, as a share of the cell.
const RADIUS: f32 = 0.3;
/// Orbit radius about the cell centre, as a share of the cell: the spheres of neighbours
/// (centres at least 1 − 2·0.12 = 0.76 apart) never overlap (0.6 < 0.76).
const ORBIT: f32 = 0.12;
/// Height of the sphere's centre above the plane (a gap of 0.02 under the sphere).
const HEIGHT: f32 = RADIUS + 0.02;

/// The sizes of one run.
pub struct Profile {
    /// Caster counts, perfect squares.
    pub counts: Vec<usize>,
    pub frames: usize,
    /// Frame time step (seconds of the motion).
    pub dt: f32,
    /// The meshes, taken in turn: registered models, or `supershape:T` (T triangles).
    pub models: Vec<&'static str>,
    /// Receiver plane vertices per cell side.
    pub plane_per_cell: usize,
    /// Rays per point (k²).
    pub k: u32,
    pub field: (usize, u32, Precision),
    /// The per-object peers: the distance volumes' samples along each mesh box's longest side
    /// and the AO fields' texels per cube face side (both f32, one per mesh).
    pub sdf_res: usize,
    pub aofield_res: usize,
    /// The converged reference of every frame.
    pub truth: TruthOptions,
    /// The crowd drawn as an animation (`crowd.png`, APNG).
    pub animate: usize,
    /// The approach sweep's gaps between the caster's sphere and the plane, in sphere radii.
    pub gaps: Vec<f32>,
}

impl Profile {
    pub fn new(quick: bool) -> Profile {
        if quick {
            Profile {
                counts: vec![1, 4, 16],
                frames: 3,
                dt: 0.1,
                models: vec!["supershape:2000", "supershape:4000"],
                plane_per_cell: 8,
                k: 4,
                field: (290, 16, Precision::U8),
                sdf_res: 32,
                aofield_res: 8,
                truth: TruthOptions {
                    target_stderr_255: 1.0,
                    max_rays: 1024,
                    batches: 4,
                    start_k: 4,
                    seed: 7,
                },
                gaps: vec![0.5, 0.0, -0.25, -0.5],
                animate: 4,
            }
        } else {
            Profile {
                counts: vec![1, 4, 16, 64, 256],
                frames: 8,
                dt: 0.1,
                models: vec![
                    "stanford-bunny_39k",
                    "igea_67k",
                    "dragon",
                    "Tree_3",
                    "elephant",
                ],
                plane_per_cell: 16,
                k: 8,
                field: (1090, 32, Precision::U8),
                sdf_res: 64,
                aofield_res: 16,
                truth: TruthOptions {
                    target_stderr_255: 0.5,
                    max_rays: 1024,
                    batches: 4,
                    start_k: 8,
                    seed: 7,
                },
                gaps: vec![
                    1.0, 0.5, 0.25, 0.1, 0.05, 0.0, -0.05, -0.1, -0.2, -0.3, -0.4, -0.5,
                ],
                animate: 16,
            }
        }
    }

    /// The profile as run.json records it.
    pub fn describe(&self) -> serde_json::Value {
        serde_json::json!({
            "counts": self.counts,
            "frames": self.frames,
            "dt": self.dt,
            "models": self.models,
            "plane_vertices_per_cell": self.plane_per_cell,
            "rays_per_point": self.k * self.k,
            "cell": CELL,
            "sphere_radius": RADIUS * CELL,
            "orbit_radius": ORBIT * CELL,
            "sphere_centre_height": HEIGHT * CELL,
            "truth": self.truth,
            "approach_gaps_radii": self.gaps,
            "sdf": { "res": self.sdf_res, "margin": 2, "precision": "f32" },
            "aofield": { "res": self.aofield_res, "precision": "f32" },
        })
    }

    /// The per-object peers: the `sdf` and `aofield` methods at the profile's resolutions (their
    /// other keys' defaults: f32, margin 2), read by the registry as a spec's `methods` entry is.
    pub fn peers(&self) -> Vec<Box<dyn Method>> {
        [("sdf", self.sdf_res), ("aofield", self.aofield_res)]
            .into_iter()
            .flat_map(|(name, res)| {
                let entry = crate::experiment::methods::lookup(name).expect("a built-in method");
                let options = (entry.read)(serde_json::json!({ "res": [res] }));
                options.expect("the peer's options read").settings()
            })
            .collect()
    }

    /// The model names that need a model folder (the generated ones need none).
    pub fn registered(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.models
            .iter()
            .copied()
            .filter(|m| !m.starts_with("supershape:"))
    }
}

/// The field of every caster mesh, as a label ("1090x32² u8").
pub fn field_label(p: &Profile) -> String {
    let (c, r, prec) = p.field;
    format!("{c}x{r}² {}", prec.name())
}

fn load(name: &str) -> Result<Mesh> {
    match name.strip_prefix("supershape:") {
        Some(t) => {
            let t: usize = t.parse().map_err(|_| {
                Error::invalid(
                    "dynamic: models",
                    format!("\"{name}\": not supershape:TRIANGLES"),
                )
            })?;
            supershape(&Supershape::default(), t).map_err(Error::geometry(name))
        }
        None => Ok(models::load_model(name)?),
    }
}

/// One crowd: its meshes, fields, receiver points and rays.
pub struct Crowd {
    /// `crowd` or `approach`.
    sweep: &'static str,
    n: usize,
    /// For the approach sweep: per frame, the gap between the caster's sphere and the plane in
    /// sphere radii (negative: the sphere cuts the plane).
    gaps: Option<Vec<f32>>,
    meshes: Vec<Arc<Mesh>>,
    /// One field per mesh (the field's forms read them).
    fields: MeshFields,
    /// The per-object peers ([`Profile::peers`]) and the cache their bakes are kept in.
    peers: Vec<Box<dyn Method>>,
    cache: Option<std::path::PathBuf>,
    /// Per caster: its mesh, its scale, the mesh's bounding sphere centre (model space), its
    /// orbit phase and tumble axis.
    casters: Vec<CasterMotion>,
    points: Vec<Vec3>,
    normals: Vec<Vec3>,
    /// The plane's vertices per side (the points are its `side × side` grid).
    pub plane_side: usize,
    rays: RaySet,
    opts: AoOptions,
}

struct CasterMotion {
    mesh: usize,
    scale: f32,
    centre: Vec3,
    cell: Vec3,
    phase: f32,
    axis: Vec3,
    spin: f32,
}

/// A value in [0, 1) of (i, salt): the crowd's seeded phases and axes.
fn unit(i: usize, salt: u64) -> f32 {
    crate::geometry::motion::seeded_unit(i, salt)
}

impl Crowd {
    pub fn new(p: &Profile, n: usize, supply: &FieldSupply) -> Result<Crowd> {
        let side = (n as f64).sqrt().round() as usize;
        if side * side != n {
            return Err(Error::invalid(
                "dynamic: counts",
                format!("{n} is not a square"),
            ));
        }
        let used = p.models.len().min(n);
        let mut meshes = Vec::new();
        let mut fields = Vec::new();
        let (count, res, precision) = p.field;
        let params = FieldParams {
            sphere: SphereKind::Slater,
            count,
            layout: LayoutKind::Concentric,
            res,
            precision,
        };
        for name in &p.models[..used] {
            let mesh = Arc::new(load(name)?);
            let lm = LoadedMesh {
                label: name.to_string(),
                sha256: mesh_sha256(&mesh),
                mesh: mesh.clone(),
                model_origin: glam::DVec3::ZERO,
                file: None,
            };
            fields.push(supply.obtain(&lm, params)?.field);
            meshes.push(mesh);
        }
        let width = side as f32 * CELL;
        let casters = (0..n)
            .map(|i| {
                let m = i % used;
                let s = meshes[m].bounding_sphere();
                let (row, col) = (i / side, i % side);
                let a = unit(i, 1) * std::f32::consts::TAU;
                let z = 2.0 * unit(i, 2) - 1.0;
                let r = (1.0 - z * z).max(0.0).sqrt();
                CasterMotion {
                    mesh: m,
                    scale: RADIUS * CELL / s.radius,
                    centre: s.center,
                    cell: Vec3::new(
                        (col as f32 + 0.5) * CELL - 0.5 * width,
                        HEIGHT * CELL,
                        (row as f32 + 0.5) * CELL - 0.5 * width,
                    ),
                    phase: unit(i, 3) * std::f32::consts::TAU,
                    axis: Vec3::new(r * a.cos(), z, r * a.sin()).normalize(),
                    spin: 1.0 + unit(i, 4),
                }
            })
            .collect();
        let plane_side = side * p.plane_per_cell + 1;
        let plane =
            procedural::plane(width, plane_side).map_err(Error::geometry("dynamic: plane"))?;
        let bounds = crate::geometry::Sphere {
            center: Vec3::ZERO,
            radius: 0.75 * width,
        };
        Ok(Crowd {
            sweep: "crowd",
            n,
            gaps: None,
            meshes,
            fields: MeshFields {
                fields,
                normals: Vec::new(),
                options: LookupOptions::default(),
            },
            peers: p.peers(),
            cache: supply.cache.clone(),
            casters,
            points: plane.positions.clone(),
            normals: plane.normals.clone(),
            plane_side,
            rays: RaySet::new(p.k, 1),
            opts: AoOptions::for_scene(bounds),
        })
    }

    /// The approach: one caster (the profile's first mesh) lowered onto the middle of a plane
    /// 2 cells wide, frame by frame, its sphere's gap to the plane going through `gaps` (in
    /// sphere radii; below 0 the sphere cuts the plane, and further down the mesh itself).
    pub fn approach(p: &Profile, supply: &FieldSupply, gaps: Vec<f32>) -> Result<Crowd> {
        let mut c = Crowd::new(p, 4, supply)?;
        c.sweep = "approach";
        c.n = 1;
        c.casters.truncate(1);
        c.casters[0].cell = Vec3::new(0.0, HEIGHT * CELL, 0.0);
        c.gaps = Some(gaps);
        Ok(c)
    }

    /// Frames of this scene: the profile's, or one per gap of the approach.
    fn frame_count(&self, p: &Profile) -> usize {
        self.gaps.as_ref().map_or(p.frames, Vec::len)
    }

    /// Every caster's (mesh, transform) at frame `f`.
    fn frame(&self, p: &Profile, f: usize) -> Vec<(usize, Similarity)> {
        match &self.gaps {
            None => self.at(f as f32 * p.dt),
            Some(gaps) => {
                let c = &self.casters[0];
                let r = RADIUS * CELL;
                let pos = Vec3::new(c.cell.x, r + gaps[f] * r, c.cell.z);
                let translation = pos - c.scale * c.centre;
                vec![(
                    c.mesh,
                    Similarity::new(Quat::IDENTITY, translation, c.scale),
                )]
            }
        }
    }

    /// Every caster's (mesh, transform) at time `t`: the sphere's centre on its orbit, the
    /// mesh turned about its axis.
    pub fn at(&self, t: f32) -> Vec<(usize, Similarity)> {
        self.casters
            .iter()
            .map(|c| {
                let a = c.phase + t;
                let pos = c.cell + ORBIT * CELL * Vec3::new(a.cos(), 0.0, a.sin());
                let rot = Quat::from_axis_angle(c.axis, c.spin * t);
                let translation = pos - c.scale * (rot * c.centre);
                (c.mesh, Similarity::new(rot, translation, c.scale))
            })
            .collect()
    }

    /// Caster pairs whose world spheres overlap, and receiver points inside some sphere.
    fn overlaps(&self, frame: &[(usize, Similarity)]) -> (usize, usize) {
        let spheres: Vec<(usize, crate::geometry::Sphere)> = frame
            .iter()
            .enumerate()
            .map(|(i, &(m, t))| (i, t.to_world_sphere(&self.meshes[m].bounding_sphere())))
            .collect();
        motion::overlaps(&spheres, &self.points, |_| None)
    }

    /// The receiver points.
    pub fn point_count(&self) -> usize {
        self.points.len()
    }

    /// The AO rays of a frame: points × rays per point.
    pub fn ray_count(&self) -> usize {
        self.points.len() * self.rays.len()
    }

    /// The methods of this build, each with its precompute done (per-mesh BVHs or scenes, the
    /// peers' bakes): the world rebuild first, then the other ray casters, the field's forms
    /// and the per-object peers ([`Profile::peers`]), each built by its method.
    pub fn movers(&self) -> Result<Vec<Box<dyn Mover>>> {
        let names = &crate::experiment::spec::FRAME_METHODS;
        let on = |fields| MoverInputs {
            meshes: &self.meshes,
            cache: self.cache.as_deref(),
            fields,
        };
        let mut v = motion::movers(names, &on(None))?;
        v.extend(motion::movers(names, &on(Some(&self.fields)))?);
        for m in &self.peers {
            for f in m.frame_forms() {
                v.push(m.mover(f.name, &on(None))?);
            }
        }
        Ok(v)
    }

    /// What frame `f` costs `mover`: its update to the frame's transforms, then the vertex AO
    /// of the receiver points (the values returned).
    pub fn step(&self, p: &Profile, mover: &mut dyn Mover, f: usize) -> Result<Vec<f32>> {
        let frame = self.frame(p, f % self.frame_count(p));
        mover.update(&FrameCasters {
            meshes: &self.meshes,
            instances: &frame,
        })?;
        Ok(mover.ao(&self.points, &self.normals, &self.rays, &self.opts))
    }

    /// Every frame, every method: its update, its query, its errors against the world rebuild
    /// on the same rays and against the frame's converged reference (from the cache in
    /// `cache` where it holds it: the key covers the frame's world triangles).
    /// With them, the frames of the animation: the approach's, and the crowd's of
    /// `p.animate` casters (empty for the others).
    pub fn frames(
        &self,
        p: &Profile,
        cache: Option<&std::path::Path>,
    ) -> Result<(Vec<FrameRow>, Vec<super::animation::Frame>)> {
        let animated = self.sweep == "approach" || self.n == p.animate;
        let mut pictures = Vec::new();
        let mut movers = self.movers()?;
        let tris: usize = self
            .casters
            .iter()
            .map(|c| self.meshes[c.mesh].triangle_count())
            .sum();
        let rays = (self.points.len() * self.rays.len()) as u64;
        let mut rows = Vec::new();
        // The previous frame's values per method, and the converged reference's (the flicker).
        let mut prev: Vec<(&'static str, Vec<f32>)> = Vec::new();
        let mut prev_truth: Option<Vec<f32>> = None;
        let keep = vec![true; self.points.len()];
        for f in 0..self.frame_count(p) {
            let frame = self.frame(p, f);
            let (sphere_overlaps, points_in_spheres) = self.overlaps(&frame);
            let gap_radii = self.gaps.as_ref().map(|g| g[f] as f64);
            // The lowest point of the moved meshes over the plane, in sphere radii (below 0 the
            // mesh itself goes through the plane).
            let mesh_clearance = self.gaps.as_ref().map(|_| {
                let (m, t) = frame[0];
                let low = self.meshes[m]
                    .positions
                    .iter()
                    .map(|&v| t.to_world_point(v).y)
                    .fold(f32::INFINITY, f32::min);
                (low / (RADIUS * CELL)) as f64
            });
            let casters = FrameCasters {
                meshes: &self.meshes,
                instances: &frame,
            };
            let mut reference: Option<Vec<f32>> = None;
            let mut truth = None;
            let mut raycast_flicker = None;
            let mut now: Vec<(&'static str, Vec<f32>)> = Vec::new();
            for m in movers.iter_mut() {
                let motion::Timed {
                    update_s,
                    query_s,
                    values: ao,
                    ..
                } = motion::timed(m.as_mut(), &casters, |m| {
                    Ok(m.ao(&self.points, &self.normals, &self.rays, &self.opts))
                })?;
                let reference = reference.get_or_insert_with(|| ao.clone());
                if animated && m.name() == "field" {
                    pictures.push(super::animation::Frame {
                        reference: reference.clone(),
                        field: ao.clone(),
                    });
                }
                if truth.is_none() {
                    // The first method is the world rebuild: the frame's exact ray caster.
                    let world = casters.world_triangles();
                    let est = AoEstimator { opts: self.opts };
                    let inputs = TruthInputs {
                        estimator: &est,
                        tracer: m.vis(),
                        casters: &world,
                        at: Points {
                            points: &self.points,
                            normals: &self.normals,
                        },
                    };
                    let name = format!("crowd{}-f{f}", self.n);
                    truth = Some(load_or_compute(cache, &name, &inputs, &p.truth)?.0);
                }
                let t = truth.as_ref().expect("the frame's truth");
                let before = prev.iter().find(|(n, _)| *n == m.name()).map(|(_, v)| v);
                let flicker = match (before, &prev_truth) {
                    (Some(b), Some(bt)) => Some(metrics::flicker(b, &ao, bt, &t.values, &keep)),
                    _ => None,
                };
                // The first method is the world rebuild: the same-ray ray cast.
                if now.is_empty() {
                    raycast_flicker = flicker;
                }
                let row = FrameRow {
                    scene: self.sweep.to_string(),
                    frame: f,
                    time_s: None,
                    method: m.name().to_string(),
                    cell: String::new(),
                    points: self.points.len(),
                    crease_points: None,
                    rays,
                    caster_triangles: tris,
                    points_s: None,
                    update_s,
                    query_s,
                    frame_s: update_s + query_s,
                    mrays_s: rays as f64 / query_s.max(1e-12) / 1e6,
                    rms_vs_raycast: rms_unquantised(&ao, reference),
                    rms_vs_truth: rms_unquantised(&ao, &t.values),
                    truth_stderr: t.rms_stderr_255(),
                    mean_value: ao.iter().map(|&v| v as f64).sum::<f64>() / ao.len().max(1) as f64,
                    bytes: m.bytes(),
                    sphere_overlaps,
                    points_in_spheres,
                    flip_mean_vs_raycast: None,
                    flip_weighted_median_vs_raycast: None,
                    flip_mean_vs_truth: None,
                    flip_weighted_median_vs_truth: None,
                    flicker,
                    raycast_flicker,
                    flicker_points: None,
                    flip_frame_change: None,
                    truth_flip_frame_change: None,
                    gap_radii,
                    mesh_clearance,
                    casters: Some(self.n),
                };
                println!(
                    "dynamic {} N={:<4} frame {f:<2} {:<15} update {:>9.4} s  query {:>8.4} s  RMS {:.3} (vs truth {:.3})",
                    self.sweep, self.n, row.method, row.update_s, row.query_s, row.rms_vs_raycast, row.rms_vs_truth
                );
                rows.push(row);
                now.push((m.name(), ao));
            }
            prev = now;
            prev_truth = truth.map(|t| t.values);
        }
        Ok((rows, pictures))
    }
}
