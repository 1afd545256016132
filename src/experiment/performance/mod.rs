//! `experiment performance`: field lookup against ray casting on the same rays, and how each
//! one's cost grows, in one run (`results/performance/`).
//!
//! The rays are the field bench's: a caster over the corner, 256 stratified cosine rays at each
//! of the corner's receiver vertices (vertex AO, `occluded_many` per vertex, all threads). Every
//! backend answers the same rays in the same pass: our ray caster (obvhs CWBVH + watertight
//! triangles), Embree where the crate is built with `--features embree`, the field's batched
//! nearest lookup, and the two cost floors of [`floor`] (what any lookup must do at least).
//! Each time is the fastest of a few passes, the backends taking turns pass by pass so that
//! each meets the same load on a shared machine, each timed pass right after an untimed one of
//! the same backend (warm caches).
//!
//! Three sweeps, each written to `backend_times.csv` (column `sweep`) and plotted, for AO rays and again
//! for the 2010 paper's shadow and reflection rays on the same casters, fields and receivers
//! (sweeps `shadow_*` and `reflection_*`, [`secondary`]):
//! - `triangles`: real models from 3.7k to 269k triangles, one field shape (4226 × 32² u8);
//! - `field_size`: one caster, fields from tens of KiB (in L2) to tens of MiB (beyond L3);
//! - `entering`: one caster and field, each vertex's rays drawn so that a set share of them
//!   enters the caster's bounding sphere (the rays whose answer the field must read).

pub mod floor;
pub mod plots;
pub mod secondary;

use super::fields::FieldSupply;
use super::scenes::{mesh_sha256, LoadedMesh};
use super::{Error, Result};
use crate::field::lookup::{LookupOptions, SphereOrigin};
use crate::field::scene::{FieldInstance, FieldScene};
use crate::field::{FieldParams, Precision, Selection};
use crate::geometry::procedural::{over_corner, supershape, Supershape};
use crate::geometry::{models, Mesh, Scene};
use crate::render::ao::{ao_at_points, AoOptions};
use crate::render::receivers::Receivers;
use crate::sampling::rays::RaySet;
use crate::sampling::{Frame, LayoutKind, SphereKind};
use crate::visibility::Visibility;
use floor::{NoQuery, SphereCull};
use glam::{Quat, Vec3};
use secondary::{RayKind, Secondary};
use serde::Serialize;
use std::path::Path;
use std::rc::Rc;
use std::sync::Arc;
use std::time::Instant;

/// One backend's time on one sweep point.
#[derive(Clone, Debug, Serialize)]
pub struct PerfRow {
    /// `triangles`, `field_size` or `entering` (vertex AO rays); the same prefixed by
    /// `shadow_` or `reflection_` for those rays ([`secondary`]).
    pub sweep: &'static str,
    pub caster: String,
    pub triangles: usize,
    /// The field of the lookup and floor rows ("4226x32² u8"), its storage bytes.
    pub field: String,
    pub field_bytes: u64,
    /// Share of the rays that enter the caster's bounding sphere.
    pub entering_share: f64,
    /// `raycast` (ours), `embree`, `field_nearest`, `floor_sphere_cull`, `floor_no_query`.
    pub backend: &'static str,
    pub rays: u64,
    /// Fastest timed pass, seconds (all threads).
    pub seconds: f64,
    pub mrays_s: f64,
    /// This backend's speed over our ray caster's on the same rays (> 1: faster).
    pub vs_raycast: f64,
    /// Over Embree's, where it ran.
    pub vs_embree: Option<f64>,
    /// The pass's answer: the share of the rays answered free on the AO sweeps and every
    /// `entering` sweep, the mean light fraction on the shadow sweeps, the mean reflected
    /// radiance on the reflection sweeps; equal for every exact backend.
    pub free_share: f64,
    /// Preparation before the timed passes (BVH build; field bake or cache read), seconds.
    pub setup_s: f64,
}

/// Sizes of one run.
struct Profile {
    stride: usize,
    passes: usize,
    models: Vec<&'static str>,
    sizes: Vec<(usize, u32, Precision)>,
    shares: Vec<f64>,
    /// The field of the `triangles` and `entering` sweeps.
    standard: (usize, u32, Precision),
}

