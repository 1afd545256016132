//! The planner: expands a spec's axes into cells, then lists the steps that build only what the
//! cells need, in an order that keeps memory bounded (streaming):
//!
//! - per scene: the G-buffer (when an image is asked for), the ray-cast reference once per ray
//!   set, the ray-cast sweep of the error-against-time plot;
//! - per field geometry (positional set and count, layout, resolution; cells sharing it form a
//!   group): every caster mesh's field baked once. Cells that differ only in selection or
//!   backend share the bake. When a mesh needs several precisions and its f32 field fits the
//!   memory limit, the f32 distances are baked once and the other precisions derived from them
//!   (bit-identical to baking at that precision: the bake quantises the same f32 rows); else
//!   each precision is baked on its own;
//! - each precision's fields are released after its cells are evaluated, the group's f32
//!   source after the group, so at most one group's fields are alive at a time.
//!
//! Per scene, each method setting's precompute ([`Step::Precompute`]: an AO field's or a
//! distance volume's bake with its rays as configured and the bytes it keeps, a world BVH)
//! comes before the setting's evaluation, and its peak bytes are held against the memory
//! limit when the plan is made, before any step runs (dry run included). An animated spec's
//! fields, kept for all its frames, are checked the same way ([`check_animated_fields`]).
//!
//! Only what the render kind declares ([`super::kinds::Needs`]) is planned: a G-buffer where it
//! has an image, normal fields where it reads them (reflections), a GPU device
//! only where a cell's backend is "gpu".

pub use super::cells::{cells_of, selection_name, Cell, Geometry};
use super::kinds::Kind;
pub use super::methods::BVH_BYTES_PER_TRIANGLE;
use super::scenes::Scenes;
use super::spec::{exact_sqrt, Backend, Spec};
use super::{Error, Result};
use crate::field::{ByteSize, FieldParams, Precision};
use crate::sampling::HemisphereLayout;
use std::collections::HashSet;
use std::fmt::Write as _;

/// Bytes a mesh's normal fields take in memory at `geometry`: the 16-bit normals of the bake
/// and each other precision derived from them, 4 bytes a texel each.
pub fn normal_field_bytes(geometry: &Geometry, precisions: usize) -> u64 {
    let texels = geometry.with(Precision::F32).texels() as u64;
    geometry.count as u64 * texels * 4 * precisions as u64
}

/// One step of a plan.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// Primary visibility of a scene's image (rays = pixels).
    Primary { scene: usize, pixels: u64 },
    /// The converged reference of a scene (CPU, from the cache when there): at most
    /// `max_rays` per point; `rays` is that bound times the points.
    Truth {
        scene: usize,
        max_rays: u32,
        rays: u64,
    },
    /// The ray-cast reference of a scene (CPU, exact), on every seed.
    Reference { scene: usize, k: u32, rays: u64 },
    /// Ray-cast AO with `k²` rays per point on the CPU (error-against-time sweep).
    Sweep { scene: usize, k: u32, rays: u64 },
    /// Ray-cast AO timing on a non-CPU backend with the render's rays.
    Raycast {
        scene: usize,
        backend: Backend,
        k: u32,
        rays: u64,
    },
    /// Bake (or load from the cache) the field of `mesh`; with `normals`, bake it with its
    /// normal fields (2010 §4.2; distance fields with normals are not cached). `bytes` counts
    /// both.
    Bake {
        normals: bool,
        mesh: usize,
        params: FieldParams,
        rays: u64,
        bytes: u64,
    },
    /// Requantise the f32 field of `mesh` to `to`.
    Derive {
        mesh: usize,
        geometry: Geometry,
        to: Precision,
        bytes: u64,
    },
    /// What the method step after it precomputes on the scene (a bake, a BVH:
    /// [`super::methods::Precompute`]): listed with its rays and the bytes it keeps, and held
    /// against the memory limit when the plan is made. The [`Step::Method`] that follows runs
    /// it.
    Precompute {
        scene: usize,
        setting: usize,
        what: String,
        rays: u64,
        bytes: u64,
    },
    /// A method's setting on a scene (`setting`: index into [`Plan::methods`]): its
    /// precompute, then the kind through it on every seed.
    Method {
        scene: usize,
        setting: usize,
        rays: u64,
    },
    /// Field-lookup AO of cell `cell` (index into [`Plan::cells`]).
    Lookup { cell: usize, rays: u64 },
    /// Drop these fields.
    Release {
        fields: Vec<(usize, FieldParams)>,
        bytes: u64,
    },
}

