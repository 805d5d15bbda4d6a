//! `coray`: render, benchmark, compare and inspect scenes.
//!
//! With no arguments it runs the main job: `coray render` of the built-in
//! default scene (spd:balls) to coray.png.

mod bench;
mod budget;
mod built;
mod compare;
mod export;
mod kd_jobs;
mod lcts_table;
mod method;
mod plot;
mod projrig;
mod render;
mod scene;
mod series;
mod shoot;
mod spd;
mod stats;
mod summary;

use bench::Settings;
use clap::{Parser, Subcommand};
use coray::kd::Traversal;
use coray_scenes::nff::shown;
use coray_scenes::spd::Options;
use method::{Method, Preset};
use scene::SceneData;
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "coray",
    version,
    about = "Allocation-free ray shooting: render, benchmark, compare and inspect scenes",
    after_help = "With no command: `coray render spd:balls -o coray.png`."
)]
struct Cli {
    /// Cut SPD floors into K x K polygons (thesis 6.3.6), 1 to 1024.
    #[arg(long, global = true, default_value_t = 1, value_name = "K")]
    floor_split: u32,
    #[command(subcommand)]
    command: Option<Command>,
}

/// Threads and repeats a command accepts at most.
const MAX_THREADS: usize = 1024;
const MAX_REPEAT: usize = 1000;

