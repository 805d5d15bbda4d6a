//! A [`Method`] built over a scene: the owned structure, what the build
//! took, and the one [`Shooter`] that traces through it. Callers pass a
//! [`Visit`] that receives the shooter with its concrete type, so every
//! structure gets its own monomorphised loops.

use crate::method::{Method, Preset};
use crate::projrig::ProjRig;
use crate::shoot::{AccelShooter, Shooter};
use coray::kd::Traversal;
use coray::owned::{OwnedBvh, OwnedKd, OwnedWide};
use coray::{Aabb, Scene};
use coray_scenes::SceneMesh;
use std::time::Instant;

enum Inner<'s> {
    Kd(OwnedKd, Traversal),
    KdC(coray_ffi::through_c::CKdTree<'s>, crate::method::CCalls),
    WideC(coray_ffi::through_c::CWide<'s>, crate::method::CCalls),
    Bvh(OwnedBvh),
    Wide(OwnedWide, bool),
    Proj(Box<ProjRig<'s>>),
    #[cfg(feature = "embree")]
    Embree(coray_embree::EmbreeScene, bool),
}

/// A method built over a scene.
pub struct Built<'s> {
    /// The method.
    pub method: Method,
    /// Build time, allocation excluded (ms).
    pub build_ms: f64,
    /// Bytes of the structure (a C arena's size for a kd-tree).
    pub bytes: Option<usize>,
    /// A kd-tree whose room ran out.
    pub truncated: bool,
    scene: Scene<'s>,
    bounds: Aabb,
    inner: Inner<'s>,
}

/// Work done with a structure's shooter, whatever its type.
pub trait Visit {
    /// What the work returns.
    type Out;
    /// Does it.
    fn visit<S: Shooter>(self, shooter: &S) -> Self::Out;
}

impl<'s> Built<'s> {
    /// Builds `method` over `mesh`'s scene; `preset` is the command's, for
    /// kd methods that name none; `threads` build a kd-tree (its jobs) and
    /// Embree's.
    pub fn new(
        method: Method,
        mesh: &'s SceneMesh,
        preset: Preset,
        threads: usize,
    ) -> Result<Built<'s>, String> {
        method.available()?;
        let scene = mesh.scene();
        let bounds = scene.bounds();
        let err = |e: coray::Error| format!("{method} build: {e}");
        let mut b = Built {
            method,
            build_ms: 0.0,
            bytes: None,
            truncated: false,
            scene,
            bounds,
            inner: Inner::Kd(
                OwnedKd::with_room(&Default::default()),
                Traversal::Hierarchical,
            ),
        };
        match method {
            Method::Kd {
                preset: p,
                traversal,
            } => {
                let params = coray::kd::KdParams {
                    // Ropes only for the traversal that walks them.
                    ropes: traversal == Traversal::Ropes,
                    ..p.unwrap_or(preset).params()
                };
                let mut o =
                    OwnedKd::with_room(&coray::kd::requirements(scene.prim_count(), &params));
                let t = Instant::now();
                o.build_with_jobs(&scene, &params, threads, |jobs| {
                    crate::kd_jobs::run(jobs, threads, scene.prim_count())
                })
                .map_err(err)?;
                b.build_ms = ms(t);
                b.bytes = Some(o.arena_bytes());
                b.truncated = o.info().truncated();
                b.inner = Inner::Kd(o, traversal);
            }
            Method::KdC { calls } => {
                let (p, omit_ropes) = preset.c_params(false);
                let t = Instant::now();
                let tree = coray_ffi::through_c::CKdTree::new(
                    &scene,
                    p,
                    omit_ropes,
                    coray_ffi::CORAY_TRAVERSAL_HIERARCHICAL,
                )
                .map_err(|s| format!("{method} build: {}", coray_ffi::status_description(s as i32).to_string_lossy()))?;
                b.build_ms = ms(t);
                b.bytes = Some(tree.arena_bytes());
                b.inner = Inner::KdC(tree, calls);
            }
            Method::WideC { calls } => {
                let t = Instant::now();
                let wide = coray_ffi::through_c::CWide::new(&scene).map_err(|s| {
                    format!(
                        "{method} build: {}",
                        coray_ffi::status_description(s as i32).to_string_lossy()
                    )
                })?;
                b.build_ms = ms(t);
                b.bytes = Some(wide.arena_bytes());
                b.inner = Inner::WideC(wide, calls);
            }
            Method::Cast { .. } => {
                return Err(format!(
                    "{method} casts images: use it with `coray bench`, or for the eye rays of `coray render --spd`"
                ))
            }
            Method::Bvh { build, .. } => {
                let mut o = OwnedBvh::with_room(scene.prim_count(), build);
                let t = Instant::now();
                o.build(&scene).map_err(err)?;
                b.build_ms = ms(t);
                b.bytes = Some(o.bytes());
                b.inner = Inner::Bvh(o);
            }
            Method::Wide { leaf_size, packets } => {
                let mut o = OwnedWide::with_room(scene.prim_count());
                let t = Instant::now();
                o.build(&scene, leaf_size).map_err(err)?;
                b.build_ms = ms(t);
                b.bytes = Some(o.bytes());
                b.inner = Inner::Wide(o, packets);
            }
            Method::Proj(m) => {
                let rig = ProjRig::for_mesh(mesh, m)?;
                b.build_ms = rig.view_ms + rig.light_ms + rig.global_ms;
                b.inner = Inner::Proj(Box::new(rig));
            }
            #[cfg(feature = "embree")]
            Method::Embree(call) => {
                let e = coray_embree::EmbreeScene::new(&scene, Some(threads as u32));
                // rtcCommitScene alone, as coray's builds are timed (device
                // creation and the copies into Embree's buffers excluded).
                b.build_ms = e.build_cost().0 * 1e3;
                b.bytes = Some(e.memory_bytes().0 as usize);
                b.inner = Inner::Embree(e, call == crate::method::EmbreeCall::Eight);
            }
            #[cfg(not(feature = "embree"))]
            Method::Embree(_) => unreachable!("available() refused it"),
        }
        let _ = threads;
        Ok(b)
    }

    /// Does `v` with this structure's shooter.
    pub fn visit<V: Visit>(&self, v: V) -> V::Out {
        match &self.inner {
            Inner::Kd(o, Traversal::Packets) => v.visit(&crate::shoot::KdPacketShooter {
                tree: o.tree(self.scene).expect("just built"),
                bounds: self.bounds,
            }),
            Inner::Kd(o, traversal) => v.visit(&AccelShooter {
                accel: o.tree(self.scene).expect("just built"),
                method: *traversal,
                bounds: self.bounds,
            }),
            Inner::KdC(tree, calls) => v.visit(&crate::shoot::CShooter {
                structure: tree,
                calls: *calls,
                bounds: self.bounds,
            }),
            Inner::WideC(wide, calls) => v.visit(&crate::shoot::CShooter {
                structure: wide,
                calls: *calls,
                bounds: self.bounds,
            }),
            Inner::Bvh(o) => v.visit(&AccelShooter {
                accel: o.view(self.scene).expect("just built"),
                method: (),
                bounds: self.bounds,
            }),
            Inner::Wide(o, packets) => v.visit(&crate::shoot::WideShooter {
                wide: o.view(self.scene).expect("just built"),
                packets: *packets,
                bounds: self.bounds,
            }),
            Inner::Proj(rig) => v.visit(rig.as_ref()),
            #[cfg(feature = "embree")]
            Inner::Embree(e, packets) => v.visit(&crate::shoot::EmbreeShooter {
                scene: e,
                packets: *packets,
                bounds: self.bounds,
            }),
        }
    }

    /// The kd-tree, for the statistics and casts of kd methods.
    pub fn kd(&self) -> Option<&OwnedKd> {
        match &self.inner {
            Inner::Kd(o, _) => Some(o),
            _ => None,
        }
    }

    /// A hierarchy's size and shape, from its validation.
    pub fn bvh_stats(&self) -> Result<coray::bvh::BvhTreeStats, String> {
        match &self.inner {
            Inner::Bvh(o) => o.validate(self.scene).map_err(|e| e.to_string()),
            _ => Err(format!("{} is not a hierarchy", self.method)),
        }
    }

    /// The projection rig, for its split preprocessing times.
    pub fn rig(&self) -> Option<&ProjRig<'s>> {
        match &self.inner {
            Inner::Proj(r) => Some(r),
            _ => None,
        }
    }
}

/// Milliseconds since `t`.
pub fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
