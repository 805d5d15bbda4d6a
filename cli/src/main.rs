//! `coray`: render, benchmark and inspect scenes.
//!
//! With no arguments it runs the main job: `coray render` of the built-in
//! default scene (spd:balls) to coray.png.

mod bench;
mod bvhbuild;
#[cfg(feature = "embree")]
mod compare;
mod kdbuild;
mod plot;
mod proj_series;
mod projbuild;
mod render;
mod scene;
mod series;
mod stats;
mod tables;

use clap::{Parser, Subcommand};
use coray::kd::Traversal;
use coray_scenes::spd::Options;
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "coray",
    version,
    about = "Allocation-free ray shooting: render, benchmark and inspect scenes"
)]
struct Cli {
    /// Cut SPD floors into K x K polygons (thesis 6.3.6).
    #[arg(long, global = true, default_value_t = 1, value_name = "K")]
    floor_split: u32,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Whitted ray tracing to a PNG: primary, shadow, reflection and refraction rays.
    Render {
        /// Scene: an NFF file, `spd:NAME[:SIZE]` or `random[:N]`.
        #[arg(default_value = "spd:balls")]
        scene: String,
        /// Output PNG.
        #[arg(short, long, default_value = "coray.png")]
        output: PathBuf,
        /// Resolution WxH (default: the scene's).
        #[arg(long)]
        res: Option<String>,
        /// Structure and traversal: kd, kd-rope, kd-paper, kd-paper-rope, or a
        /// hierarchy: tdbs, tdbs-sah, nn, nn-chain, rtree, rstar, rstar-reinsert,
        /// or projection hierarchies proj-BUILDER-CRITERIA-SCHEME (BUILDER
        /// tdbs|nn-chain|rtree|rstar, CRITERIA 2d|dummy, SCHEME 2d|3d|comb).
        #[arg(long, default_value = "kd")]
        accel: String,
        /// Reflection and refraction depth.
        #[arg(long, default_value_t = 5)]
        depth: u32,
        /// Threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Every method on the same primary and shadow rays, one thread; a table or JSON.
    Bench {
        /// Scene: an NFF file, `spd:NAME[:SIZE]` or `random[:N]` (100,000 triangles, 10,000 spheres).
        #[arg(default_value = "random")]
        scene: String,
        /// Resolution N (N x N primary rays).
        #[arg(long, default_value_t = 1024)]
        res: u32,
        /// Comma-separated methods (default: every method of this build);
        /// `slcts1d:N` and `slcts2d:NxM` cast with other windows than the paper's.
        #[arg(long, value_delimiter = ',')]
        methods: Option<Vec<String>>,
        /// kd-tree preset: `auto` (SAH termination) or `paper` (depth 16, 2 per leaf).
        #[arg(long, default_value = "auto")]
        preset: String,
        /// Timed runs per method; the best one counts.
        #[arg(long, default_value_t = 3)]
        repeat: usize,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
        /// A paper's table instead of the method table: `bvh` (the thesis'
        /// hierarchy metrics per builder on SCENE), `proj` (its chapter 6
        /// metrics per projection hierarchy, criterion and scheme, beside the
        /// 3D hierarchies), `proj-series` (chapter 6 over the thesis' ladders,
        /// its 6.4 conclusions checked; SCENE is ignored), `bvh-series` (thesis
        /// 6.3.1: tree 1-11 floor whole and split, balls 1-4, gears 1-4, with
        /// its observations checked; SCENE is ignored), `lcts` (Havran and
        /// Bittner's Table 2: SCENE may be a comma-separated list, or `spd:all`
        /// for the eight SPD scenes) or `lcts-res` (Table 3: SCENE, default
        /// spd:teapot, at 256 to --max-res pixels square).
        #[arg(long)]
        table: Option<String>,
        /// `--table lcts-res`: the largest resolution (Table 3 goes to 4096).
        #[arg(long, default_value_t = 4096)]
        max_res: u32,
        /// `--table bvh-series|proj-series`: leave out sizes above this one.
        #[arg(long)]
        max_size: Option<u32>,
        /// `--table bvh-series|proj-series`: also draw the series as charts in this PNG.
        #[arg(long)]
        plot: Option<PathBuf>,
    },
    /// Primary and shadow rays through coray and Embree, ray by ray; a diff
    /// image; exits with status 1 when any ray disagrees beyond a documented tie.
    #[cfg(feature = "embree")]
    Compare {
        /// Scene: an NFF file, `spd:NAME[:SIZE]` or `random[:N]`.
        scene: String,
        /// Resolution N (N x N primary rays).
        #[arg(long, default_value_t = 1024)]
        res: u32,
        /// kd-tree preset.
        #[arg(long, default_value = "auto")]
        preset: String,
        /// Diff image.
        #[arg(long, default_value = "coray-diff.png")]
        diff: PathBuf,
    },
    /// Objects by type and, per structure, its size and shape.
    Stats {
        /// Scene: an NFF file, `spd:NAME[:SIZE]` or `random[:N]`.
        scene: String,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
}

fn main() {
    let cli = Cli::parse();
    let opts = Options {
        floor_split: cli.floor_split,
    };
    let command = cli.command.unwrap_or(Command::Render {
        scene: "spd:balls".into(),
        output: "coray.png".into(),
        res: None,
        accel: "kd".into(),
        depth: 5,
        threads: None,
    });
    if let Err(e) = run(command, &opts) {
        eprintln!("coray: {e}");
        std::process::exit(2);
    }
}

fn parse_res(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').unwrap_or((s, s));
    let p = |v: &str| {
        v.parse::<u32>()
            .ok()
            .filter(|&n| (1..=1 << 15).contains(&n))
            .ok_or(format!("bad resolution `{s}` (WxH)"))
    };
    Ok((p(w)?, p(h)?))
}

/// A scene with its camera set to `res` x `res` pixels.
fn load_square(scene: &str, res: u32, opts: &Options) -> Result<scene::SceneData, String> {
    if res == 0 {
        return Err("--res must be at least 1".into());
    }
    let mut s = scene::load(scene, opts)?;
    s.mesh.camera.width = res;
    s.mesh.camera.height = res;
    Ok(s)
}

/// Where `coray render` writes, and how.
struct RenderOut<'a> {
    scene: &'a scene::SceneData,
    output: &'a std::path::Path,
    threads: usize,
    depth: u32,
}

impl RenderOut<'_> {
    fn render<S: render::Shooter>(&self, shooter: &S, build_ms: f64) -> Result<(), String> {
        let s = self.scene;
        let tracer = render::Tracer {
            mesh: &s.mesh,
            shooter,
            max_depth: self.depth,
            secondary: Default::default(),
        };
        let threads = self.threads;
        let t = std::time::Instant::now();
        let (rgb, st) = render::render(&tracer, threads, true);
        let secs = t.elapsed().as_secs_f64();
        let (w, h) = (s.mesh.camera.width, s.mesh.camera.height);
        render::write_png(self.output, w, h, &rgb)?;
        println!(
            "{}: {} objects, {w}x{h}, {} rays ({:.2} Mrays/s on {threads} threads, build {:.0} ms) -> {}",
            s.name,
            s.mesh.counts.objects(),
            st.rays,
            st.rays as f64 / secs / 1e6,
            build_ms,
            self.output.display()
        );
        Ok(())
    }
}

