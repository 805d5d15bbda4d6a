//! Embree 3 as the reference coray is checked and timed against: the same
//! [`coray::Scene`] built as an Embree scene (triangles; spheres as sphere
//! points; cones as linear cone curves with both neighbour flags, which is
//! NFF's open cone), traced with `rtcIntersect1` and `rtcOccluded1`.
//!
//! Embree 3.13's linear cone curves assume unit ray directions: give
//! [`EmbreeScene`] normalised directions when the scene has cones (the
//! cross-check tests show the error otherwise).
#![deny(unsafe_op_in_unsafe_fn)]
#![warn(missing_docs)]

pub mod sys;

use coray::{Hit, Ray, Scene, Vec3};
use std::ffi::CString;
use sys::*;

/// An Embree device and committed scene holding a copy of a coray scene.
pub struct EmbreeScene {
    device: RTCDevice,
    scene: RTCScene,
}

// SAFETY: Embree scenes are thread-safe for rtcIntersect1/rtcOccluded1 once
// committed (Embree's documentation); the handles are only released in Drop.
unsafe impl Send for EmbreeScene {}
// SAFETY: as above; tracing takes &self and Embree allows concurrent traces.
unsafe impl Sync for EmbreeScene {}

/// Copies `n` items of `T` into a new Embree buffer of `geom`.
///
/// # Safety
/// `geom` is a live geometry; `ty`/`format`/`T` agree in size with `stride`.
unsafe fn new_buffer<T: Copy>(geom: RTCGeometry, ty: u32, format: u32, items: &[T]) {
    let stride = std::mem::size_of::<T>();
    // SAFETY: Embree allocates `items.len()` items of `stride` bytes (plus
    // its own padding) and returns a pointer aligned for them.
    let dst =
        unsafe { rtcSetNewGeometryBuffer(geom, ty, 0, format, stride, items.len()) }.cast::<T>();
    assert!(!dst.is_null(), "Embree could not allocate a buffer");
    // SAFETY: dst holds items.len() elements of T and does not overlap items.
    unsafe { std::ptr::copy_nonoverlapping(items.as_ptr(), dst, items.len()) };
}

impl EmbreeScene {
    /// Builds the scene. `threads` limits Embree's build threads (1 for a
    /// single-threaded comparison); `None` lets Embree choose.
    pub fn new(s: &Scene, threads: Option<u32>) -> EmbreeScene {
        let config =
            CString::new(threads.map(|t| format!("threads={t}")).unwrap_or_default()).unwrap();
        // SAFETY: every call below follows Embree's API contract: handles
        // come from the matching rtcNew* call and are used while alive;
        // buffers are sized by rtcSetNewGeometryBuffer for what is copied in.
        unsafe {
            let device = rtcNewDevice(config.as_ptr());
            assert!(
                !device.is_null(),
                "rtcNewDevice failed (error {})",
                rtcGetDeviceError(std::ptr::null_mut())
            );
            let scene = rtcNewScene(device);
            rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
            rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
            if !s.triangles.is_empty() {
                let g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
                new_buffer(g, RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT3, s.vertices);
                new_buffer(g, RTC_BUFFER_TYPE_INDEX, RTC_FORMAT_UINT3, s.triangles);
                rtcCommitGeometry(g);
                rtcAttachGeometryByID(scene, g, coray::geom::GEOM_TRIANGLES);
                rtcReleaseGeometry(g);
            }
            if !s.spheres.is_empty() {
                let g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
                new_buffer(g, RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT4, s.spheres);
                rtcCommitGeometry(g);
                rtcAttachGeometryByID(scene, g, coray::geom::GEOM_SPHERES);
                rtcReleaseGeometry(g);
            }
            if !s.cones.is_empty() {
                let g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_CONE_LINEAR_CURVE);
                // Two curve vertices (x y z radius) per cone: base, then apex.
                let verts: Vec<[f32; 4]> = s
                    .cones
                    .iter()
                    .flat_map(|c| {
                        let (b, a) = (c.base, c.apex);
                        [
                            [b[0], b[1], b[2], c.base_radius],
                            [a[0], a[1], a[2], c.apex_radius],
                        ]
                    })
                    .collect();
                new_buffer(g, RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT4, &verts);
                let starts: Vec<u32> = (0..s.cones.len() as u32).map(|i| 2 * i).collect();
                new_buffer(g, RTC_BUFFER_TYPE_INDEX, RTC_FORMAT_UINT, &starts);
                let flags = vec![
                    RTC_CURVE_FLAG_NEIGHBOR_LEFT | RTC_CURVE_FLAG_NEIGHBOR_RIGHT;
                    s.cones.len()
                ];
                new_buffer(g, RTC_BUFFER_TYPE_FLAGS, RTC_FORMAT_UCHAR, &flags);
                rtcCommitGeometry(g);
                rtcAttachGeometryByID(scene, g, coray::geom::GEOM_CONES);
                rtcReleaseGeometry(g);
            }
            rtcCommitScene(scene);
            EmbreeScene { device, scene }
        }
    }

    fn context() -> RTCIntersectContext {
        RTCIntersectContext {
            flags: RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT,
            filter: std::ptr::null(),
            instID: [RTC_INVALID_GEOMETRY_ID],
        }
    }

    fn rtc_ray(r: &Ray) -> RTCRay {
        RTCRay {
            org_x: r.origin.x,
            org_y: r.origin.y,
            org_z: r.origin.z,
            tnear: r.t_min,
            dir_x: r.dir.x,
            dir_y: r.dir.y,
            dir_z: r.dir.z,
            time: 0.0,
            tfar: r.t_max,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        }
    }

    /// Closest hit with `rtcIntersect1`, as a coray [`Hit`].
    pub fn intersect(&self, r: &Ray) -> Hit {
        let mut ctx = Self::context();
        let mut rh = RTCRayHit {
            ray: Self::rtc_ray(r),
            hit: RTCHit::default(),
        };
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
        // SAFETY: a committed scene, an initialised context and ray-hit on our stack.
        unsafe { rtcIntersect1(self.scene, &mut ctx, &mut rh) };
        if rh.hit.geomID == RTC_INVALID_GEOMETRY_ID {
            return Hit::MISS;
        }
        Hit {
            t: rh.ray.tfar,
            u: rh.hit.u,
            v: rh.hit.v,
            ng: Vec3::new(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z),
            geom_id: rh.hit.geomID,
            prim_id: rh.hit.primID,
        }
    }

    /// Any hit with `rtcOccluded1`.
    pub fn occluded(&self, r: &Ray) -> bool {
        let mut ctx = Self::context();
        let mut ray = Self::rtc_ray(r);
        // SAFETY: as in intersect.
        unsafe { rtcOccluded1(self.scene, &mut ctx, &mut ray) };
        ray.tfar == f32::NEG_INFINITY
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: handles from new(), released once.
        unsafe {
            rtcReleaseScene(self.scene);
            rtcReleaseDevice(self.device);
        }
    }
}

