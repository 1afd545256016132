//! A sample of the numbers README.md, docs/results.md, docs/performance.md and docs/own_mesh.md
//! quote, recomputed from the committed CSV files under results/ and looked for in the documents,
//! so that a rerun which moves a number fails here until the text follows it. Each claim is the
//! text as the document writes it (whitespace runs compared as one space), formatted from the
//! files it names. With `VISFIELD_DUMP_CLAIMS=FILE` every claim is appended to FILE (document,
//! tab, text): run once before and once after a rerun to get the old and the new text of each
//! quoted number.

mod common;
#[path = "doc_numbers/flip.rs"]
mod flip;
#[path = "doc_numbers/gpu_moving.rs"]
mod gpu_moving;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use visfield::experiment::outputs::table_path;

type Row = HashMap<String, String>;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// `rel` under the root; a command's table in a folder written before it had its name, under
/// its former name (`outputs::table_path`).
fn path(rel: &str) -> PathBuf {
    let p = root().join(rel);
    table_path(
        p.parent().unwrap(),
        p.file_name().unwrap().to_str().unwrap(),
    )
}

fn read(rel: &str) -> Vec<Row> {
    common::read_csv_maps(&path(rel))
}

/// The columns named otherwise in tables written before the names said what they hold for
/// every kind: (the name now, the name then).
const FORMER: [(&str, &str); 5] = [
    ("estimate_s", "ao_s"),
    ("raycast_s", "ao_s"),
    ("estimate_mrays_s", "ao_mrays_s"),
    ("ours_estimate_s", "ours_ao_s"),
    ("paper_estimate_s", "paper_ao_s"),
];

/// Column `col` of `r` as a number; in a table written before, under its name then.
fn f(r: &Row, col: &str) -> f64 {
    let was = FORMER
        .iter()
        .find(|(now, _)| *now == col)
        .map(|(_, was)| *was);
    let v = r
        .get(col)
        .or_else(|| was.and_then(|w| r.get(w)))
        .unwrap_or_else(|| panic!("no column {col}"));
    v.parse().unwrap_or_else(|_| panic!("column {col}: `{v}`"))
}

fn squash(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// `x` as the docs write small times per ray: "4.4·10⁻⁵".
fn sci(x: f64) -> String {
    let e = x.log10().floor() as i32;
    let m = x / 10f64.powi(e);
    let (m, e) = if format!("{m:.1}") == "10.0" {
        (1.0, e + 1)
    } else {
        (m, e)
    };
    let sup: String =
        e.to_string()
            .chars()
            .map(|c| match c {
                '-' => '⁻',
                d => ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹']
                    [d.to_digit(10).unwrap() as usize],
            })
            .collect();
    format!("{m:.1}·10{sup}")
}

fn min_max(v: impl IntoIterator<Item = f64>) -> (f64, f64) {
    v.into_iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        })
}

struct Claims {
    docs: HashMap<&'static str, String>,
    missing: Vec<String>,
    count: usize,
}

impl Claims {
    fn new() -> Claims {
        let docs = [
            "README.md",
            "docs/results.md",
            "docs/performance.md",
            "docs/own_mesh.md",
        ]
        .into_iter()
        .map(|d| (d, squash(&std::fs::read_to_string(root().join(d)).unwrap())))
        .collect();
        Claims {
            docs,
            missing: Vec::new(),
            count: 0,
        }
    }

    /// `doc` must quote `text`, computed from `from`.
    fn quotes(&mut self, doc: &'static str, text: &str, from: &str) {
        self.count += 1;
        if let Ok(p) = std::env::var("VISFIELD_DUMP_CLAIMS") {
            use std::io::Write;
            let mut f = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(p)
                .unwrap();
            // The text as formatted, its line breaks written `\n`, so that a table keeps its rows.
            writeln!(f, "{doc}\t{}", text.trim().replace('\n', "\\n")).unwrap();
        }
        if !self.docs[doc].contains(&squash(text)) {
            self.missing
                .push(format!("{doc} should say `{text}` ({from})"));
        }
    }
}

/// 2008 Figure 6: the bake ratios, the RMS table, and which fields came from the cache.
fn figure6(c: &mut Claims) {
    let from = "results/figure6/table.csv";
    let rows: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["backend"] == "cpu")
        .collect();
    let cell = |n: usize, d: u32| {
        rows.iter()
            .find(|r| {
                r["positional_samples"] == n.to_string() && r["directional_res"] == d.to_string()
            })
            .unwrap_or_else(|| panic!("no {n} × {d}² row"))
    };
    let base = f(cell(290, 32), "bake_s");
    let rel = |n, d| f(cell(n, d), "bake_s") / base;
    let text = format!(
        "{:.2}×, {:.2}×, {:.1}× along the first row",
        rel(290, 64),
        rel(290, 128),
        rel(290, 256)
    );
    c.quotes("docs/results.md", &text, from);
    let text = format!("{:.2}×, {:.2}× down to 4226", rel(1090, 32), rel(4226, 32));
    c.quotes("docs/results.md", &text, from);
    let text = format!("{:.1}× at 4226 × 256²", rel(4226, 256));
    c.quotes("docs/results.md", &text, from);
    c.quotes("README.md", &text, from);
    c.quotes(
        "docs/results.md",
        &format!("Our smallest bake takes {base:.2} s"),
        from,
    );
    let timed: Vec<&Row> = rows
        .iter()
        .filter(|r| r["bake_cached"] == "false")
        .collect();
    let text = match &timed[..] {
        [one] => format!(
            "every field but {} × {}² came from the cache",
            one["positional_samples"], one["directional_res"]
        ),
        _ => format!("{} fields timed in the run", timed.len()),
    };
    c.quotes("docs/results.md", &text, from);
    // The paper's ratios, from the spec's numbers as paper_vs_ours.csv holds them.
    let pv_from = "results/figure6/paper_vs_ours.csv";
    let pv = read(pv_from);
    let paper = |label: &str| {
        let r = pv.iter().find(|r| r["label"] == label).unwrap();
        f(r, "paper_preprocess_rel")
    };
    let text = format!(
        "(paper {:.1}×, {:.0}×, {:.0}×)",
        paper("290x64"),
        paper("290x128"),
        paper("290x256")
    );
    c.quotes("docs/results.md", &text, pv_from);
    let text = format!("(paper {:.1}×, {:.0}×)", paper("1090x32"), paper("4226x32"));
    c.quotes("docs/results.md", &text, pv_from);
    let text = format!("(paper {:.0}×)", paper("4226x256"));
    c.quotes("docs/results.md", &text, pv_from);
    // The lookup against ray casting and Embree on the same rays (one seed's).
    let embree = read("results/figure6/methods.csv")
        .into_iter()
        .find(|r| r["method"] == "embree" && r["backend"] == "cpu")
        .map(|r| f(&r, "estimate_s"))
        .expect("an Embree row (run with --features embree)");
    let (lo, hi) = min_max(rows.iter().map(|r| f(r, "estimate_s")));
    let largest = f(cell(16642, 256), "estimate_s");
    let text = format!(
        "on the same {} rays it is not: our CWBVH (obvhs) with watertight triangles takes {:.3} s, \
         Embree 3 {embree:.3} s, the field lookup {lo:.3}–{hi:.3} s ({:.1}–{:.1}× Embree; {largest:.3} \
         s for the largest field",
        with_commas(f(&rows[0], "rays_cast") as u64),
        f(&rows[0], "raycast_s"),
        embree / hi,
        embree / lo,
    );
    c.quotes("README.md", &text, from);
    c.quotes("docs/results.md", &text, from);
    // The RMS table, with the paper's in brackets.
    for n in [290usize, 1090, 4226, 16642] {
        let mut text = format!("| {n} |");
        for d in [32u32, 64, 128, 256] {
            let ours = f(cell(n, d), "rms_image");
            let label = format!("{n}x{d}");
            match pv.iter().find(|r| r["label"] == label) {
                Some(p) => text.push_str(&format!(" {ours:.2} ({:.2}) |", f(p, "paper_rms"))),
                None => text.push_str(&format!(" {ours:.2} |")),
            }
        }
        c.quotes("docs/results.md", &text, from);
        c.quotes("README.md", &text, from);
    }
}

/// 2010 Figure 4: the field's time against rays, and ray casting's.
fn figure4(c: &mut Claims) {
    let from = "results/ao2010_figure4/field_sweep.csv";
    let sweep: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["backend"] == "cpu")
        .collect();
    let time = |n: u32, k: u32| {
        let r = sweep
            .iter()
            .find(|r| {
                r["positional_samples"] == n.to_string() && r["rays_per_point"] == k.to_string()
            })
            .unwrap();
        f(r, "estimate_s")
    };
    let maps = [1090, 4226, 16642];
    let (lo, hi) = min_max(maps.map(|n| time(n, 256) / time(n, 16)));
    let text = format!("{lo:.1}–{hi:.1}× for 16× the rays");
    c.quotes("docs/results.md", &text, from);
    let at = |k| maps.map(|n| format!("{:.2}", time(n, k))).join(" / ");
    let text = format!("{} s at 256 rays", at(256));
    c.quotes("docs/results.md", &text, from);
    c.quotes(
        "README.md",
        &format!("field {} s at 256 rays", at(256)),
        from,
    );
    let at3 = maps.map(|n| format!("{:.3}", time(n, 16))).join(" / ");
    c.quotes("docs/results.md", &format!("{at3} s at 16"), from);
    let rc_from = "results/ao2010_figure4/raycast_sweep.csv";
    let rc = read(rc_from);
    let ray = |k: u32| {
        let r = rc
            .iter()
            .find(|r| r["backend"] == "cpu" && r["rays_per_point"] == k.to_string())
            .unwrap();
        f(r, "raycast_s")
    };
    let text = format!(
        "ray casting takes {:.2} s at 16 rays and {:.2} s at 256 ({:.1}× the 4226-map field",
        ray(16),
        ray(256),
        ray(256) / time(4226, 256)
    );
    c.quotes("docs/results.md", &text, rc_from);
    c.quotes(
        "README.md",
        &format!("ray casting {:.2} s |", ray(256)),
        rc_from,
    );
}

