//! `coray render --spd`: the Standard Procedural Database's testing
//! procedure (its README, "Testing Procedures") and its ray statistics.
//!
//! The procedure: 512 x 512 pixels with eye rays through the pixel corners
//! (513 x 513 rays, the outer rows and columns at plus and minus half of
//! NFF's angle, which NFF.TXT measures between the outermost rows), a ray
//! tree of depth 5 with the eye ray at depth 1, and [`Rules::SPD`] for
//! reflection, refraction and shadows ([`crate::render::Tracer::shade`]).
//! The counts ([`RayCounts`]) depend on the scene alone: every structure,
//! traversal and thread count gives the same ones (tested below, on every
//! structure and an LCTS cast of the eye rays). The image is the average
//! of each pixel's four corners.

use crate::render::{self, RayCounts, Rules, TraceCtx, Tracer};
use crate::shoot::{AccelShooter, Shooter};
use coray::kd::{KdTree, Traversal};
use coray::lcts::image::{image_requirements, Scheme};
use coray::owned::OwnedCast;
use coray::{Camera, TraceStats, Vec3};
use coray_ffi::simd::cast_image_with;
use coray_scenes::SceneMesh;

/// Pixels per side of the procedure's image.
pub const PIXELS: u32 = 512;

/// The procedure's maximum ray tree depth, the eye ray being depth 1.
pub const TREE_DEPTH: u32 = 5;

/// History records per corner row of an LCTS cast (the benchmark's).
const CAST_HISTORY: usize = 512;

/// The camera whose pixel centres are the corner rays of a `pixels` x
/// `pixels` image of `cam`: `pixels + 1` rays per side, the outermost at
/// plus and minus half of `cam`'s angle. ([`Camera::basis`] puts the
/// centres of pixels 0 and n - 1 of n at `(1 - n) / n` and `(n - 1) / n`
/// of the half-angle's tangent, so that tangent grows by n / (n - 1).)
pub fn corner_camera(cam: &Camera, pixels: u32) -> Camera {
    let n = pixels + 1;
    let half = (cam.angle_deg.to_radians() * 0.5).tan();
    let wide = (half * n as f32 / pixels as f32).atan() * 2.0;
    Camera {
        angle_deg: wide.to_degrees(),
        width: n,
        height: n,
        ..*cam
    }
}

/// A scene with the procedure's eye rays in place of its camera's.
pub fn procedure_mesh(mesh: &SceneMesh, pixels: u32) -> SceneMesh {
    let mut m = mesh.clone();
    m.camera = corner_camera(&mesh.camera, pixels);
    m
}

/// What a run of the procedure gives.
pub struct Outcome {
    /// Linear colour of every corner ray, row 0 on top.
    pub corners: Vec<Vec3>,
    /// Traversal statistics over every ray.
    pub stats: TraceStats,
    /// Rays by kind.
    pub counts: RayCounts,
    /// Seconds taken.
    pub secs: f64,
}

fn tracer<'a, S: Shooter>(mesh: &'a SceneMesh, shooter: &'a S) -> Tracer<'a, S> {
    Tracer {
        mesh,
        shooter,
        max_depth: TREE_DEPTH - 1,
        rules: Rules::SPD,
    }
}

/// The procedure over a built method, on `threads` threads; `mesh` comes
/// from [`procedure_mesh`].
pub struct Job<'a> {
    /// The scene with the corner camera.
    pub mesh: &'a SceneMesh,
    /// Threads.
    pub threads: usize,
    /// Show a progress bar.
    pub progress: bool,
}

impl crate::built::Visit for Job<'_> {
    type Out = Result<Outcome, String>;
    fn visit<S: Shooter>(self, shooter: &S) -> Self::Out {
        let t = std::time::Instant::now();
        let tr = tracer(self.mesh, shooter);
        let (corners, stats, counts) =
            render::render_colors(&tr, &self.mesh.camera, self.threads, self.progress)?;
        Ok(Outcome {
            corners,
            stats,
            counts,
            secs: t.elapsed().as_secs_f64(),
        })
    }
}