impl Profile {
    fn new(quick: bool) -> Profile {
        if quick {
            Profile {
                stride: 16,
                passes: 1,
                models: vec!["bunny_npm", "stanford-bunny_39k"],
                sizes: vec![(290, 8, Precision::U8), (290, 16, Precision::U8)],
                shares: vec![0.0, 0.5, 1.0],
                standard: (290, 16, Precision::U8),
            }
        } else {
            Profile {
                stride: 1,
                passes: 6,
                models: vec![
                    "bunny_npm",
                    "elephant",
                    "armadillo",
                    "stanford-bunny_39k",
                    "igea_67k",
                    "dragon",
                    "supershape",
                    "igea",
                ],
                sizes: vec![
                    (290, 16, Precision::U8),
                    (1090, 16, Precision::U8),
                    (1090, 32, Precision::U8),
                    (4226, 32, Precision::U8),
                    (4226, 32, Precision::F32),
                    (4226, 64, Precision::U8),
                    (4226, 64, Precision::F32),
                ],
                shares: vec![0.0, 0.1, 0.25, 0.5, 0.75, 1.0],
                standard: (4226, 32, Precision::U8),
            }
        }
    }
}

fn field_params((count, res, precision): (usize, u32, Precision)) -> FieldParams {
    FieldParams {
        sphere: SphereKind::Slater,
        count,
        layout: LayoutKind::Concentric,
        res,
        precision,
    }
}

/// The registered models among the casters of the quick or the full profile (`supershape` is
/// generated).
pub fn models(quick: bool) -> Vec<&'static str> {
    Profile::new(quick)
        .models
        .into_iter()
        .filter(|m| *m != "supershape")
        .collect()
}

/// A caster by name: a registered model (`geometry::models`) or `supershape` (261,120
/// triangles).
fn caster(name: &str) -> Result<LoadedMesh> {
    let mesh: Mesh = if name == "supershape" {
        supershape(&Supershape::default(), 261_120).map_err(Error::geometry("supershape"))?
    } else {
        models::load_model(name)?
    };
    Ok(LoadedMesh {
        label: name.to_string(),
        sha256: mesh_sha256(&mesh),
        mesh: Arc::new(mesh),
        model_origin: glam::DVec3::ZERO,
        file: None,
    })
}

/// The receivers (every `stride`-th corner vertex) of a caster's scene.
struct Rays {
    points: Vec<Vec3>,
    normals: Vec<Vec3>,
    set: RaySet,
}

impl Rays {
    fn of(scene: &Scene, stride: usize) -> Rays {
        let recv = Receivers::of(scene);
        let pick = |v: &[Vec3]| v.iter().copied().step_by(stride).collect::<Vec<_>>();
        Rays {
            points: pick(&recv.points),
            normals: pick(&recv.normals),
            set: RaySet::new(16, 1),
        }
    }

    fn count(&self) -> u64 {
        (self.points.len() * self.set.len()) as u64
    }

    /// The share of the rays whose line meets the world sphere ahead of the origin.
    fn entering_share(&self, center: Vec3, radius: f32, opts: &AoOptions) -> f64 {
        let prep = self.set.prepare();
        let mut dirs = Vec::new();
        let mut n = 0usize;
        for (i, (&p, &nrm)) in self.points.iter().zip(&self.normals).enumerate() {
            // As `ao_at_point` makes the rays of point i.
            let from = SphereOrigin::new(p + opts.offset * nrm, center, radius);
            prep.fill_world(i as u32, &Frame::from_normal(nrm), &mut dirs);
            n += dirs
                .iter()
                .filter(|&&d| from.crossing(d).is_some_and(|c| c.t1 >= 0.0))
                .count();
        }
        n as f64 / self.count().max(1) as f64
    }
}

/// A backend to time, with its preparation time. The ray casters of a caster serve every
/// field shape and kind of ray, so a backend is shared, not copied.
#[derive(Clone)]
struct Backend<'a> {
    name: &'static str,
    vis: Rc<dyn Visibility + 'a>,
    setup_s: f64,
}

/// For each backend: the fastest of `passes` timed passes of `pass(backend)`, and its answer
/// (share free). The backends take turns (round k runs each backend's pass k), so that a change
/// of load on a shared machine meets all of them, not the one timed then; each timed pass
/// follows an untimed one of the same backend, so that it finds its own data in the caches, as
/// it would when run alone, not the previous backend's.
fn time_interleaved(
    passes: usize,
    backends: &[Backend],
    pass: impl Fn(&Backend) -> f64,
) -> Vec<(f64, f64)> {
    let mut timed: Vec<(f64, f64)> = backends.iter().map(|b| (f64::INFINITY, pass(b))).collect();
    for _ in 0..passes {
        for (b, (best, free)) in backends.iter().zip(timed.iter_mut()) {
            let warm = pass(b);
            assert_eq!(warm.to_bits(), free.to_bits(), "a pass changed its answer");
            let t = Instant::now();
            let f = pass(b);
            *best = best.min(t.elapsed().as_secs_f64());
            assert_eq!(f.to_bits(), free.to_bits(), "a pass changed its answer");
        }
    }
    timed
}