#[derive(Subcommand)]
enum Command {
    /// Whitted ray tracing to an image: primary, shadow, reflection and refraction rays.
    Render {
        /// Scene: an NFF file, a mesh (`.obj`, `.ply`), `spd:NAME[:SIZE]` or `random[:N]`.
        #[arg(default_value = "spd:balls")]
        scene: String,
        /// Output image; the format comes from the extension (.png or .ppm).
        #[arg(short, long, default_value = "coray.png")]
        output: PathBuf,
        /// Resolution WxH or N (default: the scene's).
        #[arg(long)]
        res: Option<String>,
        /// The method rays are traced with (`coray bench --help` lists them all).
        #[arg(long, default_value = "kd")]
        accel: String,
        /// kd-tree preset of `kd` and `kd-rope`: auto, paper or compact.
        #[arg(long, default_value = "auto")]
        preset: String,
        /// Reflection and refraction depth (0 to 64; default 5). `--spd` fixes it.
        #[arg(long)]
        depth: Option<u32>,
        /// Threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// The SPD testing procedure: 512x512 pixels (or --res N), eye rays
        /// through the pixel corners, ray tree depth 5, the SPD's shadow and
        /// refraction rules; prints its ray statistics. `--accel` may also
        /// name an image cast (slcts1d, slcts2d, hlcts1d, hlcts2d, cast-packets)
        /// for the eye rays.
        #[arg(long)]
        spd: bool,
        /// With --spd: print the statistics as one JSON object.
        #[arg(long, requires = "spd")]
        json: bool,
    },
    /// Methods side by side on the same rays in one run; a table with a legend, or JSON.
    Bench {
        /// Scene: an NFF file, a mesh (`.obj`, `.ply`), `spd:NAME[:SIZE]` or `random[:N]` (100,000 triangles, 10,000 spheres).
        #[arg(default_value = "random")]
        scene: String,
        /// Resolution N (N x N primary rays).
        #[arg(long, default_value_t = 1024)]
        res: u64,
        /// Comma-separated methods (default: every method of this build). See the list below.
        #[arg(long, value_delimiter = ',')]
        methods: Option<Vec<String>>,
        /// kd-tree preset: `auto` (SAH termination), `paper` (depth 16, 2 per leaf) or
        /// `compact` (auto without the empty leaves beside full ones).
        #[arg(long, default_value = "auto")]
        preset: String,
        /// Timed runs per method; the best one counts.
        #[arg(long, default_value_t = 3)]
        repeat: usize,
        /// Threads tracing (default 1: the tables' per-ray figures are single-threaded).
        #[arg(long, default_value_t = 1)]
        threads: usize,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
        /// A paper's table instead of the method table (see the list below).
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
    /// image; exit status 1 when any ray disagrees beyond a documented tie.
    /// Needs a build with `--features embree` (Debian's libembree-dev).
    Compare {
        /// Scene: an NFF file, a mesh (`.obj`, `.ply`), `spd:NAME[:SIZE]` or `random[:N]`.
        scene: String,
        /// Resolution N (N x N primary rays).
        #[arg(long, default_value_t = 1024)]
        res: u64,
        /// kd-tree preset.
        #[arg(long, default_value = "auto")]
        preset: String,
        /// Diff image (.png or .ppm).
        #[arg(long, default_value = "coray-diff.png")]
        diff: PathBuf,
        /// Threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Builds a kd-tree and saves it with its scene in one file, for a C
    /// program to map and trace (examples/trace_saved.c; format in
    /// ffi/src/saved.rs).
    Build {
        /// Scene: an NFF file, a mesh (`.obj`, `.ply`), `spd:NAME[:SIZE]` or `random[:N]`.
        scene: String,
        /// The file to write.
        #[arg(short, long, default_value = "scene.coray")]
        output: PathBuf,
        /// kd-tree preset: auto, paper or compact (auto without the empty
        /// leaves beside full ones, and never with ropes).
        #[arg(long, default_value = "auto")]
        preset: String,
        /// Leave the ropes out (48 bytes a leaf): a smaller file whose tree
        /// rope traversal walks hierarchically and the LCTS casts refuse
        /// (`compact` has none either way).
        #[arg(long)]
        no_ropes: bool,
    },
    /// Objects by type and, per structure, its size and shape.
    Stats {
        /// Scene: an NFF file, a mesh (`.obj`, `.ply`), `spd:NAME[:SIZE]` or `random[:N]`.
        scene: String,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// The README's results table from a speed table (`coray bench --table
    /// speed` output, as docs/speed-1024.txt).
    Summary {
        /// The speed table file.
        #[arg(default_value = "docs/speed-1024.txt")]
        file: PathBuf,
    },
    /// Writes a scene as C arrays in CorayScene's layout (for firmware
    /// without a file system; embedded/ is built with one), or as NFF.
    Export {
        /// Scene: an NFF file, a mesh (`.obj`, `.ply`), `spd:NAME[:SIZE]` or `random[:N]`.
        scene: String,
        /// The file to write (default scene.h, or scene.nff with --nff).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Prefix of the C names: PREFIX_vertices, PREFIX_SPHERE_COUNT, ...
        #[arg(long, default_value = "scene")]
        prefix: String,
        /// Write NFF instead of C: the scene's view, lights, materials and
        /// primitives (triangles as `p 3`), which `coray` and
        /// examples/render.c read back.
        #[arg(long)]
        nff: bool,
    },
}

/// `coray render SCENE --spd`: the SPD testing procedure ([`spd`]).
#[allow(clippy::too_many_arguments)]
fn render_spd(
    scene: &str,
    output: &std::path::Path,
    res: Option<String>,
    accel: &str,
    preset: &str,
    threads: Option<usize>,
    json: bool,
    opts: &Options,
) -> Result<i32, String> {
    let threads = threads_or_all(threads)?;
    let method = Method::parse(accel)?;
    let preset = Preset::parse(preset)?;
    let pixels = match res {
        None => spd::PIXELS,
        Some(r) => match parse_res(&r)? {
            (w, h) if w == h && (1..u64::from(coray::limits::MAX_IMAGE_SIDE)).contains(&w) => {
                w as u32
            }
            _ => {
                return Err(format!(
                    "--spd wants a square image of 1 to {} pixels a side: --res N, not `{}`",
                    coray::limits::MAX_IMAGE_SIDE - 1,
                    shown(&r)
                ))
            }
        },
    };
    let s = scene::load(scene, opts)?;
    let n = f64::from(pixels + 1);
    budget::check_memory(&format!("{n}x{n} corner rays"), n * n * 12.0)?;
    let mesh = spd::procedure_mesh(&s.mesh, pixels);
    let (outcome, threads) = if let Method::Cast { scheme } = method {
        let b = built::Built::new(Method::kd_for_casts(), &mesh, preset, 1)?;
        let tree = b
            .kd()
            .expect("a kd method")
            .tree(mesh.scene())
            .map_err(|e| e.to_string())?;
        (spd::run_cast(&mesh, tree, scheme)?, 1)
    } else {
        let b = built::Built::new(method, &mesh, preset, threads)?;
        let job = spd::Job {
            mesh: &mesh,
            threads,
            progress: !json,
        };
        (b.visit(job)?, threads)
    };
    render::write_image(
        output,
        pixels,
        pixels,
        &spd::image(&outcome.corners, pixels),
    )?;
    let report = spd::Report::new(&s.name, &method.to_string(), pixels, threads, &outcome);
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?
        );
    } else {
        print!("{}", report.text());
        println!("  -> {}", output.display());
    }
    Ok(0)
}

/// The paper tables of `bench --table`, with what each shows: the help
/// text and the error list both come from here.
const TABLES: [(&str, &str); 8] = [
    ("build", "build ms and bytes per primitive of kd-auto, kd-paper, tdbs-sah, wide and Embree (1 thread and --threads N), builders interleaved, and the primary rays at --res through kd-auto's tree and Embree's; SCENE as for speed"),
    ("speed", "every method's Mrays/s per ray set against Embree's one-ray and packet calls; SCENE a list, `spd:all`, `meshes` (the bunny and spot from $CORAY_MESHES, default ../shared/meshes, spd:mount:9, spd:tetra:9, random:1000000) or default all of those, the eight SPD scenes and random; at 1 thread and at --threads N; --methods picks the coray methods (the casts run only by default)"),
    ("lcts", "Havran and Bittner's Table 2: SCENE may be a comma-separated list, or `spd:all`"),
    ("lcts-res", "their Table 3: SCENE (default spd:teapot) at 256 to --max-res pixels square"),
    ("bvh", "the thesis' hierarchy metrics per builder on SCENE (6.3.1)"),
    ("proj", "the thesis' chapter 6 metrics per projection method on SCENE"),
    ("bvh-series", "thesis 6.3.1 over its ladders with its observations checked; SCENE ignored"),
    ("proj-series", "thesis chapter 6 over its ladders with 6.4's conclusions checked; SCENE ignored"),
];

fn bench_help() -> String {
    let tables: Vec<String> = TABLES.iter().map(|(n, d)| format!("  {n}: {d}")).collect();
    format!(
        "methods: {}\n\ntables (--table):\n{}\n\n{}",
        Method::help(),
        tables.join("\n"),
        bench::report::LEGEND
    )
}

fn main() {
    let argv: Vec<String> = std::env::args().collect();
    let cmd = <Cli as clap::CommandFactory>::command()
        .mut_subcommand("bench", |c| c.after_help(bench_help()));
    let cli = match <Cli as clap::FromArgMatches>::from_arg_matches(&cmd.get_matches_from(argv)) {
        Ok(c) => c,
        Err(e) => e.exit(),
    };
    let command = cli.command.unwrap_or(Command::Render {
        scene: "spd:balls".into(),
        output: "coray.png".into(),
        res: None,
        accel: "kd".into(),
        preset: "auto".into(),
        depth: None,
        threads: None,
        spd: false,
        json: false,
    });
    match run(command, cli.floor_split) {
        Ok(0) => {}
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("coray: {e}");
            std::process::exit(2);
        }
    }
}