/// The procedure with the eye rays cast by an LCTS `scheme` through `tree`
/// (one thread) and every other ray by hierarchical traversal of it.
pub fn run_cast(mesh: &SceneMesh, tree: KdTree, scheme: Scheme) -> Result<Outcome, String> {
    let t = std::time::Instant::now();
    let cam = &mesh.camera;
    let shooter = AccelShooter {
        accel: tree,
        method: Traversal::Hierarchical,
        bounds: tree.scene().bounds(),
    };
    let tr = tracer(mesh, &shooter);
    let mut ctx: TraceCtx<_> = tr.ctx();
    let mut scratch = OwnedCast::new(&image_requirements(
        cam.width,
        cam.height,
        scheme,
        CAST_HISTORY,
    ));
    let mut corners = vec![Vec3::ZERO; cam.width as usize * cam.height as usize];
    let (basis, t_min) = (cam.basis(), render::eye_t_min(mesh, Rules::SPD));
    let cast = cast_image_with(&tree, cam, scheme, scratch.scratch(), |x, y, h| {
        let ray = render::eye_ray(cam, basis, x, y, t_min);
        corners[y as usize * cam.width as usize + x as usize] = tr.shade(&ray, h, 0, &mut ctx);
    })
    .map_err(|e| format!("{scheme:?} cast: {e}"))?;
    ctx.stats.add(&cast.trace);
    Ok(Outcome {
        corners,
        stats: ctx.stats,
        counts: ctx.counts,
        secs: t.elapsed().as_secs_f64(),
    })
}

/// RGB bytes of the `pixels` x `pixels` image: each pixel the average of
/// its four corner rays.
pub fn image(corners: &[Vec3], pixels: u32) -> Vec<u8> {
    let (p, n) = (pixels as usize, pixels as usize + 1);
    let mut rgb = Vec::with_capacity(p * p * 3);
    for y in 0..p {
        for x in 0..p {
            let c = corners[y * n + x]
                + corners[y * n + x + 1]
                + corners[(y + 1) * n + x]
                + corners[(y + 1) * n + x + 1];
            rgb.extend(render::to_rgb8(c * 0.25));
        }
    }
    rgb
}

/// The statistics of one run, as printed and as `--json` writes them.
#[derive(serde::Serialize)]
pub struct Report {
    /// The scene as given.
    pub scene: String,
    /// The method.
    pub method: String,
    /// Pixels per side (eye rays: one more per side).
    pub pixels: u32,
    /// Maximum ray tree depth (the eye ray is depth 1).
    pub tree_depth: u32,
    /// Rays by kind.
    #[serde(flatten)]
    pub counts: RayCounts,
    /// Every ray.
    pub all_rays: u64,
    /// Rays whose query had to find an intersection.
    pub intersections_required: u64,
    /// Traversal steps per ray, over every ray.
    pub tspr: f64,
    /// Ray-primitive tests per ray, over every ray.
    pub tests_per_ray: f64,
    /// Hierarchy objects (boxes, rectangles) tested per ray.
    pub box_tests_per_ray: f64,
    /// Seconds (build excluded).
    pub secs: f64,
    /// Threads.
    pub threads: usize,
}

impl Report {
    /// The report of `o`.
    pub fn new(scene: &str, method: &str, pixels: u32, threads: usize, o: &Outcome) -> Report {
        let rays = o.counts.all_rays().max(1) as f64;
        Report {
            scene: scene.to_string(),
            method: method.to_string(),
            pixels,
            tree_depth: TREE_DEPTH,
            counts: o.counts,
            all_rays: o.counts.all_rays(),
            intersections_required: o.counts.intersections_required(),
            tspr: o.stats.traversal_steps as f64 / rays,
            tests_per_ray: o.stats.prim_tests as f64 / rays,
            box_tests_per_ray: o.stats.box_tests as f64 / rays,
            secs: o.secs,
            threads,
        }
    }

