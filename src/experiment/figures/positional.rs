//! `rms_vs_positional.png`: the error against positional samples, one line per directional
//! resolution (and other varying axis), the devices' lines drawn once where they coincide (GPU
//! parity), and the paper's published values (`paper_vs_ours.csv`'s `paper_rms`, at the cell
//! each names) on the same axes, outlined and dashed in the colour of ours.

use super::facet::{pack, Group};
use super::labels::{merge_devices, Devices};
use super::{key, metric, RunData};
use crate::experiment::plot::{distinct, Axes, Figure, Marker, Panel, Series, Style, MAX_SERIES};
use crate::experiment::table::Row;

/// The figure (see the module's doc).
pub fn figure(run: &RunData) -> Figure {
    let (m, m_label) = metric(&run.rows);
    let devices = Devices::of(&run.rows);
    let scenes = run.scenes();
    let skip = ["backend", "scene"];
    // Every key in order, for a colour per key that is the same in every panel.
    let keys = distinct(run.rows.iter().map(|r| key(&run.rows, r, &skip)));
    let color = |k: &str| Style::palette(keys.iter().position(|o| o == k).unwrap_or(0)).color;
    let mut groups_by_scene: Vec<(String, Vec<Group>)> = Vec::new();
    let mut merged_any = false;
    let mut paper_any = false;
    for sc in &scenes {
        let rows: Vec<&Row> = run.rows.iter().filter(|r| &r.scene == sc).collect();
        let mut parts: Vec<super::labels::DevicePart> = Vec::new();
        for r in &rows {
            let Some(y) = m(r) else { continue };
            let k = key(&run.rows, r, &skip);
            let d = devices.name(r.backend).to_string();
            let p = (r.positional_samples as f64, y);
            match parts.iter_mut().find(|(pk, pd, _)| *pk == k && *pd == d) {
                Some(part) => part.2.push(p),
                None => parts.push((k, d, vec![p])),
            }
        }
        let ours = merge_devices(&parts, true);
        merged_any |= ours.len() < parts.len();
        // Each key's group: its own line(s), then the paper's (the count: 1 or 0 of them).
        let mut groups: Vec<(Group, usize)> = Vec::new();
        for (k, s) in ours {
            let ours = s.styled(Style::new(color(&k), Marker::Circle));
            // A key's lines (one per device where they differ) and the paper's stay together.
            if let Some((last, paper)) = groups.last_mut().filter(|(l, _)| l.title == k) {
                last.series.insert(last.series.len() - *paper, ours);
                continue;
            }
            let mut g = vec![ours];
            // The paper's values of this key's cells.
            let mut paper: Vec<(f64, f64)> = run
                .paper
                .iter()
                .filter_map(|p| {
                    let r = rows.iter().find(|r| r.cell == p.cell)?;
                    let y = p.paper_rms.filter(|_| key(&run.rows, r, &skip) == k)?;
                    Some((r.positional_samples as f64, y))
                })
                .collect();
            paper.dedup();
            let has_paper = !paper.is_empty();
            if has_paper {
                paper_any = true;
                let style = Style::new(color(&k), Marker::Circle).hollow().dashed();
                g.push(Series::line(format!("paper: {k}"), paper).styled(style));
            }
            let group = Group {
                title: k,
                series: g,
            };
            groups.push((group, has_paper as usize));
        }
        let groups = groups.into_iter().map(|(g, _)| g).collect();
        groups_by_scene.push((sc.to_string(), groups));
    }
    let total: usize = groups_by_scene
        .iter()
        .flat_map(|(_, g)| g.iter().map(|g| g.series.len()))
        .sum();
    let several = scenes.len() > 1;
    let panels: Vec<Panel> = if total <= MAX_SERIES {
        // One panel: the scene in each label where there are several.
        let series = groups_by_scene
            .into_iter()
            .flat_map(|(sc, g)| {
                g.into_iter().flat_map(|g| g.series).map(move |mut s| {
                    if several {
                        s.series.label = format!("{sc} {}", s.series.label);
                    }
                    s
                })
            })
            .collect();
        vec![Panel::new("", series)]
    } else {
        // A panel per scene (more where a scene's lines do not fit one), titled by it.
        groups_by_scene
            .into_iter()
            .flat_map(|(sc, groups)| {
                let mut ps = pack(groups, &[], "");
                let n = ps.len();
                for (i, p) in ps.iter_mut().enumerate() {
                    let name = if several { sc.clone() } else { String::new() };
                    p.title = if n > 1 {
                        format!("{name} ({}/{n})", i + 1).trim().to_string()
                    } else {
                        name
                    };
                }
                ps
            })
            .collect()
    };
    let mut notes = Vec::new();
    if merged_any {
        notes.push(format!(
            "one line where CPU and {} agree within {}% (GPU parity)",
            devices.name(crate::experiment::spec::Backend::Gpu),
            super::labels::COINCIDE * 100.0
        ));
    }
    if paper_any {
        notes.push(
            "paper: the published RMS (paper_vs_ours.csv), measured on the paper's own images and pixels"
                .into(),
        );
    }
    Figure {
        axes: Axes::new(
            format!("{}: error against positional samples", run.title),
            "positional samples (maps; log)",
            m_label,
        )
        .log_x(),
        panels,
        notes,
    }
}