fn threads_or_all(threads: Option<usize>) -> Result<usize, String> {
    let n = threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    budget::check_count("--threads", n, MAX_THREADS)
}

/// `WxH` or `N`.
fn parse_res(s: &str) -> Result<(u64, u64), String> {
    let (w, h) = s.split_once('x').unwrap_or((s, s));
    let p = |v: &str| {
        v.parse::<u64>()
            .map_err(|_| format!("bad resolution `{}` (WxH or N)", shown(s)))
    };
    Ok((p(w)?, p(h)?))
}

/// The scenes of `--table speed|build`: the default (`random`) is the
/// eight SPD scenes, random and the mesh rows ([`mesh_rows`]), `spd:all`
/// the eight SPD scenes, `meshes` the mesh rows, else a comma-separated
/// list.
fn table_scenes(scene: &str) -> Vec<String> {
    let spd = lcts_table::SPD_SCENES.iter().map(|n| format!("spd:{n}"));
    match scene {
        "random" => spd
            .chain(["random".to_string()])
            .chain(mesh_rows())
            .collect(),
        "spd:all" => spd.collect(),
        "meshes" => mesh_rows(),
        _ => scene.split(',').map(str::to_string).collect(),
    }
}

/// Where the mesh rows' files are: `$CORAY_MESHES`, else `../shared/meshes`
/// (beside the repository, as its CI has them).
fn mesh_dir() -> PathBuf {
    std::env::var_os("CORAY_MESHES")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("../shared/meshes"))
}

