//! `coray bench`: methods side by side on the same rays in one run. The
//! harness times ([`harness`]), the ray sets ([`rays`]), the runners and
//! their rows ([`row`]) and the printed and JSON reports ([`report`]) are
//! each their own module; the paper tables live in `lcts_table` and
//! `series`.

pub mod build;
pub mod harness;
pub mod rays;
pub mod report;
pub mod row;
pub mod speed;

use crate::built::Built;
use crate::method::{Method, Preset};
use crate::scene::SceneData;
use coray::kd::Traversal;
pub use row::{ratios, Row};

/// How a benchmark runs.
#[derive(Clone, Copy, Debug)]
pub struct Settings {
    /// The kd-tree preset of methods that name none (and of the reference).
    pub preset: Preset,
    /// Timed runs per method; the best counts.
    pub repeat: usize,
    /// Threads tracing (and building, where a structure builds in parallel).
    pub threads: usize,
    /// Show progress on a terminal.
    pub progress: bool,
}

/// A progress bar on stderr when it is a terminal and `on`; hidden else.
pub fn progress(len: usize, on: bool) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !on || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let pb = indicatif::ProgressBar::new(len as u64);
    pb.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} ({elapsed})")
            .expect("a valid template"),
    );
    pb
}

/// Runs `methods` on the same rays. The reference for mismatches, alpha
/// and eta is the kd-tree's hierarchical traversal with `set.preset`,
/// traced in the same run whether or not `kd` is listed (for LCTS rows:
/// its image cast).
pub fn bench(s: &SceneData, methods: &[Method], set: &Settings) -> Result<Vec<Row>, String> {
    for m in methods {
        m.available()?;
    }
    let reference = Built::new(
        Method::kd(Traversal::Hierarchical),
        &s.mesh,
        set.preset,
        set.threads,
    )?;
    let kd = reference.kd().expect("a kd method");
    let tree = kd.tree(s.mesh.scene()).map_err(|e| e.to_string())?;
    // The casts walk ropes: their own tree, the reference's with ropes.
    let for_casts = if methods.iter().any(|m| matches!(m, Method::Cast { .. })) {
        Some(Built::new(
            Method::kd_for_casts(),
            &s.mesh,
            set.preset,
            set.threads,
        )?)
    } else {
        None
    };
    let w = row::workload(&s.mesh, &tree);
    let mut rows = Vec::new();
    let pb = progress(methods.len() + 1, set.progress);
    pb.set_message("kd (reference)");
    let reference_row = row::run_rays(&reference, &w, &tree, set.repeat, set.threads).row;
    pb.inc(1);
    if !methods.contains(&Method::kd(Traversal::Hierarchical)) {
        rows.push(reference_row.clone());
    }
    for &m in methods {
        pb.set_message(m.to_string());
        let r = match m {
            Method::Kd {
                preset: None,
                traversal: Traversal::Hierarchical,
            } => reference_row.clone(),
            Method::Cast { scheme } => {
                let b = for_casts.as_ref().expect("built for the casts");
                let kd = b.kd().expect("a kd method");
                row::run_cast(
                    &kd.tree(s.mesh.scene()).map_err(|e| e.to_string())?,
                    &s.mesh.camera,
                    scheme,
                    &m.to_string(),
                    b.build_ms,
                    kd.arena_bytes(),
                    set.repeat,
                )?
            }
            _ => {
                let b = Built::new(m, &s.mesh, set.preset, set.threads)?;
                row::run_rays(&b, &w, &tree, set.repeat, set.threads).row
            }
        };
        rows.push(r);
        pb.inc(1);
    }
    pb.finish_and_clear();
    Ok(rows)
}