/// 2010 Figure 9: the speed range, and whose bounding sphere reaches the floor (y = 0).
fn figure9(c: &mut Claims) {
    let from = "results/reflections2010_figure9/table.csv";
    let rows = read(from);
    let view = |v: &str| {
        rows.iter()
            .filter(|r| r["scene"] == v && r["backend"] == "cpu")
            .collect::<Vec<_>>()
    };
    let (a, b) = (view("view_a"), view("view_b"));
    let (flo, fhi) = min_max(rows.iter().map(|r| f(r, "estimate_s")));
    let rc = |v: &[&Row]| f(v[0], "raycast_s");
    let text = format!(
        "Field {flo:.3}–{fhi:.3} s, ray casting {:.3} s (view_a) and {:.3} s (view_b)",
        rc(&a),
        rc(&b)
    );
    c.quotes("docs/results.md", &text, from);
    let (mlo, mhi) = min_max(rows.iter().map(|r| f(r, "estimate_mrays_s")));
    let text = format!(
        "same {:.2} and {:.2} M reflection rays ({mlo:.1}–{mhi:.1} against {:.1} and {:.1} Mrays/s)",
        f(a[0], "rays_cast") / 1e6,
        f(b[0], "rays_cast") / 1e6,
        f(a[0], "raycast_mrays_s"),
        f(b[0], "raycast_mrays_s"),
    );
    c.quotes("docs/results.md", &text, from);
    let gain = |v: &[&Row]| min_max(v.iter().map(|r| f(r, "raycast_s") / f(r, "estimate_s")));
    let ((alo, ahi), (blo, bhi)) = (gain(&a), gain(&b));
    let text = format!("{alo:.1}–{ahi:.1}× and {blo:.1}–{bhi:.1}×.");
    c.quotes("docs/results.md", &text, from);
    let (slo, shi) = min_max(
        read("results/shadows2010_figure7/table.csv")
            .iter()
            .chain(&read("results/shadows2010_figure8/table.csv"))
            .filter(|r| r["backend"] == "cpu")
            .map(|r| f(r, "raycast_s") / f(r, "estimate_s")),
    );
    let (rlo, rhi) = min_max(rows.iter().map(|r| f(r, "raycast_s") / f(r, "estimate_s")));
    let (alo, ahi) = min_max(
        read("results/ao2010_figure3/table.csv")
            .iter()
            .filter(|r| r["backend"] == "cpu" && r["scene"] == "bunny")
            .map(|r| f(r, "raycast_s") / f(r, "estimate_s")),
    );
    let text = format!(
        "({slo:.1}–{shi:.1}× and {rlo:.1}–{rhi:.1}× against {alo:.1}–{ahi:.0}× for Figure 3's AO pass"
    );
    c.quotes(
        "README.md",
        &text,
        "results/shadows2010_figure7/, figure8/, ao2010_figure3/ and this table.csv",
    );
    // The casters' fitted spheres, from the spec the run copied.
    let spec_from = "results/reflections2010_figure9/spec.json";
    let spec: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(root().join(spec_from)).unwrap()).unwrap();
    let fit = |model: &str| {
        let i = spec["scenes"][0]["instances"]
            .as_array()
            .unwrap()
            .iter()
            .find(|i| i["mesh"]["model"] == model)
            .unwrap();
        let fit = &i["transform"]["fit"];
        (
            fit["center"][1].as_f64().unwrap(),
            fit["radius"].as_f64().unwrap(),
        )
    };
    let (by, br) = fit("stanford-bunny_39k");
    let (ey, er) = fit("elephant");
    assert!(
        by - br < 0.0,
        "the docs say the bunny's sphere cuts the floor"
    );
    assert!(
        ey - er > 0.0,
        "the docs say the elephant's sphere stays clear of the floor"
    );
    let text = format!("(radius {br} about a centre {by} above the floor");
    c.quotes("docs/results.md", &text, spec_from);
    let text = format!("(radius {er} about a centre {ey} above the floor)");
    c.quotes("docs/results.md", &text, spec_from);
}

/// 2010 Figure 8 and Figure 6 (Sponza): the pairings of paper_vs_ours.csv.
fn sponza(c: &mut Claims) {
    let from = "results/shadows2010_figure8/paper_vs_ours.csv";
    let pv = read(from);
    let (field, sharp) = (&pv[0], &pv[1]);
    let field_ms = f(field, "ours_estimate_s") / f(field, "ours_rays_cast") * 1e3;
    let sharp_ms = f(sharp, "ours_raycast_s") / f(sharp, "ours_rays_cast") * 1e3;
    let paper_field = f(field, "paper_estimate_s") * 0.7 / f(field, "paper_rays_cast") * 1e3;
    // The paper's 591,930 sharp rays (its note): 70% of 48,047 ms.
    let paper_sharp = f(sharp, "paper_raycast_s") * 0.7 / 591_930.0 * 1e3;
    let text = format!(
        "{} against {} ms per shadow ray, {:.0}×; paired so, ours are {} against {} ms, {:.1}×",
        sci(paper_field),
        sci(paper_sharp),
        paper_sharp / paper_field,
        sci(field_ms),
        sci(sharp_ms),
        sharp_ms / field_ms
    );
    c.quotes("docs/results.md", &text, from);
    let rays = f(field, "ours_rays_cast");
    let text = format!(
        "the field took {:.3} s for {} shadow rays ({} ms per ray) and ray casting {:.3} s on the \
         same rays ({} ms): {:.1}× on the same rays",
        f(field, "ours_estimate_s"),
        with_commas(rays as u64),
        sci(f(field, "ours_estimate_s") / rays * 1e3),
        f(field, "ours_raycast_s"),
        sci(f(field, "ours_raycast_s") / rays * 1e3),
        f(field, "ours_raycast_s") / f(field, "ours_estimate_s"),
    );
    c.quotes("docs/results.md", &text, from);
    let sweep = read("results/shadows2010_figure8/raycast_sweep.csv");
    let one = sweep.iter().find(|r| r["rays_per_point"] == "1").unwrap();
    let text = format!(
        "Sharp shadows, one ray per light to its centre, took {:.3} s by ray casting ({} ms per \
         ray, RMS {:.1} from the converged soft shadows)",
        f(one, "raycast_s"),
        sci(sharp_ms),
        f(one, "rms_vs_truth"),
    );
    c.quotes(
        "docs/results.md",
        &text,
        "results/shadows2010_figure8/raycast_sweep.csv",
    );
    let from = "results/ao2010_sponza/paper_vs_ours.csv";
    let pv = read(from);
    let (sum, one) = (&pv[0], &pv[1]);
    let table = read("results/ao2010_sponza/table.csv");
    let ao = |scene: &str| {
        let r = table
            .iter()
            .find(|r| r["scene"] == scene && r["backend"] == "cpu")
            .unwrap();
        f(r, "estimate_s")
    };
    let all = table
        .iter()
        .find(|r| r["scene"] == "all" && r["backend"] == "cpu")
        .unwrap();
    let px = f(all, "receiver_points");
    let text = format!(
        "the AO of {} receiver pixels took {:.2} s ({} pixels per second on 2 CPU threads; RMS \
         {:.2} against ray casting, which took {:.2} s)",
        with_commas(px as u64),
        f(all, "estimate_s"),
        with_commas(((px / f(all, "estimate_s") / 1e3).round() * 1e3) as u64),
        f(all, "rms_image"),
        f(all, "raycast_s"),
    );
    c.quotes("docs/results.md", &text, "results/ao2010_sponza/table.csv");
    let text = format!(
        "{:.2} + {:.2} + {:.2} = {:.2} s, the same within the noise ({:.2}×;",
        ao("bunny"),
        ao("cow"),
        ao("elephant"),
        f(sum, "ours_estimate_s"),
        f(sum, "ours_estimate_s") / f(one, "ours_estimate_s")
    );
    c.quotes("docs/results.md", &text, from);
}

/// 2008 Figure 8 and 2010 Figure 3: RMS and times per caster, the AO pass against ray casting.
fn figure8_and_figure3(c: &mut Claims) {
    let from = "results/figure8/table.csv";
    let rows: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["backend"] == "cpu")
        .collect();
    let scene = |s: &str| rows.iter().find(|r| r["scene"] == s).unwrap();
    let three = ["tree", "bunny", "igea"].map(scene);
    let text = format!(
        "tree ({} triangles) {:.2}, bunny {:.2}, Igea ({}) {:.2} per image ({:.2} / {:.2} / {:.2} \
         against the converged reference",
        with_commas(f(three[0], "caster_triangles") as u64),
        f(three[0], "rms_image"),
        f(three[1], "rms_image"),
        with_commas(f(three[2], "caster_triangles") as u64),
        f(three[2], "rms_image"),
        f(three[0], "rms_vs_truth"),
        f(three[1], "rms_vs_truth"),
        f(three[2], "rms_vs_truth"),
    );
    c.quotes("docs/results.md", &text, from);
    c.quotes("README.md", &text, from);
    // Embree is a method: its row of methods.csv per scene, on the same rays.
    let methods = read("results/figure8/methods.csv");
    let embree = |r: &Row| {
        let m = methods
            .iter()
            .find(|m| m["scene"] == r["scene"] && m["method"] == "embree")
            .expect("an Embree row per scene (run with --features embree)");
        f(m, "estimate_s")
    };
    let join = |col: &str, p: usize| three.map(|r| format!("{:.*}", p, f(r, col))).join(" / ");
    let join_embree = three.map(|r| format!("{:.3}", embree(r))).join(" / ");
    let text = format!(
        "our ray caster's {} s and Embree's {join_embree} s on the same rays",
        join("raycast_s", 3),
    );
    c.quotes("README.md", &text, from);
    let gain = |t: &dyn Fn(&Row) -> f64| {
        three
            .map(|r| format!("{:.1}×", t(r) / f(r, "estimate_s")))
            .join(", ")
    };
    let raycast = |r: &Row| f(r, "raycast_s");
    let text = format!(
        "our ray caster's {} s ({}) and Embree's {join_embree} s ({})",
        join("raycast_s", 3),
        gain(&raycast),
        gain(&embree)
    );
    c.quotes("docs/results.md", &text, from);
    c.quotes("README.md", &format!("({} Embree)", gain(&embree)), from);
    let from = "results/ao2010_figure3/table.csv";
    let rows: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["backend"] == "cpu" && r["scene"] == "bunny")
        .collect();
    let (lo, hi) = min_max(rows.iter().map(|r| f(r, "estimate_s")));
    let (glo, ghi) = min_max(rows.iter().map(|r| f(r, "raycast_s") / f(r, "estimate_s")));
    let rays = f(&rows[0], "receiver_points") * f(&rows[0], "rays_per_point");
    let text = format!(
        "The AO pass took {lo:.2}–{hi:.2} s through the fields against {:.2} s for ray casting the \
         same {:.1} M rays ({glo:.1}–{ghi:.0}×",
        f(&rows[0], "raycast_s"),
        rays / 1e6
    );
    c.quotes("docs/results.md", &text, from);
}