    /// The text table.
    pub fn text(&self) -> String {
        let c = &self.counts;
        let rows: [(&str, String); 13] = [
            ("eye rays", c.eye_rays.to_string()),
            ("eye hit rays", c.eye_hits.to_string()),
            ("reflect rays", c.reflect_rays.to_string()),
            ("refract rays", c.refract_rays.to_string()),
            ("shadow rays", c.shadow_rays.to_string()),
            ("shadow hit rays", c.shadow_hits.to_string()),
            ("secondary hit rays", c.secondary_hits.to_string()),
            ("all rays", self.all_rays.to_string()),
            (
                "intersections required",
                self.intersections_required.to_string(),
            ),
            ("traversal steps per ray", format!("{:.3}", self.tspr)),
            (
                "primitive tests per ray",
                format!("{:.3}", self.tests_per_ray),
            ),
            (
                "box tests per ray",
                format!("{:.3}", self.box_tests_per_ray),
            ),
            (
                "Mrays/s",
                format!(
                    "{:.2} ({:.2} s, {} thread{})",
                    self.all_rays as f64 / self.secs.max(1e-9) / 1e6,
                    self.secs,
                    self.threads,
                    if self.threads == 1 { "" } else { "s" }
                ),
            ),
        ];
        let mut s = format!(
            "{}: SPD testing procedure, {p}x{p} pixels, {e}x{e} eye rays, tree depth {d}, {m}\n",
            self.scene,
            p = self.pixels,
            e = self.pixels + 1,
            d = self.tree_depth,
            m = self.method
        );
        for (k, v) in rows {
            s += &format!("  {k:<26}{v:>14}\n");
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::built::Built;
    use crate::method::{Method, Preset};
    use coray_scenes::spd::{Options, SCENES};

    fn scene(name: &str) -> SceneMesh {
        let nff = coray_scenes::spd::generate(name, None, &Options::default()).unwrap();
        SceneMesh::from_nff(&nff)
    }

    #[test]
    fn corner_camera_puts_the_outer_rays_at_half_the_angle() {
        let cam = Camera {
            from: Vec3::ZERO,
            at: Vec3::new(0.0, 0.0, -1.0),
            up: Vec3::Y,
            angle_deg: 45.0,
            width: 512,
            height: 512,
        };
        let c = corner_camera(&cam, 512);
        assert_eq!((c.width, c.height), (513, 513));
        let (f, r, u) = c.basis();
        let deg = |x: f32, y: f32| {
            let d = c.ray_in(f, r, u, x + 0.5, y + 0.5).dir.normalize();
            d.angle_between(Vec3::new(0.0, 0.0, -1.0)).to_degrees()
        };
        assert!((deg(0.0, 256.0) - 22.5).abs() < 1e-3, "{}", deg(0.0, 256.0));
        assert!((deg(512.0, 256.0) - 22.5).abs() < 1e-3);
        assert!((deg(256.0, 0.0) - 22.5).abs() < 1e-3);
        assert!(deg(256.0, 256.0) < 1e-3);
    }

    /// Pixels per side in the test: 65 x 65 eye rays per scene and method
    /// (the full 513 x 513 is `coray render SCENE --spd`).
    const TEST_PIXELS: u32 = 64;

    fn counts_of(mesh: &SceneMesh, method: Method, threads: usize) -> RayCounts {
        if let Method::Cast { scheme } = method {
            let b = Built::new(Method::kd_for_casts(), mesh, Preset::Auto, 1).unwrap();
            let tree = b.kd().unwrap().tree(mesh.scene()).unwrap();
            return run_cast(mesh, tree, scheme).unwrap().counts;
        }
        let b = Built::new(method, mesh, Preset::Auto, 1).unwrap();
        b.visit(Job {
            mesh,
            threads,
            progress: false,
        })
        .unwrap()
        .counts
    }

    /// The SPD's statistics do not depend on the structure or the thread
    /// count: every kd preset and traversal, every BVH builder, every
    /// projection hierarchy and the LCTS casts give the one-thread
    /// hierarchical kd-tree's counts (one test per scene, so they run side
    /// by side).
    fn counts_are_identical_across_every_structure(name: &str) {
        let mut methods: Vec<Method> = Method::all()
            .into_iter()
            .filter(|m| !matches!(m, Method::Embree(_)))
            .collect();
        for p in ["kd-paper", "kd-paper-rope", "kd-paper-packet"] {
            methods.push(Method::parse(p).unwrap());
        }
        methods.extend(Method::projections());
        let mesh = procedure_mesh(&scene(name), TEST_PIXELS);
        let reference = counts_of(&mesh, Method::kd(Traversal::Hierarchical), 1);
        let side = u64::from(TEST_PIXELS + 1);
        assert_eq!(reference.eye_rays, side * side);
        assert!(
            reference.eye_hits > 0 && reference.shadow_rays > 0 && reference.reflect_rays > 0,
            "{name}: {reference:?}"
        );
        for &m in &methods {
            assert_eq!(counts_of(&mesh, m, 2), reference, "{name}, {m}");
        }
    }

    macro_rules! per_scene {
        ($($test:ident: $name:literal,)*) => {
            $(
                #[test]
                fn $test() {
                    counts_are_identical_across_every_structure($name);
                }
            )*
            /// The scenes the tests above cover.
            const TESTED: &[&str] = &[$($name),*];
        };
    }

    per_scene! {
        counts_agree_on_balls: "balls",
        counts_agree_on_gears: "gears",
        counts_agree_on_lattice: "lattice",
        counts_agree_on_mount: "mount",
        counts_agree_on_rings: "rings",
        counts_agree_on_teapot: "teapot",
        counts_agree_on_tetra: "tetra",
        counts_agree_on_tree: "tree",
    }

    #[test]
    fn every_built_in_scene_has_a_test() {
        let built_in: Vec<&str> = SCENES.iter().map(|(n, _)| *n).collect();
        assert_eq!(TESTED, built_in.as_slice());
    }
}