impl Step {
    /// The rays the step casts (a primary visibility: its pixels; none to derive or release).
    fn rays(&self) -> u64 {
        match *self {
            Step::Primary { pixels: rays, .. }
            | Step::Truth { rays, .. }
            | Step::Reference { rays, .. }
            | Step::Sweep { rays, .. }
            | Step::Raycast { rays, .. }
            | Step::Bake { rays, .. }
            | Step::Precompute { rays, .. }
            | Step::Method { rays, .. }
            | Step::Lookup { rays, .. } => rays,
            Step::Derive { .. } | Step::Release { .. } => 0,
        }
    }

    /// The bytes of the fields or the precompute the step makes or drops (none for the others).
    fn bytes(&self) -> Option<u64> {
        match *self {
            Step::Bake { bytes, .. }
            | Step::Derive { bytes, .. }
            | Step::Precompute { bytes, .. }
            | Step::Release { bytes, .. } => Some(bytes),
            _ => None,
        }
    }
}

/// Everything a run will do.
#[derive(Clone, Debug)]
pub struct Plan {
    pub cells: Vec<Cell>,
    /// The labels of the spec's method settings on their backends
    /// ([`super::methods::settings_of`], [`super::methods::Setting::label`]), in order.
    pub methods: Vec<String>,
    pub steps: Vec<Step>,
    /// Largest sum of live field bytes.
    pub peak_field_bytes: u64,
    pub needs_gpu: bool,
    /// Whether the render kind reads normal fields (reflections).
    pub needs_normal_field: bool,
    /// Receiver rays per point of the render (k).
    pub render_k: u32,
}

/// Limits the planner respects.
#[derive(Clone, Copy, Debug)]
pub struct PlanLimits {
    /// Largest field allowed (bytes).
    pub memory_limit: u64,
}

impl Plan {
    /// Plans a spec profile over its built scenes: per scene the reference steps
    /// (`scene_steps`), then per field geometry its bakes, lookups and releases
    /// (`GroupPlanner`).
    pub fn new(spec: &Spec, scenes: &Scenes, limits: PlanLimits) -> Result<Plan> {
        Plan::new_shard(spec, scenes, limits, None)
    }

