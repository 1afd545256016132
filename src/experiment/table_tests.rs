use super::*;
use crate::experiment::columns::read_csv as read_named;
use crate::experiment::outputs::{read_csv, write_csv};

/// Parts with a distinct value in every column that has one (so a column fed from the wrong
/// part, or two columns swapped, changes the row).
fn parts() -> Parts {
    Parts {
        cell: CellColumns {
            cell: "s-290-16-u8-cpu".into(),
            scene: "s".into(),
            sphere: SphereKind::Slater,
            positional_samples: 290,
            directional_res: 16,
            layout: LayoutKind::Concentric,
            precision: Precision::U8,
            selection: Selection::Nearest,
            backend: Backend::Cpu,
            adapter: "cpu, with a comma (2 threads)".into(),
            rays_per_point: 16,
            normal_bits: Some(8),
            rays_cast: 4000,
            receiver_points: 250,
            crease_points: 7,
            points_in_spheres: 11,
            caster_triangles: 1234,
            channels: 3,
        },
        times: TimeColumns {
            bake_s: Some(1.5),
            estimate_s: 0.002,
            raycast_s: Some(0.008),
            estimate_kernel_s: Some(0.001),
            raycast_kernel_s: None,
            setup_s: Some(0.25),
        },
        fields: FieldColumns {
            field_bytes: 74240,
            bake_rays: 999,
            bake_cached: true,
        },
        errors: ErrorColumns {
            seeds: 3,
            rms_vertex: Some((1.25, Some(0.125))),
            rms_image: Some((2.5, None)),
            max_error_vertex: Some(9.0),
            max_error_image: Some(10.0),
            share_pixels_off_1: Some(0.375),
            rms_vs_truth: Some((3.5, Some(0.0625))),
            rms_vs_truth_crease: Some(4.5),
            rms_vs_truth_interior: Some(5.5),
            rms_vs_truth_in_spheres: None,
            rms_vs_truth_outside_spheres: Some(6.5),
            rms_outside_spheres: Some(7.5),
            truth_stderr: Some(0.25),
            truth_rays: Some(4096),
            raycast_rms_vs_truth: Some(8.5),
            signal_rms: Some(40.0),
            grain: Some(0.75),
            second_reference: Some("mirror".into()),
            rms_image_vs_second: Some(12.0),
            rms_image_window: Some(2.25),
            rms_image_shaded: Some(1.5),
            flip: Some(crate::experiment::flip::FlipStats {
                mean: 0.125,
                weighted_median: 0.375,
            }),
            flip_vs_truth: None,
            image: "images/s.png".into(),
        },
    }
}

#[test]
fn a_row_is_its_parts_under_the_column_list_and_reads_back_by_name() {
    let p = parts();
    let row = Row::from_parts(&p);
    // Each column from its part, the derived ones computed: 4000 rays in 2 ms and 8 ms.
    assert_eq!((row.estimate_s, row.raycast_s), (0.002, Some(0.008)));
    assert_eq!(row.rms_vertex_sd, Some(0.125));
    assert_eq!(row.rms_image_sd, None);
    assert_eq!(row.points_in_spheres, Some(11));
    assert!((row.estimate_mrays_s.unwrap() - 2.0).abs() < 1e-12);
    assert!((row.raycast_mrays_s.unwrap() - 0.5).abs() < 1e-12);
    assert_eq!((row.signal_rms, row.channels), (Some(40.0), 3));
    assert_eq!(
        (row.flip_mean, row.flip_weighted_median),
        (Some(0.125), Some(0.375))
    );
    assert_eq!(row.flip_mean_vs_truth, None);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("table.csv");
    let own = vec![("rms_c0".to_string(), 0.5), ("rms_c1".to_string(), 1.5)];
    let written = [
        TableRow {
            row: row.clone(),
            own: own.clone(),
        },
        TableRow {
            row: Row {
                cell: "second".into(),
                ..row.clone()
            },
            own: own.clone(),
        },
    ];
    write_table(&path, &written).unwrap();
    // The header: the column list in order, then the kind's own columns.
    let text = std::fs::read_to_string(&path).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    assert_eq!(header.len(), TABLE_COLUMNS.len() + 2);
    assert_eq!(&header[..TABLE_COLUMNS.len()], TABLE_COLUMNS);
    assert_eq!(&header[TABLE_COLUMNS.len()..], ["rms_c0", "rms_c1"]);
    // Read back by name: the typed view, and the own columns by name.
    let back: Vec<Row> = read_csv(&path).unwrap();
    assert_eq!(back, [row.clone(), written[1].row.clone()]);
    let named = read_named(&path).unwrap();
    assert_eq!(named[1].get("cell"), Some("second"));
    assert_eq!(named[0].number("rms_c1"), Some(1.5));
    assert_eq!(
        named[0].get("adapter"),
        Some("cpu, with a comma (2 threads)")
    );
    // Without own columns the bytes are serde's writer's, as tables were written before.
    let plain = TableRow {
        row: row.clone(),
        own: Vec::new(),
    };
    let serde_path = dir.path().join("serde.csv");
    write_table(&path, &[plain]).unwrap();
    write_csv(&serde_path, &[row]).unwrap();
    assert_eq!(
        std::fs::read(&path).unwrap(),
        std::fs::read(&serde_path).unwrap()
    );
    // No row: the header alone.
    write_table(&path, &[]).unwrap();
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        format!("{}\n", TABLE_COLUMNS.join(","))
    );
}