/// Where a sweep point is: its caster, its field and the share of rays entering the sphere.
struct At<'a> {
    caster: &'a str,
    triangles: usize,
    field: (&'a str, u64),
    share: f64,
}

/// Rows of every backend on the same rays of `kind` at every receiver of `rays`.
fn measure(
    kind: RayKind,
    base: &str,
    at: &At,
    backends: &[Backend],
    rays: &Rays,
    (opts, sec): (&AoOptions, &Secondary),
    passes: usize,
) -> Vec<PerfRow> {
    let pass = |b: &Backend| match kind {
        RayKind::Ao => {
            let ao = ao_at_points(&*b.vis, &rays.points, &rays.normals, &rays.set, opts);
            ao.iter().map(|&v| v as f64).sum::<f64>() / ao.len().max(1) as f64
        }
        RayKind::Shadow => sec.shadow_pass(&*b.vis, rays),
        RayKind::Reflection => sec.reflection_pass(&*b.vis, rays),
    };
    let timed = time_interleaved(passes, backends, pass);
    rows(
        kind.sweep(base),
        at,
        backends,
        &timed,
        sec.count(kind, rays),
    )
}

fn rows(
    sweep: &'static str,
    at: &At,
    backends: &[Backend],
    timed: &[(f64, f64)],
    rays: u64,
) -> Vec<PerfRow> {
    let (caster, triangles, (field, field_bytes), share) =
        (at.caster, at.triangles, at.field, at.share);
    let secs_of = |name: &str| {
        backends
            .iter()
            .zip(timed)
            .find(|(b, _)| b.name == name)
            .map(|(_, t)| t.0)
    };
    let (raycast, embree) = (secs_of("raycast"), secs_of("embree"));
    backends
        .iter()
        .zip(timed)
        .map(|(b, &(seconds, free))| {
            let row = PerfRow {
                sweep,
                caster: caster.to_string(),
                triangles,
                field: field.to_string(),
                field_bytes,
                entering_share: share,
                backend: b.name,
                rays,
                seconds,
                mrays_s: rays as f64 / seconds / 1e6,
                vs_raycast: raycast.map_or(f64::NAN, |r| r / seconds),
                vs_embree: embree.map(|e| e / seconds),
                free_share: free,
                setup_s: b.setup_s,
            };
            println!(
                "performance {sweep:<21} {caster:<20} {field:<16} {:<18} {:>8.2} Mrays/s  ({:.2}x ray casting)",
                b.name, row.mrays_s, row.vs_raycast
            );
            row
        })
        .collect()
}

/// The ray casters of a scene: every registered method that is a ray caster over world
/// triangles ([`super::methods::Method::world_caster`]), in registry order: ours and, with
/// the feature, Embree.
fn ray_casters(scene: &Scene) -> Vec<Backend<'static>> {
    let tris = scene.caster_triangles();
    let mut v = Vec::new();
    for m in super::methods::default_settings() {
        let t = Instant::now();
        match m.world_caster(&tris) {
            Some(Ok(vis)) => v.push(Backend {
                name: m.name(),
                vis: Rc::<dyn Visibility + Send>::from(vis),
                setup_s: t.elapsed().as_secs_f64(),
            }),
            Some(Err(e)) => eprintln!("performance: {} not timed: {e}", m.name()),
            None => {}
        }
    }
    v
}

/// The ray casters `casters`, then the field lookup and the floors over `fs`.
fn field_backends<'a>(
    casters: &[Backend<'a>],
    fs: &'a FieldScene,
    bake_s: f64,
) -> Vec<Backend<'a>> {
    let mut v = casters.to_vec();
    v.extend([
        Backend {
            name: "field_nearest",
            vis: Rc::new(fs.clone()),
            setup_s: bake_s,
        },
        Backend {
            name: "floor_sphere_cull",
            vis: Rc::new(SphereCull(fs)),
            setup_s: 0.0,
        },
        no_query(),
    ]);
    v
}

