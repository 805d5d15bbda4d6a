//! The `coray` command end to end.
use std::path::PathBuf;
use std::process::Command;

fn coray(args: &[&str], dir: &std::path::Path) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_coray"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run coray");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("coray-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `coray stats --json` against DESIGN.md's table, all eight SPD scenes.
#[test]
fn stats_counts_match_the_design_table() {
    let d = tmp("stats");
    let table = [
        ("balls", 7382, 7381, 1, 0, 0),
        ("gears", 9345, 0, 9345, 0, 0),
        ("lattice", 8281, 2197, 0, 0, 6084),
        ("mount", 8196, 4, 8192, 0, 0),
        ("rings", 8401, 4200, 1, 0, 4200),
        ("teapot", 9264, 0, 9264, 0, 0),
        ("tetra", 4096, 0, 4096, 0, 0),
        ("tree", 8191, 4095, 1, 4095, 0),
    ];
    for (name, objects, spheres, polygons, cones, cylinders) in table {
        let (code, out, err) = coray(&["stats", &format!("spd:{name}"), "--json"], &d);
        assert_eq!(code, 0, "{err}");
        for (key, want) in [
            ("objects", objects),
            ("spheres", spheres),
            ("polygons", polygons),
            ("cones", cones),
            ("cylinders", cylinders),
        ] {
            assert!(
                out.contains(&format!("\"{key}\": {want},")),
                "{name}: {key} should be {want}: {out}"
            );
        }
        assert!(
            out.contains("\"structure\": \"kd-auto\"")
                && out.contains("\"structure\": \"kd-paper\"")
        );
    }
}

#[test]
fn main_job_renders_the_default_scene() {
    let d = tmp("main");
    let (code, out, err) = coray(&[], &d);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("spd:balls: 7382 objects, 512x512"), "{out}");
    let png = std::fs::read(d.join("coray.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // Width and height in the IHDR chunk.
    assert_eq!(u32::from_be_bytes(png[16..20].try_into().unwrap()), 512);
    assert_eq!(u32::from_be_bytes(png[20..24].try_into().unwrap()), 512);
}

#[test]
fn render_every_accel_from_an_nff_file() {
    let d = tmp("render");
    std::fs::write(
        d.join("scene.nff"),
        "v\nfrom 0 -5 2\nat 0 0 0\nup 0 0 1\nangle 40\nhither 0.01\nresolution 48 32\nb 0.1 0.1 0.1\nl 3 -3 6\n\
         f 1 1 1 1 0 0 0 1\np 4\n-3 -3 0\n3 -3 0\n3 3 0\n-3 3 0\nf 0.2 0.4 1 0.5 0.5 20 0.3 1.5\ns 0 0 1 1\nc 2 0 0 0.3 2 0 2 0.1\n",
    )
    .unwrap();
    const ACCELS: [&str; 14] = [
        "kd",
        "kd-rope",
        "kd-paper",
        "kd-paper-rope",
        "tdbs",
        "tdbs-sah",
        "nn",
        "nn-chain",
        "rtree",
        "rstar",
        "rstar-reinsert",
        "proj-rstar-2d-2d",
        "proj-tdbs-dummy-comb",
        "proj-nn-chain-2d-3d",
    ];
    for accel in ACCELS {
        let (code, out, err) = coray(
            &[
                "render",
                "scene.nff",
                "--accel",
                accel,
                "-o",
                &format!("{accel}.png"),
            ],
            &d,
        );
        assert_eq!(code, 0, "{err}");
        assert!(out.contains("3 objects, 48x32"), "{out}");
    }
    // Every structure and traversal renders the same picture.
    let first = std::fs::read(d.join("kd.png")).unwrap();
    for accel in &ACCELS[1..] {
        assert_eq!(
            std::fs::read(d.join(format!("{accel}.png"))).unwrap(),
            first,
            "{accel}"
        );
    }
}

#[test]
fn bad_input_is_reported_with_its_position() {
    let d = tmp("bad");
    std::fs::write(d.join("bad.nff"), "s 0 0 0 1\ns 1 2 x 4\n").unwrap();
    let (code, _, err) = coray(&["stats", "bad.nff"], &d);
    assert_eq!(code, 2);
    assert!(err.contains("bad.nff:2:7:"), "{err}");
    let (code, _, err) = coray(&["render", "spd:nothing"], &d);
    assert_eq!(code, 2);
    assert!(err.contains("no SPD scene"), "{err}");
    let (code, _, err) = coray(&["bench", "spd:tree:2", "--methods", "kd,warp"], &d);
    assert_eq!(code, 2);
    assert!(err.contains("unknown method `warp`"), "{err}");
}

#[test]
fn bench_json_has_every_row_and_exact_ropes() {
    let d = tmp("bench");
    let (code, out, err) = coray(
        &[
            "bench",
            "spd:tree:5",
            "--res",
            "48",
            "--repeat",
            "1",
            "--json",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("{\"scene\": \"spd:tree:5\", \"objects\": 127, \"primitives\": 128, \"res\": [48, 48], \"rows\": ["), "{out}");
    for m in ["kd", "kd-rope"] {
        assert!(out.contains(&format!("{{\"method\": \"{m}\"")), "{out}");
    }
    // The rope traversal gives exactly the hierarchical hits.
    let rope = &out[out.find("\"method\": \"kd-rope\"").unwrap()..];
    assert!(
        rope.contains("\"alpha\": ") && rope.contains("\"mismatches\": 0"),
        "{rope}"
    );
}

#[cfg(feature = "embree")]
#[test]
fn compare_agrees_with_embree_on_small_spd_scenes() {
    let d = tmp("compare");
    for scene in [
        "spd:balls:2",
        "spd:gears:1",
        "spd:lattice:3",
        "spd:mount:3",
        "spd:rings:1",
        "spd:teapot:4",
        "spd:tetra:4",
        "spd:tree:6",
    ] {
        let (code, out, err) = coray(&["compare", scene, "--res", "96"], &d);
        assert_eq!(code, 0, "{scene}: {out}{err}");
        assert!(out.contains("mismatches: 0 of"), "{scene}: {out}");
    }
    assert!(d.join("coray-diff.png").exists());
}

/// `--table lcts`: one column per scene, every method's block, exact
/// schemes (mismatches 0); `--table lcts-res` stops at --max-res.
#[test]
fn bench_paper_tables() {
    let d = tmp("tables");
    let (code, out, err) = coray(
        &[
            "bench",
            "spd:tetra,spd:teapot",
            "--res",
            "64",
            "--repeat",
            "1",
            "--table",
            "lcts",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    for block in [
        "hierarchical traversal",
        "rope traversal",
        "SLCTS-1D window 5 x 1 pixels",
        "HLCTS-1D",
        "SLCTS-2D window 5 x 5 pixels",
        "HLCTS-2D",
    ] {
        assert!(out.contains(&format!("\n{block}\n")), "{block}: {out}");
    }
    let mism: Vec<&str> = out
        .lines()
        .filter(|l| l.trim_start().starts_with("mismatches"))
        .collect();
    assert_eq!(mism.len(), 6, "{out}");
    for l in mism {
        assert_eq!(
            l.split_whitespace().collect::<Vec<_>>(),
            ["mismatches", "0", "0"],
            "{out}"
        );
    }
    let (code, out, err) = coray(
        &[
            "bench",
            "--table",
            "lcts-res",
            "--max-res",
            "256",
            "--repeat",
            "1",
            "--json",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("[{\"scene\": \"spd:teapot\""), "{out}");
    assert_eq!(out.matches("\"res\": [256, 256]").count(), 1, "{out}");
    assert_eq!(out.matches("\"scene\"").count(), 1, "{out}");
    let (code, _, err) = coray(&["bench", "--table", "nope", "--res", "8"], &d);
    assert_eq!(code, 2);
    assert!(err.contains("unknown --table `nope`"), "{err}");
}

/// `--table bvh`: every hierarchy builder traced exactly (0 mismatches
/// against the kd-tree on primary and shadow rays), with the thesis' costs.
#[test]
fn bench_bvh_table() {
    let d = tmp("bvh");
    let (code, out, err) = coray(
        &[
            "bench",
            "spd:tree:4",
            "--res",
            "48",
            "--repeat",
            "1",
            "--table",
            "bvh",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    for m in [
        "tdbs",
        "tdbs-sah",
        "nn",
        "nn-chain",
        "rtree",
        "rstar",
        "rstar-reinsert",
    ] {
        let line = out
            .lines()
            .find(|l| l.split_whitespace().next() == Some(m))
            .unwrap_or_else(|| panic!("{m}: {out}"));
        let cells: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(cells.len(), 7, "{line}");
        assert_eq!(cells[6], "0", "{m} mismatches: {line}");
        let cost_box: f64 = cells[4].parse().unwrap();
        assert!((2.0..=51.0).contains(&cost_box), "{line}");
    }
}

/// `--table bvh-series`: every ladder, every builder, exact against the
/// kd-tree, the six observations judged, and the charts written as a PNG.
#[test]
fn bench_bvh_series_with_plot() {
    let d = tmp("series");
    let (code, out, err) = coray(
        &[
            "bench",
            "--table",
            "bvh-series",
            "--res",
            "24",
            "--repeat",
            "1",
            "--max-size",
            "2",
            "--plot",
            "series.png",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    for block in [
        "\ntree\n",
        "\ntree, floor split\n",
        "\nballs\n",
        "\ngears\n",
    ] {
        assert!(out.contains(block), "{block}: {out}");
    }
    // Tree sizes 1 and 2 have 7 and 15 objects; the split floor adds 255 pieces.
    assert!(
        out.contains("objects                                       7        15"),
        "{out}"
    );
    assert!(
        out.contains("objects                                     262       270"),
        "{out}"
    );
    let mismatch_lines: Vec<&str> = out
        .lines()
        .filter(|l| l.starts_with("mismatches vs kd"))
        .collect();
    assert_eq!(mismatch_lines.len(), 4, "{out}");
    for l in mismatch_lines {
        assert!(l.split_whitespace().skip(4).all(|c| c == "0"), "{l}");
    }
    for k in 1..=6 {
        let line = out
            .lines()
            .find(|l| l.starts_with(&format!("{k}. ")))
            .unwrap_or_else(|| panic!("observation {k}: {out}"));
        assert!(line.contains("confirmed"), "{line}");
    }
    let png = std::fs::read(d.join("series.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    assert!(png.len() > 20_000, "{} bytes", png.len());
    let (code, _, err) = coray(&["bench", "spd:tree:2", "--plot", "x.png"], &d);
    assert_eq!(code, 2);
    assert!(
        err.contains("--plot and --max-size go with --table bvh-series"),
        "{err}"
    );
}

/// `--table proj`: every projection hierarchy x criterion x scheme, with
/// 0 mismatches against the kd-tree for primary and shadow rays (and
/// between the two shadow-ray modes), beside the 3D hierarchies.
#[test]
fn bench_proj_table() {
    let d = tmp("proj");
    let (code, out, err) = coray(
        &[
            "bench",
            "spd:balls:2",
            "--res",
            "40",
            "--repeat",
            "1",
            "--table",
            "proj",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    let rows: Vec<&str> = out.lines().filter(|l| l.starts_with("proj-")).collect();
    assert_eq!(rows.len(), 20, "{out}");
    for l in out.lines().skip(2) {
        let cells: Vec<&str> = l.split_whitespace().collect();
        assert_eq!(cells.len(), 11, "{l}");
        assert_eq!(cells[10], "0", "mismatches: {l}");
        if cells[0].ends_with("-2d") && cells[0].starts_with("proj-") {
            // Pure 2D traversal: every hierarchy test costs the thesis' 4.
            assert_eq!(cells[8], "4.00", "{l}");
        }
    }
    let (code, _, err) = coray(
        &["bench", "spd:balls:1", "--methods", "proj-tdbs-dummy-3d"],
        &d,
    );
    assert_eq!(code, 2);
    assert!(err.contains("unknown method"), "{err}");
}

/// `--table proj-series`: every ladder and method exact against the
/// kd-tree, the nine conclusions of the thesis' 6.4 judged, charts written.
#[test]
fn bench_proj_series_with_plot() {
    let d = tmp("proj-series");
    let (code, out, err) = coray(
        &[
            "bench",
            "--table",
            "proj-series",
            "--res",
            "16",
            "--repeat",
            "1",
            "--max-size",
            "1",
            "--plot",
            "proj.png",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    let ladders = [
        "\ntree, 7 lights\n",
        "\ntree, floor split, 7 lights\n",
        "\ntree, 1 light\n",
        "\nballs\n",
        "\ngears\n",
    ];
    for l in ladders {
        assert!(out.contains(l), "{l}: {out}");
    }
    let totals: Vec<&str> = out
        .lines()
        .filter(|l| l.contains("mismatches against the kd-tree"))
        .collect();
    assert_eq!(totals.len(), 5, "{out}");
    assert!(totals.iter().all(|l| l.ends_with(": 0")), "{totals:?}");
    for k in 1..=9 {
        let line = out
            .lines()
            .find(|l| l.starts_with(&format!("{k}. ")))
            .unwrap_or_else(|| panic!("conclusion {k}: {out}"));
        assert!(line.contains("confirmed"), "{line}");
    }
    let png = std::fs::read(d.join("proj.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
}