#[test]
fn a_table_under_the_former_names_reads_back_the_same() {
    let row = Row::from_parts(&parts());
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("table.csv");
    write_csv(&path, std::slice::from_ref(&row)).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let (head, body) = text.split_once('\n').unwrap();
    // The header as tables were written before: former names, none of the columns from
    // `channels` on (`channels` read as 1, the later ones as none).
    let names: Vec<&str> = head.split(',').collect();
    let kept = names.iter().position(|n| *n == "channels").unwrap();
    let former: Vec<&str> = names[..kept]
        .iter()
        .copied()
        .map(|n| {
            FORMER_NAMES
                .iter()
                .find(|(_, now)| *now == n)
                .map_or(n, |(was, _)| was)
        })
        .collect();
    assert!(former.contains(&"ao_s") && former.contains(&"occlusion_rms"));
    // The values of the dropped columns are numbers, with no comma.
    let dropped = names.len() - kept;
    let body: Vec<&str> = body.trim_end().rsplitn(dropped + 1, ',').collect();
    std::fs::write(&path, format!("{}\n{}\n", former.join(","), body[dropped])).unwrap();
    let back: Vec<Row> = read_csv(&path).unwrap();
    assert_eq!(
        back,
        [Row {
            channels: 1,
            rms_image_window: None,
            rms_image_shaded: None,
            flip_mean: None,
            flip_weighted_median: None,
            ..row
        }]
    );
}

#[test]
fn the_committed_tables_read_and_keep_their_column_order() {
    // A committed quick table, under the names of whichever build wrote it: its header is the
    // column list's, renamed, up to the columns added since.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("results/quick/figure7/table.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let header: Vec<&str> = text
        .lines()
        .next()
        .unwrap()
        .split(',')
        .map(|n| {
            FORMER_NAMES
                .iter()
                .find(|(was, _)| *was == n)
                .map_or(n, |(_, now)| now)
        })
        .collect();
    assert!(header.len() >= 51, "{header:?}");
    assert_eq!(header, TABLE_COLUMNS[..header.len()]);
    let rows: Vec<Row> = read_csv(&path).unwrap();
    assert_eq!(rows.len(), 2);
    for r in &rows {
        assert!(r.estimate_s > 0.0 && r.estimate_mrays_s.unwrap() > 0.0);
        assert!(r.signal_rms.unwrap() > 0.0);
        assert_eq!(r.channels, 1);
    }
}

#[test]
fn methods_csv_writes_the_error_columns_of_the_list_in_its_order() {
    let p = parts();
    let mut named = NamedRow::new();
    p.errors.push_to(&mut named);
    let names: Vec<&str> = named.columns().map(|c| c.0).collect();
    // The committed methods.csv's error block, from `seeds` on, in its order.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("results/quick/figure6/methods.csv");
    let text = std::fs::read_to_string(path).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let at = header.iter().position(|n| *n == "seeds").unwrap();
    assert_eq!(names, header[at..at + names.len()]);
    // Each value the table's, as `Display` writes it (`9`, where serde writes `9.0`).
    let table = columns::of_serialized(&Row::from_parts(&p));
    for (name, v) in named.columns() {
        let t = table.get(name).unwrap();
        assert_eq!(v.parse::<f64>().ok(), t.parse::<f64>().ok(), "{name}");
        assert!(v == t || v.parse::<f64>().is_ok(), "{name}: {v} {t}");
    }
    assert_eq!(named.get("max_error_vertex"), Some("9"));
    assert_eq!(named.get("rms_vs_truth_in_spheres"), Some(""));
    assert_eq!(named.get("second_reference"), Some("mirror"));
}
