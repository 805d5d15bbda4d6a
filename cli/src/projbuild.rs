//! Owned projection hierarchies for the CLI: the camera's, every light's
//! planes', and the global 3D hierarchy for secondary rays, built by name
//! (`proj-BUILDER-CRITERIA-SCHEME`).

use crate::bvhbuild::OwnedBvh;
use coray::bvh::{Builder, BvhNode, BvhScratch, BvhStackItem, RTreeParams};
use coray::proj::lights::{Light, LightPlanes};
use coray::proj::{
    build_proj, proj_requirements, Criteria, ProjBuilder, ProjHierarchy, ProjPlane, ProjScheme,
    ProjScratch, ProjStats, ProjStorage, Rect,
};
use coray::{Aabb, Camera, Hit, Ray, Scene};
use std::time::Instant;

/// Builders of projection hierarchies, as method names spell them.
pub const BUILDERS: [&str; 4] = ["tdbs", "nn-chain", "rtree", "rstar"];

/// Every projection method: 2D criteria with the three schemes; dummy
/// (3D structure) with 2D and combination (its 3D scheme is the plain 3D
/// hierarchy).
pub fn methods() -> Vec<String> {
    let mut v = Vec::new();
    for b in BUILDERS {
        for s in ["2d", "3d", "comb"] {
            v.push(format!("proj-{b}-2d-{s}"));
        }
        for s in ["2d", "comb"] {
            v.push(format!("proj-{b}-dummy-{s}"));
        }
    }
    v
}

/// A method name taken apart.
#[derive(Clone, Copy, Debug)]
pub struct ProjMethod {
    pub builder: ProjBuilder,
    pub criteria: Criteria,
    pub scheme: ProjScheme,
    /// The 3D builder's name for the global hierarchy.
    pub global: &'static str,
}

/// Parses `proj-BUILDER-CRITERIA-SCHEME`.
pub fn parse(name: &str) -> Option<ProjMethod> {
    let rest = name.strip_prefix("proj-")?;
    let (b, rest) = BUILDERS.iter().find_map(|b| {
        rest.strip_prefix(b)
            .and_then(|r| r.strip_prefix('-'))
            .map(|r| (*b, r))
    })?;
    let (c, s) = rest.split_once('-')?;
    let builder = match b {
        "tdbs" => ProjBuilder::Static(Builder::Tdbs),
        "nn-chain" => ProjBuilder::Static(Builder::NnChain),
        "rtree" => ProjBuilder::RTree(RTreeParams::rtree()),
        _ => ProjBuilder::RTree(RTreeParams::rstar()),
    };
    let criteria = match c {
        "2d" => Criteria::TwoD,
        "dummy" => Criteria::Dummy,
        _ => return None,
    };
    let scheme = match s {
        "2d" => ProjScheme::TwoD,
        "3d" if criteria == Criteria::TwoD => ProjScheme::ThreeD,
        "comb" => ProjScheme::Combination,
        _ => return None,
    };
    Some(ProjMethod {
        builder,
        criteria,
        scheme,
        global: BUILDERS
            .iter()
            .find(|x| **x == b)
            .copied()
            .unwrap_or("tdbs"),
    })
}

/// Memory of one projection hierarchy.
pub struct OwnedProj {
    nodes: Vec<BvhNode>,
    refs: Vec<u32>,
    rects: Vec<Rect>,
    prim_rects: Vec<Rect>,
    info: coray::bvh::BvhInfo,
    plane: ProjPlane,
}

