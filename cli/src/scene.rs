//! Scenes the command works on: `random[:N]`, `spd:NAME[:SIZE]`, an NFF
//! file or a mesh (OBJ, PLY), checked against the limits before anything
//! large is allocated.

use crate::budget;
use coray_scenes::nff::shown;
use coray_scenes::spd::{self, Options};
use coray_scenes::{NffScene, SceneMesh};

/// A scene and the name the user gave it.
pub struct SceneData {
    /// The name as given.
    pub name: String,
    /// The scene.
    pub mesh: SceneMesh,
}

impl SceneData {
    /// Primitives after triangulation.
    pub fn prim_count(&self) -> usize {
        self.mesh.scene().prim_count()
    }

    /// Sets the camera to `w` x `h` pixels, within the image limit.
    pub fn set_resolution(&mut self, w: u64, h: u64) -> Result<(), String> {
        self.mesh.camera.width = budget::check_side("the image width", w)?;
        self.mesh.camera.height = budget::check_side("the image height", h)?;
        Ok(())
    }
}

/// Most triangles `random:N` makes: the core's primitive limit less the
/// spheres that come with them.
pub const MAX_RANDOM: usize = coray::limits::MAX_PRIMS / 11 * 10;

/// Reads a scene name: `random[:N]`, `spd:NAME[:SIZE]`, or a path to an NFF
/// file or to a mesh (`.obj`, `.ply`: a camera framed from its box and one
/// light). Its camera is checked; its memory (mesh and one kd-tree) too.
pub fn load(spec: &str, opts: &Options) -> Result<SceneData, String> {
    let mesh = if let Some(rest) = spec.strip_prefix("spd:") {
        let (name, size) = match rest.split_once(':') {
            Some((n, s)) => (
                n,
                Some(
                    s.parse::<u32>()
                        .map_err(|_| format!("`{}` is not a size factor", shown(s)))?,
                ),
            ),
            None => (rest, None),
        };
        SceneMesh::from_nff(&spd::generate(name, size, opts)?)
    } else if spec == "random" || spec.starts_with("random:") {
        let n = match spec.split_once(':') {
            None => coray_scenes::random::DEFAULT_TRIANGLES,
            Some((_, a)) => a
                .parse::<usize>()
                .ok()
                .filter(|n| (1..=MAX_RANDOM).contains(n))
                .ok_or_else(|| {
                    format!("`{}` is not a triangle count (1 to {MAX_RANDOM})", shown(a))
                })?,
        };
        let params = coray::kd::KdParams::auto();
        let per = coray_scenes::random::BYTES_PER_TRIANGLE as f64;
        let tree = budget::kd_bytes(&coray::kd::requirements(n + n / 10, &params));
        budget::check_memory(&format!("random:{n}"), n as f64 * per + tree)?;
        coray_scenes::random::random(n)
    } else if coray_scenes::mesh_file::MeshFormat::of(std::path::Path::new(spec)).is_some() {
        coray_scenes::mesh_file::read_mesh(std::path::Path::new(spec))?
    } else {
        let text = std::fs::read_to_string(spec).map_err(|e| format!("{}: {e}", shown(spec)))?;
        let nff = NffScene::parse(&text).map_err(|e| format!("{}:{e}", shown(spec)))?;
        SceneMesh::from_nff(&nff)
    };
    if let Some(why) = mesh.camera.fault() {
        return Err(format!("{}: the camera cannot be used: {why}", shown(spec)));
    }
    Ok(SceneData {
        name: spec.to_string(),
        mesh,
    })
}
