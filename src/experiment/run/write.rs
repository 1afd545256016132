//! The end of a run: the pair table, the CSV files, the per-point values, `run.json`, the spec
//! copy and the plots.

use super::steps::Runner;
use super::LoadedSpec;
use crate::experiment::metrics::{rms_u8, rms_unquantised};
use crate::experiment::outputs::{self, PairRow};
use crate::experiment::spec::Backend;
use crate::experiment::table::{write_table, Row, TableRow};
use crate::experiment::{Error, Result};

/// Writes `summary` as `out/run.json` and the spec as run as `out/spec.json`, atomically.
pub(super) fn write_summary(
    out: &std::path::Path,
    summary: &serde_json::Value,
    ls: &LoadedSpec,
) -> Result<()> {
    let p = out.join("run.json");
    let json = serde_json::to_string_pretty(summary).expect("run summary serialises");
    crate::io::write_atomic(&p, json.as_bytes()).map_err(Error::io(&p))?;
    let p = out.join("spec.json");
    crate::io::write_atomic(&p, ls.text.as_bytes()).map_err(Error::io(&p))
}

/// Each mesh of `scenes` as `run.json` lists it: its label and content hash (the field cache's
/// key), its counts, and for a user's file the path as the spec gives it and its bytes' sha256.
pub(super) fn meshes_json(scenes: &crate::experiment::scenes::Scenes) -> Vec<serde_json::Value> {
    scenes
        .meshes
        .iter()
        .map(|m| {
            serde_json::json!({
                "label": m.label,
                "mesh_sha256": m.sha256,
                "vertices": m.mesh.vertex_count(),
                "triangles": m.mesh.triangle_count(),
                "file": m.file,
            })
        })
        .collect()
}

