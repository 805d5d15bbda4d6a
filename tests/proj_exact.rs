//! Projection hierarchies are exact: on the eight SPD scenes, every
//! builder, both criteria and all three schemes give every primary ray the
//! primitive and t of 3D traversal, and every shadow ray (through the light
//! planes, in both selection modes) the same answer.
mod common;

use common::*;
use coray::bvh::{Builder, BvhNode, BvhScratch, BvhStackItem, RTreeParams};
use coray::kd::{KdParams, Traversal};
use coray::proj::lights::{Light, LightPlanes};
use coray::proj::{
    self, Criteria, ProjBuilder, ProjHierarchy, ProjPlane, ProjScheme, ProjScratch, ProjStorage,
    Rect,
};
use coray::{Aabb, Hit, Ray, Scene, TraceStats};
use coray_scenes::spd::{self, Options};
use coray_scenes::SceneMesh;

/// Owned memory of one projection hierarchy.
struct Owned {
    nodes: Vec<BvhNode>,
    refs: Vec<u32>,
    rects: Vec<Rect>,
    prim_rects: Vec<Rect>,
}

fn build<'a>(
    scene: &Scene<'a>,
    plane: ProjPlane,
    b: ProjBuilder,
    c: Criteria,
    o: &'a mut Owned,
) -> ProjHierarchy<'a> {
    let n = scene.prim_count();
    let req = proj::requirements(n, &b);
    o.nodes = vec![BvhNode::default(); req.nodes];
    o.refs = vec![0; req.refs];
    o.rects = vec![Rect::EMPTY; req.rects];
    o.prim_rects = vec![Rect::EMPTY; req.prim_rects];
    let s = &req.bvh_scratch;
    let (mut boxes, mut keys, mut links, mut clusters) = (
        vec![Aabb::EMPTY; s.boxes],
        vec![0f32; s.keys],
        vec![0u32; s.links],
        vec![BvhNode::default(); s.clusters],
    );
    let (mut source, mut stack) = (vec![Aabb::EMPTY; req.source], vec![0u32; req.stack]);
    let h = proj::build(
        scene,
        plane,
        b,
        c,
        ProjStorage {
            nodes: &mut o.nodes,
            refs: &mut o.refs,
            rects: &mut o.rects,
            prim_rects: &mut o.prim_rects,
        },
        ProjScratch {
            bvh: BvhScratch {
                boxes: &mut boxes,
                keys: &mut keys,
                links: &mut links,
                clusters: &mut clusters,
            },
            source: &mut source,
            stack: &mut stack,
        },
    )
    .unwrap();
    let min = match b {
        ProjBuilder::RTree(p) => Some(p.min_children),
        _ => None,
    };
    h.validate(min, &mut vec![BvhStackItem::default(); h.stack_len()])
        .unwrap();
    h
}

fn owned() -> Owned {
    Owned {
        nodes: Vec::new(),
        refs: Vec::new(),
        rects: Vec::new(),
        prim_rects: Vec::new(),
    }
}

const BUILDERS: [ProjBuilder; 4] = [
    ProjBuilder::Static(Builder::Tdbs),
    ProjBuilder::Static(Builder::NnChain),
    ProjBuilder::RTree(RTreeParams::rtree()),
    ProjBuilder::RTree(RTreeParams::rstar()),
];
const SCHEMES: [ProjScheme; 3] = [
    ProjScheme::TwoD,
    ProjScheme::ThreeD,
    ProjScheme::Combination,
];

/// Same hit or miss at the same t, bit for bit, and the same primitive,
/// or another that the ray meets at exactly that t (a tie).
fn same(scene: &Scene, ray: &Ray, a: &Hit, b: &Hit) -> bool {
    if a.is_hit() != b.is_hit() {
        return false;
    }
    if !a.is_hit() || (a.geom_id, a.prim_id) == (b.geom_id, b.prim_id) {
        return !a.is_hit() || a.t.to_bits() == b.t.to_bits();
    }
    let base = [
        0,
        scene.triangles.len(),
        scene.triangles.len() + scene.spheres.len(),
    ];
    let p = base[a.geom_id as usize] + a.prim_id as usize;
    let pr = coray::geom::PreparedRay::new(ray);
    a.t == b.t
        && scene
            .intersect_prim(p, &pr, ray.t_max)
            .is_some_and(|h| h.t == a.t)
}

/// Primary rays of the scene's camera at `res` x `res`, as coray render
/// makes them (origin exactly the eye).
fn primary(m: &SceneMesh, res: u32) -> (coray::Camera, Vec<Ray>) {
    let mut cam = m.camera;
    cam.width = res;
    cam.height = res;
    let (f, r, u) = cam.basis();
    let mut rays = Vec::new();
    for y in 0..res {
        for x in 0..res {
            let ray = cam.ray_in(f, r, u, x as f32 + 0.5, y as f32 + 0.5);
            rays.push(Ray::new(ray.origin, ray.dir, 0.0, f32::INFINITY));
        }
    }
    (cam, rays)
}