impl OwnedProj {
    pub fn build(scene: &Scene, plane: ProjPlane, m: &ProjMethod) -> Result<OwnedProj, String> {
        let n = scene.prim_count();
        let req = proj_requirements(n, &m.builder);
        let mut o = OwnedProj {
            nodes: vec![BvhNode::default(); req.nodes],
            refs: vec![0; req.refs],
            rects: vec![Rect::EMPTY; req.rects],
            prim_rects: vec![Rect::EMPTY; req.prim_rects],
            info: Default::default(),
            plane,
        };
        let s = &req.bvh_scratch;
        let (mut boxes, mut keys, mut links, mut clusters) = (
            vec![Aabb::EMPTY; s.boxes],
            vec![0f32; s.keys],
            vec![0u32; s.links],
            vec![BvhNode::default(); s.clusters],
        );
        let (mut source, mut stack) = (vec![Aabb::EMPTY; req.source], vec![0u32; req.stack]);
        let h = build_proj(
            scene,
            plane,
            m.builder,
            m.criteria,
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
        .map_err(|e| format!("projection build: {e}"))?;
        o.info = h.bvh.info;
        Ok(o)
    }

    pub fn view<'a>(&'a self, scene: Scene<'a>) -> ProjHierarchy<'a> {
        ProjHierarchy {
            bvh: coray::bvh::Bvh {
                scene,
                nodes: &self.nodes,
                refs: &self.refs,
                info: self.info,
            },
            rects: &self.rects,
            prim_rects: &self.prim_rects,
            plane: self.plane,
        }
    }
}

/// Everything a projection method renders with.
pub struct ProjRig {
    pub method: ProjMethod,
    pub camera: OwnedProj,
    pub lights: Vec<(LightPlanes, Vec<OwnedProj>)>,
    pub global: OwnedBvh,
    /// Preprocessing split as the thesis reports it (ms).
    pub view_ms: f64,
    pub light_ms: f64,
    pub global_ms: f64,
}

impl ProjRig {
    pub fn build(
        scene: &Scene,
        cam: &Camera,
        lights: &[Light],
        bounds: &Aabb,
        m: ProjMethod,
    ) -> Result<ProjRig, String> {
        let t = Instant::now();
        let camera = OwnedProj::build(scene, ProjPlane::camera(cam), &m)?;
        let view_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let mut ls = Vec::new();
        for l in lights {
            let lp = LightPlanes::new(*l, bounds);
            let faces = (0..lp.count)
                .map(|k| OwnedProj::build(scene, lp.planes[k], &m))
                .collect::<Result<Vec<_>, _>>()?;
            ls.push((lp, faces));
        }
        let light_ms = t.elapsed().as_secs_f64() * 1e3;
        let global = OwnedBvh::build(scene, m.global)?;
        Ok(ProjRig {
            method: m,
            camera,
            lights: ls,
            global_ms: global.build_ms,
            global,
            view_ms,
            light_ms,
        })
    }

    /// [`ProjRig::build`] for a loaded scene: its camera, its point lights,
    /// its primitives' bounds.
    pub fn for_scene(s: &crate::scene::SceneData, m: ProjMethod) -> Result<ProjRig, String> {
        let scene = s.mesh.scene();
        let lights: Vec<Light> = s
            .mesh
            .lights
            .iter()
            .map(|(p, _)| Light::Point(*p))
            .collect();
        ProjRig::build(&scene, &s.mesh.camera, &lights, &scene.bounds(), m)
    }

    /// Deepest stack any of its hierarchies needs.
    pub fn stack_len(&self, scene: Scene) -> usize {
        let mut d = self.camera.view(scene).bvh.stack_len();
        d = d.max(self.global.bvh(scene).stack_len());
        for (_, faces) in &self.lights {
            for f in faces {
                d = d.max(f.view(scene).bvh.stack_len());
            }
        }
        d
    }

    /// Closest hit: the camera's hierarchy for rays from the eye, the
    /// global 3D hierarchy for the rest.
    pub fn intersect(
        &self,
        scene: Scene,
        ray: &Ray,
        stack: &mut [BvhStackItem],
        st: &mut ProjStats,
    ) -> Hit {
        if let Some(h) = self
            .camera
            .view(scene)
            .intersect(ray, self.method.scheme, stack, st)
        {
            return h;
        }
        self.global.bvh(scene).intersect(ray, stack, &mut st.bvh)
    }

    /// Any hit of a shadow ray: with `light` known, that light's plane; in
    /// the uniform mode (`None`) the first light the ray serves; the global
    /// hierarchy when no plane takes it.
    pub fn occluded(
        &self,
        scene: Scene,
        ray: &Ray,
        light: Option<usize>,
        stack: &mut [BvhStackItem],
        st: &mut ProjStats,
    ) -> bool {
        let pick = match light {
            Some(i) => self
                .lights
                .get(i)
                .and_then(|(lp, _)| Some((i, lp.plane_for(ray)?))),
            None => self
                .lights
                .iter()
                .enumerate()
                .find_map(|(i, (lp, _))| Some((i, lp.plane_for(ray)?))),
        };
        if let Some((i, face)) = pick {
            let h = self.lights[i].1[face].view(scene);
            if let Some(o) = h.occluded(ray, self.method.scheme, stack, st) {
                return o;
            }
        }
        self.global.bvh(scene).occluded(ray, stack, &mut st.bvh)
    }
}