impl Runner<'_> {
    /// RMS between every two cells that differ only in precision.
    fn pairs(&self) -> Vec<PairRow> {
        let vertex = self.kind.columns().vertex;
        let mut out = Vec::new();
        for (i, a) in self.results.iter().enumerate() {
            for b in &self.results[i + 1..] {
                let (ca, cb) = (self.plan.cells[a.cell], self.plan.cells[b.cell]);
                let same = ca.scene == cb.scene
                    && ca.geometry() == cb.geometry()
                    && ca.selection == cb.selection
                    && ca.backend == cb.backend
                    && ca.normal_bits == cb.normal_bits
                    && ca.params.precision != cb.params.precision;
                if !same {
                    continue;
                }
                let st = self.states[ca.scene].as_ref().expect("scene state");
                let rms_image = match (&a.image, &b.image, &st.ref_image) {
                    (Some(x), Some(y), Some((_, mask))) => {
                        Some(rms_u8(&x.data, &y.data, Some(mask)))
                    }
                    _ => None,
                };
                let scene = &self.scenes.scenes[ca.scene].name;
                out.push(PairRow {
                    scene: scene.clone(),
                    sphere: ca.params.sphere,
                    positional_samples: ca.params.count,
                    directional_res: ca.params.res,
                    layout: ca.params.layout,
                    selection: ca.selection,
                    backend: ca.backend,
                    precision_a: ca.params.precision,
                    precision_b: cb.params.precision,
                    rms_vertex: vertex.then(|| rms_unquantised(&a.values, &b.values)),
                    rms_image,
                    cell_a: ca.id(scene),
                    cell_b: cb.id(scene),
                });
            }
        }
        out
    }

    /// Per-point values of every scene whose kind has per-vertex columns: the reference and
    /// each cell, one column each (one per channel, `NAME_cC`, for a kind with channels).
    fn write_point_values(&self) -> Result<()> {
        if !self.kind.columns().vertex {
            return Ok(());
        }
        for (s, bs) in self.scenes.scenes.iter().enumerate() {
            let Some(st) = self.states[s].as_ref() else {
                continue;
            };
            let c = st.channels;
            let cols: Vec<_> = self
                .results
                .iter()
                .filter(|r| self.plan.cells[r.cell].scene == s)
                .collect();
            let mut text = String::from("point,x,y,z,crease");
            let mut names = vec!["reference".to_string()];
            if st.truth.is_some() {
                names.extend(["truth".to_string(), "truth_stderr".to_string()]);
            }
            names.extend(cols.iter().map(|r| self.plan.cells[r.cell].id(&bs.name)));
            for name in &names {
                for k in 0..c {
                    text.push(',');
                    text.push_str(name);
                    if c > 1 {
                        text.push_str(&format!("_c{k}"));
                    }
                }
            }
            text.push('\n');
            let push = |text: &mut String, v: &[f32], i: usize| {
                for x in &v[i * c..(i + 1) * c] {
                    text.push_str(&format!(",{x}"));
                }
            };
            for (i, p) in st.at.points.iter().enumerate() {
                let crease = st.at.crease[i] as u8;
                text.push_str(&format!("{i},{},{},{},{crease}", p.x, p.y, p.z));
                push(&mut text, &st.reference, i);
                if let Some(t) = &st.truth {
                    push(&mut text, &t.values, i);
                    push(&mut text, &t.stderr, i);
                }
                for r in &cols {
                    push(&mut text, &r.values, i);
                }
                text.push('\n');
            }
            let p = self.opts.out.join(format!("values_{}.csv", bs.name));
            crate::io::write_atomic(&p, text.as_bytes()).map_err(Error::io(&p))?;
        }
        Ok(())
    }

    /// Writes every output and returns the table rows in cell order.
    pub(super) fn finish(mut self, ls: &LoadedSpec) -> Result<Vec<Row>> {
        self.rows.sort_by_key(|(c, _)| *c);
        self.results.sort_by_key(|r| r.cell);
        // The sweep's rows in cell order too (they are made in step order), so that the
        // shards of a run (`--shard`, contiguous in cell order) concatenate into it.
        let ids: Vec<String> = (self.plan.cells.iter())
            .map(|c| c.id(&self.scenes.scenes[c.scene].name))
            .collect();
        (self.field_sweep).sort_by_key(|r| ids.iter().position(|id| *id == r.cell));
        let written: Vec<TableRow> = self.rows.iter().map(|(_, r)| r.clone()).collect();
        let rows: Vec<Row> = written.iter().map(|r| r.row.clone()).collect();
        let pairs = self.pairs();
        let (spec, opts, out) = (self.spec, self.opts, &self.opts.out);
        write_table(&out.join("table.csv"), &written)?;
        outputs::write_csv(&out.join("raycast_sweep.csv"), &self.sweep)?;
        if !self.field_sweep.is_empty() {
            outputs::write_csv(&out.join("field_sweep.csv"), &self.field_sweep)?;
        }
        if !pairs.is_empty() {
            outputs::write_csv(&out.join("pairs.csv"), &pairs)?;
        }
        if !self.method_rows.is_empty() {
            crate::experiment::columns::write_csv(&out.join("methods.csv"), &self.method_rows)?;
        }
        if let Some(paper) = &spec.paper {
            let t = crate::experiment::paper::RunTables {
                rows: &rows,
                sweep: &self.sweep,
                pairs: &pairs,
            };
            let pv = crate::experiment::paper::paper_vs_ours(paper, &t);
            outputs::write_csv(&out.join("paper_vs_ours.csv"), &pv)?;
        }
        self.write_point_values()?;
        let mut meta = crate::experiment::meta::RunMeta::collect(Some(&ls.text)).timed();
        meta.gpu_adapter = self.backends.get(&Backend::Gpu).map(|be| be.adapter());
        let scene_info: Vec<_> = self
            .scenes
            .scenes
            .iter()
            .zip(&self.states)
            .map(|(bs, st)| {
                let raycast: Option<Vec<_>> = st.as_ref().map(|st| {
                    st.raycast_s
                        .iter()
                        .map(|((b, k), s)| {
                            serde_json::json!({"backend": b, "rays_per_point": k * k, "seconds": s})
                        })
                        .collect()
                });
                serde_json::json!({
                    "name": bs.name,
                    "instances": bs.scene.instances.len(),
                    "points": st.as_ref().map(|st| st.at.len()),
                    "caster_triangles": bs.caster_triangles(),
                    "ray_offset": st.as_ref().map(|st| st.offset),
                    "crease_points": st.as_ref().map(|st| st.at.crease_count()),
                    "truth": st.as_ref().and_then(|st| st.truth.as_ref().map(|t| serde_json::json!({
                        "rays_per_point": t.rays_per_point,
                        "batches": t.batches,
                        "rms_stderr_255": t.rms_stderr_255(),
                        "max_stderr_255": t.max_stderr_255(),
                        "rounds": t.rounds,
                        "source": st.truth_source,
                    }))),
                    "raycast_s": raycast,
                })
            })
            .collect();
        let meshes = meshes_json(self.scenes);
        let plan = self.plan;
        let summary = serde_json::json!({
            "spec": ls.name,
            "spec_file": crate::experiment::meta::portable_path(&ls.path),
            "reproduces": spec.reproduces,
            "profile": if opts.quick { "quick" } else { "full" },
            "shard": opts.shard,
            "meta": meta,
            "render": self.kind.name(),
            "quantity": self.kind.answers().quantity(),
            "rays_per_point": spec.render.rays_per_point,
            "reference_rays_per_point": spec.reference.rays_per_point,
            "seed": spec.reference.seed,
            "seeds": spec.reference.seeds,
            "truth": spec.reference.truth,
            "flip": crate::experiment::flip::metadata(),
            "timing": format!(
                "stages under {} s: best of {} runs",
                opts.short_stage_s, opts.repeats
            ),
            "cache": opts.supply.cache.as_deref().map(crate::experiment::meta::portable_path),
            "cache_limit_bytes": opts.supply.cache_limit,
            "plan": {
                "cells": plan.cells.len(),
                "methods": plan.methods,
                "bakes": plan.bakes(),
                "peak_field_bytes": plan.peak_field_bytes,
                "needs_gpu": plan.needs_gpu,
                "needs_normal_field": plan.needs_normal_field,
            },
            "scenes": scene_info,
            "skipped_methods": self.skipped_methods,
            "meshes": meshes,
            "effective_spec": spec,
        });
        write_summary(out, &summary, ls)?;
        if rows.is_empty() && opts.shard.is_some() {
            // An empty shard (more shards than field groups): its run.json and header-only
            // table.csv mark it done for `experiment merge`; there is nothing to plot.
            return Ok(rows);
        }
        let title = format!("{}{}", ls.name, if opts.quick { " (quick)" } else { "" });
        crate::experiment::figures::draw_all(out, &title)?;
        Ok(rows)
    }
}
