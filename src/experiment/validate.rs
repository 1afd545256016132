//! Spec validation: everything a spec can get wrong that serde cannot see, each error naming the
//! file and the field path (`fields[0].counts[2]`, `quick.thresholds[1]`), with what was
//! expected. Both profiles are checked: the full one, and the quick one with the paths of the
//! parts it replaces prefixed by `quick.`.

use super::spec::{
    exact_sqrt, FieldAxes, MeshSource, OursSource, PaperCell, SceneSpec, Spec, SpecError,
    FRAME_METHODS,
};
use crate::geometry::models::ModelRegistry;
use crate::sampling::{HemisphereLayout, SphereKind, SpherePoints};
use std::path::Path;

/// The largest procedural mesh a spec may ask for (triangles): sizes past it would abort or
/// hang before any check could run (a 10¹² supershape, a corner of n = 100000).
pub const MAX_PROCEDURAL_TRIANGLES: u64 = 1 << 24;
/// The most rays per point of any render, reference or sweep (k ≤ 256).
pub const MAX_RAYS_PER_POINT: u32 = 1 << 16;
/// The most seeds per cell.
pub const MAX_SEEDS: u32 = 64;
/// The most rays per point of the converged reference, all batches together.
pub const MAX_TRUTH_RAYS: u32 = 1 << 20;
/// The most batches of the converged reference.
pub const MAX_TRUTH_BATCHES: u32 = 64;
/// The most frames of an animation: each costs every per-frame method a BVH build or an update
/// and a query, and a converged reference.
pub const MAX_FRAMES: u32 = 10_000;

/// Where each replaceable part of a profile lives in the file.
pub(crate) struct Paths {
    pub(crate) scenes: &'static str,
    pub(crate) fields: &'static str,
    pub(crate) render_rays: &'static str,
    pub(crate) reference_rays: &'static str,
    pub(crate) image: &'static str,
    pub(crate) sweep: &'static str,
    pub(crate) field_sweep: &'static str,
    pub(crate) truth_max_rays: &'static str,
    pub(crate) thresholds: &'static str,
    pub(crate) backends: &'static str,
    pub(crate) frames: &'static str,
}

/// Validation of one spec file: its errors name the file ([`Validator::err`]); the render
/// kinds' and methods' own checks (`kinds::KindOptions::validate`) are given one.
pub struct Validator<'a> {
    file: &'a Path,
}