fn run(command: Command, opts: &Options) -> Result<(), String> {
    match command {
        Command::Render {
            scene,
            output,
            res,
            accel,
            depth,
            threads,
        } => {
            let mut s = scene::load(&scene, opts)?;
            if let Some(r) = res {
                let (w, h) = parse_res(&r)?;
                s.mesh.camera.width = w;
                s.mesh.camera.height = h;
            }
            let threads = threads
                .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
            let kd = match accel.as_str() {
                "kd" => Some(("auto", Traversal::Hierarchical)),
                "kd-rope" => Some(("auto", Traversal::Ropes)),
                "kd-paper" => Some(("paper", Traversal::Hierarchical)),
                "kd-paper-rope" => Some(("paper", Traversal::Ropes)),
                _ => None,
            };
            let out = RenderOut {
                scene: &s,
                output: &output,
                threads,
                depth,
            };
            if let Some((preset, method)) = kd {
                let owned = kdbuild::OwnedKd::build(&s.mesh.scene(), &kdbuild::preset(preset)?)?;
                let tree = owned.tree(s.mesh.scene());
                out.render(
                    &render::KdShooter {
                        tree: &tree,
                        method,
                    },
                    owned.build_ms,
                )
            } else if let Some(m) = projbuild::parse(&accel) {
                let scene = s.mesh.scene();
                let rig = projbuild::ProjRig::for_scene(&s, m)?;
                let ms = rig.view_ms + rig.light_ms + rig.global_ms;
                out.render(&render::ProjShooter { rig: &rig, scene }, ms)
            } else if bvhbuild::METHODS.contains(&accel.as_str()) {
                let owned = bvhbuild::OwnedBvh::build(&s.mesh.scene(), &accel)?;
                let bvh = owned.bvh(s.mesh.scene());
                out.render(&render::BvhShooter { bvh }, owned.build_ms)
            } else {
                Err(format!(
                    "unknown --accel `{accel}` (kd, kd-rope, kd-paper, kd-paper-rope, {}, or \
                     proj-BUILDER-CRITERIA-SCHEME: {})",
                    bvhbuild::METHODS.join(", "),
                    projbuild::methods().join(", ")
                ))
            }
        }
        Command::Bench {
            scene,
            res,
            methods,
            preset,
            repeat,
            json,
            table,
            max_res,
            max_size,
            plot,
        } => {
            let params = kdbuild::preset(&preset)?;
            if table.as_deref() == Some("bvh-series") {
                let pts = series::run(res, max_size, &params, repeat)?;
                if json {
                    println!("{}", series::to_json(&pts));
                } else {
                    series::print(&pts, res);
                    println!();
                    for o in series::observations(&pts) {
                        println!("{o}");
                    }
                }
                if let Some(path) = plot {
                    series::write_plot(&pts, &path, res)?;
                    eprintln!("charts -> {}", path.display());
                }
                return Ok(());
            }
            if table.as_deref() == Some("proj-series") {
                let pts = proj_series::run(res, max_size, &params, repeat)?;
                proj_series::print(&pts, res);
                println!();
                for c in proj_series::conclusions(&pts) {
                    println!("{c}");
                }
                if let Some(path) = plot {
                    proj_series::write_plot(&pts, &path, res)?;
                    eprintln!("charts -> {}", path.display());
                }
                return Ok(());
            }
            if plot.is_some() || max_size.is_some() {
                return Err(
                    "--plot and --max-size go with --table bvh-series or proj-series".into(),
                );
            }
            if let Some(table) = table {
                return paper_table(&table, &scene, res, max_res, &params, repeat, json, opts);
            }
            let s = load_square(&scene, res, opts)?;
            let methods = methods
                .unwrap_or_else(|| bench::all_methods().iter().map(|m| m.to_string()).collect());
            let rows = bench::bench(&s, &methods, &params, repeat, true)?;
            if json {
                println!("{}", bench::to_json(&s, &rows));
            } else {
                bench::print_table(&s, &rows);
            }
            Ok(())
        }
        #[cfg(feature = "embree")]
        Command::Compare {
            scene,
            res,
            preset,
            diff,
        } => {
            let s = load_square(&scene, res, opts)?;
            let out = compare::compare(&s, &kdbuild::preset(&preset)?, &diff)?;
            if out.mismatches > 0 {
                eprintln!(
                    "coray: {} of {} rays disagree with Embree",
                    out.mismatches, out.rays
                );
                std::process::exit(1);
            }
            Ok(())
        }
        Command::Stats { scene, json } => {
            let s = scene::load(&scene, opts)?;
            let report = stats::stats(&s)?;
            println!("{}", if json { report.json } else { report.text });
            Ok(())
        }
    }
}