/// The floor without a query ([`NoQuery`]).
fn no_query() -> Backend<'static> {
    Backend {
        name: "floor_no_query",
        vis: Rc::new(NoQuery),
        setup_s: 0.0,
    }
}

/// The backends of the reflection rays: the ray casters `casters`, the field with its 16-bit
/// normal field (baked with it, the distances those of [`field_scene`]'s), and the floor
/// without a query.
fn reflection_backends<'a>(
    casters: &[Backend<'a>],
    supply: &FieldSupply,
    mesh: &LoadedMesh,
    scene: &Scene,
    shape: (usize, u32, Precision),
) -> Result<Vec<Backend<'a>>> {
    let (got, normals) = supply.obtain_with_normals(mesh, field_params(shape), &[16])?;
    let fs = FieldScene {
        instances: vec![FieldInstance::new(got.field, scene.instances[1].transform)
            .with_normals(normals[0].1.clone())],
        options: LookupOptions {
            selection: Selection::Nearest,
            ..LookupOptions::default()
        },
    };
    let mut v = casters.to_vec();
    v.push(Backend {
        name: "field_nearest",
        vis: Rc::new(fs),
        setup_s: got.bake_s.unwrap_or(0.0),
    });
    v.push(no_query());
    Ok(v)
}

/// The scene's one caster's field, baked or read from the cache.
fn field_scene(
    supply: &FieldSupply,
    mesh: &LoadedMesh,
    scene: &Scene,
    shape: (usize, u32, Precision),
) -> Result<(FieldScene, String, u64, f64)> {
    let params = field_params(shape);
    let t = Instant::now();
    let got = supply.obtain(mesh, params)?;
    let label = format!("{}x{}² {}", shape.0, shape.1, shape.2.name());
    let bytes = got.field.bytes();
    let fs = FieldScene {
        instances: vec![FieldInstance::new(got.field, scene.instances[1].transform)],
        options: LookupOptions {
            selection: Selection::Nearest,
            ..LookupOptions::default()
        },
    };
    Ok((fs, label, bytes, t.elapsed().as_secs_f64()))
}

/// What [`run`] would do, for `--dry-run`: the casters, fields, shares and passes.
pub fn plan(quick: bool) -> String {
    let p = Profile::new(quick);
    let field = |(c, r, pr): &(usize, u32, Precision)| format!("{c}x{r}² {}", pr.name());
    format!(
        "performance ({}): 256 AO rays, 3 lights × 16 shadow rays and 16 Phong reflection rays \
         at every{} corner vertex, best of {} passes, the backends taking turns, each timed pass after an untimed one, on ray casting (ours{}), the field lookup and the two floors\n  \
         triangles: {} with {}\n  field_size (stanford-bunny_39k): {}\n  \
         entering shares: {}",
        if quick { "quick" } else { "full" },
        ordinal(p.stride),
        p.passes,
        if cfg!(feature = "embree") {
            ", Embree"
        } else {
            ""
        },
        p.models.join(", "),
        field(&p.standard),
        p.sizes.iter().map(field).collect::<Vec<_>>().join(", "),
        p.shares
            .iter()
            .map(|s| format!("{s}"))
            .collect::<Vec<_>>()
            .join(", ")
    )
}

/// "" for every vertex, " 16th" for every 16th.
fn ordinal(n: usize) -> String {
    if n == 1 {
        String::new()
    } else {
        format!(" {n}th")
    }
}

