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

fn json(out: &str) -> serde_json::Value {
    serde_json::from_str(out).unwrap_or_else(|e| panic!("{e}: {out}"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("coray-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `coray stats --json` against the table in docs/techniques.md, all eight SPD scenes.
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
        let v = json(&out);
        for (key, want) in [
            ("objects", objects),
            ("spheres", spheres),
            ("polygons", polygons),
            ("cones", cones),
            ("cylinders", cylinders),
        ] {
            assert_eq!(v[key], want, "{name}: {key}");
        }
        let names: Vec<&str> = v["structures"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s["structure"].as_str().unwrap())
            .collect();
        assert_eq!(
            names,
            [
                "kd-auto",
                "kd-paper",
                "tdbs",
                "tdbs-sah",
                "nn",
                "nn-chain",
                "rtree",
                "rstar",
                "rstar-reinsert"
            ]
        );
        assert_eq!(v["skipped"], serde_json::json!([]), "{name}");
    }
}

/// Above 40,000 primitives `stats` leaves the quadratic matching out and
/// says so (the Stanford bunny's took 42 s), keeping the chain.
#[test]
fn stats_skips_the_quadratic_matching_on_large_scenes() {
    let d = tmp("stats_large");
    let (code, out, err) = coray(&["stats", "random:36400", "--json"], &d);
    assert_eq!(code, 0, "{err}");
    let v = json(&out);
    assert_eq!(v["objects"], 40_040);
    let names: Vec<&str> = v["structures"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["structure"].as_str().unwrap())
        .collect();
    assert!(
        names.contains(&"nn-chain") && !names.contains(&"nn"),
        "{names:?}"
    );
    let skipped = v["skipped"].as_array().unwrap();
    assert_eq!(skipped.len(), 1);
    assert!(skipped[0].as_str().unwrap().starts_with("nn: quadratic"));
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
    let v = json(&out);
    assert_eq!(v["scene"], "spd:tree:5");
    assert_eq!(
        (v["objects"].as_u64(), v["primitives"].as_u64()),
        (Some(127), Some(128))
    );
    assert_eq!(v["res"], serde_json::json!([48, 48]));
    let rows = v["rows"].as_array().unwrap();
    let names: Vec<&str> = rows.iter().map(|r| r["method"].as_str().unwrap()).collect();
    for m in [
        "kd",
        "kd-rope",
        "slcts2d",
        "hlcts2d",
        "cast-packets",
        "tdbs",
        "rstar-reinsert",
    ] {
        assert!(names.contains(&m), "{m}: {names:?}");
    }
    // Every exact technique gives exactly the hierarchical hits.
    for r in rows {
        if !r["method"].as_str().unwrap().starts_with("embree") {
            assert_eq!(r["mismatches"], 0, "{r}");
        }
    }
    let rope = rows.iter().find(|r| r["method"] == "kd-rope").unwrap();
    assert!(rope["alpha"].as_f64().unwrap() < 1.0, "{rope}");
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
        .filter(|l| l.trim_start().starts_with("mismatches "))
        .filter(|l| !l.contains('='))
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
    let v = json(&out);
    let cols = v.as_array().unwrap();
    assert_eq!(cols.len(), 1, "{out}");
    assert_eq!(cols[0]["scene"], "spd:teapot");
    assert_eq!(cols[0]["res"], serde_json::json!([256, 256]));
    assert_eq!(cols[0]["rows"].as_array().unwrap().len(), 6);
    let (code, _, err) = coray(&["bench", "--table", "nope", "--res", "8"], &d);
    assert_eq!(code, 2);
    assert!(
        err.contains(
            "unknown --table `nope` (have: build, speed, lcts, lcts-res, bvh, proj, bvh-series, proj-series)"
        ),
        "{err}"
    );
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
/// kd-tree, every observation judged, and the charts written as a PNG.
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
            "--json",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    let v = json(&out);
    let pts = v["points"].as_array().unwrap();
    // 4 ladders x 2 sizes x 6 methods.
    assert_eq!(pts.len(), 48);
    assert!(pts.iter().all(|p| p["mismatches"] == 0), "{out}");
    // Tree sizes 1 and 2 have 7 and 15 objects; the split floor adds 255 pieces.
    let objects = |ladder: &str, size: u64| {
        pts.iter()
            .find(|p| p["ladder"] == ladder && p["size"] == size)
            .unwrap()["objects"]
            .as_u64()
    };
    assert_eq!(
        (objects("tree", 1), objects("tree", 2)),
        (Some(7), Some(15))
    );
    assert_eq!(
        (
            objects("tree, floor split", 1),
            objects("tree, floor split", 2)
        ),
        (Some(262), Some(270))
    );
    let claims = v["claims"].as_array().unwrap();
    assert_eq!(claims.len(), 8);
    for c in claims {
        assert!(c["confirmed"].is_boolean(), "{c}");
        assert!(!c["evidence"].as_str().unwrap().is_empty(), "{c}");
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
            "--json",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    let rows = json(&out)["rows"].as_array().unwrap().clone();
    let proj: Vec<_> = rows
        .iter()
        .filter(|r| r["method"].as_str().unwrap().starts_with("proj-"))
        .collect();
    assert_eq!(proj.len(), 20, "{out}");
    for r in &rows {
        let m = r["method"].as_str().unwrap();
        if !m.starts_with("embree") {
            assert_eq!(r["mismatches"], 0, "{r}");
        }
        if m.starts_with("proj-") && m.ends_with("-2d") {
            // Pure 2D traversal: every hierarchy test costs the thesis' 4.
            assert_eq!(r["cost_per_box"].as_f64(), Some(4.0), "{r}");
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
    for l in [
        "\ntree, 7 lights\n",
        "\ntree, floor split, 7 lights\n",
        "\ntree, 1 light\n",
        "\nballs\n",
        "\ngears\n",
    ] {
        assert!(out.contains(l), "{l}: {out}");
    }
    let totals: Vec<&str> = out
        .lines()
        .filter(|l| l.contains("otherwise than the kd-tree"))
        .collect();
    assert_eq!(totals.len(), 5, "{out}");
    assert!(totals.iter().all(|l| l.ends_with(": 0")), "{totals:?}");
    for k in ["1", "2", "3", "4", "5", "6", "7", "8", "9", "9b"] {
        let line = out
            .lines()
            .find(|l| l.starts_with(&format!("{k}. ")))
            .unwrap_or_else(|| panic!("conclusion {k}: {out}"));
        assert!(
            line.contains("confirmed") || line.contains("undecided"),
            "{line}"
        );
    }
    assert!(out.contains("rows: ray tracing s"), "the legend: {out}");
    let png = std::fs::read(d.join("proj.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
}

/// Every bad input of issue 17's list gets a message naming the limit and
/// exit status 2; none panics (101) or is killed.
#[test]
fn bad_inputs_get_a_message_and_status_2() {
    let d = tmp("hostile");
    let view = |from: &str, at: &str, res: &str| {
        format!(
            "v\nfrom {from}\nat {at}\nup 0 0 1\nangle 40\nhither 0.01\nresolution {res}\ns 0 0 0 1\n"
        )
    };
    std::fs::write(d.join("res0.nff"), view("0 -5 2", "0 0 0", "0 0")).unwrap();
    std::fs::write(d.join("eye.nff"), view("1 1 1", "1 1 1", "8 8")).unwrap();
    let mut comb = String::from("p 120002\n0 0 0\n");
    for k in 0..40_000 {
        comb += &format!("{} 1 0\n{}.5 3 0\n{} 1 0\n", 2 * k, 2 * k, 2 * k + 1);
    }
    comb += "80000 0 0\n";
    std::fs::write(d.join("comb.nff"), comb).unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["render", "res0.nff"], "1 to 32768 pixels"),
        (&["stats", "eye.nff"], "eye (from) is the point it looks at"),
        (&["stats", "comb.nff"], "concave corners"),
        (
            &["bench", "spd:tetra:1", "--res", "100000"],
            "must be 1 to 32768 pixels, not 100000",
        ),
        (
            &["compare", "spd:tetra:1", "--res", "0"],
            "must be 1 to 32768 pixels, not 0",
        ),
        (
            &["render", "spd:tetra:1", "--res", "70000x20"],
            "1 to 32768 pixels, not 70000",
        ),
        (&["stats", "random:100000000"], "needs about"),
        (&["stats", "random:2000000000"], "is not a triangle count"),
        (
            &["bench", "spd:tetra:1", "--threads", "0"],
            "--threads must be 1 to 1024, not 0",
        ),
        (
            &["bench", "spd:tetra:1", "--repeat", "0"],
            "--repeat must be 1 to 1000, not 0",
        ),
        (
            &["render", "spd:tetra:1", "--threads", "0"],
            "--threads must be 1 to 1024, not 0",
        ),
        (&["render", "spd:tetra:1", "-o", "x.jpg"], ".png or .ppm"),
        (
            &["compare", "spd:tetra:1", "--diff", "d.gif"],
            ".png or .ppm",
        ),
        (
            &["bench", "--table", "bogus"],
            "have: build, speed, lcts, lcts-res, bvh, proj, bvh-series, proj-series",
        ),
        (
            &["bench", "--table", "bvh-series", "--plot", "c.svg"],
            "charts are written as .png",
        ),
        (
            &["render", "--accel", "warp"],
            "proj-BUILDER-CRITERIA-SCHEME",
        ),
        (
            &["render", "--accel", "slcts2d"],
            "casts images: use it with `coray bench`",
        ),
        (&["render", "--depth", "1000"], "--depth must be 0 to 64"),
        (&["render", "spd:tree:99"], "size of `tree` must be 1 to 18"),
        (
            &["render", "--floor-split", "0"],
            "--floor-split must be 1 to 1024",
        ),
        (
            &["bench", "--table", "lcts", "--methods", "kd"],
            "other tables have their methods",
        ),
        // Audit 55.7: the PNG writer answered "Zero width not allowed".
        (
            &["render", "spd:tetra:1", "--spd", "--res", "0"],
            "1 to 32767 pixels a side",
        ),
    ];
    for (args, want) in cases {
        let (code, out, err) = coray(args, &d);
        assert_eq!(code, 2, "{args:?}: {out}{err}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
    // Audit 55.7: a hostile token was echoed whole. Every message cuts
    // it to 80 characters and says how long it was.
    let long = "q".repeat(100_000);
    for args in [
        vec!["render", "--accel", &long],
        vec!["render", "--preset", &long],
        vec!["render", "--res", &long],
        vec!["stats", &long],
        vec!["stats", &format!("spd:{long}")],
        vec!["stats", &format!("random:{long}")],
    ] {
        let (code, out, err) = coray(&args, &d);
        assert_eq!(code, 2, "{out}{}", &err[..err.len().min(300)]);
        assert!(err.len() < 1000, "{} bytes: {}", err.len(), &err[..300]);
        assert!(err.contains("(100000 bytes)"), "{err}");
    }
    let ppm = coray(&["render", "spd:tetra:1", "--res", "8", "-o", "t.ppm"], &d);
    assert_eq!(ppm.0, 0, "{}", ppm.2);
    assert!(std::fs::read(d.join("t.ppm"))
        .unwrap()
        .starts_with(b"P6\n8 8\n255\n"));
}

/// `render --spd` on two facing mirrors with a light between them: every
/// count follows from the procedure by hand. 16 x 16 pixels give 17 x 17 =
/// 289 eye rays; each bounces between the mirrors to tree depth 5 (4
/// reflection rays, all hitting), and every hit whose front faces the
/// light casts one unblocked shadow ray. With the far mirror wound
/// backwards (one-sided), its hits (depths 2 and 4) cast none.
#[test]
fn spd_procedure_counts_mirrors_by_hand() {
    let d = tmp("spd");
    let scene = |far: &str| {
        format!(
            "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0.01\nresolution 16 16\n\
             b 0 0 0\nl 0 0 5\nf 1 1 1 0.5 0.5 10 0 1\n\
             p 4\n-100 -100 0\n100 -100 0\n100 100 0\n-100 100 0\np 4\n{far}"
        )
    };
    let facing = "-100 -100 10\n-100 100 10\n100 100 10\n100 -100 10\n";
    let away = "-100 -100 10\n100 -100 10\n100 100 10\n-100 100 10\n";
    for (file, far, shadow_per_eye) in [("facing.nff", facing, 5), ("away.nff", away, 3)] {
        std::fs::write(d.join(file), scene(far)).unwrap();
        for accel in ["kd", "tdbs", "proj-rstar-2d-2d", "slcts2d"] {
            let (code, out, err) = coray(
                &[
                    "render", file, "--spd", "--res", "16", "--json", "--accel", accel,
                ],
                &d,
            );
            assert_eq!(code, 0, "{err}");
            let v = json(&out);
            let want = [
                ("eye_rays", 289),
                ("eye_hits", 289),
                ("reflect_rays", 4 * 289),
                ("refract_rays", 0),
                ("secondary_hits", 4 * 289),
                ("shadow_rays", shadow_per_eye * 289),
                ("shadow_hits", 0),
                ("all_rays", (5 + shadow_per_eye) * 289),
                ("intersections_required", 5 * 289),
                ("tree_depth", 5),
                ("pixels", 16),
            ];
            for (key, n) in want {
                assert_eq!(v[key], n, "{file}, {accel}: {key}");
            }
        }
    }
    let png = std::fs::read(d.join("coray.png")).unwrap();
    assert_eq!(u32::from_be_bytes(png[16..20].try_into().unwrap()), 16);
    for (args, msg) in [
        (
            &["render", "--spd", "--depth", "3"][..],
            "leave out --depth",
        ),
        (&["render", "--spd", "--res", "16x8"][..], "square image"),
    ] {
        let (code, _, err) = coray(args, &d);
        assert_eq!(code, 2, "{args:?}");
        assert!(err.contains(msg), "{args:?}: {err}");
    }
    let (code, out, err) = coray(&["render", "spd:tetra:1", "--spd", "--res", "8"], &d);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("eye rays") && out.contains("81"), "{out}");
}

/// `coray export`: a scene as C arrays, counts as macros, names prefixed.
#[test]
fn export_writes_the_scene_as_c_arrays() {
    let d = tmp("export");
    let (code, out, err) = coray(
        &["export", "spd:tetra:1", "--prefix", "t4", "-o", "t.h"],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("spd:tetra:1: 4 objects -> t.h"), "{out}");
    let h = std::fs::read_to_string(d.join("t.h")).unwrap();
    for want in [
        "#define T4_TRIANGLE_COUNT 4\n",
        "#define T4_VERTEX_COUNT 12\n",
        "#define T4_SPHERE_COUNT 0\n",
        "static const float t4_spheres[] = {0};",
        "static const uint32_t t4_indices[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};",
        "#define T4_ANGLE_DEG ",
    ] {
        assert!(h.contains(want), "{want} not in\n{h}");
    }
    let (code, _, err) = coray(&["export", "spd:tetra:1", "--prefix", "9x"], &d);
    assert_eq!(code, 2);
    assert!(err.contains("C identifier"), "{err}");
}

/// `bench --table build`: one row per scene, every builder, Embree at one
/// thread and at --threads N, bytes per primitive from each.
#[test]
fn build_table_has_every_builder() {
    let d = tmp("build-table");
    let (code, out, err) = coray(
        &[
            "bench",
            "--table",
            "build",
            "spd:tetra:2,spd:balls:1",
            "--repeat",
            "1",
            "--threads",
            "2",
            "--json",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    let v = json(&out);
    let rows = v.as_array().unwrap();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0]["scene"], "spd:tetra:2");
    assert_eq!(rows[0]["prims"], 16);
    // balls 1: 10 spheres and a floor polygon of 2 triangles.
    assert_eq!(rows[1]["prims"], 12);
    let names: Vec<&str> = rows[0]["cells"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["builder"].as_str().unwrap())
        .collect();
    let mut want = vec![
        "kd-auto",
        "kd-auto (2 thr)",
        "kd-paper",
        "kd-compact",
        "tdbs-sah",
        "wide",
    ];
    if cfg!(feature = "embree") {
        want.extend(["embree (1 thr)", "embree (2 thr)"]);
    }
    assert_eq!(names, want);
    for c in rows[0]["cells"].as_array().unwrap() {
        assert!(c["bytes_per_prim"].as_f64().unwrap() > 0.0, "{c}");
        // 16 triangles fit the default room: no kd build is cut short.
        assert_eq!(c["truncated"], false, "{c}");
    }
    // Every coray build borrows scratch; TDBS-SAH's is a box, a key and
    // eight links per primitive: 24 + 4 + 32 bytes.
    let cells = rows[0]["cells"].as_array().unwrap();
    assert!(cells[0]["scratch_per_prim"].as_f64().unwrap() > 0.0);
    assert_eq!(cells[4]["scratch_per_prim"], 60.0);
    // The wide hierarchy keeps less than the binary one it is collapsed
    // from (nodes of four entries, leaves of up to four).
    let kept = |i: usize| cells[i]["bytes_per_prim"].as_f64().unwrap();
    assert!(kept(5) < kept(4), "wide {} tdbs-sah {}", kept(5), kept(4));
    // A compact tree keeps no more than kd-auto's (less where the SAH
    // cuts empty space off beside a full child).
    for row in rows {
        let c = row["cells"].as_array().unwrap();
        let b = |i: usize| c[i]["bytes_per_prim"].as_f64().unwrap();
        assert!(b(3) <= b(0), "{row}");
    }
    // The build's jobs on two threads make the same tree.
    for row in rows {
        let c = row["cells"].as_array().unwrap();
        assert_eq!(c[0]["bytes_per_prim"], c[1]["bytes_per_prim"], "{row}");
    }
    // Beside the builds, the primary rays through kd-auto's tree and
    // Embree's, every one answering as kd-auto's hierarchical traversal.
    let mut want = vec!["kd", "kd-packet", "kd-compact", "kd-compact-packet"];
    if cfg!(feature = "embree") {
        want.extend(["embree", "embree8"]);
    }
    for row in rows {
        let trace = row["trace"].as_array().unwrap();
        let names: Vec<&str> = trace
            .iter()
            .map(|t| t["method"].as_str().unwrap())
            .collect();
        assert_eq!(names, want, "{row}");
        let rays = row["rays"].as_u64().unwrap();
        assert!(rays > 0, "{row}");
        for t in trace {
            assert!(t["mrays"].as_f64().unwrap() > 0.0, "{t}");
            assert_eq!(t["mismatches"], 0, "{t}");
        }
    }
}

/// The speed table traces every set with every method, the C-ABI rows
/// (`kd-c` array calls, `kd-c1` and `wide-c1` one call per ray) among
/// them, and every
/// coray method answers exactly as the hierarchical kd-tree.
#[test]
fn speed_table_has_the_c_abi_rows_and_no_mismatch() {
    let d = tmp("speed");
    let (code, out, err) = coray(
        &[
            "bench",
            "--table",
            "speed",
            "spd:tree:3",
            "--res",
            "32",
            "--repeat",
            "1",
            "--json",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    let v = json(&out);
    let rows = v.as_array().unwrap();
    let sets: Vec<&str> = rows.iter().map(|r| r["set"].as_str().unwrap()).collect();
    assert_eq!(sets, ["primary", "shadow", "incoherent", "diffuse"]);
    // The primary set has the image casts too, the packet tiles among them.
    let primary = rows[0]["cells"].as_array().unwrap();
    for m in ["slcts2d", "hlcts2d", "cast-packets"] {
        assert!(primary.iter().any(|c| c["method"] == m), "{m}");
    }
    for r in rows {
        let cells = r["cells"].as_array().unwrap();
        for m in ["kd", "kd-c", "kd-c1", "wide-c1"] {
            let c = cells.iter().find(|c| c["method"] == m).expect(m);
            assert!(c["mrays"].as_f64().unwrap() > 0.0, "{c}");
        }
        for c in cells {
            if !c["method"].as_str().unwrap().starts_with("embree") {
                assert_eq!(
                    (&c["mismatches"], &c["ties"]),
                    (&0.into(), &0.into()),
                    "{c}"
                );
            }
        }
    }
}

/// Audit 55.7: under `ulimit -v` the budget read MemAvailable only, so
/// the command planned memory the process could not have and aborted on
/// a failed allocation. The budget is now the least of the machine's, the
/// address-space limit's and the control group's memory, and images are
/// allocated fallibly: a message and status 2.
#[test]
fn address_space_limits_are_budgeted() {
    let d = tmp("ulimit");
    let bin = env!("CARGO_BIN_EXE_coray");
    for args in [
        "render spd:balls --res 32768x32768 -o big.png",
        "render random:30000000 --res 64x64 -o r.png",
    ] {
        let out = Command::new("sh")
            .arg("-c")
            .arg(format!("ulimit -v 8000000 && exec {bin} {args}"))
            .current_dir(&d)
            .output()
            .expect("run sh");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args}: {err}");
        assert!(
            err.contains("needs") && err.contains("ulimit"),
            "{args}: {err}"
        );
    }
}

/// The README's results table is `coray summary docs/speed-1024.txt`, and
/// that file begins with the command that wrote it: no figure copied by
/// hand.
#[test]
fn readme_results_are_the_summary_of_the_speed_table() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let (code, table, err) = coray(&["summary", "docs/speed-1024.txt"], &root);
    assert_eq!(code, 0, "{err}");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    assert!(
        readme.contains(&table),
        "README.md's results differ from `coray summary docs/speed-1024.txt`:\n{table}"
    );
    let speed = std::fs::read_to_string(root.join("docs/speed-1024.txt")).unwrap();
    assert!(speed.starts_with("$ coray bench --table speed"));
}

/// `coray export --nff`: any scene (SPD, a mesh file, random) as NFF that
/// renders as the scene does.
#[test]
fn exported_nff_renders_as_the_scene() {
    let d = tmp("export-nff");
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nf 1 2 3 4\nf 1 2 5\n";
    std::fs::write(d.join("quad.obj"), obj).unwrap();
    for scene in ["spd:tetra:2", "spd:balls:1", "quad.obj", "random:200"] {
        let (code, _, err) = coray(&["export", "--nff", scene, "-o", "x.nff"], &d);
        assert_eq!(code, 0, "{scene}: {err}");
        let render = |s: &str, out: &str| {
            let (code, _, err) = coray(
                &["render", s, "--res", "48x32", "-o", out, "--threads", "1"],
                &d,
            );
            assert_eq!(code, 0, "{s}: {err}");
            std::fs::read(d.join(out)).unwrap()
        };
        assert_eq!(
            render(scene, "a.ppm"),
            render("x.nff", "b.ppm"),
            "{scene}: the exported NFF renders otherwise"
        );
    }
}