/// `coray bench --table lcts|lcts-res`.
#[allow(clippy::too_many_arguments)]
fn paper_table(
    table: &str,
    scene: &str,
    res: u32,
    max_res: u32,
    params: &coray::kd::KdParams,
    repeat: usize,
    json: bool,
    opts: &Options,
) -> Result<(), String> {
    let mut cols = Vec::new();
    let kind = match table {
        "proj" => {
            let s = load_square(scene, res, opts)?;
            let mut methods = vec!["kd".to_string()];
            methods.extend(projbuild::BUILDERS.iter().map(|m| m.to_string()));
            methods.extend(projbuild::methods());
            if cfg!(feature = "embree") {
                methods.push("embree".into());
            }
            let rows = bench::bench(&s, &methods, params, repeat, true)?;
            if json {
                println!("{}", bench::to_json(&s, &rows));
            } else {
                bench::print_proj_table(&s, &rows);
            }
            return Ok(());
        }
        "bvh" => {
            let s = load_square(scene, res, opts)?;
            let mut methods = vec!["kd".to_string()];
            methods.extend(bvhbuild::METHODS.iter().map(|m| m.to_string()));
            let rows = bench::bench(&s, &methods, params, repeat, true)?;
            if json {
                println!("{}", bench::to_json(&s, &rows));
            } else {
                bench::print_bvh_table(&s, &rows);
            }
            return Ok(());
        }
        "lcts" => {
            let scenes: Vec<String> = if scene == "spd:all" {
                tables::SPD_SCENES
                    .iter()
                    .map(|n| format!("spd:{n}"))
                    .collect()
            } else {
                scene.split(',').map(str::to_string).collect()
            };
            for name in &scenes {
                let s = load_square(name, res, opts)?;
                let label = name.strip_prefix("spd:").unwrap_or(name).to_string();
                cols.push(tables::column(&s, label, params, repeat)?);
            }
            tables::Table::Scenes
        }
        "lcts-res" => {
            // The default scene of `bench` is random; Table 3 is teapot's.
            let name = if scene == "random" {
                "spd:teapot"
            } else {
                scene
            };
            for r in tables::RESOLUTIONS.iter().filter(|&&r| r <= max_res) {
                let s = load_square(name, *r, opts)?;
                cols.push(tables::column(&s, format!("{r}^2"), params, repeat)?);
            }
            tables::Table::Resolutions
        }
        t => return Err(format!("unknown --table `{t}` (lcts, lcts-res, bvh)")),
    };
    if cols.is_empty() {
        return Err(format!(
            "--max-res {max_res} leaves no resolution (smallest 256)"
        ));
    }
    if json {
        println!("{}", tables::to_json(&cols));
    } else {
        tables::print(kind, &cols);
    }
    Ok(())
}