    /// [`Self::new`] for one shard's cells ([`super::shard`]); the per-scene steps only for
    /// the scenes that hold one of them.
    pub fn new_shard(
        spec: &Spec,
        scenes: &Scenes,
        limits: PlanLimits,
        shard: Option<super::shard::Shard>,
    ) -> Result<Plan> {
        let kind = super::kinds::of(&spec.render);
        let cells = super::shard::select(cells_of(spec), shard, |c| (c.scene, c.geometry()));
        let render_k = square_root(spec.render.rays_per_point, "render.rays_per_point")?;
        let ref_k = square_root(spec.reference.rays_per_point, "reference.rays_per_point")?;
        let settings = super::methods::settings_of(spec);
        let methods: Vec<String> = settings.iter().map(|m| m.label()).collect();
        let mut steps = Vec::new();
        for s in 0..scenes.scenes.len() {
            if shard.is_some() && !cells.iter().any(|c| c.scene == s) {
                continue;
            }
            steps.extend(scene_steps(spec, scenes, kind.as_ref(), s, render_k, ref_k));
            let rays = kind.max_points(&scenes.scenes[s])
                * kind.rays_cast_per_point()
                * spec.reference.seeds as u64;
            for (setting, m) in settings.iter().enumerate() {
                if let Some(step) = precompute_step(&scenes.scenes[s], s, setting, m, limits)? {
                    steps.push(step);
                }
                steps.push(Step::Method {
                    scene: s,
                    setting,
                    rays,
                });
            }
        }
        let mut groups = GroupPlanner {
            cells: &cells,
            scenes,
            limits,
            points: |scene: usize| kind.max_points(&scenes.scenes[scene]),
            rays_per_lookup: rays_per_lookup(spec, render_k),
            normal_precisions: if kind.needs().normal_field {
                kind.normal_bits().len()
            } else {
                0
            },
            with_normals: HashSet::new(),
            steps,
            live: 0,
            peak: 0,
        };
        for (geometry, members) in field_groups(&cells) {
            groups.group(geometry, &members)?;
        }
        let (steps, peak) = (groups.steps, groups.peak);
        Ok(Plan {
            needs_gpu: cells.iter().any(|c| c.backend == Backend::Gpu)
                || settings.iter().any(|m| m.backend == Backend::Gpu),
            needs_normal_field: kind.needs().normal_field,
            cells,
            methods,
            steps,
            peak_field_bytes: peak,
            render_k,
        })
    }

    /// What a step does, as a line of [`Self::describe`] names it.
    fn step_what(&self, step: &Step, scenes: &Scenes) -> String {
        let sc = |s: usize| scenes.scenes[s].name.as_str();
        match step {
            Step::Primary { scene, .. } => format!("primary visibility {}", sc(*scene)),
            Step::Truth {
                scene, max_rays, ..
            } => format!(
                "converged reference {}, at most {max_rays} rays/point",
                sc(*scene)
            ),
            Step::Reference { scene, k, .. } => {
                format!("ray-cast reference {}, {} rays/point", sc(*scene), k * k)
            }
            Step::Sweep { scene, k, .. } => {
                format!("ray cast {}, {} rays/point (cpu)", sc(*scene), k * k)
            }
            Step::Raycast {
                scene, backend, k, ..
            } => format!(
                "ray cast {}, {} rays/point ({})",
                sc(*scene),
                k * k,
                backend.name()
            ),
            Step::Bake {
                mesh,
                params,
                normals,
                ..
            } => format!(
                "bake {} {} {} × {}² {} {}{}",
                scenes.meshes[*mesh].label,
                params.sphere.name(),
                params.count,
                params.res,
                params.layout.name(),
                params.precision.name(),
                if *normals { " + normal field" } else { "" },
            ),
            Step::Derive {
                mesh, geometry, to, ..
            } => format!(
                "derive {} {} × {}² f32 -> {}",
                scenes.meshes[*mesh].label,
                geometry.count,
                geometry.res,
                to.name()
            ),
            Step::Precompute {
                scene,
                setting,
                what,
                ..
            } => format!(
                "precompute {} on {}: {what}",
                self.methods[*setting],
                sc(*scene)
            ),
            Step::Method { scene, setting, .. } => {
                format!("method {} on {}", self.methods[*setting], sc(*scene))
            }
            Step::Lookup { cell, .. } => {
                let c = &self.cells[*cell];
                format!("lookup {}", c.id(sc(c.scene)))
            }
            Step::Release { fields, .. } => format!("release {} field(s)", fields.len()),
        }
    }

    /// Number of bake steps.
    pub fn bakes(&self) -> usize {
        self.steps
            .iter()
            .filter(|s| matches!(s, Step::Bake { .. }))
            .count()
    }

