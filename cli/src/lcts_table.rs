//! `coray bench --table lcts|lcts-res`: the layout of Havran and Bittner's
//! Tables 2 and 3 (one block per traversal method, one column per scene or
//! resolution), with the paper's alpha and eta printed beside ours.

use crate::bench::{self, Row, Settings};
use crate::built::Built;
use crate::method::Method;
use crate::scene::SceneData;
use coray::lcts::Scheme;

/// The six methods of the paper's tables, in its order: the row's name,
/// the image cast, the paper's title. The hierarchical and rope rows are
/// casts too (the same harness as the LCTS schemes).
pub const LCTS_METHODS: [(&str, Scheme, &str); 6] = [
    ("kd", Scheme::Hierarchical, "hierarchical traversal"),
    ("kd-rope", Scheme::Ropes, "rope traversal"),
    (
        "slcts1d",
        Scheme::Slcts1d { n: 5 },
        "SLCTS-1D window 5 x 1 pixels",
    ),
    ("hlcts1d", Scheme::Hlcts1d, "HLCTS-1D"),
    (
        "slcts2d",
        Scheme::Slcts2d { n: 5, m: 5 },
        "SLCTS-2D window 5 x 5 pixels",
    ),
    ("hlcts2d", Scheme::Hlcts2d, "HLCTS-2D"),
];

/// The eight SPD scenes of Table 2 (the paper's `fluid` is not an SPD scene).
pub const SPD_SCENES: [&str; 8] = [
    "balls", "gears", "lattice", "mount", "rings", "teapot", "tetra", "tree",
];

/// Table 3's resolutions.
pub const RESOLUTIONS: [u32; 5] = [256, 512, 1024, 2048, 4096];

/// The paper's (alpha, eta) at 1024 x 1024 (Table 2), per method and scene
/// in the order of [`SPD_SCENES`].
fn paper_table2(method: &str, scene: &str) -> Option<(f64, f64)> {
    let i = SPD_SCENES.iter().position(|s| *s == scene)?;
    let (a, e): ([f64; 8], [f64; 8]) = match method {
        "kd" => ([1.0; 8], [1.0; 8]),
        "kd-rope" => (
            [0.862, 0.940, 0.383, 0.873, 0.828, 0.856, 0.847, 0.728],
            [1.04, 1.00, 0.918, 1.03, 1.12, 1.06, 1.16, 1.03],
        ),
        "slcts1d" => (
            [0.434, 0.430, 0.234, 0.388, 0.380, 0.381, 0.416, 0.424],
            [0.958, 0.990, 0.812, 0.853, 0.999, 0.925, 1.16, 0.988],
        ),
        "hlcts1d" => (
            [0.332, 0.336, 0.277, 0.278, 0.266, 0.286, 0.339, 0.33],
            [0.958, 0.998, 0.872, 0.913, 0.960, 0.929, 0.990, 0.970],
        ),
        "slcts2d" => (
            [0.408, 0.389, 0.216, 0.349, 0.334, 0.348, 0.398, 0.394],
            [0.819, 0.971, 0.768, 0.772, 0.949, 0.846, 0.97, 0.939],
        ),
        "hlcts2d" => (
            [0.372, 0.384, 0.297, 0.305, 0.308, 0.329, 0.388, 0.371],
            [0.887, 0.987, 0.846, 0.805, 0.921, 0.838, 0.846, 0.903],
        ),
        _ => return None,
    };
    Some((a[i], e[i]))
}

/// The paper's (alpha, eta) for teapot at `res` x `res` (Table 3).
fn paper_table3(method: &str, res: u32) -> Option<(f64, f64)> {
    let i = RESOLUTIONS.iter().position(|r| *r == res)?;
    let (a, e): ([f64; 5], [f64; 5]) = match method {
        "kd" => ([1.0; 5], [1.0; 5]),
        "kd-rope" => (
            [0.855, 0.856, 0.856, 0.856, 0.856],
            [1.080, 1.066, 1.064, 1.060, 1.057],
        ),
        "slcts1d" => (
            [0.516, 0.445, 0.381, 0.329, 0.289],
            [1.010, 0.959, 0.924, 0.889, 0.871],
        ),
        "hlcts1d" => (
            [0.484, 0.374, 0.286, 0.221, 0.177],
            [1.065, 0.990, 0.929, 0.868, 0.815],
        ),
        "slcts2d" => (
            [0.525, 0.435, 0.348, 0.274, 0.213],
            [0.930, 0.883, 0.846, 0.809, 0.796],
        ),
        "hlcts2d" => (
            [0.561, 0.437, 0.329, 0.244, 0.184],
            [0.969, 0.90, 0.838, 0.784, 0.751],
        ),
        _ => return None,
    };
    Some((a[i], e[i]))
}

/// One column of a table: a scene at one resolution, all six methods.
pub struct Column {
    /// Its heading.
    pub label: String,
    /// The scene's name.
    pub scene: String,
    /// The resolution (square).
    pub res: u32,
    /// One row per method.
    pub rows: Vec<Row>,
    /// The column as a `coray bench --json` object.
    pub json: serde_json::Value,
}