/// README's table of the 2010 headline figures: the "ours" column, cell by cell.
fn headline_2010(c: &mut Claims) {
    let cpu = |from: &str| -> Vec<Row> {
        read(from)
            .into_iter()
            .filter(|r| r["backend"] == "cpu")
            .collect()
    };
    let from = "results/ao2010_figure3/table.csv";
    let rows: Vec<Row> = cpu(from)
        .into_iter()
        .filter(|r| r["scene"] == "bunny")
        .collect();
    let cell = |n: &str, res: &str| {
        rows.iter()
            .find(|r| r["positional_samples"] == n && r["directional_res"] == res)
            .unwrap()
    };
    let (lo, hi) = min_max(rows.iter().map(|r| f(r, "estimate_s")));
    let text = format!(
        "same-ray RMS {:.2} (1090 × 32²) … {:.2} (16642 × 128²); field {lo:.2}–{hi:.2} s vs ray \
         casting {:.2} s on the same {:.1} M rays",
        f(cell("1090", "32"), "rms_image"),
        f(cell("16642", "128"), "rms_image"),
        f(&rows[0], "raycast_s"),
        f(&rows[0], "receiver_points") * f(&rows[0], "rays_per_point") / 1e6,
    );
    c.quotes("README.md", &text, from);
    let from = "results/ao2010_figure4/table.csv";
    let rows = cpu(from);
    let at = |n: &str| {
        rows.iter()
            .find(|r| r["positional_samples"] == n && r["rays_per_point"] == "256")
            .unwrap()
    };
    let text = format!(
        "field {:.2} / {:.2} / {:.2} s at 256 rays for 1090 / 4226 / 16642 maps; ray casting {:.2} s",
        f(at("1090"), "estimate_s"),
        f(at("4226"), "estimate_s"),
        f(at("16642"), "estimate_s"),
        f(at("1090"), "raycast_s"),
    );
    c.quotes("README.md", &text, from);
    let from = "results/ao2010_models/table.csv";
    let rows = cpu(from);
    let (lo, hi) = min_max(rows.iter().map(|r| f(r, "estimate_s")));
    let (tlo, thi) = min_max(rows.iter().map(|r| f(r, "caster_triangles")));
    let (rlo, rhi) = min_max(rows.iter().map(|r| f(r, "raycast_s")));
    let text = format!(
        "field {lo:.2}–{hi:.2} s for {:.0}k–{:.0}k triangles; ray casting {rlo:.1}–{rhi:.1} s",
        tlo / 1e3,
        thi / 1e3
    );
    c.quotes("README.md", &text, from);
    let from = "results/ao2010_sponza/paper_vs_ours.csv";
    let pv = read(from);
    let text = format!(
        "one pass {:.2} s; one pass per caster {:.2} s; RMS {:.2}",
        f(&pv[1], "ours_estimate_s"),
        f(&pv[0], "ours_estimate_s"),
        f(&pv[1], "ours_rms_image"),
    );
    c.quotes("README.md", &text, from);
    let from = "results/shadows2010_figure7/table.csv";
    let (lo, hi) = min_max(cpu(from).iter().map(|r| f(r, "rms_image")));
    c.quotes(
        "README.md",
        &format!("RMS {lo:.1}–{hi:.1}; ray casting wins"),
        from,
    );
    let from = "results/shadows2010_figure8/paper_vs_ours.csv";
    let pv = read(from);
    let per_ray = |r: &Row, col: &str| f(r, col) / f(r, "ours_rays_cast") * 1e3;
    let (field, rc) = (
        per_ray(&pv[0], "ours_estimate_s"),
        per_ray(&pv[0], "ours_raycast_s"),
    );
    let text = format!(
        "{} ms through the field vs {} by ray casting ({:.1}×)",
        sci(field),
        sci(rc),
        rc / field
    );
    c.quotes("README.md", &text, from);
    let from = "results/reflections2010_figure9/table.csv";
    let rows = cpu(from);
    let view =
        |v: &str, col: &str| min_max(rows.iter().filter(|r| r["scene"] == v).map(|r| f(r, col)));
    let ((alo, ahi), (blo, bhi)) = (view("view_a", "rms_image"), view("view_b", "rms_image"));
    let (mlo, mhi) = min_max(rows.iter().map(|r| f(r, "rms_image_vs_second")));
    let (slo, shi) = min_max(rows.iter().map(|r| f(r, "raycast_s") / f(r, "estimate_s")));
    // "8- and 16-bit normals alike": the same cell's RMS with either normal field.
    for r8 in rows.iter().filter(|r| r["normal_bits"] == "8") {
        let r16 = rows
            .iter()
            .find(|r| {
                r["normal_bits"] == "16"
                    && ["scene", "positional_samples", "directional_res"]
                        .iter()
                        .all(|k| r[*k] == r8[*k])
            })
            .unwrap();
        assert!(
            (f(r8, "rms_image") - f(r16, "rms_image")).abs() < 0.01,
            "README says 8- and 16-bit normals give the same RMS"
        );
    }
    let text = format!(
        "RMS {alo:.1}–{ahi:.1} and {blo:.1}–{bhi:.1} (two views) against the glossy ray cast, \
         {mlo:.1}–{mhi:.1} against the mirror; 8- and 16-bit normals alike; {slo:.1}–{shi:.1}× ray \
         casting's speed"
    );
    c.quotes("README.md", &text, from);
}

fn with_commas(n: u64) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, ch) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(ch);
    }
    out
}

/// The performance table and the field's gain over Embree.
fn performance(c: &mut Claims) {
    let from = "results/performance/backend_times.csv";
    let rows: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["sweep"] == "triangles")
        .collect();
    let get = |caster: &str, backend: &str| {
        rows.iter()
            .find(|r| r["caster"] == caster && r["backend"] == backend)
            .unwrap_or_else(|| panic!("no {caster} {backend}"))
    };
    let mut gains: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r["backend"] == "field_nearest")
        .map(|r| (f(r, "triangles"), f(r, "vs_embree")))
        .collect();
    gains.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (slo, shi) = min_max(gains.iter().filter(|g| g.0 < 40_000.0).map(|g| g.1));
    let top = &gains[gains.len() - 2..];
    let (tlo, thi) = min_max(top.iter().map(|g| g.1));
    let igea67 = f(get("igea_67k", "field_nearest"), "vs_embree");
    // A range whose ends round alike is one number.
    let range = |lo: f64, hi: f64| match (format!("{lo:.1}"), format!("{hi:.1}")) {
        (l, h) if l == h => l,
        (l, h) => format!("{l}–{h}"),
    };
    let text = format!(
        "gains {}× on small casters and {}× on the two largest ({igea67:.1}× on the 67k-triangle \
         Igea)",
        range(slo, shi),
        range(tlo, thi)
    );
    c.quotes("README.md", &text, from);
    for caster in [
        "bunny_npm",
        "stanford-bunny_39k",
        "dragon",
        "supershape",
        "igea",
    ] {
        let field = get(caster, "field_nearest");
        let text = format!(
            "| {caster} ({}) | {:.1} | {:.1} | {:.1} | {:.1}× | {:.0} |",
            with_commas(f(field, "triangles") as u64),
            f(get(caster, "raycast"), "mrays_s"),
            f(get(caster, "embree"), "mrays_s"),
            f(field, "mrays_s"),
            f(field, "vs_embree"),
            f(get(caster, "floor_sphere_cull"), "mrays_s"),
        );
        c.quotes("README.md", &text, from);
    }
}

/// 2010 Figure 3 by population: the pixels inside the bunny's sphere, and the lifted bunny.
fn figure3_population(c: &mut Claims) {
    let from = "results/ao2010_figure3/table.csv";
    let rows: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["backend"] == "cpu")
        .collect();
    let cell = |scene: &str, n: u32, d: u32| {
        rows.iter()
            .find(|r| {
                r["scene"] == scene
                    && r["positional_samples"] == n.to_string()
                    && r["directional_res"] == d.to_string()
            })
            .unwrap_or_else(|| panic!("no {scene} {n} × {d}² row"))
    };
    let a = cell("bunny", 1090, 32);
    let (k, n) = (f(a, "points_in_spheres"), f(a, "receiver_points"));
    let (fin, fout, all) = (
        f(a, "rms_vs_truth_in_spheres"),
        f(a, "rms_vs_truth_outside_spheres"),
        f(a, "rms_vs_truth"),
    );
    let col = |s: &str| {
        [1090, 4226, 16642]
            .map(|m| format!("{:.2}", f(cell(s, m, 32), "rms_image")))
            .join(" / ")
    };
    let text = format!(
        "the {} receiver pixels inside the bunny's bounding sphere ({:.1}% of {}) have an RMS of \
         {fin:.2} against the converged reference at 1090 × 32², the others {fout:.2}: they carry \
         {:.0}% of the squared error. With the bunny lifted until its sphere clears the plane \
         (scene `bunny_lifted`), the same-ray RMS of the 32² column is {} for 1090 / 4226 / \
         16642 maps, against {} resting",
        with_commas(k as u64),
        100.0 * k / n,
        with_commas(n as u64),
        100.0 * fin * fin * k / (all * all * n),
        col("bunny_lifted"),
        col("bunny"),
    );
    c.quotes("docs/results.md", &text, from);
}

/// The moving crowd: per caster count, each method's mean frame time and the field's gains and
/// errors, as docs/results.md's table writes them.
fn dynamic_table(rows: &[Row]) -> String {
    let crowd: Vec<&Row> = rows.iter().filter(|r| r["sweep"] == "crowd").collect();
    let mut counts: Vec<u64> = crowd.iter().map(|r| f(r, "casters") as u64).collect();
    counts.dedup();
    let mean = |n: u64, m: &str, col: &str| {
        let v: Vec<f64> = crowd
            .iter()
            .filter(|r| f(r, "casters") as u64 == n && r["method"] == m)
            .map(|r| f(r, col))
            .collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    };
    let ms = |v: Option<f64>| v.map_or("–".to_string(), |s| format!("{:.1}", 1e3 * s));
    let mut out = String::from(
        "| casters (triangles) | world BVH rebuilt | two levels | Embree rebuilt | Embree instances | field, every sphere | field, sphere BVH | field's gain over Embree instances / Embree rebuilt / world | field RMS same rays / vs truth (ray casting's) |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    for n in counts {
        let tris = crowd
            .iter()
            .find(|r| f(r, "casters") as u64 == n)
            .map(|r| f(r, "caster_triangles") as u64)
            .unwrap();
        let field = mean(n, "field", "frame_s").unwrap();
        let gain = |m: &str| {
            mean(n, m, "frame_s").map_or("–".to_string(), |t| format!("{:.1}×", t / field))
        };
        out.push_str(&format!(
            "| {n} ({}) | {} | {} | {} | {} | {} | {} | {} / {} / {} | {:.2} / {:.2} ({:.2}) |\n",
            with_commas(tris),
            ms(mean(n, "world_rebuild", "frame_s")),
            ms(mean(n, "two_level", "frame_s")),
            ms(mean(n, "embree_rebuild", "frame_s")),
            ms(mean(n, "embree_instances", "frame_s")),
            ms(mean(n, "field_every_sphere", "frame_s")),
            ms(Some(field)),
            gain("embree_instances"),
            gain("embree_rebuild"),
            gain("world_rebuild"),
            mean(n, "field", "rms_vs_raycast").unwrap(),
            mean(n, "field", "rms_vs_truth").unwrap(),
            mean(n, "world_rebuild", "rms_vs_truth").unwrap(),
        ));
    }
    out
}