/// The tables' rows of real meshes and large scenes: the scanned and the
/// modelled mesh of [`mesh_dir`] (those present), SPD mount and tetra at
/// size 9 (about 524k and 262k triangles), a million random triangles.
fn mesh_rows() -> Vec<String> {
    let dir = mesh_dir();
    ["stanford-bunny.obj", "spot.obj"]
        .iter()
        .map(|f| dir.join(f))
        .filter(|p| p.is_file())
        .map(|p| p.display().to_string())
        .chain(
            ["spd:mount:9", "spd:tetra:9", "random:1000000"]
                .iter()
                .map(|s| s.to_string()),
        )
        .collect()
}

/// A scene with its camera set to `res` x `res` pixels, its memory for
/// a benchmark of `methods` methods checked.
fn load_square(name: &str, res: u64, opts: &Options) -> Result<SceneData, String> {
    let mut s = scene::load(name, opts)?;
    s.set_resolution(res, res)?;
    let px = res as f64 * res as f64;
    budget::check_memory(
        &format!("{res}x{res} rays on {name}"),
        px * budget::bytes_per_pixel(s.mesh.lights.len()),
    )?;
    Ok(s)
}

/// Runs one command; the process's exit status.
fn run(command: Command, floor_split: u32) -> Result<i32, String> {
    let opts = Options { floor_split };
    if !(1..=1024).contains(&floor_split) {
        return Err(format!(
            "--floor-split must be 1 to 1024, not {floor_split}"
        ));
    }
    match command {
        Command::Render {
            scene,
            output,
            res,
            accel,
            preset,
            depth,
            threads,
            spd,
            json,
        } => {
            render::ImageFormat::for_path(&output)?;
            if spd {
                if depth.is_some() {
                    return Err("--spd fixes the ray tree depth at 5: leave out --depth".into());
                }
                return render_spd(&scene, &output, res, &accel, &preset, threads, json, &opts);
            }
            let depth = depth.unwrap_or(5);
            if depth > 64 {
                return Err(format!("--depth must be 0 to 64, not {depth}"));
            }
            let threads = threads_or_all(threads)?;
            let method = Method::parse(&accel)?;
            let preset = Preset::parse(&preset)?;
            let mut s = scene::load(&scene, &opts)?;
            if let Some(r) = res {
                let (w, h) = parse_res(&r)?;
                s.set_resolution(w, h)?;
            }
            let (w, h) = (s.mesh.camera.width, s.mesh.camera.height);
            budget::check_memory(
                &format!("a {w}x{h} image"),
                w as f64 * h as f64 * budget::IMAGE_BYTES_PER_PIXEL,
            )?;
            let b = built::Built::new(method, &s.mesh, preset, threads)?;
            let (rgb, rays, secs) = b.visit(render::Job {
                mesh: &s.mesh,
                depth,
                threads,
            })?;
            render::write_image(&output, w, h, &rgb)?;
            println!(
                "{}: {} objects, {w}x{h}, {rays} rays ({:.2} Mrays/s on {threads} thread{}, {method} \
                 build {:.0} ms) -> {}",
                s.name,
                s.mesh.counts.objects(),
                rays as f64 / secs / 1e6,
                if threads == 1 { "" } else { "s" },
                b.build_ms,
                output.display()
            );
            Ok(0)
        }
        Command::Bench {
            scene,
            res,
            methods,
            preset,
            repeat,
            threads,
            json,
            table,
            max_res,
            max_size,
            plot,
        } => {
            let set = Settings {
                preset: Preset::parse(&preset)?,
                repeat: budget::check_count("--repeat", repeat, MAX_REPEAT)?,
                threads: budget::check_count("--threads", threads, MAX_THREADS)?,
                progress: !json,
            };
            if let Some(p) = &plot {
                if render::ImageFormat::for_path(p).ok() != Some(render::ImageFormat::Png) {
                    return Err(format!("{}: charts are written as .png", p.display()));
                }
            }
            let is_series = matches!(table.as_deref(), Some("bvh-series" | "proj-series"));
            if (plot.is_some() || max_size.is_some()) && !is_series {
                return Err(
                    "--plot and --max-size go with --table bvh-series or proj-series".into(),
                );
            }
            if methods.is_some() && table.as_deref().is_some_and(|t| t != "speed") {
                return Err(
                    "--methods goes with no --table or with --table speed: other tables have their methods".into(),
                );
            }
            let methods = methods
                .map(|v| {
                    v.iter()
                        .map(|m| Method::parse(m))
                        .collect::<Result<Vec<_>, _>>()
                })
                .transpose()?;
            match table {
                None => {
                    let methods = methods.unwrap_or_else(Method::all);
                    let s = load_square(&scene, res, &opts)?;
                    let rows = bench::bench(&s, &methods, &set)?;
                    if json {
                        println!("{}", bench::report::to_json(&s, &rows, set.threads));
                    } else {
                        bench::report::print_table(&s, &rows, set.threads);
                    }
                }
                Some(t) => paper_table(
                    &t,
                    &scene,
                    (res, max_res, max_size),
                    plot,
                    json,
                    &set,
                    methods.as_deref(),
                    &opts,
                )?,
            }
            Ok(0)
        }
        Command::Compare {
            scene,
            res,
            preset,
            diff,
            threads,
        } => {
            render::ImageFormat::for_path(&diff)?;
            // The arguments first, then whether this build has Embree: a
            // bad resolution gets the same answer in every build.
            budget::check_side("--res", res)?;
            Method::Embree(method::EmbreeCall::One).available()?;
            let threads = threads_or_all(threads)?;
            let s = load_square(&scene, res, &opts)?;
            let out = compare::compare(&s, Preset::parse(&preset)?, threads, &diff)?;
            if out.mismatches > 0 {
                eprintln!(
                    "coray: {} of {} rays disagree with Embree",
                    out.mismatches, out.rays
                );
                return Ok(1);
            }
            Ok(0)
        }
        Command::Build {
            scene,
            output,
            preset,
            no_ropes,
        } => {
            let (preset, omit_ropes) = Preset::parse(&preset)?.c_params(!no_ropes);
            let s = scene::load(&scene, &opts)?;
            let n = s.prim_count();
            budget::check_memory(
                &format!("a kd-tree over {n} primitives"),
                budget::kd_bytes(&coray::kd::requirements(
                    n,
                    &coray::kd::KdParams::auto_with_ropes(),
                )),
            )?;
            let bytes = coray_ffi::saved::kdtree_file(
                &s.mesh.scene(),
                Some(&s.mesh.camera),
                preset,
                omit_ropes,
            )
            .map_err(|st| format!("{scene}: the build failed: {}", status_text(st)))?;
            std::fs::write(&output, &bytes).map_err(|e| format!("{}: {e}", output.display()))?;
            println!(
                "{}: {} objects, a kd-tree and its scene in {} bytes -> {}",
                s.name,
                s.mesh.counts.objects(),
                bytes.len(),
                output.display()
            );
            Ok(0)
        }
        Command::Export {
            scene,
            output,
            prefix,
            nff,
        } => {
            if nff {
                let output = output.unwrap_or_else(|| PathBuf::from("scene.nff"));
                let s = scene::load(&scene, &opts)?;
                std::fs::write(&output, s.mesh.to_nff().to_nff())
                    .map_err(|e| format!("{}: {e}", output.display()))?;
                println!(
                    "{}: {} objects -> {}",
                    shown(&scene),
                    s.mesh.counts.objects(),
                    output.display()
                );
                return Ok(0);
            }
            let output = output.unwrap_or_else(|| PathBuf::from("scene.h"));
            let ident = |c: char| c == '_' || c.is_ascii_alphanumeric();
            if prefix.is_empty()
                || prefix.starts_with(|c: char| c.is_ascii_digit())
                || !prefix.chars().all(ident)
            {
                return Err(format!(
                    "--prefix must be a C identifier, not `{}`",
                    shown(&prefix)
                ));
            }
            let s = scene::load(&scene, &opts)?;
            std::fs::write(&output, export::c_header(&scene, &prefix, &s.mesh))
                .map_err(|e| format!("{}: {e}", output.display()))?;
            println!(
                "{scene}: {} objects -> {}",
                s.mesh.counts.objects(),
                output.display()
            );
            Ok(0)
        }
        Command::Summary { file } => {
            let text =
                std::fs::read_to_string(&file).map_err(|e| format!("{}: {e}", file.display()))?;
            print!("{}", summary::summary(&text)?);
            Ok(0)
        }
        Command::Stats { scene, json } => {
            let s = scene::load(&scene, &opts)?;
            let report = stats::stats(&s)?;
            if json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&report).map_err(|e| e.to_string())?
                );
            } else {
                stats::print(&report);
            }
            Ok(0)
        }
    }
}