impl Validator<'_> {
    /// The validation of the spec file `file`.
    pub(crate) fn new(file: &Path) -> Validator<'_> {
        Validator { file }
    }

    /// The error at `field` (a path such as `render.lights[1].radius`) of this file.
    pub fn err(&self, field: &str, message: String) -> SpecError {
        SpecError::Invalid {
            file: self.file.to_path_buf(),
            field: field.to_string(),
            message,
        }
    }

    /// The frames and every instance's motion: a motion only with `animation`; frames in
    /// 1..=[`MAX_FRAMES`], a positive finite time step, known per-frame methods, each named
    /// once; each motion's own values ([`crate::geometry::motion::Motion::problem`]). An
    /// animated spec writes `frames.csv`, so the keys of the static table (`methods`, `paper`,
    /// `thresholds`, `reference.field_rays_sweep`) are refused in it; its "gpu" backend adds the
    /// GPU twins of its methods (`methods::motion::gpu_twins`).
    pub(crate) fn animation(&self, s: &Spec, p: &Paths) -> Result<(), SpecError> {
        let motions = s.scenes.iter().enumerate().flat_map(|(i, sc)| {
            let here = format!("{}[{i}]", p.scenes);
            (sc.instances.iter().enumerate()).filter_map(move |(j, inst)| {
                Some((
                    format!("{here}.instances[{j}].motion"),
                    inst.motion.as_ref()?,
                ))
            })
        });
        let Some(a) = &s.animation else {
            if let Some((at, _)) = motions.into_iter().next() {
                return Err(self.err(
                    &at,
                    "moves only in a spec with `animation` (its frames and time step)".into(),
                ));
            }
            if let Some(f) = s.quick.frames {
                return Err(self.err(
                    "quick.frames",
                    format!("{f} frames: the spec has no `animation`"),
                ));
            }
            return Ok(());
        };
        if !(1..=MAX_FRAMES).contains(&a.frames) {
            return Err(self.err(
                p.frames,
                format!("{} frames: needs 1 to {MAX_FRAMES}", a.frames),
            ));
        }
        let end = a.time_step * (a.frames - 1) as f64;
        if !(a.time_step > 0.0 && a.time_step.is_finite() && end.is_finite()) {
            return Err(self.err(
                "animation.time_step",
                format!("{} must be positive and finite", a.time_step),
            ));
        }
        let known = FRAME_METHODS;
        for (i, m) in a.methods.iter().flatten().enumerate() {
            let at = format!("animation.methods[{i}]");
            if !known.contains(&m.as_str()) {
                return Err(self.err(
                    &at,
                    format!(
                        "unknown per-frame method \"{m}\"; known: {}",
                        known.join(", ")
                    ),
                ));
            }
            if a.methods.iter().flatten().take(i).any(|o| o == m) {
                return Err(self.err(&at, format!("\"{m}\" twice")));
            }
        }
        let refuse =
            |field: &str, why: &str| Err(self.err(field, format!("an animated spec {why}")));
        if !s.methods.is_empty() {
            return refuse(
                "methods",
                "measures its per-frame methods: list them in `animation.methods`",
            );
        }
        if s.paper.is_some() {
            return refuse("paper", "pairs no paper cell (its rows are frames)");
        }
        if !s.thresholds.is_empty() {
            return refuse(
                p.thresholds,
                "has no thresholds (`check` compares its frames with the committed run)",
            );
        }
        if !s.reference.field_rays_sweep.is_empty() {
            return refuse(p.field_sweep, "has no field sweep");
        }
        let max = super::scenes::MAX_WORLD_COORDINATE as f64;
        for (at, m) in motions {
            if let Some((field, message)) = m.problem(a.frames, a.time_step, max) {
                let at = if field.is_empty() {
                    at
                } else {
                    format!("{at}.{field}")
                };
                return Err(self.err(&at, message));
            }
        }
        Ok(())
    }

    pub(crate) fn paper_source(
        &self,
        s: &Spec,
        c: &PaperCell,
        path: &str,
        sweep: &str,
    ) -> Result<(), SpecError> {
        let known = |n: &str| s.scenes.iter().any(|sc| sc.name == n);
        if let Some(n) = &c.scene {
            if !known(n) {
                return Err(self.err(&format!("{path}.scene"), format!("no scene `{n}`")));
            }
        }
        if c.versus_precision.is_some() && c.ours != OursSource::Table {
            return Err(self.err(
                &format!("{path}.versus_precision"),
                "pairs two table cells; drop it or `ours`".into(),
            ));
        }
        match &c.ours {
            OursSource::Table => Ok(()),
            OursSource::RaycastSweep { rays_per_point: k } => {
                if s.reference.raycast_sweep.contains(k) {
                    Ok(())
                } else {
                    Err(self.err(
                        &format!("{path}.ours.rays_per_point"),
                        format!("{k} rays: {sweep} is {:?}", s.reference.raycast_sweep),
                    ))
                }
            }
            OursSource::SumOfScenes { scenes } => {
                if c.scene.is_some() {
                    return Err(self.err(
                        &format!("{path}.scene"),
                        "a sum names its scenes in `ours.scenes`; drop `scene`".into(),
                    ));
                }
                if scenes.len() < 2 {
                    return Err(self.err(
                        &format!("{path}.ours.scenes"),
                        format!("{} scene(s): a sum needs at least two", scenes.len()),
                    ));
                }
                for (j, n) in scenes.iter().enumerate() {
                    let here = format!("{path}.ours.scenes[{j}]");
                    if !known(n) {
                        return Err(self.err(&here, format!("no scene `{n}`")));
                    }
                    if scenes[..j].contains(n) {
                        return Err(self.err(&here, format!("`{n}` twice")));
                    }
                }
                Ok(())
            }
        }
    }

    pub(crate) fn scenes(&self, scenes: &[SceneSpec], path: &str) -> Result<(), SpecError> {
        if scenes.is_empty() {
            return Err(self.err(path, "needs at least one scene".into()));
        }
        for (i, sc) in scenes.iter().enumerate() {
            let here = format!("{path}[{i}]");
            let ok = !sc.name.is_empty()
                && sc
                    .name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            if !ok {
                return Err(self.err(
                    &format!("{here}.name"),
                    format!(
                        "`{}` must be non-empty letters, digits, `_` or `-`",
                        sc.name
                    ),
                ));
            }
            if scenes[..i].iter().any(|o| o.name == sc.name) {
                return Err(self.err(
                    &format!("{here}.name"),
                    format!("scene `{}` twice", sc.name),
                ));
            }
            if let Some(cam) = &sc.camera {
                camera_problem(cam).map_or(Ok(()), |(field, message)| {
                    Err(self.err(&format!("{here}.camera.{field}"), message))
                })?;
            }
            if !sc.instances.iter().any(|i| i.receiver) {
                return Err(self.err(&here, "no instance is a receiver".into()));
            }
            if !sc.instances.iter().any(|i| i.caster) {
                return Err(self.err(&here, "no instance is a caster".into()));
            }
            for (j, inst) in sc.instances.iter().enumerate() {
                let at = format!("{here}.instances[{j}]");
                self.mesh(&inst.mesh, &format!("{at}.mesh"))?;
                let t = &inst.transform;
                if let Some(f) = &t.fit {
                    if !(f.radius > 0.0 && f.radius.is_finite() && f.center.is_finite()) {
                        return Err(self.err(
                            &format!("{at}.transform.fit"),
                            "needs a finite centre and a positive finite radius".into(),
                        ));
                    }
                }
                if let Some(s) = t.scale {
                    if !(s > 0.0 && s.is_finite()) {
                        return Err(self.err(
                            &format!("{at}.transform.scale"),
                            format!("{s} must be positive and finite"),
                        ));
                    }
                }
                let finite = |v: Option<glam::Vec3>| v.is_none_or(|v| v.is_finite());
                if !finite(t.rotate_deg) || !t.translate.is_none_or(|v| v.is_finite()) {
                    return Err(self.err(
                        &format!("{at}.transform"),
                        "rotation and translation must be finite".into(),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Lights: finite centres within the world's range, a radius of 0 (a point light) or positive
    /// within that range, a positive finite intensity.
    pub fn lights(&self, lights: &[crate::render::shadow::SphereLight]) -> Result<(), SpecError> {
        for (i, l) in lights.iter().enumerate() {
            let at = |f: &str| format!("render.lights[{i}].{f}");
            if !l.center.is_finite()
                || l.center.abs().max_element() > super::scenes::MAX_WORLD_COORDINATE
            {
                return Err(self.err(
                    &at("center"),
                    format!(
                        "{} must be finite, within ±{:e}",
                        l.center,
                        super::scenes::MAX_WORLD_COORDINATE
                    ),
                ));
            }
            let max = super::scenes::MAX_WORLD_COORDINATE;
            if !(l.radius >= 0.0 && l.radius <= max) {
                return Err(self.err(
                    &at("radius"),
                    format!(
                        "{} must be 0 (a point light) or positive, at most {max:e}",
                        l.radius
                    ),
                ));
            }
            if !(l.intensity > 0.0 && l.intensity.is_finite()) {
                return Err(self.err(
                    &at("intensity"),
                    format!("{} must be positive and finite", l.intensity),
                ));
            }
        }
        Ok(())
    }

    fn mesh(&self, m: &MeshSource, path: &str) -> Result<(), SpecError> {
        let bad = |what: &str| Err(self.err(path, what.to_string()));
        let pos = |x: f32| x > 0.0 && x.is_finite();
        // Triangles a procedural mesh would have, checked before anything is generated.
        let grid = |n: usize| 2 * (n as u128).saturating_sub(1).pow(2);
        let triangles: Option<u128> = match m {
            MeshSource::Corner { n } => Some(3 * grid(*n)),
            MeshSource::Plane { n, .. } => Some(grid(*n)),
            MeshSource::Supershape { triangles } => Some(*triangles as u128),
            MeshSource::Sphere { stacks, slices, .. }
            | MeshSource::Ellipsoid { stacks, slices, .. } => {
                Some(2 * *stacks as u128 * *slices as u128)
            }
            _ => None,
        };
        if let Some(t) = triangles.filter(|&t| t > MAX_PROCEDURAL_TRIANGLES as u128) {
            return Err(self.err(
                path,
                format!(
                    "{t} triangles: a procedural mesh may have at most {MAX_PROCEDURAL_TRIANGLES}"
                ),
            ));
        }
        match m {
            MeshSource::Model(name) => {
                let entry = ModelRegistry::embedded()
                    .get(name)
                    .map_err(|e| self.err(&format!("{path}.model"), e.to_string()))?;
                if !entry.loadable {
                    return Err(self.err(
                        &format!("{path}.model"),
                        format!("model `{name}` is listed but not loadable"),
                    ));
                }
                Ok(())
            }
            MeshSource::File(f) => {
                if f.file.trim().is_empty() {
                    return Err(self.err(&format!("{path}.file"), "an empty path".into()));
                }
                crate::geometry::MeshFormat::of(std::path::Path::new(&f.file))
                    .map_err(|e| self.err(&format!("{path}.file"), e.to_string()))?;
                match &f.sha256 {
                    Some(h) if !(h.len() == 64 && h.bytes().all(|b| b.is_ascii_hexdigit())) => {
                        Err(self.err(
                            &format!("{path}.sha256"),
                            format!("`{h}` is not a sha256 (64 hexadecimal digits)"),
                        ))
                    }
                    _ => Ok(()),
                }
            }
            MeshSource::Corner { n } if *n < 2 => bad("corner: n must be at least 2"),
            MeshSource::CubeWithHole { size, hole }
                if !(pos(*size) && pos(*hole) && hole < size) =>
            {
                bad("cube_with_hole: needs 0 < hole < size")
            }
            MeshSource::Supershape { triangles } if *triangles < 8 => {
                bad("supershape: needs at least 8 triangles")
            }
            MeshSource::Sphere {
                radius,
                stacks,
                slices,
            } if !(pos(*radius) && *stacks >= 2 && *slices >= 3) => {
                bad("sphere: needs radius > 0, stacks >= 2, slices >= 3")
            }
            MeshSource::Plane { size, n } if !(pos(*size) && *n >= 2) => {
                bad("plane: needs size > 0 and n >= 2")
            }
            MeshSource::Ellipsoid {
                radii,
                stacks,
                slices,
            } if !(radii.to_array().into_iter().all(pos) && *stacks >= 2 && *slices >= 3) => {
                bad("ellipsoid: needs radii > 0, stacks >= 2, slices >= 3")
            }
            _ => Ok(()),
        }
    }

    pub(crate) fn axes(&self, f: &FieldAxes, path: &str) -> Result<(), SpecError> {
        for (name, empty) in [
            ("spheres", f.spheres.is_empty()),
            ("counts", f.counts.is_empty()),
            ("layouts", f.layouts.is_empty()),
            ("resolutions", f.resolutions.is_empty()),
            ("precisions", f.precisions.is_empty()),
            ("selections", f.selections.is_empty()),
        ] {
            if empty {
                return Err(self.err(&format!("{path}.{name}"), "must not be empty".into()));
            }
        }
        for (i, &c) in f.counts.iter().enumerate() {
            for &k in &f.spheres {
                if let Err(e) = SpherePoints::check_count(k, c) {
                    let near = nearest_valid_counts(k, c);
                    return Err(self.err(
                        &format!("{path}.counts[{i}]"),
                        format!("{e}; nearest valid {} counts: {near:?}", k.name()),
                    ));
                }
            }
        }
        for (i, &r) in f.resolutions.iter().enumerate() {
            let at = format!("{path}.resolutions[{i}]");
            if !(2..=4096).contains(&r) {
                return Err(self.err(&at, format!("{r} is outside 2..=4096")));
            }
            for &l in &f.layouts {
                HemisphereLayout::try_new(l, r).map_err(|e| self.err(&at, e.to_string()))?;
            }
        }
        Ok(())
    }

    pub(crate) fn square(&self, n: u32, path: &str) -> Result<(), SpecError> {
        if n > MAX_RAYS_PER_POINT {
            return Err(self.err(
                path,
                format!("{n} rays per point: at most {MAX_RAYS_PER_POINT} (256²)"),
            ));
        }
        if exact_sqrt(n).is_none() {
            let k = (n as f64).sqrt().floor().max(1.0) as u32;
            return Err(self.err(
                path,
                format!(
                    "{n} rays is not a positive perfect square (rays are k × k stratified cells); \
                     nearest: {} or {}",
                    k * k,
                    (k + 1) * (k + 1)
                ),
            ));
        }
        Ok(())
    }
}

/// The f32 steps of a camera's coordinates its eye must be from its target: the view direction
/// then holds to 1e-3 rad, about a pixel of a 1000-pixel, 60° image.
const CAMERA_DIRECTION_STEPS: f64 = 1e3;

/// What is wrong with a camera, if anything: (its field, why). A camera must be finite, within
/// the spec coordinates' range (±1.15e18), look somewhere (its target more than
/// [`CAMERA_DIRECTION_STEPS`] f32 steps from its eye), have an up hint not along the view, and
/// a field of view in (0°, 180°).
pub(crate) fn camera_problem(
    cam: &crate::render::camera::Camera,
) -> Option<(&'static str, String)> {
    for (field, v) in [("eye", cam.eye), ("target", cam.target), ("up", cam.up)] {
        if !v.is_finite() {
            return Some((field, format!("{v} is not finite")));
        }
    }
    let max = super::scenes::MAX_WORLD_COORDINATE;
    for (field, v) in [("eye", cam.eye), ("target", cam.target)] {
        if v.abs().max_element() > max {
            return Some((
                field,
                format!("{v} is beyond ±{max:e}, the range of every spec coordinate"),
            ));
        }
    }
    // A spec camera's coordinates are f32: at magnitude m they are spaced about m·2⁻²³, and
    // the view direction is only as good as that spacing over the eye's distance to the target.
    let m = cam.eye.abs().max(cam.target.abs()).max_element() as f64;
    let spacing = m * f32::EPSILON as f64;
    let view = (cam.target.as_dvec3() - cam.eye.as_dvec3()).length();
    if view == 0.0 {
        let limit = if m >= 1.0 {
            format!(" (f32 coordinates, spaced {spacing:.1e} at {m:.1e}: nearer points are one)")
        } else {
            String::new()
        };
        return Some((
            "target",
            format!("equals the eye{limit}: the camera looks nowhere"),
        ));
    }
    if view < CAMERA_DIRECTION_STEPS * spacing {
        return Some((
            "target",
            format!(
                "is {view:.3e} from the eye, under {CAMERA_DIRECTION_STEPS} f32 steps ({spacing:.1e} \
                 at {m:.1e}): the view direction cannot be resolved to 1e-3 rad (precision limit \
                 of a spec camera's f32 coordinates; move the scene and the camera nearer the origin)"
            ),
        ));
    }
    let side = (cam.target - cam.eye).normalize().cross(cam.up);
    if !(side.length() > 1e-6 && side.normalize().is_finite()) {
        return Some(("up", format!("{} is zero or along the view", cam.up)));
    }
    if !(cam.fov_y_deg > 0.0 && cam.fov_y_deg < 180.0) {
        return Some((
            "fov_y_deg",
            format!("{} is outside (0, 180) degrees", cam.fov_y_deg),
        ));
    }
    None
}

/// Up to two valid counts of `kind` on either side of `count` (for the Fibonacci set, whose
/// every count in its range is valid, the nearest end of that range).
fn nearest_valid_counts(kind: SphereKind, count: usize) -> Vec<usize> {
    if kind == SphereKind::Fibonacci {
        use crate::sampling::{MAX_FIBONACCI, MIN_FIBONACCI};
        return vec![count.clamp(MIN_FIBONACCI, MAX_FIBONACCI)];
    }
    let all = SpherePoints::valid_counts(kind, 5000);
    let i = all.partition_point(|&c| c < count);
    all[i.saturating_sub(2)..(i + 2).min(all.len())].to_vec()
}
