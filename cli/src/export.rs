//! `coray export SCENE -o scene.h`: a scene as C arrays in the layout of
//! `CorayScene`, for firmware that has no file system (the Cortex-M4
//! program in `embedded/` is built with one). Floats are written in Rust's
//! shortest round-trip form, so the C compiler reads back the same bits.

use coray_scenes::SceneMesh;
use std::fmt::Write;

fn floats(out: &mut String, name: &str, values: impl Iterator<Item = f32>) {
    let v: Vec<String> = values.map(|f| format!("{f:?}f")).collect();
    // C forbids empty initialisers: a lone 0 keeps an empty array legal.
    let body = if v.is_empty() {
        "0".to_string()
    } else {
        v.join(", ")
    };
    let _ = writeln!(out, "static const float {name}[] = {{{body}}};");
}

/// The C header for `mesh`, named `spec` in its comment, its arrays
/// `PREFIX_vertices` and so on, its macros `PREFIX_VERTEX_COUNT` in capitals.
pub fn c_header(spec: &str, prefix: &str, mesh: &SceneMesh) -> String {
    let up = prefix.to_ascii_uppercase();
    let mut s = String::new();
    let _ = writeln!(
        s,
        "/* {spec}: written by `coray export {spec}`; do not edit. Arrays in the\n   \
         layout of CorayScene, the camera and lights of the scene's NFF view. */\n\
         #include <stdint.h>\n"
    );
    floats(
        &mut s,
        &format!("{prefix}_vertices"),
        mesh.vertices.iter().flatten().copied(),
    );
    let idx: Vec<String> = mesh
        .triangles
        .iter()
        .flatten()
        .map(u32::to_string)
        .collect();
    let body = if idx.is_empty() {
        "0".to_string()
    } else {
        idx.join(", ")
    };
    let _ = writeln!(s, "static const uint32_t {prefix}_indices[] = {{{body}}};");
    floats(
        &mut s,
        &format!("{prefix}_spheres"),
        mesh.spheres
            .iter()
            .flat_map(|p| [p.center[0], p.center[1], p.center[2], p.radius]),
    );
    floats(
        &mut s,
        &format!("{prefix}_cones"),
        mesh.cones.iter().flat_map(|c| {
            let (b, a) = (c.base, c.apex);
            [
                b[0],
                b[1],
                b[2],
                c.base_radius,
                a[0],
                a[1],
                a[2],
                c.apex_radius,
            ]
        }),
    );
    let cam = &mesh.camera;
    floats(
        &mut s,
        &format!("{prefix}_from"),
        cam.from.to_array().into_iter(),
    );
    floats(
        &mut s,
        &format!("{prefix}_at"),
        cam.at.to_array().into_iter(),
    );
    floats(
        &mut s,
        &format!("{prefix}_up"),
        cam.up.to_array().into_iter(),
    );
    floats(
        &mut s,
        &format!("{prefix}_lights"),
        mesh.lights.iter().flat_map(|(p, _)| p.to_array()),
    );
    let _ = writeln!(
        s,
        "#define {up}_NAME \"{spec}\"\n\
         #define {up}_VERTEX_COUNT {}\n#define {up}_TRIANGLE_COUNT {}\n\
         #define {up}_SPHERE_COUNT {}\n#define {up}_CONE_COUNT {}\n\
         #define {up}_LIGHT_COUNT {}\n#define {up}_ANGLE_DEG {:?}f\n\
         /* tan(angle / 2): the program needs no libm, so host and board agree */\n\
         #define {up}_TAN_HALF_ANGLE {:?}f",
        mesh.vertices.len(),
        mesh.triangles.len(),
        mesh.spheres.len(),
        mesh.cones.len(),
        mesh.lights.len(),
        cam.angle_deg,
        (cam.angle_deg.to_radians() * 0.5).tan()
    );
    s
}
