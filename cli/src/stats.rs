//! `coray stats`: objects by type, and per structure (the kd-tree in both
//! presets, every hierarchy builder) its size and shape.

use crate::budget;
use crate::built::Built;
use crate::method::{Method, Preset, BVH_NAMES};
use crate::scene::SceneData;
use coray::kd::Traversal;
use serde::Serialize;

/// One structure's size and shape.
#[derive(Serialize)]
pub struct Structure {
    /// Method name (`kd-auto`, `kd-paper`, a hierarchy builder).
    pub structure: String,
    /// Nodes (for a kd-tree: interior and leaf).
    pub nodes: u32,
    /// Leaves.
    pub leaves: u32,
    /// Leaves with no primitive (kd-trees).
    pub empty_leaves: Option<u32>,
    /// Deepest leaf.
    pub depth: u32,
    /// References per primitive.
    pub refs_per_prim: f64,
    /// SAH cost relative to the root's area (kd-trees).
    pub sah_cost: Option<f32>,
    /// Bytes of the structure.
    pub bytes: usize,
    /// Build time (ms).
    pub build_ms: f64,
    /// A kd-tree whose room ran out.
    pub truncated: bool,
}

/// The report: the scene's counts and its structures.
#[derive(Serialize)]
pub struct Report {
    /// The scene's name.
    pub scene: String,
    /// Objects as the SPD counts them.
    pub objects: usize,
    /// Spheres.
    pub spheres: usize,
    /// Polygons.
    pub polygons: usize,
    /// Polygons with vertex normals.
    pub polygons_with_normals: usize,
    /// Triangles after triangulation.
    pub triangles: usize,
    /// Cones.
    pub cones: usize,
    /// Cylinders.
    pub cylinders: usize,
    /// Lights.
    pub lights: usize,
    /// Per structure.
    pub structures: Vec<Structure>,
    /// Structures left out, each with why.
    pub skipped: Vec<String>,
}

/// Most primitives `stats` builds the quadratic `nn` matching over: the
/// 36,610 of `spd:gears` took 12 s here, the 69,451 of the Stanford bunny
/// 42 s (the chain, `nn-chain`, makes the same joins in 0.1-0.2 s).
pub const NN_MAX_PRIMS: usize = 40_000;

/// Builds every structure over `s` and describes it.
pub fn stats(s: &SceneData) -> Result<Report, String> {
    let c = &s.mesh.counts;
    let n = s.prim_count();
    let req = coray::kd::requirements(n, &Preset::Auto.params());
    budget::check_memory(
        &format!("the structures of {} ({n} primitives)", s.name),
        budget::kd_bytes(&req),
    )?;
    let per = n.max(1) as f64;
    let mut structures = Vec::new();
    let mut skipped = Vec::new();
    for preset in [Preset::Auto, Preset::Paper] {
        let m = Method::Kd {
            preset: Some(preset),
            traversal: Traversal::Hierarchical,
        };
        let b = Built::new(m, &s.mesh, preset, 1)?;
        let kd = b.kd().expect("a kd method");
        let params = preset.params();
        let v = kd
            .tree(s.mesh.scene())
            .and_then(|t| t.validate_with_costs(params.cost_traversal, params.cost_intersection))
            .map_err(|e| format!("{m}: {e}"))?;
        structures.push(Structure {
            structure: m.to_string(),
            nodes: v.nodes,
            leaves: v.leaves,
            empty_leaves: Some(v.empty_leaves),
            depth: v.depth,
            refs_per_prim: v.refs as f64 / per,
            sah_cost: Some(v.sah_cost),
            bytes: kd.arena_bytes(),
            build_ms: b.build_ms,
            truncated: b.truncated,
        });
    }
    for &(name, build) in &BVH_NAMES {
        if name == "nn" && n > NN_MAX_PRIMS {
            skipped.push(format!(
                "nn: quadratic, over {NN_MAX_PRIMS} primitives (nn-chain makes its joins)"
            ));
            continue;
        }
        let b = Built::new(Method::Bvh { name, build }, &s.mesh, Preset::Auto, 1)?;
        let v = b.bvh_stats().map_err(|e| format!("{name}: {e}"))?;
        structures.push(Structure {
            structure: name.to_string(),
            nodes: v.nodes,
            leaves: v.leaves,
            empty_leaves: None,
            depth: v.depth,
            refs_per_prim: v.refs as f64 / per,
            sah_cost: None,
            bytes: b.bytes.unwrap_or(0),
            build_ms: b.build_ms,
            truncated: false,
        });
    }
    Ok(Report {
        scene: s.name.clone(),
        objects: c.objects(),
        spheres: c.spheres,
        polygons: c.polygons,
        polygons_with_normals: c.polygons_with_normals,
        triangles: c.triangles,
        cones: c.cones,
        cylinders: c.cylinders,
        lights: c.lights,
        structures,
        skipped,
    })
}

/// The report as text.
pub fn print(r: &Report) {
    println!(
        "scene {}: {} objects: {} spheres, {} polygons ({} with normals; {} triangles after \
         triangulation), {} cones, {} cylinders; {} lights",
        r.scene,
        r.objects,
        r.spheres,
        r.polygons,
        r.polygons_with_normals,
        r.triangles,
        r.cones,
        r.cylinders,
        r.lights
    );
    println!(
        "{:<16} {:>9} {:>9} {:>9} {:>6} {:>10} {:>9} {:>12} {:>9} {:>5}",
        "structure",
        "nodes",
        "leaves",
        "empty",
        "depth",
        "refs/prim",
        "SAH",
        "bytes",
        "build ms",
        "trunc"
    );
    for s in &r.structures {
        let opt = |v: Option<String>| v.unwrap_or_else(|| "-".into());
        println!(
            "{:<16} {:>9} {:>9} {:>9} {:>6} {:>10.3} {:>9} {:>12} {:>9.1} {:>5}",
            s.structure,
            s.nodes,
            s.leaves,
            opt(s.empty_leaves.map(|e| e.to_string())),
            s.depth,
            s.refs_per_prim,
            opt(s.sah_cost.map(|c| format!("{c:.1}"))),
            s.bytes,
            s.build_ms,
            if s.truncated { "yes" } else { "no" }
        );
    }
    println!(
        "columns: nodes = nodes reached from the root (a kd-tree's: interior and leaf); empty = \
         leaves with no primitive; refs/prim = primitive references per primitive; SAH = the \
         kd-tree's surface area cost relative to its root's area; bytes = the structure's \
         memory (a C arena's for the kd-tree); trunc = the kd build ran out of room"
    );
    for why in &r.skipped {
        println!("skipped {why}");
    }
}