fn dynamic(c: &mut Claims) {
    let from = "results/dynamic/sweep_frames.csv";
    if !path(from).is_file() {
        c.missing
            .push(format!("{from} is missing: run `experiment dynamic`"));
        return;
    }
    let rows = read(from);
    let text = dynamic_table(&rows);
    if std::env::var("VISFIELD_PRINT_DYNAMIC").is_ok() {
        println!("{text}");
    }
    c.quotes("docs/results.md", &text, from);
    c.quotes("README.md", &text, from);
    let (lo, hi) = min_max(
        rows.iter()
            .filter(|r| r["sweep"] == "crowd")
            .map(|r| f(r, "rays")),
    );
    let text = format!("to N, from {} to {:.1} M", with_commas(lo as u64), hi / 1e6);
    c.quotes("docs/results.md", &text, from);
    // README's headline: the field's gain over Embree at 64 and 256 casters.
    let mean = |n: &str, m: &str| {
        let v: Vec<f64> = rows
            .iter()
            .filter(|r| r["sweep"] == "crowd" && r["casters"] == n && r["method"] == m)
            .map(|r| f(r, "frame_s"))
            .collect();
        v.iter().sum::<f64>() / v.len() as f64
    };
    let gain = |n: &str, m: &str| mean(n, m) / mean(n, "field");
    let text = format!(
        "Embree rebuilding its scene takes {:.1}× the field's frame, and Embree's instances \
         {:.1}× ({:.1}× at 256 casters)",
        gain("64", "embree_rebuild"),
        gain("64", "embree_instances"),
        gain("256", "embree_instances"),
    );
    c.quotes("README.md", &text, from);
}

/// The per-object peers beside the field and the ray casters (methods.csv): AO fields on the
/// 2010 Figure 3 scene.
fn peers(c: &mut Claims) {
    let from = "results/ao2010_figure3/methods.csv";
    let rows: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["scene"] == "bunny" && r["backend"] == "cpu")
        .collect();
    let one = |m: &str| {
        rows.iter()
            .find(|r| r["method"] == m)
            .unwrap_or_else(|| panic!("no {m} row in {from}"))
    };
    let ao: Vec<&Row> = rows.iter().filter(|r| r["method"] == "aofield").collect();
    assert!(!ao.is_empty(), "no aofield rows in {from}");
    let range = |col: &str, digits: usize| {
        let (lo, hi) = min_max(ao.iter().map(|r| f(r, col)));
        format!("{lo:.digits$}–{hi:.digits$}")
    };
    let (lo, hi) = min_max(ao.iter().map(|r| f(r, "bytes")));
    let text = format!(
        "answer the resting bunny's {} pixels in {} s with no rays, against {:.2} s for our ray \
         caster and {:.2} s for Embree on {} rays per pixel; their error against the converged \
         reference is {} where the {}-ray ray cast is {:.2}, and {} against {:.2} inside the \
         caster's bounding sphere, where the cap approximation fails. Their bytes: {} to {}",
        with_commas(f(one("raycast"), "points") as u64),
        range("estimate_s", 3),
        f(one("raycast"), "estimate_s"),
        f(one("embree"), "estimate_s"),
        one("raycast")["rays_per_point"],
        range("rms_vs_truth", 2),
        one("raycast")["rays_per_point"],
        f(one("raycast"), "rms_vs_truth"),
        range("rms_vs_truth_in_spheres", 1),
        f(one("raycast"), "rms_vs_truth_in_spheres"),
        with_commas(lo as u64),
        with_commas(hi as u64),
    );
    c.quotes("docs/results.md", &text, from);

    // The AO fields' own paper's one timing (Kontkanen & Laine 2005, Figure 1: the tank scene,
    // 1024 × 768 pixels at 136 frames a second on an ATI Radeon 9800XT, the whole frame), as
    // pixels a second, beside ours per caster on the CPU.
    let paper_mpix = 1024.0 * 768.0 * 136.0 / 1e6;
    let (t_lo, t_hi) = min_max(ao.iter().map(|r| f(r, "estimate_s")));
    let px = f(one("raycast"), "points");
    let (ours_lo, ours_hi) = (px / t_hi / 1e6, px / t_lo / 1e6);
    let text = format!(
        "{paper_mpix:.0} million pixels a second for the whole frame. Ours answer \
         {ours_lo:.1}–{ours_hi:.1} million pixels a second on this machine's CPU, one caster, \
         {:.1}–{:.1} times fewer",
        paper_mpix / ours_hi,
        paper_mpix / ours_lo,
    );
    c.quotes("docs/results.md", &text, from);

    // Figure 6's vertices: the mesh distance fields, traced and cone traced, and the AO fields.
    let from = "results/figure6/methods.csv";
    let rows: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["backend"] == "cpu")
        .collect();
    let one = |m: &str| {
        rows.iter()
            .find(|r| r["method"] == m)
            .unwrap_or_else(|| panic!("no {m} row in {from}"))
    };
    let of = |m: &str, query: &str| -> Vec<&Row> {
        rows.iter()
            .filter(|r| r["method"] == m && r.get("query").map_or("", |q| q.as_str()) == query)
            .collect()
    };
    let range = |set: &[&Row], col: &str, digits: usize| {
        assert!(!set.is_empty(), "no rows for {col} in {from}");
        let (lo, hi) = min_max(set.iter().map(|r| f(r, col)));
        format!("{lo:.digits$}–{hi:.digits$}")
    };
    let bytes = |set: &[&Row]| {
        let (lo, hi) = min_max(set.iter().map(|r| f(r, "bytes")));
        format!(
            "{} to {} bytes",
            with_commas(lo as u64),
            with_commas(hi as u64)
        )
    };
    let (trace, cone, ao) = (of("sdf", "trace"), of("sdf", "cone"), of("aofield", ""));
    let text = format!(
        "the {}-ray ray cast is {:.2} from the converged reference in {:.3} s (Embree {:.3} s); \
         sphere tracing the mesh distance fields on the same rays is {} in {} s ({}); cone \
         tracing them takes {} s and is {} from the truth; the AO fields are {} in {} ms ({})",
        one("raycast")["rays_per_point"],
        f(one("raycast"), "rms_vs_truth"),
        f(one("raycast"), "estimate_s"),
        f(one("embree"), "estimate_s"),
        range(&trace, "rms_vs_truth", 2),
        range(&trace, "estimate_s", 3),
        bytes(&trace),
        range(&cone, "estimate_s", 3),
        range(&cone, "rms_vs_truth", 1),
        range(&ao, "rms_vs_truth", 2),
        {
            let (lo, hi) = min_max(ao.iter().map(|r| 1e3 * f(r, "estimate_s")));
            format!("{lo:.2}–{hi:.2}")
        },
        bytes(&ao),
    );
    c.quotes("docs/results.md", &text, from);
    c.quotes("README.md", &text, from);
}

/// 2010 Figure 4 on lavapipe, and 2008 Figure 8's lookup times against the triangle count.
fn gpu_and_figure8_lookups(c: &mut Claims) {
    let from = "results/ao2010_figure4/field_sweep.csv";
    let (lo, hi) = min_max(
        read(from)
            .iter()
            .filter(|r| r["backend"] == "gpu" && r["rays_per_point"] == "256")
            .map(|r| f(r, "estimate_s")),
    );
    let rc = read("results/ao2010_figure4/raycast_sweep.csv")
        .into_iter()
        .find(|r| r["backend"] == "gpu" && r["rays_per_point"] == "256")
        .map(|r| f(&r, "raycast_s"))
        .expect("a GPU ray-cast row at 256 rays");
    let text = format!("({lo:.1}–{hi:.1} s against {rc:.1} s at 256 rays)");
    c.quotes("docs/results.md", &text, from);
    let from = "results/figure8/table.csv";
    let (lo, hi) = min_max(
        read(from)
            .iter()
            .filter(|r| r["backend"] == "cpu" && r["scene"] != "multi")
            .map(|r| f(r, "estimate_s")),
    );
    let text = format!("the lookup's time does not follow the triangle count: {lo:.3}–{hi:.3} s");
    c.quotes("README.md", &text, from);
    c.quotes("docs/results.md", &text, from);
}

/// README's Performance prose: the field's Mrays/s over the triangle sweep against Embree's, the
/// entering sweep, Figure 8's multiple-object scene and lavapipe's ratio on Figure 6's rays.
fn performance_prose(c: &mut Claims) {
    let from = "results/performance/backend_times.csv";
    let rows = read(from);
    let sweep = |s: &str, b: &str| -> Vec<&Row> {
        rows.iter()
            .filter(|r| r["sweep"] == s && r["backend"] == b)
            .collect()
    };
    let (flo, fhi) = min_max(
        sweep("triangles", "field_nearest")
            .iter()
            .map(|r| f(r, "mrays_s")),
    );
    let embree = sweep("triangles", "embree");
    let by_tris = |pick: fn(f64, f64) -> bool| {
        embree
            .iter()
            .copied()
            .reduce(|a, b| {
                if pick(f(b, "triangles"), f(a, "triangles")) {
                    b
                } else {
                    a
                }
            })
            .unwrap()
    };
    let (small, big) = (by_tris(|b, a| b < a), by_tris(|b, a| b > a));
    let text = format!(
        "Its cost does not follow the caster: {flo:.0}–{fhi:.0} Mrays/s from {:.1}k to {:.0}k \
         triangles, while Embree falls from {:.0} to {:.0}",
        f(small, "triangles") / 1e3,
        f(big, "triangles") / 1e3,
        f(small, "mrays_s"),
        f(big, "mrays_s"),
    );
    c.quotes("README.md", &text, from);
    let entering: Vec<&Row> = sweep("entering", "field_nearest")
        .into_iter()
        .filter(|r| f(r, "entering_share") > 0.0)
        .collect();
    let (lo, hi) = min_max(entering.iter().map(|r| f(r, "vs_embree")));
    let all = entering
        .iter()
        .find(|r| f(r, "entering_share") == 1.0)
        .expect("an entering share of 1");
    let text = format!(
        "it is {lo:.1}–{hi:.1}× Embree ({:.0} against {:.0} Mrays/s when all do)",
        f(all, "mrays_s"),
        f(all, "mrays_s") / f(all, "vs_embree"),
    );
    c.quotes("README.md", &text, from);
    let from = "results/figure8/table.csv";
    let multi = read(from)
        .into_iter()
        .find(|r| r["backend"] == "cpu" && r["scene"] == "multi")
        .unwrap();
    let embree = read("results/figure8/methods.csv")
        .into_iter()
        .find(|r| r["scene"] == "multi" && r["method"] == "embree")
        .map(|r| f(&r, "estimate_s"))
        .unwrap();
    let text = format!(
        "many casters sharing the rays, is {:.1}× Embree",
        embree / f(&multi, "estimate_s")
    );
    c.quotes("README.md", &text, from);
    let from = "results/figure6/table.csv";
    let rows = read(from);
    let ratio = |b: &str| {
        min_max(
            rows.iter()
                .filter(|r| r["backend"] == b)
                .map(|r| f(r, "raycast_s") / f(r, "estimate_s")),
        )
    };
    let ((glo, ghi), (clo, chi)) = (ratio("gpu"), ratio("cpu"));
    let text = format!(
        "On lavapipe the WGSL field kernel is {glo:.1}–{ghi:.1}× the WGSL CWBVH on Figure 6's \
         rays, short of the CPU's {clo:.1}–{chi:.1}×"
    );
    c.quotes("README.md", &text, from);
}