    /// The plan as text (`--dry-run`): one line per step with its rays and bytes, and totals.
    /// `cached` tells how a bake would be served (from the cache or not), shown as a note.
    pub fn describe(
        &self,
        spec_name: &str,
        scenes: &Scenes,
        cached: &dyn Fn(usize, &FieldParams) -> &'static str,
    ) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "plan for {spec_name}: {} scene(s), {} cell(s), {} bake(s); GPU device: {}; normal \
             fields: {}",
            scenes.scenes.len(),
            self.cells.len(),
            self.bakes(),
            if self.needs_gpu { "yes" } else { "no" },
            if self.needs_normal_field { "yes" } else { "no" },
        );
        for s in &scenes.scenes {
            let _ = writeln!(
                out,
                "  scene {}: {} instance(s), {} receiver vertices, {} caster triangles",
                s.name,
                s.scene.instances.len(),
                s.receiver_vertices(),
                s.caster_triangles()
            );
        }
        let _ = writeln!(
            out,
            "  {:>4}  {:<66} {:>12} {:>11}  note",
            "step", "what", "rays", "bytes"
        );
        let (mut total_rays, mut bake_rays) = (0u64, 0u64);
        for (i, step) in self.steps.iter().enumerate() {
            let note = match step {
                Step::Bake { normals: true, .. } => "bake (fields with normals: not cached)",
                Step::Bake { mesh, params, .. } => cached(*mesh, params),
                Step::Precompute { rays: 1.., .. } => "bake, or the method's cache",
                _ => "",
            };
            let (what, rays) = (self.step_what(step, scenes), step.rays());
            if let Step::Bake { .. } | Step::Precompute { .. } = step {
                bake_rays += rays;
            }
            total_rays += rays;
            let bytes = step
                .bytes()
                .map_or("-".to_string(), |b| ByteSize(b).to_string());
            let rays = if rays == 0 {
                "-".into()
            } else {
                rays.to_string()
            };
            let line = format!("  {:>4}  {what:<66} {rays:>12} {bytes:>11}  {note}", i + 1);
            let _ = writeln!(out, "{}", line.trim_end());
        }
        let _ = writeln!(
            out,
            "  total: {total_rays} rays, every seed and sweep counted ({bake_rays} in bakes); peak \
             field memory {}",
            ByteSize(self.peak_field_bytes)
        );
        out
    }
}

/// The step listing what method setting `setting` (`m`) precomputes on scene `s` (`bs`), if
/// the method can say ([`super::methods::Method::precompute`]); refused, naming the setting,
/// the scene and the flag, where its peak bytes pass the memory limit, or where the
/// precompute could not run.
fn precompute_step(
    bs: &super::scenes::BuiltScene,
    s: usize,
    setting: usize,
    m: &super::methods::Setting,
    limits: PlanLimits,
) -> Result<Option<Step>> {
    let at = || format!("methods \"{}\" on scene {}", m.label(), bs.name);
    let Some(p) = m
        .method
        .precompute(bs)
        .map_err(|why| Error::invalid(at(), why))?
    else {
        return Ok(None);
    };
    if p.peak_bytes > limits.memory_limit {
        return Err(Error::invalid(
            at(),
            format!(
                "its precompute ({}) keeps {} and needs {} at its peak, over the memory limit \
                 of {} (--max-memory-mib)",
                p.what,
                ByteSize(p.bytes),
                ByteSize(p.peak_bytes),
                ByteSize(limits.memory_limit)
            ),
        ));
    }
    Ok(Some(Step::Precompute {
        scene: s,
        setting,
        what: p.what,
        rays: p.rays,
        bytes: p.bytes,
    }))
}

/// `k` with `k² = n`, or the error naming the spec field.
fn square_root(n: u32, field: &str) -> Result<u32> {
    exact_sqrt(n).ok_or_else(|| Error::invalid(field, format!("{n} is not a perfect square")))
}