/// A status's description, as `coray_status_str` gives it.
fn status_text(s: coray_ffi::CorayStatus) -> String {
    coray_ffi::status_description(s as i32)
        .to_string_lossy()
        .into_owned()
}

/// `coray bench --table NAME`.
#[allow(clippy::too_many_arguments)]
fn paper_table(
    table: &str,
    scene: &str,
    (res, max_res, max_size): (u64, u32, Option<u32>),
    plot: Option<PathBuf>,
    json: bool,
    set: &Settings,
    methods: Option<&[Method]>,
    opts: &Options,
) -> Result<(), String> {
    let one = Settings { threads: 1, ..*set };
    match table {
        "build" => {
            let mut rows = Vec::new();
            for name in &table_scenes(scene) {
                let s = load_square(name, res, opts)?;
                rows.push(bench::build::run(&s, set.repeat, set.threads)?);
            }
            if json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?
                );
            } else {
                bench::build::print(&rows);
            }
        }
        "speed" => {
            let scenes = table_scenes(scene);
            let mut counts = vec![1];
            if set.threads > 1 {
                counts.push(set.threads);
            }
            let mut rows = Vec::new();
            for name in &scenes {
                let s = load_square(name, res, opts)?;
                rows.extend(bench::speed::run(&s, set, &counts, methods)?);
            }
            if json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?
                );
            } else {
                bench::speed::print(&rows);
            }
        }
        "bvh" | "proj" => {
            let s = load_square(scene, res, opts)?;
            let mut methods = vec![Method::kd(Traversal::Hierarchical)];
            if table == "bvh" {
                methods.extend(
                    method::BVH_NAMES
                        .iter()
                        .map(|&(name, build)| Method::Bvh { name, build }),
                );
            } else {
                methods.extend(
                    method::PROJ_BUILDERS
                        .iter()
                        .map(|m| Method::parse(m).expect("registered")),
                );
                methods.extend(Method::projections());
                if cfg!(feature = "embree") {
                    methods.push(Method::Embree(method::EmbreeCall::One));
                }
            }
            let rows = bench::bench(&s, &methods, &one)?;
            if json {
                println!("{}", bench::report::to_json(&s, &rows, 1));
            } else if table == "bvh" {
                bench::report::print_bvh_table(&s, &rows);
            } else {
                bench::report::print_proj_table(&s, &rows);
            }
        }
        "bvh-series" | "proj-series" => {
            let study = series::STUDIES
                .iter()
                .find(|s| s.table == table)
                .expect("every series table has a study");
            let side = budget::check_side("--res", res)?;
            let pts = series::run(study, side, max_size, &one)?;
            if json {
                println!("{}", series::to_json(study, &pts));
            } else {
                series::print(study, &pts, side);
            }
            if let Some(path) = plot {
                series::write_plot(study, &pts, &path, side)?;
                eprintln!("charts -> {}", path.display());
            }
        }
        "lcts" | "lcts-res" => {
            let mut cols = Vec::new();
            let kind = if table == "lcts" {
                let scenes: Vec<String> = if scene == "spd:all" {
                    lcts_table::SPD_SCENES
                        .iter()
                        .map(|n| format!("spd:{n}"))
                        .collect()
                } else {
                    scene.split(',').map(str::to_string).collect()
                };
                for name in &scenes {
                    let s = load_square(name, res, opts)?;
                    let label = name.strip_prefix("spd:").unwrap_or(name).to_string();
                    cols.push(lcts_table::column(&s, label, &one)?);
                }
                lcts_table::Table::Scenes
            } else {
                // The default scene of `bench` is random; Table 3 is teapot's.
                let name = if scene == "random" {
                    "spd:teapot"
                } else {
                    scene
                };
                for r in lcts_table::RESOLUTIONS.iter().filter(|&&r| r <= max_res) {
                    let s = load_square(name, *r as u64, opts)?;
                    cols.push(lcts_table::column(&s, format!("{r}^2"), &one)?);
                }
                if cols.is_empty() {
                    return Err(format!(
                        "--max-res {max_res} leaves no resolution (the smallest is {})",
                        lcts_table::RESOLUTIONS[0]
                    ));
                }
                lcts_table::Table::Resolutions
            };
            if json {
                println!("{}", lcts_table::to_json(&cols));
            } else {
                lcts_table::print(kind, &cols);
            }
        }
        t => {
            let names: Vec<&str> = TABLES.iter().map(|(n, _)| *n).collect();
            return Err(format!(
                "unknown --table `{t}` (have: {})",
                names.join(", ")
            ));
        }
    }
    Ok(())
}