/// README's Performance on the 2010 paper's other rays: the shadow and reflection sweeps of
/// `experiment performance`, the 2010 scenes against Embree, and lavapipe's ratios.
fn secondary_rays(c: &mut Claims) {
    let from = "results/performance/backend_times.csv";
    let rows = read(from);
    let get = |sweep: &str, caster: &str, backend: &str| -> &Row {
        rows.iter()
            .find(|r| r["sweep"] == sweep && r["caster"] == caster && r["backend"] == backend)
            .unwrap_or_else(|| panic!("no {sweep} {caster} {backend}"))
    };
    let casters: Vec<&str> = rows
        .iter()
        .filter(|r| r["sweep"] == "triangles" && r["backend"] == "field_nearest")
        .map(|r| r["caster"].as_str())
        .collect();
    let share_of_ao = |c: &str| {
        f(get("shadow_triangles", c, "field_nearest"), "mrays_s")
            / f(get("triangles", c, "field_nearest"), "mrays_s")
    };
    for caster in [
        "bunny_npm",
        "stanford-bunny_39k",
        "dragon",
        "supershape",
        "igea",
    ] {
        let (sh, rf) = (
            get("shadow_triangles", caster, "field_nearest"),
            get("reflection_triangles", caster, "field_nearest"),
        );
        let text = format!(
            "| {caster} | {:.1} | {:.1} | {:.1}× | {:.0}% | {:.1} | {:.1} | {:.1}× |",
            f(get("shadow_triangles", caster, "embree"), "mrays_s"),
            f(sh, "mrays_s"),
            f(sh, "vs_embree"),
            100.0 * share_of_ao(caster),
            f(get("reflection_triangles", caster, "embree"), "mrays_s"),
            f(rf, "mrays_s"),
            f(rf, "vs_embree"),
        );
        c.quotes("docs/performance.md", &text, from);
    }
    let (plo, phi) = min_max(casters.iter().map(|c| 100.0 * share_of_ao(c)));
    let gain = |sweep: &str| {
        min_max(
            casters
                .iter()
                .map(|c| f(get(sweep, c, "field_nearest"), "vs_embree")),
        )
    };
    let ((slo, shi), (rlo, rhi)) = (gain("shadow_triangles"), gain("reflection_triangles"));
    let text = format!(
        "shadow rays through the field run at {plo:.0}–{phi:.0}% of its AO rate on the same \
         caster and field and {slo:.1}–{shi:.1}× Embree; reflection rays at {rlo:.1}–{rhi:.1}× Embree"
    );
    c.quotes("README.md", &text, from);
    // The 2010 scenes: the field's cells against the Embree row of methods.csv.
    let embree = |spec: &str, scene: &str| {
        read(&format!("results/{spec}/methods.csv"))
            .into_iter()
            .find(|r| r["scene"] == scene && r["method"] == "embree")
            .map(|r| f(&r, "estimate_s"))
            .unwrap_or_else(|| panic!("no Embree row in {spec} for {scene}"))
    };
    let vs_embree = |spec: &str, scene: &str| {
        let e = embree(spec, scene);
        min_max(
            read(&format!("results/{spec}/table.csv"))
                .iter()
                .filter(|r| r["backend"] == "cpu" && r["scene"] == scene)
                .map(|r| e / f(r, "estimate_s")),
        )
    };
    let (alo, ahi) = vs_embree("shadows2010_figure7", "bunny");
    let (blo, _) = vs_embree("shadows2010_figure8", "all");
    let (va, vb) = (
        vs_embree("reflections2010_figure9", "view_a"),
        vs_embree("reflections2010_figure9", "view_b"),
    );
    let text = format!(
        "soft shadows {alo:.1}–{ahi:.1}× Embree on Figure 7 and {blo:.1}× on Figure 8 (most of a \
         wide floor's shadow rays miss every sphere, one box test for Embree too), and glossy \
         reflections {:.1}–{:.1}× Embree on Figure 9",
        va.0.min(vb.0),
        va.1.max(vb.1),
    );
    c.quotes(
        "README.md",
        &text,
        "results/{shadows2010_figure7,shadows2010_figure8,reflections2010_figure9}/{table,methods}.csv",
    );
    // docs/results.md's Figure 7, 8 and 9 prose.
    let from = "results/shadows2010_figure7/{table,methods,raycast_sweep}.csv";
    let t7 = read("results/shadows2010_figure7/table.csv");
    let (flo, fhi) = min_max(
        t7.iter()
            .filter(|r| r["backend"] == "cpu")
            .map(|r| f(r, "estimate_s")),
    );
    let rc = f(&t7[0], "raycast_s");
    let sweep = read("results/shadows2010_figure7/raycast_sweep.csv");
    let four = sweep.iter().find(|r| r["rays_per_point"] == "4").unwrap();
    let best = min_max(t7.iter().map(|r| f(r, "rms_vs_truth"))).0;
    let text = format!(
        "The fields took {flo:.2}–{fhi:.2} s, our ray cast {rc:.2} s and Embree {:.2} s on the same \
         {:.1} M shadow rays ({:.1}–{:.1}× ours, {alo:.1}–{ahi:.1}× Embree), yet at equal error ray \
         casting wins: with 4 rays per light ours takes {:.2} s and is {:.1} from the truth, nearer \
         than the best field ({best:.1}).",
        embree("shadows2010_figure7", "bunny"),
        f(&t7[0], "rays_cast") / 1e6,
        rc / fhi,
        rc / flo,
        f(four, "raycast_s"),
        f(four, "rms_vs_truth"),
    );
    assert!(
        f(four, "rms_vs_truth") < best,
        "docs/results.md says the 4-ray ray cast is nearer"
    );
    c.quotes("docs/results.md", &text, from);
    let text = format!(
        "Embree took {:.3} s on the same rays, {blo:.1}× slower than the field.",
        embree("shadows2010_figure8", "all")
    );
    c.quotes(
        "docs/results.md",
        &text,
        "results/shadows2010_figure8/methods.csv",
    );
    let text = format!(
        "Embree's packets answer the same rays in {:.3} s (view_a) and {:.3} s (view_b): the field \
         is {:.1}–{:.1}× Embree here, it loses.",
        embree("reflections2010_figure9", "view_a"),
        embree("reflections2010_figure9", "view_b"),
        va.0.min(vb.0),
        va.1.max(vb.1),
    );
    assert!(
        va.1.max(vb.1) <= 1.0,
        "docs/results.md says the field loses on Figure 9"
    );
    c.quotes(
        "docs/results.md",
        &text,
        "results/reflections2010_figure9/methods.csv",
    );
    // lavapipe: the GPU field kernel over the GPU ray cast, against the CPU's, quick runs.
    let ratio = |spec: &str, backend: &str| {
        min_max(
            read(&format!("results/quick/{spec}/table.csv"))
                .iter()
                .filter(|r| r["backend"] == backend)
                .map(|r| f(r, "raycast_s") / f(r, "estimate_s")),
        )
    };
    let (g7, c7) = (
        ratio("shadows2010_figure7", "gpu"),
        ratio("shadows2010_figure7", "cpu"),
    );
    let (g8, c8) = (
        ratio("shadows2010_figure8", "gpu"),
        ratio("shadows2010_figure8", "cpu"),
    );
    let (g9, c9) = (
        ratio("reflections2010_figure9", "gpu"),
        ratio("reflections2010_figure9", "cpu"),
    );
    let text = format!(
        "over GPU ray casting {:.1}× and {:.1}× on Figures 7 and 8 against the CPU's {:.1}× and \
         {:.1}×, and {:.1}–{:.1}× against {:.1}–{:.1}× on Figure 9.",
        g7.0, g8.0, c7.0, c8.0, g9.0, g9.1, c9.0, c9.1
    );
    c.quotes(
        "README.md",
        &text,
        "results/quick/{shadows2010_figure7,shadows2010_figure8,reflections2010_figure9}/table.csv",
    );
}

/// 2010 models table: our columns per caster, as docs/results.md's table writes them.
fn models_table(c: &mut Claims) {
    let from = "results/ao2010_models/table.csv";
    for r in read(from).iter().filter(|r| r["backend"] == "cpu") {
        let tris = f(r, "caster_triangles") as u64;
        let label = match r["scene"].as_str() {
            "igea" => format!("Igea ({})", with_commas(tris)),
            "elephant" => format!("elephant ({}; paper 157,160)", with_commas(tris)),
            s => format!("{s} ({})", with_commas(tris)),
        };
        let rays = f(r, "receiver_points") * f(r, "rays_per_point") / 1e6;
        let text = format!(
            "| {label} | {:.2} ({:.0}) | {:.2} ({:.0}) | {:.2} |",
            f(r, "estimate_s"),
            rays / f(r, "estimate_s"),
            f(r, "raycast_s"),
            rays / f(r, "raycast_s"),
            f(r, "rms_image"),
        );
        c.quotes("docs/results.md", &text, from);
    }
    let rows: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["backend"] == "cpu")
        .collect();
    let scene = |s: &str| rows.iter().find(|r| r["scene"] == s).unwrap();
    let (lo, hi) = min_max(rows.iter().map(|r| f(r, "raycast_s") / f(r, "estimate_s")));
    let text = format!(
        "the 12,064-triangle elephant took {:.2} s and the 67,170-triangle Igea {:.2} s. The field \
         is {lo:.1}–{hi:.1}× faster on the same rays",
        f(scene("elephant"), "raycast_s"),
        f(scene("igea"), "raycast_s"),
    );
    c.quotes("docs/results.md", &text, from);
}