/// Checks every scene's evaluation state ([`scene_state_bytes`]) against the memory limit:
/// the error names the scene, its size and the flag. The runner calls it beside
/// [`Plan::new`], dry run included, before any work.
pub fn check_scene_memory(spec: &Spec, scenes: &Scenes, limits: PlanLimits) -> Result<()> {
    let kind = super::kinds::of(&spec.render);
    for s in 0..scenes.scenes.len() {
        let bytes = scene_state_bytes(spec, scenes, kind.as_ref(), s);
        if bytes > limits.memory_limit {
            return Err(Error::invalid(
                format!("scenes[{s}] ({})", scenes.scenes[s].name),
                format!(
                    "its evaluation state (BVHs over {} triangles, {} points with their \
                 values on every seed and sweep, the G-buffer) needs about {}, over the \
                 memory limit of {} (--max-memory-mib)",
                    scenes.scenes[s].scene.triangle_count(),
                    kind.max_points(&scenes.scenes[s]),
                    ByteSize(bytes),
                    ByteSize(limits.memory_limit)
                ),
            ));
        }
    }
    Ok(())
}

/// The bytes an animated spec keeps for scene `s` while its frames run: each of the scene's
/// field cells' fields, one per caster mesh (with its normal field where the kind reads one),
/// supplied once before the first frame; 0 where `animation.methods` names no field method.
pub fn animated_field_bytes(spec: &Spec, scenes: &Scenes, s: usize) -> u64 {
    let asked = spec.animation.as_ref().and_then(|a| a.methods.as_ref());
    if !asked.is_none_or(|m| m.iter().any(|m| m.starts_with("field"))) {
        return 0;
    }
    let meshes = scenes.scenes[s].caster_meshes().len() as u64;
    cells_of(spec)
        .iter()
        .filter(|c| c.scene == s)
        .map(|c| {
            let normals = c
                .normal_bits
                .map_or(0, |_| normal_field_bytes(&c.geometry(), 1));
            (c.params.storage_bytes() + normals).saturating_mul(meshes)
        })
        .fold(0, u64::saturating_add)
}

/// Checks every scene's [`animated_field_bytes`] against the memory limit, naming the scene,
/// its bytes and the flag: the runner calls it for an animated spec before any work, dry run
/// included.
pub fn check_animated_fields(spec: &Spec, scenes: &Scenes, limits: PlanLimits) -> Result<()> {
    for (s, bs) in scenes.scenes.iter().enumerate() {
        let bytes = animated_field_bytes(spec, scenes, s);
        if bytes > limits.memory_limit {
            return Err(Error::invalid(
                format!("scenes[{s}] ({})", bs.name),
                format!(
                    "an animated spec keeps every field cell's fields of a scene for all its \
                     frames: {} ({bytes} bytes), over the memory limit of {} (--max-memory-mib)",
                    ByteSize(bytes),
                    ByteSize(limits.memory_limit)
                ),
            ));
        }
    }
    Ok(())
}

/// A conservative estimate of the bytes a scene's state takes while its cells run, apart from
/// the fields (which the plan counts step by step): two BVHs over its triangles (primary
/// visibility and the casters: 128 bytes a triangle each, the triangles included), the
/// G-buffer, and per evaluation point its position, normal, origin, offset and crease flag
/// (45 bytes), the converged reference (8 bytes) and one f32 value for each seed of the
/// reference, each cell's seeds held at once, and each sweep count.
pub fn scene_state_bytes(spec: &Spec, scenes: &Scenes, kind: &dyn Kind, s: usize) -> u64 {
    let bs = &scenes.scenes[s];
    let triangles = bs.scene.triangle_count() as u64;
    let pixels = kind.image().map_or(0, |i| i.width as u64 * i.height as u64);
    let gbuffer = pixels * std::mem::size_of::<Option<crate::render::primary::PixelHit>>() as u64;
    let points = kind.max_points(bs);
    let r = &spec.reference;
    let values =
        2 * r.seeds as u64 + r.raycast_sweep.len() as u64 + r.field_rays_sweep.len() as u64 + 2;
    let per_point = 45 + 8 + 4 * values;
    (2 * BVH_BYTES_PER_TRIANGLE)
        .saturating_mul(triangles)
        .saturating_add(gbuffer)
        .saturating_add(points.saturating_mul(per_point))
}