/// How a coray hit and an Embree hit of the same ray relate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Agreement {
    /// Both miss, or both hit the same primitive within the tolerance.
    Same,
    /// Different primitives at the same distance (shared edges, coincident surfaces).
    TieSameDistance,
    /// The nearer answer grazes (see [`grazing`]), where a rounding error
    /// turns a hit into a miss.
    TieGrazing,
    /// Anything else.
    Mismatch,
}

/// The cross-check's tolerance: |dt| <= 1e-4 max(1, |t|).
pub fn tolerance(t: f32) -> f32 {
    1e-4 * t.abs().max(1.0)
}

/// True when rounding can turn `h` into a miss on `r`: near a triangle's
/// edge, at a cone's rim, tangent to the surface, or within the tolerance
/// of the ray's start (a ray leaving a surface meeting that surface again).
pub fn grazing(r: &Ray, h: &Hit) -> bool {
    if h.t < r.t_min + tolerance(r.t_min) {
        return true;
    }
    let edge = match h.geom_id {
        coray::geom::GEOM_TRIANGLES => h.u.min(h.v).min(1.0 - h.u - h.v) < 1e-4,
        coray::geom::GEOM_CONES => h.u < 1e-3 || h.u > 1.0 - 1e-3,
        _ => false,
    };
    let cos = r.dir.normalize().dot(h.ng.normalize()).abs();
    edge || cos < 2e-2
}

/// Classifies a ray's two answers (the documented tie rules of the cross-checks).
pub fn classify(r: &Ray, a: &Hit, b: &Hit) -> Agreement {
    match (a.is_hit(), b.is_hit()) {
        (false, false) => return Agreement::Same,
        (true, true) if (a.t - b.t).abs() <= tolerance(a.t) => {
            return if (a.geom_id, a.prim_id) == (b.geom_id, b.prim_id) {
                Agreement::Same
            } else {
                Agreement::TieSameDistance
            };
        }
        _ => {}
    }
    let nearer = if !b.is_hit() || (a.is_hit() && a.t < b.t) {
        a
    } else {
        b
    };
    if grazing(r, nearer) {
        Agreement::TieGrazing
    } else {
        Agreement::Mismatch
    }
}