impl Column {
    fn row(&self, method: &str) -> Option<&Row> {
        self.rows.iter().find(|r| r.method == method)
    }
    fn alpha(&self, method: &str) -> Option<f64> {
        bench::ratios(self.row(method)?, &self.rows).0
    }
    fn eta(&self, method: &str) -> Option<f64> {
        bench::ratios(self.row(method)?, &self.rows).1
    }
}

/// Runs the six methods on one scene (primary rays only, as the paper),
/// each as an image cast through the same harness, each compared with the
/// hierarchical cast timed in its own run (so the hierarchical row's eta
/// shows the timing noise).
pub fn column(s: &SceneData, label: String, set: &Settings) -> Result<Column, String> {
    let built = Built::new(Method::kd_for_casts(), &s.mesh, set.preset, 1)?;
    let kd = built.kd().expect("a kd method");
    let tree = kd.tree(s.mesh.scene()).map_err(|e| e.to_string())?;
    let rows = LCTS_METHODS
        .iter()
        .map(|&(name, scheme, _)| {
            bench::row::run_cast(
                &tree,
                &s.mesh.camera,
                scheme,
                name,
                built.build_ms,
                kd.arena_bytes(),
                set.repeat,
            )
        })
        .collect::<Result<Vec<Row>, String>>()?;
    Ok(Column {
        label,
        scene: s.name.clone(),
        res: s.mesh.camera.width,
        json: bench::report::to_json(s, &rows, 1),
        rows,
    })
}

/// Which of the paper's tables a set of columns reproduces.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Table {
    /// Table 2: one column per scene at one resolution.
    Scenes,
    /// Table 3: one column per resolution of one scene.
    Resolutions,
}

fn paper(table: Table, c: &Column, method: &str) -> Option<(f64, f64)> {
    match table {
        Table::Scenes if c.res == 1024 => {
            paper_table2(method, c.scene.strip_prefix("spd:").unwrap_or(&c.scene))
        }
        Table::Resolutions if c.scene == "spd:teapot" => paper_table3(method, c.res),
        _ => None,
    }
}

/// Prints the table in the paper's layout.
pub fn print(table: Table, cols: &[Column]) {
    let cell = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |x| format!("{x:.p$}"));
    let line = |name: &str, cells: Vec<String>| {
        print!("  {name:<18}");
        for c in cells {
            print!(" {c:>9}");
        }
        println!();
    };
    match table {
        Table::Scenes => println!(
            "Table 2 (Havran and Bittner 2000) on coray: primary rays at {}, one thread; \
             paper alpha/eta at 1024 x 1024 beside ours",
            cols.first()
                .map_or("-".into(), |c| format!("{0} x {0}", c.res))
        ),
        Table::Resolutions => println!(
            "Table 3 (Havran and Bittner 2000) on coray: {} by resolution, one thread",
            cols.first().map_or("-", |c| c.scene.as_str())
        ),
    }
    line("", cols.iter().map(|c| c.label.clone()).collect());
    let per_col = |f: &dyn Fn(&Column) -> Option<f64>, p: usize| -> Vec<String> {
        cols.iter().map(|c| cell(f(c), p)).collect()
    };
    line("isect/ray", per_col(&|c| c.row("kd")?.isect_per_ray, 2));
    for (m, _, title) in LCTS_METHODS {
        println!("{title}");
        line("TSPR", per_col(&|c| c.row(m)?.tspr, 2));
        line("tau [s]", per_col(&|c| Some(c.row(m)?.primary_s), 3));
        line("alpha", per_col(&|c| c.alpha(m), 3));
        line(
            "alpha (paper)",
            per_col(&|c| Some(paper(table, c, m)?.0), 3),
        );
        line("eta", per_col(&|c| c.eta(m), 3));
        line("eta (paper)", per_col(&|c| Some(paper(table, c, m)?.1), 3));
        if m.starts_with("slcts") {
            line("gamma", per_col(&|c| c.row(m)?.gamma, 3));
        }
        line("isect/ray", per_col(&|c| c.row(m)?.isect_per_ray, 2));
        line(
            "mismatches",
            cols.iter()
                .map(|c| c.row(m).map_or("-".into(), |r| r.mismatches.to_string()))
                .collect(),
        );
        if m.contains("lcts") {
            line(
                "ties",
                cols.iter()
                    .map(|c| c.row(m).map_or("-".into(), |r| r.ties.to_string()))
                    .collect(),
            );
        }
    }
    println!("{LEGEND}");
}

/// The legend under the LCTS tables.
pub const LEGEND: &str = "\
rows: TSPR = traversal steps (nodes visited) per ray; tau = seconds of the cast (best of
  --repeat); alpha = TSPR and eta = tau relative to the hierarchical cast of the same pixels,
  timed in turn (so the hierarchical row's eta is the timing noise); gamma = share of windows
  whose common traversal sequence holds a leaf; isect/ray = ray-primitive tests per ray;
  mismatches = pixels whose primitive or t differ from the hierarchical cast; ties = of those,
  two primitives at one t. (paper) rows: Havran and Bittner's values. docs/design.md defines
  every metric.";

/// The columns as JSON: an array of `coray bench --json` objects.
pub fn to_json(cols: &[Column]) -> serde_json::Value {
    cols.iter().map(|c| c.json.clone()).collect()
}