/// 2010 Figure 5: intra- against inter-object AO, the table and the cost per ray.
fn figure5_intra(c: &mut Claims) {
    let from = "results/ao2010_figure5/table.csv";
    let rows: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["backend"] == "cpu")
        .collect();
    let cell = |scene: &str, n: &str, sel: &str| {
        rows.iter()
            .find(|r| r["scene"] == scene && r["positional_samples"] == n && r["selection"] == sel)
            .unwrap_or_else(|| panic!("no {scene} {n} {sel} row"))
    };
    let mut ratios = Vec::new();
    for n in ["1090", "4226", "16642"] {
        for sel in ["nearest", "interpolated"] {
            let (a, e) = (cell("intra", n, sel), cell("inter", n, sel));
            let ratio = f(e, "estimate_mrays_s") / f(a, "estimate_mrays_s");
            ratios.push(ratio);
            let text = format!(
                "| {n} | {sel} | {:.2} | {:.2} | {:.2} | {:.2} | {ratio:.1}× |",
                f(a, "rms_image"),
                f(a, "grain"),
                f(e, "rms_image"),
                f(e, "grain"),
            );
            c.quotes("docs/results.md", &text, from);
        }
    }
    let (lo, hi) = min_max(ratios);
    let near = |scene: &str| {
        min_max(["1090", "4226", "16642"].map(|n| f(cell(scene, n, "nearest"), "estimate_mrays_s")))
    };
    let ((alo, ahi), (elo, ehi)) = (near("intra"), near("inter"));
    let text = format!(
        "intra-object lookups cost {lo:.1}–{hi:.1}× inter-object ones per ray ({alo:.0}–{ahi:.0} \
         against {elo:.0}–{ehi:.0} Mrays/s with nearest selection"
    );
    c.quotes("docs/results.md", &text, from);
}

/// The "which method wins where" table: per scene and method family, the lowest error against
/// the converged reference with its time, and the fastest setting with its error.
fn wins_table() -> String {
    let mut out = String::from(
        "| scene | method | lowest error (its time, ms) | fastest, ms (its error) |\n|---|---|---|---|\n",
    );
    let scenes = [
        ("2008 Figure 6, vertex AO", "figure6", "bunny"),
        ("2010 Figure 3, per-pixel AO", "ao2010_figure3", "bunny"),
        (
            "2010 Figure 7, soft shadows",
            "shadows2010_figure7",
            "bunny",
        ),
    ];
    for (label, spec, scene) in scenes {
        let cpu = |r: &Row| r["backend"] == "cpu" && r["scene"] == scene;
        let table: Vec<Row> = read(&format!("results/{spec}/table.csv"))
            .into_iter()
            .filter(cpu)
            .collect();
        let methods: Vec<Row> = read(&format!("results/{spec}/methods.csv"))
            .into_iter()
            .filter(cpu)
            .collect();
        let mut families: Vec<(&str, Vec<&Row>)> =
            vec![("visibility field", table.iter().collect())];
        for (name, m, q) in [
            ("ray casting (ours)", "raycast", ""),
            ("Embree 3", "embree", ""),
            ("SDF, sphere traced", "sdf", "trace"),
            ("SDF, cone traced", "sdf", "cone"),
            ("AO field", "aofield", ""),
        ] {
            let rows: Vec<&Row> = methods
                .iter()
                .filter(|r| r["method"] == m && r.get("query").map_or("", |v| v.as_str()) == q)
                .collect();
            if !rows.is_empty() {
                families.push((name, rows));
            }
        }
        for (name, rows) in families {
            let by = |col: &str| {
                *rows
                    .iter()
                    .min_by(|a, b| f(a, col).total_cmp(&f(b, col)))
                    .unwrap()
            };
            let (best, fast) = (by("rms_vs_truth"), by("estimate_s"));
            let ms = |r: &Row| {
                let t = 1e3 * f(r, "estimate_s");
                if t < 10.0 {
                    format!("{t:.2}")
                } else {
                    format!("{t:.0}")
                }
            };
            out.push_str(&format!(
                "| {label} | {name} | {:.2} ({}) | {} ({:.2}) |\n",
                f(best, "rms_vs_truth"),
                ms(best),
                ms(fast),
                f(fast, "rms_vs_truth"),
            ));
        }
    }
    out
}

fn wins(c: &mut Claims) {
    let text = wins_table();
    if std::env::var("VISFIELD_PRINT_WINS").is_ok() {
        println!("{text}");
    }
    let from = "results/{figure6,ao2010_figure3,shadows2010_figure7}/{table,methods}.csv";
    c.quotes("docs/results.md", &text, from);
}

/// The 2008 Figure 8 scene animated: the field's per-frame error against the static scene's, and
/// each method's mean frame time.
fn animated_figure8(c: &mut Claims) {
    let from = "results/dynamic2008_figure8/frames.csv";
    let rows = read(from);
    let of = |m: &str| -> Vec<&Row> { rows.iter().filter(|r| r["method"] == m).collect() };
    let field = of("field");
    let (lo, hi) = min_max(field.iter().map(|r| f(r, "rms_vs_truth")));
    let still = read("results/figure8/table.csv")
        .into_iter()
        .find(|r| r["backend"] == "cpu" && r["scene"] == "multi")
        .map(|r| f(&r, "rms_vs_truth"))
        .expect("figure8's multi row");
    let overlapping = field
        .iter()
        .filter(|r| f(r, "sphere_overlaps") > 0.0)
        .count();
    let mean = |m: &str| {
        let v = of(m);
        v.iter().map(|r| f(r, "frame_s")).sum::<f64>() / v.len() as f64
    };
    let text = format!(
        "the field's error against each frame's converged reference is {lo:.2}–{hi:.2} over the \
         {} frames, against {still:.2} for the static scene ({:.2}–{:.2}×), the {overlapping} \
         frames where two casters' spheres overlap included. Mean frame: the field {:.2} s \
         (every sphere tested: {:.2} s), Embree's instances {:.2} s, Embree rebuilt {:.2} s, our \
         world BVH rebuilt {:.2} s, two levels {:.2} s",
        field.len(),
        lo / still,
        hi / still,
        mean("field"),
        mean("field_every_sphere"),
        mean("embree_instances"),
        mean("embree_rebuild"),
        mean("world_rebuild"),
        mean("two_level"),
    );
    c.quotes("docs/results.md", &text, from);
}

/// The GPU path per frame (the "gpu" backend of `dynamic2008_figure8`): the GPU twins against
/// their CPU twins on every frame, and their frame times.
fn gpu_frames(c: &mut Claims) {
    let (d_rms, d_mean, pairs) = gpu_moving::twin_gaps(
        &read("results/dynamic2008_figure8/frames.csv"),
        &[
            ("world_rebuild@gpu", "world_rebuild"),
            ("field_every_sphere@gpu", "field_every_sphere"),
        ],
    );
    let from = "results/dynamic2008_figure8/frames.csv";
    let rows = read(from);
    let of = |m: &str| -> Vec<&Row> { rows.iter().filter(|r| r["method"] == m).collect() };
    let mean = |m: &str, col: &str| {
        let v = of(m);
        assert!(!v.is_empty(), "no {m} rows in {from}");
        v.iter().map(|r| f(r, col)).sum::<f64>() / v.len() as f64
    };
    let text = format!(
        "Over the {pairs} frames and methods with a GPU twin, the GPU's error against the \
         same-ray ray cast differs from the CPU's by at most {d_rms:.2e} and its mean value by at \
         most {d_mean:.2e}. A frame of the animated Figure 8 on lavapipe: the field kernel {:.3} s ({:.4} s \
         of it moving the instances), the GPU ray caster {:.3} s ({:.3} s of it rebuilding and \
         uploading the world BVH)",
        mean("field_every_sphere@gpu", "frame_s"),
        mean("field_every_sphere@gpu", "update_s"),
        mean("world_rebuild@gpu", "frame_s"),
        mean("world_rebuild@gpu", "update_s"),
    );
    c.quotes("docs/results.md", &text, from);
}

/// The per-pixel crowd (`experiments/dynamic2010_crowd.json`): each method's mean frame, the
/// field's gains and its error per frame against ray casting's.
fn crowd_pixels(c: &mut Claims) {
    let short = crowd_pixels_of(c, "dynamic2010_crowd");
    c.quotes("README.md", &short, "results/dynamic2010_crowd/frames.csv");
    // The same crowd under spherical lights, in a glossy floor and through Sponza: the long
    // text only.
    crowd_pixels_of(c, "dynamic2010_crowd_shadows");
    crowd_pixels_of(c, "dynamic2010_crowd_reflections");
    crowd_pixels_of(c, "dynamic2010_crowd_sponza");
}

/// [`crowd_pixels`] of one animated spec's committed run: quotes its long text in
/// docs/results.md and returns README's short one.
fn crowd_pixels_of(c: &mut Claims, name: &str) -> String {
    let from = format!("results/{name}/frames.csv");
    let from = from.as_str();
    let rows = read(from);
    let of = |m: &str| -> Vec<&Row> { rows.iter().filter(|r| r["method"] == m).collect() };
    let mean = |m: &str, col: &str| {
        let v = of(m);
        v.iter().map(|r| f(r, col)).sum::<f64>() / v.len() as f64
    };
    let field = of("field");
    let (lo, hi) = min_max(field.iter().map(|r| f(r, "rms_vs_truth")));
    let (rlo, rhi) = min_max(of("world_rebuild").iter().map(|r| f(r, "rms_vs_truth")));
    let (plo, phi) = min_max(field.iter().map(|r| f(r, "points")));
    let frame = |m: &str| mean(m, "frame_s");
    let spec: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join(format!("results/{name}/spec.json"))).unwrap(),
    )
    .unwrap();
    let casters = spec["scenes"][0]["instances"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|i| i["caster"] == true)
        .count();
    let text = format!(
        "{} casters ({} triangles) over {} frames, {}–{} receiver pixels a frame, {} rays each. \
         Mean frame: the field {:.3} s (every sphere tested: {:.3} s), Embree's instances \
         {:.3} s, Embree rebuilt {:.3} s, our world BVH rebuilt {:.3} s, two levels {:.3} s: the \
         field's gain over Embree's instances {:.1}×, over Embree rebuilt {:.1}×, over the world \
         rebuild {:.1}×. The field's error against each frame's converged reference is \
         {lo:.2}–{hi:.2}, ray casting's {rlo:.2}–{rhi:.2}",
        casters,
        with_commas(f(field[0], "caster_triangles") as u64),
        field.len(),
        with_commas(plo as u64),
        with_commas(phi as u64),
        f(field[0], "rays") / f(field[0], "points"),
        frame("field"),
        frame("field_every_sphere"),
        frame("embree_instances"),
        frame("embree_rebuild"),
        frame("world_rebuild"),
        frame("two_level"),
        frame("embree_instances") / frame("field"),
        frame("embree_rebuild") / frame("field"),
        frame("world_rebuild") / frame("field"),
    );
    c.quotes("docs/results.md", &text, from);
    format!(
        "per pixel at {casters} casters (`results/{name}/`, AO at every receiver pixel of each \
         frame's G-buffer) the field's gain is {:.1}× over Embree's instances, {:.1}× over \
         Embree rebuilt and {:.1}× over the world rebuild",
        frame("embree_instances") / frame("field"),
        frame("embree_rebuild") / frame("field"),
        frame("world_rebuild") / frame("field"),
    )
}