#[test]
fn primary_rays_match_3d_traversal_on_the_spd_scenes() {
    for &(name, _) in spd::SCENES {
        let m = SceneMesh::from_nff(&spd::generate(name, None, &Options::default()).unwrap());
        let scene = m.scene();
        let (cam, rays) = primary(&m, 48);
        let (req, mut b) = ideal_storage(&scene, &KdParams::auto());
        let kd = build_with(&scene, &KdParams::auto(), &req, &mut b);
        let mut ts = TraceStats::default();
        let want: Vec<Hit> = rays
            .iter()
            .map(|r| kd.intersect(r, Traversal::Hierarchical, &mut kst(), &mut ts))
            .collect();
        assert!(want.iter().filter(|h| h.is_hit()).count() > 100, "{name}");
        let plane = ProjPlane::camera(&cam);
        for b in BUILDERS {
            for c in [Criteria::TwoD, Criteria::Dummy] {
                let mut o = owned();
                let h = build(&scene, plane, b, c, &mut o);
                let mut stack = vec![BvhStackItem::default(); h.stack_len()];
                for s in SCHEMES {
                    let mut st = TraceStats::default();
                    let bad = rays
                        .iter()
                        .zip(&want)
                        .filter(|(r, w)| {
                            let got = h.intersect(r, s, &mut stack, &mut st);
                            !same(&scene, r, &got.expect("primary rays project"), w)
                        })
                        .count();
                    assert_eq!(bad, 0, "{name} {b:?} {c:?} {s:?}: {bad} rays differ");
                    if s != ProjScheme::ThreeD {
                        assert!(st.rect_tests > 0, "{name} {b:?} {c:?} {s:?}: no 2D test");
                    }
                }
            }
        }
    }
}

/// Shadow rays from every primary hit to every light, plus lights inside
/// the scene (cubes), outside it (one face) and directional: the light
/// planes' hierarchies answer as 3D traversal does, whether the ray carries
/// its light (known origin) or every light is asked (uniform).
#[test]
fn shadow_rays_match_3d_traversal_through_the_light_planes() {
    for name in ["balls", "gears", "tree", "rings"] {
        let m = SceneMesh::from_nff(&spd::generate(name, Some(2), &Options::default()).unwrap());
        let scene = m.scene();
        let (_, rays) = primary(&m, 40);
        let (req, mut b) = ideal_storage(&scene, &KdParams::auto());
        let kd = build_with(&scene, &KdParams::auto(), &req, &mut b);
        let bounds = kd.info().bounds();
        let centre = 0.5 * (bounds.min + bounds.max);
        let mut lights: Vec<Light> = m.lights.iter().map(|(p, _)| Light::Point(*p)).collect();
        lights.push(Light::Point(centre + 0.1 * (bounds.max - centre)));
        lights.push(Light::Directional(coray::Vec3::new(-0.3, -1.0, -0.2)));
        let mut ts = TraceStats::default();
        let hits: Vec<(Ray, Hit)> = rays
            .iter()
            .map(|r| {
                (
                    *r,
                    kd.intersect(r, Traversal::Hierarchical, &mut kst(), &mut ts),
                )
            })
            .filter(|(_, h)| h.is_hit())
            .collect();
        // (light index, shadow ray, 3D answer)
        let mut shadow = Vec::new();
        for (li, l) in lights.iter().enumerate() {
            for (r, h) in &hits {
                let p = r.origin + r.dir * h.t;
                let (d, len) = match l {
                    Light::Point(lp) => {
                        let d = *lp - p;
                        (d / d.length(), d.length())
                    }
                    Light::Directional(dir) => (-dir.normalize(), f32::INFINITY),
                };
                let s = Ray::new(p, d, 1e-3 * len.clamp(1.0, 1e3), len);
                shadow.push((
                    li,
                    s,
                    kd.occluded(&s, Traversal::Hierarchical, &mut kst(), &mut ts),
                ));
            }
        }
        let blocked = shadow.iter().filter(|s| s.2).count();
        assert!(
            blocked > 50 && blocked < shadow.len(),
            "{name}: {blocked} of {}",
            shadow.len()
        );
        let kinds: Vec<usize> = lights
            .iter()
            .map(|l| LightPlanes::new(*l, &bounds).count)
            .collect();
        assert!(
            kinds.contains(&6) && kinds.contains(&1),
            "{name}: {kinds:?}"
        );
        for (b, c) in [
            (BUILDERS[0], Criteria::TwoD),
            (BUILDERS[3], Criteria::TwoD),
            (BUILDERS[2], Criteria::Dummy),
        ] {
            // Every light's planes and hierarchies.
            let planes: Vec<LightPlanes> = lights
                .iter()
                .map(|l| LightPlanes::new(*l, &bounds))
                .collect();
            let mut mem: Vec<Vec<Owned>> = planes
                .iter()
                .map(|lp| (0..lp.count).map(|_| owned()).collect())
                .collect();
            let hier: Vec<Vec<ProjHierarchy>> = planes
                .iter()
                .zip(mem.iter_mut())
                .map(|(lp, os)| {
                    os.iter_mut()
                        .enumerate()
                        .map(|(k, o)| build(&scene, lp.planes[k], b, c, o))
                        .collect()
                })
                .collect();
            let depth = hier.iter().flatten().map(|h| h.stack_len()).max().unwrap();
            let mut stack = vec![BvhStackItem::default(); depth];
            for s in SCHEMES {
                let mut st = TraceStats::default();
                for (li, ray, want) in &shadow {
                    // Known origin: the ray's own light.
                    let face = planes[*li]
                        .plane_for(ray)
                        .expect("a shadow ray serves its light");
                    let got = hier[*li][face].occluded(ray, s, &mut stack, &mut st);
                    assert_eq!(
                        got,
                        Some(*want),
                        "{name} {b:?} {c:?} {s:?} light {li}: {ray:?}"
                    );
                    // Uniform: the first light the ray serves.
                    let lj = planes.iter().position(|lp| lp.serves(ray)).unwrap();
                    let face = planes[lj].plane_for(ray).unwrap();
                    let got = hier[lj][face].occluded(ray, s, &mut stack, &mut st);
                    assert_eq!(got, Some(*want));
                }
                assert!(st.rect_tests > 0 || s == ProjScheme::ThreeD);
            }
        }
    }
}

