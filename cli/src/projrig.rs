//! A projection method as a renderer uses it (thesis chapter 6): the
//! camera's projection hierarchy for rays from the eye, each light's planes
//! for its shadow rays, and a global 3D hierarchy for every other ray.

use crate::method::{ProjMethod, BVH_NAMES};
use crate::shoot::Shooter;
use coray::bvh::BvhStackItem;
use coray::owned::{OwnedBvh, OwnedProj};
use coray::proj::lights::{Light, LightPlanes};
use coray::proj::ProjPlane;
use coray::{Aabb, Accel, Camera, Hit, Ray, Scene, TraceStats};
use std::time::Instant;

/// Everything a projection method renders with, over one scene.
pub struct ProjRig<'s> {
    /// The scene the hierarchies were built on.
    pub scene: Scene<'s>,
    /// The method.
    pub method: ProjMethod,
    /// The camera's hierarchy.
    pub camera: OwnedProj,
    /// Per light: its planes and their hierarchies.
    pub lights: Vec<(LightPlanes, Vec<OwnedProj>)>,
    /// The 3D hierarchy for the other rays.
    pub global: OwnedBvh,
    /// Preprocessing as the thesis splits it (ms): view, light, global.
    pub view_ms: f64,
    /// See `view_ms`.
    pub light_ms: f64,
    /// See `view_ms`.
    pub global_ms: f64,
    bounds: Aabb,
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

impl<'s> ProjRig<'s> {
    /// Builds the camera's, every light's and the global hierarchy.
    pub fn build(
        scene: Scene<'s>,
        cam: &Camera,
        lights: &[Light],
        m: ProjMethod,
    ) -> Result<ProjRig<'s>, String> {
        let bounds = scene.bounds();
        let err = |e: coray::Error| format!("projection build: {e}");
        let t = Instant::now();
        let camera =
            OwnedProj::new(&scene, ProjPlane::camera(cam), m.builder, m.criteria).map_err(err)?;
        let view_ms = ms(t);
        let t = Instant::now();
        let mut ls = Vec::new();
        for l in lights {
            let lp = LightPlanes::new(*l, &bounds);
            let faces = (0..lp.count)
                .map(|k| OwnedProj::new(&scene, lp.planes[k], m.builder, m.criteria))
                .collect::<Result<Vec<_>, _>>()
                .map_err(err)?;
            ls.push((lp, faces));
        }
        let light_ms = ms(t);
        let build = BVH_NAMES
            .iter()
            .find(|(n, _)| *n == m.builder_name)
            .map(|(_, b)| *b)
            .ok_or("no global hierarchy for this builder")?;
        let t = Instant::now();
        let global = OwnedBvh::new(&scene, build).map_err(err)?;
        let global_ms = ms(t);
        Ok(ProjRig {
            scene,
            method: m,
            camera,
            lights: ls,
            global,
            view_ms,
            light_ms,
            global_ms,
            bounds,
        })
    }

    /// [`ProjRig::build`] for a scene's camera and point lights.
    pub fn for_mesh(
        mesh: &'s coray_scenes::SceneMesh,
        m: ProjMethod,
    ) -> Result<ProjRig<'s>, String> {
        let lights: Vec<Light> = mesh.lights.iter().map(|(p, _)| Light::Point(*p)).collect();
        ProjRig::build(mesh.scene(), &mesh.camera, &lights, m)
    }

    /// Deepest stack any of its hierarchies needs.
    pub fn stack_len(&self) -> usize {
        let v = |o: &OwnedProj| o.view(self.scene).map_or(1, |h| h.stack_len());
        let mut d = v(&self.camera);
        d = d.max(self.global.view(self.scene).map_or(1, |b| b.stack_len()));
        for (_, faces) in &self.lights {
            for f in faces {
                d = d.max(v(f));
            }
        }
        d
    }
}

impl Shooter for ProjRig<'_> {
    type Ctx = Vec<BvhStackItem>;

    fn ctx(&self) -> Self::Ctx {
        vec![BvhStackItem::default(); self.stack_len()]
    }

    /// The camera's hierarchy for rays from the eye, the global one else.
    fn intersect(&self, ray: &Ray, stack: &mut Self::Ctx, st: &mut TraceStats) -> Hit {
        if let Ok(h) = self.camera.view(self.scene) {
            if let Ok(hit) = Accel::intersect(&h, ray, self.method.scheme, stack, st) {
                return hit;
            }
        }
        let g = self.global.view(self.scene).expect("built");
        Accel::intersect(&g, ray, (), stack, st).expect("a stack of stack_len()")
    }

    /// With `light` known, that light's plane; in the uniform mode (`None`)
    /// the first light the ray serves; the global hierarchy when no plane
    /// takes the ray.
    fn occluded(
        &self,
        ray: &Ray,
        light: Option<usize>,
        stack: &mut Self::Ctx,
        st: &mut TraceStats,
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
            if let Ok(h) = self.lights[i].1[face].view(self.scene) {
                if let Ok(o) = Accel::occluded(&h, ray, self.method.scheme, stack, st) {
                    return o;
                }
            }
        }
        let g = self.global.view(self.scene).expect("built");
        Accel::occluded(&g, ray, (), stack, st).expect("a stack of stack_len()")
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }
}
