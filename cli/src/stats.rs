//! `coray stats`: objects by type, and per structure its size and shape.

use crate::kdbuild::{preset, OwnedKd};
use crate::scene::SceneData;

pub struct Report {
    pub text: String,
    pub json: String,
}

pub fn stats(s: &SceneData) -> Result<Report, String> {
    let c = &s.mesh.counts;
    let mut text = format!(
        "scene {}: {} objects: {} spheres, {} polygons ({} with normals; {} triangles after triangulation), {} cones, {} cylinders; {} lights\n",
        s.name,
        c.objects(),
        c.spheres,
        c.polygons,
        c.polygons_with_normals,
        c.triangles,
        c.cones,
        c.cylinders,
        c.lights
    );
    let mut rows = Vec::new();
    for name in ["auto", "paper"] {
        let params = preset(name)?;
        let owned = OwnedKd::build(&s.mesh.scene(), &params)?;
        let tree = owned.tree(s.mesh.scene());
        let v = tree
            .validate_with_costs(params.cost_traversal, params.cost_intersection)
            .map_err(|e| e.to_string())?;
        let n = s.prim_count().max(1) as f64;
        text.push_str(&format!(
            "kd-{name}: {} nodes, {} leaves ({} empty), depth {}, {:.3} references per primitive, SAH cost {:.1}, {} arena bytes ({:.1} per primitive), build {:.1} ms{}\n",
            v.nodes,
            v.leaves,
            v.empty_leaves,
            v.depth,
            v.refs as f64 / n,
            v.sah_cost,
            owned.arena_bytes(),
            owned.arena_bytes() as f64 / n,
            owned.build_ms,
            if owned.info.truncated() { ", truncated" } else { "" }
        ));
        rows.push(format!(
            "{{\"structure\": \"kd-{name}\", \"nodes\": {}, \"leaves\": {}, \"empty_leaves\": {}, \"depth\": {}, \"refs_per_prim\": {}, \"sah_cost\": {}, \"arena_bytes\": {}, \"build_ms\": {}, \"truncated\": {}}}",
            v.nodes, v.leaves, v.empty_leaves, v.depth, v.refs as f64 / n, v.sah_cost, owned.arena_bytes(), owned.build_ms, owned.info.truncated()
        ));
    }
    let json = format!(
        "{{\"scene\": \"{}\", \"objects\": {}, \"spheres\": {}, \"polygons\": {}, \"polygons_with_normals\": {}, \"triangles\": {}, \"cones\": {}, \"cylinders\": {}, \"lights\": {}, \"structures\": [{}]}}",
        s.name.replace('\\', "\\\\").replace('"', "\\\""),
        c.objects(),
        c.spheres,
        c.polygons,
        c.polygons_with_normals,
        c.triangles,
        c.cones,
        c.cylinders,
        c.lights,
        rows.join(", ")
    );
    Ok(Report {
        text: text.trim_end().to_string(),
        json,
    })
}