/// The steps of one scene: its G-buffer (when an image is asked for), the converged
/// reference, the same-ray reference, the CPU ray-cast sweep and the other backends' ray casts.
fn scene_steps(
    spec: &Spec,
    scenes: &Scenes,
    kind: &dyn Kind,
    s: usize,
    render_k: u32,
    ref_k: u32,
) -> Vec<Step> {
    let pts = kind.max_points(&scenes.scenes[s]);
    // Every seed traces its own rays (the same-ray reference and the sweep's errors).
    let seeds = spec.reference.seeds as u64;
    let rays = |k: u32| pts * (k * k) as u64 * seeds;
    let mut steps = Vec::new();
    if let Some(img) = kind.image() {
        steps.push(Step::Primary {
            scene: s,
            pixels: img.width as u64 * img.height as u64,
        });
    }
    let max_rays = spec.reference.truth.max_rays;
    steps.push(Step::Truth {
        scene: s,
        max_rays,
        rays: pts * max_rays as u64,
    });
    steps.push(Step::Reference {
        scene: s,
        k: ref_k,
        rays: rays(ref_k),
    });
    let mut sweep: Vec<u32> = spec
        .reference
        .raycast_sweep
        .iter()
        .filter_map(|&n| exact_sqrt(n))
        .collect();
    sweep.push(render_k);
    sweep.sort_unstable();
    sweep.dedup();
    for k in sweep.into_iter().filter(|&k| k != ref_k) {
        steps.push(Step::Sweep {
            scene: s,
            k,
            rays: rays(k),
        });
    }
    for &b in spec.backends.iter().filter(|&&b| b != Backend::Cpu) {
        steps.push(Step::Raycast {
            scene: s,
            backend: b,
            k: render_k,
            rays: rays(render_k),
        });
    }
    steps
}

/// Rays per point of one cell's lookups: the render's k² on every seed, plus each other ray
/// count of the field sweep once (a count equal to the render's reuses its first seed).
fn rays_per_lookup(spec: &Spec, render_k: u32) -> u64 {
    let k2 = (render_k * render_k) as u64;
    let sweep: u64 = spec
        .reference
        .field_rays_sweep
        .iter()
        .filter(|&&n| n as u64 != k2)
        .map(|&n| n as u64)
        .sum();
    k2 * spec.reference.seeds as u64 + sweep
}

/// The cells grouped by field geometry, in first-use order.
fn field_groups(cells: &[Cell]) -> Vec<(Geometry, Vec<usize>)> {
    let mut groups: Vec<(Geometry, Vec<usize>)> = Vec::new();
    for (i, c) in cells.iter().enumerate() {
        match groups.iter_mut().find(|(g, _)| *g == c.geometry()) {
            Some((_, v)) => v.push(i),
            None => groups.push((c.geometry(), vec![i])),
        }
    }
    groups
}

/// Plans the field groups one after the other, tracking the live field bytes.
struct GroupPlanner<'a, P: Fn(usize) -> u64> {
    cells: &'a [Cell],
    scenes: &'a Scenes,
    limits: PlanLimits,
    /// The most evaluation points of a scene.
    points: P,
    /// Rays per point of one cell: the render's on every seed, and the field sweep's other
    /// counts once.
    rays_per_lookup: u64,
    /// Normal field precisions each bake carries (0: the kind reads no normals).
    normal_precisions: usize,
    /// The baked fields that carry normal fields (their bytes are released with them).
    with_normals: HashSet<(usize, FieldParams)>,
    steps: Vec<Step>,
    live: u64,
    peak: u64,
}