/// Runs the three sweeps of each kind of ray into `out` (see the module docs).
pub fn run(out: &Path, quick: bool, supply: &FieldSupply) -> Result<Vec<PerfRow>> {
    crate::experiment::progress::begin_run();
    super::models_cmd::require("performance", models(quick))?;
    super::run::ensure_writable(out)?;
    let meta = super::meta::RunMeta::collect(None);
    let prof = Profile::new(quick);
    let opts = AoOptions::for_scene_radius(0.9);
    let mut table = Vec::new();
    // Load every caster before any timing: a missing model fails here.
    let casters: Vec<LoadedMesh> = prof
        .models
        .iter()
        .map(|m| caster(m))
        .collect::<Result<_>>()?;
    let sec = Secondary::new(&opts);
    let both = (&opts, &sec);
    for mesh in &casters {
        let scene = over_corner((*mesh.mesh).clone(), Quat::IDENTITY);
        let rays = Rays::of(&scene, prof.stride);
        let world = scene.instances[1]
            .transform
            .to_world_sphere(&mesh.mesh.bounding_sphere());
        let share = rays.entering_share(world.center, world.radius, &opts);
        let tris = mesh.mesh.triangles.len();
        // Our BVH and Embree's, built once for every field shape and kind of ray.
        let casters = ray_casters(&scene);
        let sizes = if mesh.label == "stanford-bunny_39k" {
            &prof.sizes[..]
        } else {
            &[][..]
        };
        // The standard field on every caster (`triangles`), then the field sizes on one.
        for (base, &shape) in std::iter::once(("triangles", &prof.standard))
            .chain(sizes.iter().map(|s| ("field_size", s)))
        {
            let (fs, label, bytes, bake_s) = field_scene(supply, mesh, &scene, shape)?;
            let at = At {
                caster: &mesh.label,
                triangles: tris,
                field: (&label, bytes),
                share,
            };
            let all = field_backends(&casters, &fs, bake_s);
            for kind in [RayKind::Ao, RayKind::Shadow] {
                table.extend(measure(kind, base, &at, &all, &rays, both, prof.passes));
            }
            let with_normals = reflection_backends(&casters, supply, mesh, &scene, shape)?;
            table.extend(measure(
                RayKind::Reflection,
                base,
                &at,
                &with_normals,
                &rays,
                both,
                prof.passes,
            ));
            if base != "triangles" || mesh.label != "stanford-bunny_39k" {
                continue;
            }
            // The `triangles` sweep's backends: the same caster and field.
            let far = |o: Vec3| o.distance(world.center) + 2.0 * world.radius;
            let tmax = opts.max_distance.unwrap_or(f32::INFINITY);
            for &p in &prof.shares {
                let dirs = entering_rays(&rays, world.center, world.radius, &opts, p);
                let n = dirs.iter().map(|d| d.1.len() as u64).sum();
                // The share drawn: round(p · 256) of each receiver's 256 rays.
                let k = rays.set.len() as f64;
                let at = At {
                    share: (p * k).round() / k,
                    ..at
                };
                for (kind, backends) in [
                    (RayKind::Ao, &all),
                    (RayKind::Shadow, &all),
                    (RayKind::Reflection, &with_normals),
                ] {
                    let timed = time_interleaved(prof.passes, backends, |b| {
                        secondary::entering_pass(kind, &*b.vis, &dirs, tmax, far)
                    });
                    table.extend(rows(kind.sweep("entering"), &at, backends, &timed, n));
                }
            }
        }
    }
    std::fs::create_dir_all(out).map_err(Error::io(out))?;
    super::outputs::write_csv(&out.join(super::outputs::BACKEND_TIMES_CSV), &table)?;
    let rows: Vec<plots::PlotRow> = table.iter().map(plots::PlotRow::of).collect();
    plots::draw(out, &rows, Some(&plots::cache_sizes()))?;
    let json = out.join("run.json");
    let meta = meta.timed();
    crate::io::write_atomic(&json, meta.to_json().as_bytes()).map_err(Error::io(&json))?;
    Ok(table)
}

/// Per receiver: its origin and 256 world directions of which `round(share · 256)` enter the
/// caster's sphere, drawn in turn from a pool of 4096 cosine directions (receivers whose pool
/// lacks either kind are left out, for every share alike).
fn entering_rays(
    rays: &Rays,
    center: Vec3,
    radius: f32,
    opts: &AoOptions,
    share: f64,
) -> Vec<(Vec3, Vec<Vec3>)> {
    let pool = RaySet::new(64, 7).prepare();
    let n = rays.set.len();
    let want = (share * n as f64).round() as usize;
    let mut dirs = Vec::new();
    rays.points
        .iter()
        .zip(&rays.normals)
        .enumerate()
        .filter_map(|(i, (&p, &nrm))| {
            let origin = p + opts.offset * nrm;
            let from = SphereOrigin::new(origin, center, radius);
            pool.fill_world(i as u32, &Frame::from_normal(nrm), &mut dirs);
            let (enter, miss): (Vec<Vec3>, Vec<Vec3>) = dirs
                .iter()
                .partition(|&&d| from.crossing(d).is_some_and(|c| c.t1 >= 0.0));
            if enter.is_empty() || miss.is_empty() {
                return None;
            }
            let picked = (0..n)
                .map(|k| {
                    if k < want {
                        enter[k % enter.len()]
                    } else {
                        miss[k % miss.len()]
                    }
                })
                .collect();
            Some((origin, picked))
        })
        .collect()
}
