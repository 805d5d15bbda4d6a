//! `coray`: the command-line face of the library.
//!
//! With no arguments it runs the main job: `coray bench` on the built-in
//! default scene.

mod bench;
mod scene;

use clap::{Parser, Subcommand};
use coray::kd::KdParams;

#[derive(Parser)]
#[command(
    name = "coray",
    version,
    about = "Allocation-free ray shooting: benchmarks against Embree"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Build each method, cast one primary ray per pixel and one shadow ray
    /// per hit per light, single-threaded; print a table or JSON.
    Bench {
        /// Scene: `random` (100,000 triangles and 10,000 spheres) or `random:N`.
        #[arg(default_value = "random")]
        scene: String,
        /// Image resolution N (N x N primary rays).
        #[arg(long, default_value_t = 1024)]
        res: u32,
        /// Comma-separated methods (default: every method of this build).
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
    },
}

fn main() {
    let cli = Cli::parse();
    let command = cli.command.unwrap_or(Command::Bench {
        scene: "random".into(),
        res: 1024,
        methods: None,
        preset: "auto".into(),
        repeat: 3,
        json: false,
    });
    if let Err(e) = run(command) {
        eprintln!("coray: {e}");
        std::process::exit(2);
    }
}

fn run(command: Command) -> Result<(), String> {
    match command {
        Command::Bench {
            scene,
            res,
            methods,
            preset,
            repeat,
            json,
        } => {
            let mut s = scene::load(&scene)?;
            if res == 0 {
                return Err("--res must be at least 1".into());
            }
            s.camera.width = res;
            s.camera.height = res;
            let params = match preset.as_str() {
                "auto" => KdParams::auto(),
                "paper" => KdParams::paper(),
                p => return Err(format!("unknown preset `{p}` (auto, paper)")),
            };
            let methods = methods
                .unwrap_or_else(|| bench::all_methods().iter().map(|m| m.to_string()).collect());
            let rows = bench::bench(&s, &methods, &params, repeat)?;
            if json {
                println!("{}", bench::to_json(&s, &rows));
            } else {
                bench::print_table(&s, &rows);
            }
            Ok(())
        }
    }
}