/// The 2010 figures' errors taken as the paper takes them: Figure 3's over every pixel that
/// sees a surface, Figures 7 and 8 on the shaded images; beside ours and the paper's.
fn paper_pixel_sets(c: &mut Claims) {
    let cpu = |spec: &str, scene: &str| -> Vec<Row> {
        read(&format!("results/{spec}/table.csv"))
            .into_iter()
            .filter(|r| r["backend"] == "cpu" && r["scene"] == scene)
            .collect()
    };
    let range = |rows: &[Row], col: &str| {
        let (lo, hi) = min_max(rows.iter().map(|r| f(r, col)));
        match format!("{lo:.2}") {
            one if one == format!("{hi:.2}") => one,
            lo => format!("{lo}–{hi:.2}"),
        }
    };
    let paper = |spec: &str| {
        let rows = read(&format!("results/{spec}/paper_vs_ours.csv"));
        let (lo, hi) = min_max(
            rows.iter()
                .filter_map(|r| r.get("paper_rms").and_then(|v| v.parse::<f64>().ok())),
        );
        format!("{lo:.2}–{hi:.2}")
    };
    let fig3 = cpu("ao2010_figure3", "bunny");
    let text = format!(
        "Over the paper's pixel set, every pixel that sees a surface with the bunny's pixels \
         (drawn unevaluated, the same in both images) counted as exact (`rms_image_window`), the \
         fields' same-ray RMS is {} against {} over the receiver pixels (`rms_image`); the \
         paper's is {}",
        range(&fig3, "rms_image_window"),
        range(&fig3, "rms_image"),
        paper("ao2010_figure3"),
    );
    c.quotes("docs/results.md", &text, "results/ao2010_figure3/table.csv");
    let fig7 = cpu("shadows2010_figure7", "bunny");
    let fig8 = cpu("shadows2010_figure8", "all");
    let text = format!(
        "On the shaded images (`rms_image_shaded`: the light fraction times the unshadowed direct \
         light, the images the paper compares) the fields' same-ray RMS is {} on Figure 7, \
         against {} on the light fraction (`rms_image`) and the paper's {}; on Figure 8 it is {} \
         against {}",
        range(&fig7, "rms_image_shaded"),
        range(&fig7, "rms_image"),
        paper("shadows2010_figure7"),
        range(&fig8, "rms_image_shaded"),
        range(&fig8, "rms_image"),
    );
    c.quotes(
        "docs/results.md",
        &text,
        "results/shadows2010_figure7/table.csv",
    );
}

/// The peers' GPU rows against their CPU twins (same scene and setting) in the runs that have
/// them: how many pairs, the largest difference of the error against the converged reference.
fn peers_gpu(c: &mut Claims) {
    let (mut pairs, mut exact) = (0, 0);
    let mut worst = 0.0f64;
    for spec in ["figure6", "ao2010_figure3", "shadows2010_figure7"] {
        let rows = read(&format!("results/{spec}/methods.csv"));
        for g in rows.iter().filter(|r| r["backend"] == "gpu") {
            let twin = rows
                .iter()
                .find(|r| {
                    r["backend"] == "cpu"
                        && r["scene"] == g["scene"]
                        && r["setting"] == g["setting"]
                })
                .unwrap_or_else(|| panic!("{spec}: no CPU twin of {}", g["setting"]));
            pairs += 1;
            let d = (f(g, "rms_vs_truth") - f(twin, "rms_vs_truth")).abs();
            worst = worst.max(d);
            exact += (d == 0.0) as usize;
        }
    }
    let text = format!(
        "over the {pairs} settings with a GPU row in 2008 Figure 6, 2010 Figure 3 and 2010 Figure \
         7, the GPU row's error against the converged reference differs from its CPU twin's by at \
         most {} ({exact} of them not at all)",
        sci(worst)
    );
    c.quotes("docs/results.md", &text, "results/figure6/methods.csv");
}

/// Figure 6's peers at about a field's bytes: for the field 1090 × 32² u8, each peer family's
/// setting whose bytes are nearest to the field's (on a log scale), with its error and time.
fn equal_bytes(c: &mut Claims) {
    let from = "results/figure6/methods.csv";
    let field = read("results/figure6/table.csv")
        .into_iter()
        .find(|r| {
            r["backend"] == "cpu"
                && r["positional_samples"] == "1090"
                && r["directional_res"] == "32"
                && r["precision"] == "u8"
        })
        .expect("figure6's 1090 × 32² u8 cell");
    let fb = f(&field, "field_bytes");
    let methods: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["backend"] == "cpu" && !r["bytes"].is_empty())
        .collect();
    let nearest = |family: &dyn Fn(&Row) -> bool| -> &Row {
        methods
            .iter()
            .filter(|r| family(r))
            .min_by(|a, b| {
                let d = |r: &Row| (f(r, "bytes") / fb).ln().abs();
                d(a).partial_cmp(&d(b)).unwrap()
            })
            .expect("a setting of the family")
    };
    let say = |r: &Row| {
        format!(
            "{} ({} bytes: {:.2} in {:.2} ms)",
            r["setting"],
            with_commas(f(r, "bytes") as u64),
            f(r, "rms_vs_truth"),
            1e3 * f(r, "estimate_s")
        )
    };
    let trace = nearest(&|r| r["method"] == "sdf" && r["query"] == "trace");
    let cone = nearest(&|r| r["method"] == "sdf" && r["query"] == "cone");
    let aofield = nearest(&|r| r["method"] == "aofield");
    let text = format!(
        "At about the bytes of the field 1090 × 32² u8 ({} bytes: {:.2} against the converged \
         reference in {:.2} ms), the nearest settings are {}, {} and {}",
        with_commas(fb as u64),
        f(&field, "rms_vs_truth"),
        1e3 * f(&field, "estimate_s"),
        say(trace),
        say(cone),
        say(aofield),
    );
    c.quotes("docs/results.md", &text, from);
}

/// 2010 Figure 9: the floor pixels inside the bunny's bounding sphere, their share of the
/// squared error against the converged lobe, and the same-ray error without them beside the
/// paper's.
fn figure9_population(c: &mut Claims) {
    let from = "results/reflections2010_figure9/table.csv";
    let rows: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["backend"] == "cpu")
        .collect();
    let paper = read("results/reflections2010_figure9/paper_vs_ours.csv");
    let view = |v: &str| -> Vec<&Row> { rows.iter().filter(|r| r["scene"] == v).collect() };
    let range = |rs: &[&Row], col: &str| {
        let (lo, hi) = min_max(rs.iter().map(|r| f(r, col)));
        format!("{lo:.2}–{hi:.2}")
    };
    let paper_range = |v: &str| {
        let (lo, hi) = min_max(
            paper
                .iter()
                .filter(|r| r["label"].starts_with(v))
                .map(|r| f(r, "paper_rms")),
        );
        format!("{lo:.2}–{hi:.2}")
    };
    let share = |r: &Row| {
        let (k, n) = (f(r, "points_in_spheres"), f(r, "receiver_points"));
        let (inside, all) = (f(r, "rms_vs_truth_in_spheres"), f(r, "rms_vs_truth"));
        100.0 * inside * inside * k / (all * all * n)
    };
    let (a, b) = (view("view_a"), view("view_b"));
    let (slo, shi) = min_max(rows.iter().map(share));
    let pct = |v: &[&Row]| 100.0 * f(v[0], "points_in_spheres") / f(v[0], "receiver_points");
    let text = format!(
        "The {} (view_a) and {} (view_b) floor pixels inside the bunny's bounding sphere, {:.1}% \
         and {:.1}% of the receiver pixels, carry {slo:.0}–{shi:.0}% of the fields' squared error \
         against the converged lobe; without them the fields' same-ray RMS (per pixel, \
         unquantised) is {} (view_a) and {} (view_b), against the paper's {} and {}",
        with_commas(f(a[0], "points_in_spheres") as u64),
        with_commas(f(b[0], "points_in_spheres") as u64),
        pct(&a),
        pct(&b),
        range(&a, "rms_outside_spheres"),
        range(&b, "rms_outside_spheres"),
        paper_range("view_a"),
        paper_range("view_b"),
    );
    c.quotes("docs/results.md", &text, from);
}

/// The per-object peers in the moving crowd at 64 casters: mean frame and errors beside the
/// field's and ray casting's (`results/dynamic/sweep_frames.csv`).
fn crowd_peers(c: &mut Claims) {
    let from = "results/dynamic/sweep_frames.csv";
    let rows: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["sweep"] == "crowd" && r["casters"] == "64")
        .collect();
    let mean = |m: &str, col: &str| {
        let v: Vec<f64> = rows
            .iter()
            .filter(|r| r["method"] == m)
            .map(|r| f(r, col))
            .collect();
        assert!(!v.is_empty(), "no {m} rows at 64 casters");
        v.iter().sum::<f64>() / v.len() as f64
    };
    let say = |m: &str| {
        format!(
            "{:.1} ms a frame ({:.2} from ray casting on the same rays, {:.2} from the converged \
             reference)",
            1e3 * mean(m, "frame_s"),
            mean(m, "rms_vs_raycast"),
            mean(m, "rms_vs_truth")
        )
    };
    let text = format!(
        "At 64 casters, mesh distance fields sphere traced on the same rays take {}, AO fields {}, \
         the visibility field {}; Embree's instances take {:.1} ms, and the 64-ray ray cast is \
         {:.2} from the converged reference",
        say("sdf"),
        say("aofield"),
        say("field"),
        1e3 * mean("embree_instances", "frame_s"),
        mean("world_rebuild", "rms_vs_truth"),
    );
    c.quotes("docs/results.md", &text, from);
}

