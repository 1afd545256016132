//! A render kind added through the registry alone: a toy kind ("constant", every point's value
//! its `level` key) defined here, outside the crate, registered at run time, read from a spec in
//! two steps, validated, planned, run end to end and written as a table, with no file of the
//! crate changed; and a toy kind with three channels per point ("ao_rgb": the AO, its
//! complement and a constant) run to a table, RGB images and per-channel metrics. ARCHITECTURE.md's
//! "Adding a render kind" lists what an in-crate kind takes instead: its file under
//! `src/experiment/kinds/` and one line of `kinds::BUILT_IN`.

use std::path::Path;
use visfield::experiment::kinds::{
    self, read_as, Columns, Kind, KindEntry, KindOptions, Needs, Setup,
};
use visfield::experiment::outputs::read_csv;
use visfield::experiment::run::run;
use visfield::experiment::scenes::BuiltScene;
use visfield::experiment::spec::{RenderSpec, Spec, SpecError};
use visfield::experiment::table::Row;
use visfield::experiment::validate::Validator;
use visfield::render::estimator::{Estimator, Points};
use visfield::render::points::{EvalPoints, GBuffer};
use visfield::render::truth::{Truth, TruthOptions};
use visfield::sampling::rays::RaySet;
use visfield::visibility::Visibility;

mod common;
use common::{loaded, options, tiny, ONE_FIELD};

/// The toy kind's own keys.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ConstantOptions {
    /// Every point's value, in [0, 1].
    level: f32,
}

/// An estimator that asks nothing of visibility: `level` at every point, converged at once.
struct Constant(f32);

impl Estimator for Constant {
    fn name(&self) -> &'static str {
        "constant"
    }

    fn estimate(&self, _vis: &dyn Visibility, at: Points, _rays: &RaySet) -> Vec<f32> {
        vec![self.0; at.len()]
    }

    fn converged(&self, _vis: &dyn Visibility, at: Points, t: &TruthOptions) -> Truth {
        Truth {
            values: vec![self.0; at.len()],
            stderr: vec![0.0; at.len()],
            channels: 1,
            rays_per_point: t.batches * t.start_k * t.start_k,
            k: t.start_k,
            batches: t.batches,
            rounds: vec![(t.batches * t.start_k * t.start_k, 0.0)],
        }
    }

    fn key(&self) -> serde_json::Map<String, serde_json::Value> {
        let mut m = serde_json::Map::new();
        m.insert("level".into(), serde_json::json!(self.0));
        m
    }
}

impl KindOptions for ConstantOptions {
    fn validate(&self, _r: &RenderSpec, _s: &Spec, v: &Validator) -> Result<(), SpecError> {
        if !(0.0..=1.0).contains(&self.level) {
            return Err(v.err("render.level", format!("{} is outside [0, 1]", self.level)));
        }
        Ok(())
    }

    fn kind(&self, render: &RenderSpec) -> Box<dyn Kind> {
        Box::new(ConstantKind {
            render: render.clone(),
            level: self.level,
        })
    }
}

struct ConstantKind {
    render: RenderSpec,
    level: f32,
}

impl Kind for ConstantKind {
    fn name(&self) -> &'static str {
        "constant"
    }

    fn render(&self) -> &RenderSpec {
        &self.render
    }

    fn needs(&self) -> Needs {
        Needs::default()
    }

    fn columns(&self) -> Columns {
        Columns { vertex: true }
    }

    fn max_points(&self, scene: &BuiltScene) -> u64 {
        scene.receiver_vertices() as u64
    }

    fn setup(&self, scene: &BuiltScene, _view: Option<&GBuffer>) -> Setup {
        let points = EvalPoints::vertices(&scene.scene);
        Setup {
            offset: points.max_offset(),
            points,
            estimator: Box::new(Constant(self.level)),
            gpu: None,
            shading: None,
            second_reference: None,
        }
    }
}

const CONSTANT: KindEntry = KindEntry {
    name: "constant",
    about: "a toy kind: every point's value is `level`",
    read: read_as::<ConstantOptions>,
};

fn register_once() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| kinds::register(CONSTANT).expect("first registration"));
}