impl<P: Fn(usize) -> u64> GroupPlanner<'_, P> {
    /// One field geometry: the shared f32 bakes, then per precision its bakes or
    /// derivations, its cells' lookups and the release of its fields; the f32 source last.
    fn group(&mut self, geometry: Geometry, members: &[usize]) -> Result<()> {
        let used = HemisphereLayout::new(geometry.layout, geometry.res).used_count() as u64;
        let bake_rays = used * geometry.count as u64;
        let (needs, precisions) = self.needs(members);
        let f32_bytes = geometry.with(Precision::F32).storage_bytes();
        let shared: Vec<usize> = needs
            .iter()
            .filter(|(_, p)| p.len() > 1 && f32_bytes <= self.limits.memory_limit)
            .map(|(m, _)| *m)
            .collect();
        let mut group_fields = Vec::new();
        let normal_bytes = normal_field_bytes(&geometry, self.normal_precisions);
        for &m in &shared {
            let params = geometry.with(Precision::F32);
            self.bake(m, params, bake_rays, f32_bytes + normal_bytes);
            group_fields.push((m, params));
        }
        self.peak = self.peak.max(self.live);
        for &p in &precisions {
            let params = geometry.with(p);
            let bytes = params.storage_bytes();
            let mut stage_fields = Vec::new();
            for (m, _) in needs.iter().filter(|(_, ps)| ps.contains(&p)) {
                if shared.contains(m) {
                    if p != Precision::F32 {
                        self.steps.push(Step::Derive {
                            mesh: *m,
                            geometry,
                            to: p,
                            bytes,
                        });
                        stage_fields.push((*m, params));
                        self.live += bytes;
                    }
                } else {
                    params
                        .check_memory(self.limits.memory_limit)
                        .map_err(|source| Error::Field {
                            what: format!("caster {}", self.scenes.meshes[*m].label),
                            source,
                        })?;
                    self.bake(*m, params, bake_rays, bytes + normal_bytes);
                    stage_fields.push((*m, params));
                }
            }
            self.peak = self.peak.max(self.live);
            for &ci in members
                .iter()
                .filter(|&&ci| self.cells[ci].params.precision == p)
            {
                let rays = (self.points)(self.cells[ci].scene) * self.rays_per_lookup;
                self.steps.push(Step::Lookup { cell: ci, rays });
            }
            self.release(stage_fields);
        }
        self.release(group_fields);
        Ok(())
    }

    /// Bakes `params` of mesh `m` (with its normal fields where the kind reads them): `bytes`
    /// live from now on.
    fn bake(&mut self, m: usize, params: FieldParams, rays: u64, bytes: u64) {
        let normals = self.normal_precisions > 0;
        self.steps.push(Step::Bake {
            mesh: m,
            params,
            rays,
            bytes,
            normals,
        });
        if normals {
            self.with_normals.insert((m, params));
        }
        self.live += bytes;
    }

    /// Per caster mesh the precisions its cells need, and every precision, in first-use order.
    #[allow(clippy::type_complexity)]
    fn needs(&self, members: &[usize]) -> (Vec<(usize, Vec<Precision>)>, Vec<Precision>) {
        let mut needs: Vec<(usize, Vec<Precision>)> = Vec::new();
        let mut precisions: Vec<Precision> = Vec::new();
        for &ci in members {
            let c = &self.cells[ci];
            if !precisions.contains(&c.params.precision) {
                precisions.push(c.params.precision);
            }
            for m in self.scenes.scenes[c.scene].caster_meshes() {
                match needs.iter_mut().find(|(mm, _)| *mm == m) {
                    Some((_, v)) if !v.contains(&c.params.precision) => v.push(c.params.precision),
                    Some(_) => {}
                    None => needs.push((m, vec![c.params.precision])),
                }
            }
        }
        (needs, precisions)
    }

    /// Releases `fields` (nothing when empty).
    fn release(&mut self, fields: Vec<(usize, FieldParams)>) {
        if fields.is_empty() {
            return;
        }
        let bytes = fields
            .iter()
            .map(|f| {
                let normals = if self.with_normals.contains(f) {
                    normal_field_bytes(&Geometry::of(&f.1), self.normal_precisions)
                } else {
                    0
                };
                f.1.storage_bytes() + normals
            })
            .sum();
        self.live -= bytes;
        self.steps.push(Step::Release { fields, bytes });
    }
}
