//! Reading a spec file: its JSON as the spec's plain data (the kind and method registries
//! reading `render` and each `methods` entry as serde meets them, `kinds::RenderVisitor`,
//! `methods::MethodSpec`'s `Deserialize`), then both profiles validated: the full one, and the
//! quick one with the paths of the parts it replaces prefixed by `quick.` (`Paths`). The
//! checks of a spec's parts are [`Validator`]'s; here the ones that ask the render kind, the
//! methods and the cells: each kind's and method's own options, whether every setting answers
//! the kind, whether every threshold matches a cell.

use super::cells::cells_of;
use super::kinds::{self, Kind};
use super::spec::{Backend, Spec, SpecError, Threshold};
use super::validate::{
    camera_problem, Paths, Validator, MAX_SEEDS, MAX_TRUTH_BATCHES, MAX_TRUTH_RAYS,
};
use crate::sampling::SphereKind;
use std::path::Path;

impl Spec {
    /// Reads, parses and validates a spec file.
    pub fn load(path: &Path) -> Result<Spec, SpecError> {
        let text = std::fs::read_to_string(path).map_err(|source| SpecError::Io {
            file: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parses and validates spec text; `file` names it in errors.
    /// A UTF-8 byte-order mark before the JSON is skipped; any text after it is an error.
    pub fn parse(text: &str, file: &Path) -> Result<Spec, SpecError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let de = &mut serde_json::Deserializer::from_str(text);
        let parse_error = |path: String, message: String| SpecError::Parse {
            file: file.to_path_buf(),
            path: if path.is_empty() { ".".into() } else { path },
            message,
        };
        let spec: Spec = serde_path_to_error::deserialize(&mut *de)
            .map_err(|e| parse_error(e.path().to_string(), e.into_inner().to_string()))?;
        de.end().map_err(|e| {
            parse_error(
                ".".into(),
                format!("text after the spec's closing brace ({e})"),
            )
        })?;
        validate(&spec, file)?;
        Ok(spec)
    }
}

/// Validates both profiles of `spec`.
fn validate(spec: &Spec, file: &Path) -> Result<(), SpecError> {
    let full = Paths {
        scenes: "scenes",
        fields: "fields",
        render_rays: "render.rays_per_point",
        reference_rays: "reference.rays_per_point",
        image: "render.image",
        sweep: "reference.raycast_sweep",
        field_sweep: "reference.field_rays_sweep",
        truth_max_rays: "reference.truth.max_rays",
        thresholds: "thresholds",
        backends: "backends",
        frames: "animation.frames",
    };
    let q = &spec.quick;
    let pick = |given: bool, quick: &'static str, full: &'static str| {
        if given {
            quick
        } else {
            full
        }
    };
    let rays = q.rays_per_point.is_some();
    let quick = Paths {
        scenes: pick(q.scenes.is_some(), "quick.scenes", full.scenes),
        fields: pick(q.fields.is_some(), "quick.fields", full.fields),
        render_rays: pick(rays, "quick.rays_per_point", full.render_rays),
        reference_rays: pick(rays, "quick.rays_per_point", full.reference_rays),
        image: pick(q.image.is_some(), "quick.image", full.image),
        sweep: pick(q.raycast_sweep.is_some(), "quick.raycast_sweep", full.sweep),
        field_sweep: pick(
            q.field_rays_sweep.is_some(),
            "quick.field_rays_sweep",
            full.field_sweep,
        ),
        truth_max_rays: pick(
            q.truth_max_rays.is_some(),
            "quick.truth_max_rays",
            full.truth_max_rays,
        ),
        thresholds: "quick.thresholds",
        backends: pick(q.backends.is_some(), "quick.backends", full.backends),
        frames: pick(q.frames.is_some(), "quick.frames", full.frames),
    };
    let ctx = Validator::new(file);
    ctx.profile(spec, &full)?;
    // The paper's cells pair with the full profile's scenes and sweep; a quick run that lacks
    // one leaves the row's ours empty.
    for (i, c) in spec.paper.iter().flat_map(|p| p.cells.iter().enumerate()) {
        ctx.paper_source(spec, c, &format!("paper.cells[{i}]"), full.sweep)?;
    }
    ctx.profile(&spec.quick(), &quick)?;
    if spec.reproduces.trim().is_empty() {
        return Err(ctx.err(
            "reproduces",
            "must name the figure or table reproduced".into(),
        ));
    }
    Ok(())
}

impl Validator<'_> {
    fn profile(&self, s: &Spec, p: &Paths) -> Result<(), SpecError> {
        self.scenes(&s.scenes, p.scenes)?;
        if s.fields.is_empty() {
            return Err(self.err(p.fields, "needs at least one entry".into()));
        }
        for (i, f) in s.fields.iter().enumerate() {
            self.axes(f, &format!("{}[{i}]", p.fields))?;
        }
        self.square(s.render.rays_per_point, p.render_rays)?;
        self.square(s.reference.rays_per_point, p.reference_rays)?;
        for (i, &n) in s.reference.raycast_sweep.iter().enumerate() {
            self.square(n, &format!("{}[{i}]", p.sweep))?;
        }
        for (i, &n) in s.reference.field_rays_sweep.iter().enumerate() {
            self.square(n, &format!("{}[{i}]", p.field_sweep))?;
        }
        let t = &s.reference.truth;
        if !(t.target_stderr > 0.0 && t.target_stderr.is_finite()) {
            return Err(self.err(
                "reference.truth.target_stderr",
                format!("{} must be positive and finite", t.target_stderr),
            ));
        }
        if t.batches < 2 {
            return Err(self.err(
                "reference.truth.batches",
                format!(
                    "{} batches: needs at least 2 (their spread is the error)",
                    t.batches
                ),
            ));
        }
        if t.max_rays > MAX_TRUTH_RAYS {
            return Err(self.err(
                p.truth_max_rays,
                format!("{} rays per point: at most {MAX_TRUTH_RAYS}", t.max_rays),
            ));
        }
        if t.batches > MAX_TRUTH_BATCHES {
            return Err(self.err(
                "reference.truth.batches",
                format!("{} batches: at most {MAX_TRUTH_BATCHES}", t.batches),
            ));
        }
        if (t.max_rays as u64) < 64 * t.batches as u64 {
            return Err(self.err(
                p.truth_max_rays,
                format!(
                    "{} rays: the first round already traces {} (batches × 8²)",
                    t.max_rays,
                    64 * t.batches
                ),
            ));
        }
        if !(1..=MAX_SEEDS).contains(&s.reference.seeds) {
            return Err(self.err(
                "reference.seeds",
                format!("{} seeds: needs 1 to {MAX_SEEDS}", s.reference.seeds),
            ));
        }
        if let Some(img) = s.render.image() {
            for (name, v) in [("width", img.width), ("height", img.height)] {
                if !(1..=8192).contains(&v) {
                    return Err(self.err(
                        &format!("{}.{name}", p.image),
                        format!("{v} is outside 1..=8192 pixels"),
                    ));
                }
            }
            if let Some(cam) = &img.camera {
                let path = format!("{}.camera", p.image);
                camera_problem(cam).map_or(Ok(()), |(field, message)| {
                    Err(self.err(&format!("{path}.{field}"), message))
                })?;
            }
        }
        let kind = kinds::of(&s.render);
        if kind.needs().view && s.render.image().is_none() {
            return Err(self.err(
                "render.image",
                format!("\"{}\" computes per pixel and needs an image", kind.name()),
            ));
        }
        kinds::options_of(&s.render).validate(&s.render, s, self)?;
        self.methods(s, kind.as_ref())?;
        if let Some(b) = s.render.intra_bias {
            if !(0.0..1.0).contains(&b) {
                return Err(self.err("render.intra_bias", format!("{b} is outside [0, 1)")));
            }
        }
        if s.backends.is_empty() {
            return Err(self.err(p.backends, "needs \"cpu\" and/or \"gpu\"".into()));
        }
        for (i, b) in s.backends.iter().enumerate() {
            if s.backends[..i].contains(b) {
                return Err(self.err(&format!("{}[{i}]", p.backends), format!("{b:?} twice")));
            }
        }
        if s.backends.contains(&Backend::Gpu) {
            // The GPU kernels answer the nearest map of Slater and lat-long sets only.
            for (i, f) in s.fields.iter().enumerate() {
                if let Some(j) = f.spheres.iter().position(|&k| k == SphereKind::Fibonacci) {
                    return Err(self.err(
                        &format!("{}[{i}].spheres[{j}]", p.fields),
                        "\"fibonacci\" has no nearest-map query on the \"gpu\" backend; use \
                         \"slater\" or \"lat_long\", or drop \"gpu\" from backends"
                            .into(),
                    ));
                }
            }
        }
        if let Some(paper) = &s.paper {
            for (i, c) in paper.cells.iter().enumerate() {
                if paper.cells[..i].iter().any(|d| d.label == c.label) {
                    return Err(self.err(
                        &format!("paper.cells[{i}].label"),
                        format!("label `{}` is used twice", c.label),
                    ));
                }
            }
            if let Some(r) = &paper.reference_cell {
                if !paper.cells.iter().any(|c| &c.label == r) {
                    return Err(self.err(
                        "paper.reference_cell",
                        format!("no paper cell is labelled `{r}`"),
                    ));
                }
            }
        }
        for (i, t) in s.thresholds.iter().enumerate() {
            self.threshold(s, t, &format!("{}[{i}]", p.thresholds))?;
        }
        self.animation(s, p)
    }

    /// A paper cell's scene and `ours`: scenes the spec has, a ray count it sweeps.
    /// Each `methods` entry's own options, then whether every setting answers the kind; a
    /// setting listed twice is refused.
    fn methods(&self, s: &Spec, kind: &dyn Kind) -> Result<(), SpecError> {
        let mut seen: Vec<String> = Vec::new();
        for (i, m) in s.methods.iter().enumerate() {
            let at = format!("methods[{i}]");
            m.read_options().validate(&at, s, self)?;
            for setting in m.settings() {
                if let Some(why) = setting.refuses(kind) {
                    return Err(self.err(&at, format!("\"{}\" {why}", setting.id())));
                }
                let label = setting.label();
                if seen.contains(&label) {
                    return Err(self.err(&at, format!("setting \"{label}\" listed twice")));
                }
                seen.push(label);
            }
        }
        Ok(())
    }

    fn threshold(&self, s: &Spec, t: &Threshold, path: &str) -> Result<(), SpecError> {
        if t.rms_vertex_max.is_none() && t.rms_image_max.is_none() {
            return Err(self.err(path, "sets neither rms_vertex_max nor rms_image_max".into()));
        }
        for (name, v) in [
            ("rms_vertex_max", t.rms_vertex_max),
            ("rms_image_max", t.rms_image_max),
        ] {
            if v.is_some_and(|v| !(v >= 0.0 && v.is_finite())) {
                return Err(self.err(
                    &format!("{path}.{name}"),
                    "must be finite and non-negative".into(),
                ));
            }
        }
        if t.rms_image_max.is_some() && s.render.image().is_none() {
            return Err(self.err(
                &format!("{path}.rms_image_max"),
                "the spec renders no image".into(),
            ));
        }
        let kind = kinds::of(&s.render);
        if t.rms_vertex_max.is_some() && !kind.columns().vertex {
            return Err(self.err(
                &format!("{path}.rms_vertex_max"),
                format!("\"{}\" has no per-vertex values", kind.name()),
            ));
        }
        if !cells_of(s)
            .iter()
            .any(|c| t.matches(&s.scenes[c.scene].name, &c.params, c.selection, c.backend))
        {
            return Err(self.err(path, "matches no cell of the spec".into()));
        }
        Ok(())
    }
}