fn constant_spec(render_keys: &str) -> String {
    tiny(ONE_FIELD, "").replace(
        r#""render": { "rays_per_point": 16"#,
        &format!(r#""render": {{ "what": "constant", {render_keys}, "rays_per_point": 16"#),
    )
}

#[test]
fn a_kind_registered_at_run_time_is_read_validated_and_run_end_to_end() {
    register_once();
    assert!(kinds::names().contains(&"constant"));
    let dir = tempfile::tempdir().unwrap();
    let ls = loaded(dir.path(), &constant_spec(r#""level": 0.25"#));
    assert_eq!(ls.spec.render.what, "constant");
    let out = dir.path().join("out");
    let report = run(&ls, &options(out.clone())).unwrap();
    let rows: Vec<Row> = read_csv(&out.join("table.csv")).unwrap();
    assert_eq!(rows, report.rows);
    assert_eq!(rows.len(), 1);
    let r = &rows[0];
    // The field and the ray cast both give 0.25 everywhere, and so does the truth: every error
    // is exactly 0 (for this kind, an exact property, not a suspect one).
    assert_eq!(r.receiver_points, 243);
    assert_eq!(r.rms_vertex, Some(0.0));
    assert_eq!(r.rms_image, Some(0.0));
    assert_eq!(r.rms_vs_truth, Some(0.0));
    // The per-point values written beside the table are the kind's, in every column.
    let text = std::fs::read_to_string(out.join("values_tiny.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let value_columns: Vec<usize> = header
        .iter()
        .enumerate()
        .filter(|(_, c)| !["point", "x", "y", "z", "crease", "truth_stderr"].contains(c))
        .map(|(i, _)| i)
        .collect();
    assert_eq!(value_columns.len(), 3, "{header:?}");
    let mut n = 0;
    for line in lines {
        let cells: Vec<&str> = line.split(',').collect();
        for &i in &value_columns {
            assert_eq!(cells[i].parse::<f32>().unwrap(), 0.25, "{line}");
        }
        n += 1;
    }
    assert_eq!(n, 243);
    // run.json carries the kind's own key back.
    let meta = std::fs::read_to_string(out.join("run.json")).unwrap();
    let meta: serde_json::Value = serde_json::from_str(&meta).unwrap();
    // A kind of a user's own estimates none of the three built-in quantities.
    assert_eq!(meta["quantity"], "other");
    assert_eq!(
        meta["effective_spec"]["render"]["level"],
        serde_json::json!(0.25)
    );
}

#[test]
fn a_registered_kind_refuses_unknown_keys_bad_values_and_a_second_registration() {
    register_once();
    let parse = |t: &str| Spec::parse(t, Path::new("specs/toy.json")).map_err(|e| e.to_string());
    let e = parse(&constant_spec(r#""level": 0.5, "colour": 1"#)).unwrap_err();
    assert!(
        e.contains("unknown field `colour`") && e.contains("constant"),
        "{e}"
    );
    let e = parse(&constant_spec(r#""level": 2"#)).unwrap_err();
    assert!(e.contains("field `render.level`") && e.contains('2'), "{e}");
    let e = parse(&constant_spec(r#""lights": []"#)).unwrap_err();
    assert!(e.contains("lights") && e.contains("constant"), "{e}");
    // Names are unique, the built-in ones included.
    assert!(kinds::register(CONSTANT).is_err());
    assert!(kinds::register(KindEntry {
        name: "shadows",
        ..CONSTANT
    })
    .is_err());
    // An unknown kind lists the registered ones.
    let e = parse(&constant_spec(r#""level": 0.5"#).replace("\"constant\"", "\"bent_normals\""))
        .unwrap_err();
    assert!(
        e.contains("bent_normals") && e.contains("\"constant\""),
        "{e}"
    );
}

// A kind with three channels per point, registered the same way: "ao_rgb", each receiver
// vertex's (AO, 1 − AO, `level`), shown as red, green and blue, with its own metric columns
// (the RMS of each channel against the same-ray reference). Its red channel is the scalar
// vertex_ao kind's value, so the scalar kind's run is its closed form.

mod ao_rgb {
    use super::*;
    use visfield::render::ao::{ao_at_points, AoOptions};
    use visfield::render::truth::converged_channels;

    #[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct Options {
        /// The blue channel, in [0, 1].
        level: f32,
    }

    /// (AO, 1 − AO, level) at every point, point-major.
    pub struct Rgb {
        level: f32,
    }

    fn ao(vis: &dyn Visibility, at: Points, rays: &RaySet) -> Vec<f32> {
        let opts = AoOptions {
            max_distance: None,
            offset: 0.0,
            falloff: Default::default(),
        };
        ao_at_points(vis, at.points, at.normals, rays, &opts)
    }

    impl Rgb {
        fn of(&self, ao: Vec<f32>) -> Vec<f32> {
            ao.into_iter()
                .flat_map(|v| [v, 1.0 - v, self.level])
                .collect()
        }
    }

    impl Estimator for Rgb {
        fn name(&self) -> &'static str {
            "ao_rgb"
        }
        fn channels(&self) -> usize {
            3
        }
        fn estimate(&self, vis: &dyn Visibility, at: Points, rays: &RaySet) -> Vec<f32> {
            self.of(ao(vis, at, rays))
        }
        fn converged(&self, vis: &dyn Visibility, at: Points, t: &TruthOptions) -> Truth {
            converged_channels(at.len(), 3, t, |rays| self.of(ao(vis, at, rays)))
        }
        fn key(&self) -> serde_json::Map<String, serde_json::Value> {
            let mut m = serde_json::Map::new();
            m.insert("ao_rgb_level".into(), serde_json::json!(self.level));
            m
        }
    }

    impl KindOptions for Options {
        fn validate(&self, _r: &RenderSpec, _s: &Spec, v: &Validator) -> Result<(), SpecError> {
            if !(0.0..=1.0).contains(&self.level) {
                return Err(v.err("render.level", format!("{} is outside [0, 1]", self.level)));
            }
            Ok(())
        }
        fn kind(&self, render: &RenderSpec) -> Box<dyn Kind> {
            Box::new(RgbKind {
                render: render.clone(),
                level: self.level,
            })
        }
    }

    struct RgbKind {
        render: RenderSpec,
        level: f32,
    }

    impl Kind for RgbKind {
        fn name(&self) -> &'static str {
            "ao_rgb"
        }
        fn render(&self) -> &RenderSpec {
            &self.render
        }
        fn needs(&self) -> Needs {
            Needs::default()
        }
        fn columns(&self) -> Columns {
            Columns { vertex: true }
        }
        fn max_points(&self, scene: &BuiltScene) -> u64 {
            scene.receiver_vertices() as u64
        }
        fn setup(&self, scene: &BuiltScene, _view: Option<&GBuffer>) -> Setup {
            let points = EvalPoints::vertices(&scene.scene);
            Setup {
                offset: points.max_offset(),
                points,
                estimator: Box::new(Rgb { level: self.level }),
                gpu: None,
                shading: None,
                second_reference: None,
            }
        }
        fn own_metrics(
            &self,
            values: &[f32],
            reference: &[f32],
            _truth: Option<&Truth>,
        ) -> Vec<(String, f64)> {
            (0..3)
                .map(|c| {
                    let d: Vec<f64> = (c..values.len())
                        .step_by(3)
                        .map(|i| 255.0 * (values[i] as f64 - reference[i] as f64))
                        .collect();
                    let ms = d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64;
                    (format!("rms_c{c}"), ms.sqrt())
                })
                .collect()
        }
    }

    pub const ENTRY: KindEntry = KindEntry {
        name: "ao_rgb",
        about: "a toy kind of three channels: AO, its complement and a constant",
        read: read_as::<Options>,
    };

    pub fn register_once() {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| kinds::register(ENTRY).expect("first registration"));
    }
}

/// The 8-bit levels of a PNG and its colour type.
fn png(path: &Path) -> (image::ColorType, Vec<u8>) {
    let img = image::open(path).unwrap();
    (img.color(), img.as_bytes().to_vec())
}

/// A CSV's columns by header name.
fn csv_columns(path: &Path) -> std::collections::HashMap<String, Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let mut cols: std::collections::HashMap<String, Vec<String>> =
        header.iter().map(|h| (h.clone(), Vec::new())).collect();
    for line in lines {
        for (h, v) in header.iter().zip(line.split(',')) {
            cols.get_mut(h).unwrap().push(v.to_string());
        }
    }
    cols
}

#[test]
fn a_kind_with_three_channels_runs_to_a_table_rgb_images_and_its_own_columns() {
    ao_rgb::register_once();
    let dir = tempfile::tempdir().unwrap();
    // One seed, so that the RMS columns are the first seed's, as the kind's own are.
    let base = tiny(ONE_FIELD, "").replace(r#""reference": {"#, r#""reference": { "seeds": 1, "#);
    let scalar = loaded(dir.path(), &base);
    let scalar_out = dir.path().join("scalar");
    run(&scalar, &options(scalar_out.clone())).unwrap();
    let rgb_spec = base.replace(
        r#""render": { "rays_per_point": 16"#,
        r#""render": { "what": "ao_rgb", "level": 0.25, "rays_per_point": 16"#,
    );
    let rgb = loaded(dir.path(), &rgb_spec);
    let out = dir.path().join("rgb");
    let report = run(&rgb, &options(out.clone())).unwrap();
    let rows: Vec<Row> = read_csv(&out.join("table.csv")).unwrap();
    assert_eq!(rows, report.rows);
    let r = &rows[0];
    assert_eq!((r.channels, r.receiver_points, r.seeds), (3, 243, 1));
    // The kind's own columns follow the standard ones: the red and green channels have the
    // same error (one is the other's complement), the blue none; the table's RMS is over all
    // three channels.
    let named = visfield::experiment::columns::read_csv(&out.join("table.csv")).unwrap();
    let own = |c: usize| named[0].number(&format!("rms_c{c}")).unwrap();
    let (e0, e1, e2) = (own(0), own(1), own(2));
    assert!(e0 > 0.1, "{e0}");
    assert!((e0 - e1).abs() <= 1e-9 * e0, "{e0} vs {e1}");
    assert_eq!(e2, 0.0);
    let all = ((e0 * e0 + e1 * e1 + e2 * e2) / 3.0).sqrt();
    let rv = r.rms_vertex.unwrap();
    assert!((rv - all).abs() <= 1e-9 * all, "rms_vertex {rv} vs {all}");
    // Channel 0 is the scalar kind's AO, bit for bit: the same-ray reference and the field's
    // values per point, and so its error.
    let s = &read_csv::<Row>(&scalar_out.join("table.csv")).unwrap()[0];
    assert_eq!(s.channels, 1);
    assert!((s.rms_vertex.unwrap() - e0).abs() <= 1e-9 * e0);
    let (sc, rc) = (
        csv_columns(&scalar_out.join("values_tiny.csv")),
        csv_columns(&out.join("values_tiny.csv")),
    );
    assert_eq!(rc["reference_c0"], sc["reference"]);
    assert_eq!(rc[&format!("{}_c0", r.cell)], sc[&s.cell]);
    assert!(rc["reference_c2"].iter().all(|v| v == "0.25"));
    // The converged reference per channel: the blue one exact, with no error bar.
    assert!(rc["truth_c2"].iter().all(|v| v == "0.25"));
    assert!(rc["truth_stderr_c2"].iter().all(|v| v == "0"));
    // The images are RGB: red is the scalar kind's grey image, pixel for pixel; green its
    // complement where a receiver shows (other surfaces are grey, all three channels alike);
    // blue the level there.
    for name in ["tiny-reference.png", &r.image["images/".len()..]] {
        let (ct, px) = png(&out.join("images").join(name));
        let scalar_name = name.replace(&r.cell, &s.cell);
        let (gt, gray) = png(&scalar_out.join("images").join(&scalar_name));
        assert_eq!((ct, gt), (image::ColorType::Rgb8, image::ColorType::L8));
        assert_eq!(px.len(), 3 * gray.len());
        let mut receiver = 0;
        for (p, &g) in px.chunks(3).zip(&gray) {
            assert_eq!(p[0], g, "{name}");
            // A grey pixel has three equal levels; a receiver's never do (red + green is 255,
            // blue 64 = 0.25 · 255 rounded).
            if !(p[0] == p[1] && p[1] == p[2]) {
                receiver += 1;
                assert_eq!(p[2], 64, "{name}: {p:?}");
                assert!(
                    (p[0] as i32 + p[1] as i32 - 255).abs() <= 1,
                    "{name}: {p:?}"
                );
            }
        }
        assert!(receiver > 100, "{name}: {receiver} receiver pixels");
    }
    // The difference image is per channel: blue never differs.
    let diff = out.join(format!("images/{}-diff_x5.png", r.cell));
    let (ct, px) = png(&diff);
    assert_eq!(ct, image::ColorType::Rgb8);
    assert!(px.chunks(3).all(|p| p[2] == 0) && px.chunks(3).any(|p| p[0] > 0));
}

// A method added through the registry alone: "unoccluded" answers every ray as free, either
// through the kind's own estimator (`"answer": "rays"`, a `Visibility` that never blocks) or
// as a direct estimator of its own (`"answer": "direct"`, 1 at every point). One spec entry
// with both on its axis gives two settings, each a row of `methods.csv`.

mod toy_method {
    use visfield::experiment::kinds::Kind;
    use visfield::experiment::methods::{
        read_as, Answer, Method, MethodContext, MethodEntry, MethodOptions, Prepared,
    };
    use visfield::experiment::spec::{Spec, SpecError};
    use visfield::experiment::validate::Validator;
    use visfield::render::estimator::{Estimator, Points};
    use visfield::render::truth::{Truth, TruthOptions};
    use visfield::sampling::rays::RaySet;
    use visfield::visibility::{SurfaceHit, Visibility};

    #[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    pub struct UnoccludedOptions {
        /// The axis: "rays", "direct".
        answer: Vec<String>,
    }

    impl MethodOptions for UnoccludedOptions {
        fn validate(&self, at: &str, _s: &Spec, v: &Validator) -> Result<(), SpecError> {
            match self.answer.iter().find(|a| *a != "rays" && *a != "direct") {
                Some(a) => Err(v.err(
                    &format!("{at}.answer"),
                    format!("\"{a}\" is not rays or direct"),
                )),
                None => Ok(()),
            }
        }

        fn settings(&self) -> Vec<Box<dyn Method>> {
            self.answer
                .iter()
                .map(|a| {
                    Box::new(Unoccluded {
                        direct: a == "direct",
                    }) as Box<dyn Method>
                })
                .collect()
        }
    }

    struct Unoccluded {
        direct: bool,
    }

    struct Free;

    impl Visibility for Free {
        fn occluded(&self, _: glam::Vec3, _: glam::Vec3, _: f32, _: f32) -> bool {
            false
        }
        fn hit_distance(&self, _: glam::Vec3, _: glam::Vec3, _: f32, _: f32) -> Option<f32> {
            None
        }
        fn surface_hit(&self, _: glam::Vec3, _: glam::Vec3, _: f32, _: f32) -> Option<SurfaceHit> {
            None
        }
    }

    struct One;

    impl Estimator for One {
        fn name(&self) -> &'static str {
            "one"
        }
        fn estimate(&self, _vis: &dyn Visibility, at: Points, _rays: &RaySet) -> Vec<f32> {
            vec![1.0; at.len()]
        }
        fn converged(&self, _vis: &dyn Visibility, _at: Points, _t: &TruthOptions) -> Truth {
            unreachable!("a method's estimator is never asked for the truth")
        }
        fn key(&self) -> serde_json::Map<String, serde_json::Value> {
            serde_json::Map::new()
        }
    }

    impl Method for Unoccluded {
        fn name(&self) -> &'static str {
            "unoccluded"
        }
        fn params(&self) -> Vec<(&'static str, String)> {
            vec![("answer", if self.direct { "direct" } else { "rays" }.into())]
        }
        fn refuses(&self, kind: &dyn Kind) -> Option<String> {
            (kind.name() == "reflections").then(|| "it has no surface to reflect".into())
        }
        fn prepare(&self, _ctx: &MethodContext) -> visfield::experiment::Result<Prepared> {
            Ok(Prepared {
                answer: if self.direct {
                    Answer::Direct(Box::new(One))
                } else {
                    Answer::Rays(Box::new(Free))
                },
                bytes: Some(0),
                cached: false,
                columns: vec![("toy".into(), "yes".into())],
                gpu: None,
            })
        }
    }

    pub const ENTRY: MethodEntry = MethodEntry {
        name: "unoccluded",
        about: "a toy method: every ray is free",
        read: read_as::<UnoccludedOptions>,
    };

    pub fn register_once() {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            visfield::experiment::methods::register(ENTRY).expect("first registration")
        });
    }
}

fn with_methods(spec: &str, methods: &str) -> String {
    spec.replace(
        r#""reference": {"#,
        &format!(r#""methods": {methods}, "reference": {{"#),
    )
}

#[test]
fn a_method_registered_at_run_time_gives_one_row_per_setting_measured_like_a_cell() {
    use visfield::experiment::columns::{read_csv as read_named, NamedRow};
    toy_method::register_once();
    let both = r#"[{"method": "unoccluded", "answer": ["rays", "direct"]}]"#;
    let dir = tempfile::tempdir().unwrap();
    // Vertex AO answered as unoccluded: 1 at every point, through the rays and directly.
    let ls = loaded(dir.path(), &with_methods(&tiny(ONE_FIELD, ""), both));
    let out = dir.path().join("ao");
    run(&ls, &options(out.clone())).unwrap();
    let rows: Vec<NamedRow> = read_named(&out.join("methods.csv")).unwrap();
    let settings: Vec<&str> = rows.iter().map(|r| r.get("setting").unwrap()).collect();
    assert_eq!(settings, ["unoccluded-rays", "unoccluded-direct"]);
    for r in &rows {
        assert_eq!(r.get("scene"), Some("tiny"));
        assert_eq!(r.get("toy"), Some("yes"));
        assert_eq!(r.number("points"), Some(243.0));
        assert_eq!(r.number("rays_cast"), Some(243.0 * 16.0));
        // Its error against the same-ray reference is the signal itself (the reference's
        // occlusion, 255 · (1 − value) at every point), which the caster makes far from zero.
        let (e, occ) = (
            r.number("rms_vs_raycast").unwrap(),
            r.number("signal_rms").unwrap(),
        );
        assert!(occ > 1.0, "{occ}");
        assert!((e - occ).abs() <= 1e-9 * occ, "{e} vs {occ}");
        assert!(r.number("rms_vs_truth").unwrap() > 1.0);
        assert!(r.number("estimate_s").unwrap() > 0.0);
    }
    assert_eq!(rows[0].get("through"), Some("rays"));
    assert_eq!(rows[1].get("through"), Some("direct"));
    // Both answers give the same values, so the same errors.
    assert_eq!(rows[0].get("rms_vertex"), rows[1].get("rms_vertex"));
    // The toy kind through the toy method: the constant through a free visibility is the
    // constant, as is the reference: no error at all.
    register_once();
    let spec = with_methods(&constant_spec(r#""level": 0.25"#), both);
    let ls = loaded(dir.path(), &spec);
    let out = dir.path().join("toy");
    run(&ls, &options(out.clone())).unwrap();
    let rows: Vec<NamedRow> = read_named(&out.join("methods.csv")).unwrap();
    // The constant kind's direct answer is the method's own estimator (1), not the kind's.
    assert_eq!(rows[0].number("rms_vs_raycast"), Some(0.0));
    assert!((rows[1].number("rms_vs_raycast").unwrap() - 0.75 * 255.0).abs() < 1e-3);
}

#[test]
fn a_registered_method_refuses_unknown_keys_bad_values_a_kind_and_a_repeat() {
    toy_method::register_once();
    let parse = |methods: &str| {
        Spec::parse(
            &with_methods(&tiny(ONE_FIELD, ""), methods),
            Path::new("specs/m.json"),
        )
        .map_err(|e| e.to_string())
    };
    let e = parse(r#"[{"method": "unoccluded", "answer": ["rays"], "speed": 2}]"#).unwrap_err();
    assert!(
        e.contains("unknown field `speed`") && e.contains("unoccluded"),
        "{e}"
    );
    let e = parse(r#"[{"method": "unoccluded", "answer": ["sideways"]}]"#).unwrap_err();
    assert!(
        e.contains("methods[0].answer") && e.contains("sideways"),
        "{e}"
    );
    let e = parse(r#"[{"method": "unoccluded", "answer": ["rays", "rays"]}]"#).unwrap_err();
    assert!(e.contains("methods[0]") && e.contains("twice"), "{e}");
    let e = parse(r#"[{"method": "sdf_typo"}]"#).unwrap_err();
    assert!(
        e.contains("sdf_typo") && e.contains("\"unoccluded\""),
        "{e}"
    );
    let e = parse(r#"[{"answer": ["rays"]}]"#).unwrap_err();
    assert!(e.contains("method"), "{e}");
    assert!(visfield::experiment::methods::register(toy_method::ENTRY).is_err());
}