/// Rays from the eye in every direction: those in front of the eye plane
/// get the oracle's hits, the others and every ray off the eye are refused
/// (`None`: they belong to a 3D hierarchy). Rectangles of boxes behind the
/// eye are empty, of boxes across the eye plane unbounded.
#[test]
fn rays_from_the_eye_and_boxes_behind_it() {
    let mut rng = Rng(4);
    let o = random_scene(&mut rng, 600, 100, 100, 5.0);
    let scene = o.scene();
    let cam = coray::Camera {
        from: coray::Vec3::new(0.0, 0.0, 0.0),
        at: coray::Vec3::new(0.0, 0.0, 1.0),
        up: coray::Vec3::Y,
        angle_deg: 60.0,
        width: 32,
        height: 32,
    };
    let plane = ProjPlane::camera(&cam);
    let behind = Aabb {
        min: coray::Vec3::new(-1.0, -1.0, -3.0),
        max: coray::Vec3::new(1.0, 1.0, -2.0),
    };
    assert!(plane.project_box(&behind).is_empty());
    let across = Aabb {
        min: coray::Vec3::new(-1.0, -1.0, -1.0),
        max: coray::Vec3::new(1.0, 1.0, 1.0),
    };
    assert_eq!(plane.project_box(&across).min, Rect::ALL.min);
    let off_eye = random_rays(&mut rng, 300, 5.0);
    let from_eye: Vec<Ray> = (0..3000)
        .map(|_| Ray::new(cam.from, rng.unit(), 0.0, f32::INFINITY))
        .collect();
    let (mut taken, mut hits) = (0, 0);
    for b in BUILDERS {
        for c in [Criteria::TwoD, Criteria::Dummy] {
            let mut ow = owned();
            let h = build(&scene, plane, b, c, &mut ow);
            let mut stack = vec![BvhStackItem::default(); h.stack_len()];
            let mut st = TraceStats::default();
            for r in &off_eye {
                assert!(h
                    .intersect(r, ProjScheme::TwoD, &mut stack, &mut st)
                    .is_none());
                assert!(h
                    .occluded(r, ProjScheme::TwoD, &mut stack, &mut st)
                    .is_none());
            }
            for r in &from_eye {
                let front = r.dir.z > 0.0;
                let want = coray::oracle::intersect(&scene, r);
                for s in SCHEMES {
                    let got = h.intersect(r, s, &mut stack, &mut st);
                    assert_eq!(got.is_some(), front, "{b:?} {c:?} {s:?}: {r:?}");
                    if let Some(got) = got {
                        assert!(same(&scene, r, &got, &want), "{b:?} {c:?} {s:?}: {r:?}");
                        taken += 1;
                        hits += got.is_hit() as usize;
                    }
                }
            }
        }
    }
    assert!(taken > 10_000 && hits > 1000, "{taken} taken, {hits} hits");
}