/// The field's flicker against ray casting's in the moving crowd, per caster count
/// (`results/dynamic/sweep_frames.csv`: the mean over the frame pairs of each method's `flicker`, the
/// ray cast being the world rebuild, whose rays every ray caster shares).
fn crowd_flicker(c: &mut Claims) {
    let from = "results/dynamic/sweep_frames.csv";
    let rows: Vec<Row> = read(from)
        .into_iter()
        .filter(|r| r["sweep"] == "crowd" && !r["flicker"].is_empty())
        .collect();
    let mut counts: Vec<u64> = rows.iter().map(|r| f(r, "casters") as u64).collect();
    counts.dedup();
    let mean = |n: u64, m: &str| {
        let v: Vec<f64> = (rows.iter())
            .filter(|r| f(r, "casters") as u64 == n && r["method"] == m)
            .map(|r| f(r, "flicker"))
            .collect();
        assert!(!v.is_empty(), "no {m} flicker at {n} casters in {from}");
        v.iter().sum::<f64>() / v.len() as f64
    };
    let mut text = String::from(
        "| casters | field | ray casting (same rays) | AO fields | mesh distance fields |\n|---|---|---|---|---|\n",
    );
    for n in counts {
        text.push_str(&format!(
            "| {n} | {:.2} | {:.2} | {:.2} | {:.2} |\n",
            mean(n, "field"),
            mean(n, "world_rebuild"),
            mean(n, "aofield"),
            mean(n, "sdf"),
        ));
    }
    c.quotes("docs/results.md", &text, from);
}

/// The per-pixel crowds' flicker and frame-to-frame FLIP (`frames.csv` of the animated
/// crowd specs): the field's beside the same-ray ray cast's.
fn crowd_pixels_flicker(c: &mut Claims) {
    for name in [
        "dynamic2010_crowd",
        "dynamic2010_crowd_shadows",
        "dynamic2010_crowd_reflections",
        "dynamic2010_crowd_sponza",
    ] {
        let from = format!("results/{name}/frames.csv");
        let rows: Vec<Row> = read(&from)
            .into_iter()
            .filter(|r| r["method"] == "field" && !r["flicker"].is_empty())
            .collect();
        assert!(!rows.is_empty(), "no field flicker in {from}");
        let mean = |col: &str| rows.iter().map(|r| f(r, col)).sum::<f64>() / rows.len() as f64;
        let text = format!(
            "| `{name}` | {:.2} | {:.2} | {:.3} | {:.3} |",
            mean("flicker"),
            mean("raycast_flicker"),
            mean("flip_frame_change"),
            mean("truth_flip_frame_change"),
        );
        c.quotes("docs/results.md", &text, &from);
    }
}

/// Instructions per ray of the moving crowd's query, the field against Embree's instances
/// (`results/crowd_instructions/table.csv`, `scripts/crowd_instructions.sh`).
fn crowd_instructions(c: &mut Claims) {
    let from = "results/crowd_instructions/table.csv";
    let rows = read(from);
    let per_ray = |n: &str, m: &str| {
        let r = (rows.iter())
            .find(|r| r["casters"] == n && r["method"] == m)
            .unwrap_or_else(|| panic!("no {m} row at {n} casters in {from}"));
        f(r, "instructions_per_ray")
    };
    let mut text = String::from(
        "| casters | field | Embree's instances | Embree / field |\n|---|---|---|---|\n",
    );
    for n in ["1", "4", "16", "64", "256"] {
        let (fi, e) = (per_ray(n, "field"), per_ray(n, "embree_instances"));
        text.push_str(&format!("| {n} | {fi:.1} | {e:.1} | {:.2}× |\n", e / fi));
    }
    c.quotes("docs/performance.md", &text, from);
    let part = |n: &str, col: &str| {
        let r = (rows.iter())
            .find(|r| r["casters"] == n && r["method"] == "field")
            .unwrap_or_else(|| panic!("no field row at {n} casters in {from}"));
        f(r, col)
    };
    let total = per_ray("64", "field");
    let (node, calls, reads) = (
        part("64", "node_tests_per_ray"),
        part("64", "instance_calls_per_ray"),
        part("64", "reads_per_ray"),
    );
    let text = format!(
        "at 64 casters, of the field's {total:.1} instructions a ray {node:.1} are the top \
         level's node tests, {:.1} the rest of its traversal and {calls:.1} the per-instance \
         calls, of which {reads:.1} are the reads of the stored distances",
        total - node - calls,
    );
    c.quotes("docs/performance.md", &text, from);
    let text = format!(
        "from 1 to 256 casters the field's instructions per ray grow {:.1}×, Embree's {:.1}×",
        per_ray("256", "field") / per_ray("1", "field"),
        per_ray("256", "embree_instances") / per_ray("1", "embree_instances"),
    );
    c.quotes("docs/performance.md", &text, from);
}

/// The pairs of images whose order under FLIP differs from their order under RMS
/// ([`flip::rankings`]), and the 1-bit field's ratios to u8 under both.
fn flip_rankings(c: &mut Claims) {
    flip::rankings(c);
    let from = "results/figure7/table.csv";
    let rows = read(from);
    let at = |precision: &str| {
        (rows.iter())
            .find(|r| r["precision"] == precision && r["backend"] == "cpu")
            .unwrap_or_else(|| panic!("no {precision} row in {from}"))
    };
    let (bit, u8) = (at("bit1"), at("u8"));
    let text = format!(
        "the 1-bit field's same-ray RMS is {:.1} times the u8 field's, its mean FLIP {:.1} times",
        f(bit, "rms_image") / f(u8, "rms_image"),
        f(bit, "flip_mean") / f(u8, "flip_mean"),
    );
    c.quotes("docs/results.md", &text, from);
}

/// `experiment try` on the small bunny (docs/own_mesh.md): the 4226 × 32² field's verdict line
/// as the command prints it (RMS against ray casting on the same rays, speed against ray casting
/// and Embree, bytes), and the range of RMS and speed over the four field sizes.
fn try_mesh(c: &mut Claims) {
    let from = "results/try_bunny_npm/table.csv and methods.csv";
    let rows: Vec<Row> = read("results/try_bunny_npm/table.csv")
        .into_iter()
        .filter(|r| r["backend"] == "cpu")
        .collect();
    assert_eq!(rows.len(), 4, "{from}: the four field sizes");
    let embree = read("results/try_bunny_npm/methods.csv")
        .into_iter()
        .find(|r| r["method"] == "embree")
        .expect("an Embree row");
    let speed = |r: &Row| f(r, "raycast_s") / f(r, "estimate_s");
    let r = rows
        .iter()
        .find(|r| r["positional_samples"] == "4226" && r["directional_res"] == "32")
        .expect("a 4226 × 32² row");
    let text = format!(
        "4226 × 32² u8: RMS {:.1} of 255, {:.1}× faster than ray casting, {:.1}× faster than \
         Embree, {:.1} MiB",
        f(r, "rms_image"),
        speed(r),
        f(&embree, "estimate_s") / f(r, "estimate_s"),
        f(r, "field_bytes") / (1u64 << 20) as f64
    );
    c.quotes("docs/own_mesh.md", &text, from);
    let (rms_lo, rms_hi) = min_max(rows.iter().map(|r| f(r, "rms_image")));
    let (s_lo, s_hi) = min_max(rows.iter().map(speed));
    let text =
        format!("RMS {rms_hi:.1} to {rms_lo:.1} at {s_lo:.1}–{s_hi:.1}× ray casting's speed");
    c.quotes("docs/own_mesh.md", &text, from);
}

#[test]
fn quoted_numbers_match_the_committed_csvs() {
    let mut c = Claims::new();
    figure6(&mut c);
    figure4(&mut c);
    figure9(&mut c);
    sponza(&mut c);
    figure8_and_figure3(&mut c);
    figure3_population(&mut c);
    performance(&mut c);
    dynamic(&mut c);
    headline_2010(&mut c);
    peers(&mut c);
    animated_figure8(&mut c);
    crowd_pixels(&mut c);
    gpu_frames(&mut c);
    gpu_moving::gpu_moving(&mut c);
    paper_pixel_sets(&mut c);
    peers_gpu(&mut c);
    equal_bytes(&mut c);
    figure9_population(&mut c);
    crowd_peers(&mut c);
    crowd_flicker(&mut c);
    crowd_pixels_flicker(&mut c);
    crowd_instructions(&mut c);
    flip_rankings(&mut c);
    wins(&mut c);
    figure5_intra(&mut c);
    models_table(&mut c);
    performance_prose(&mut c);
    secondary_rays(&mut c);
    gpu_and_figure8_lookups(&mut c);
    try_mesh(&mut c);
    assert!(
        c.missing.is_empty(),
        "{} of {} quoted numbers differ from results/:\n{}",
        c.missing.len(),
        c.count,
        c.missing.join("\n")
    );
}

/// The specs' claims of equality and difference between precisions, which README and
/// docs/results.md state: without an AO radius (figure7_unbounded) every precision keeps hit or
/// miss, so its 1-bit and u8 fields agree to the bit (`pairs.csv`: RMS 0);
/// with a linear falloff (figure7_linear) every stored distance counts and they differ.
#[test]
fn the_committed_precision_pairs_hold_the_specs_claims() {
    let rows = read("results/figure7_unbounded/pairs.csv");
    assert!(!rows.is_empty(), "figure7_unbounded: no pairs");
    for r in &rows {
        for col in ["rms_vertex", "rms_image"] {
            assert_eq!(f(r, col), 0.0, "figure7_unbounded/pairs.csv {col}: {r:?}");
        }
    }
    let rows = read("results/figure7_linear/pairs.csv");
    assert!(!rows.is_empty());
    for r in &rows {
        assert!(f(r, "rms_vertex") > 0.1, "figure7_linear/pairs.csv: {r:?}");
    }
}

#[test]
fn the_formatting_helpers_write_what_the_docs_write() {
    assert_eq!(sci(4.4e-5), "4.4·10⁻⁵");
    assert_eq!(sci(0.0568), "5.7·10⁻²");
    assert_eq!(sci(9.96e-5), "1.0·10⁻⁴");
    assert_eq!(with_commas(6_667_488), "6,667,488");
    assert_eq!(with_commas(999), "999");
    assert_eq!(squash("a  b\n c"), "a b c");
}
