//! Embree 3 as the reference coray is checked and timed against: the same
//! [`coray::Scene`] built as an Embree scene (triangles; spheres as sphere
//! points; cones as linear cone curves with both neighbour flags, which is
//! NFF's open cone), traced with `rtcIntersect1` and `rtcOccluded1`.
//!
//! Embree 3.13's linear cone curves assume unit ray directions: give
//! [`EmbreeScene`] normalised directions when the scene has cones (the
//! cross-check tests show the error otherwise).
#![deny(unsafe_op_in_unsafe_fn)]

pub mod sys;

use coray::{Hit, Ray, Scene, Vec3};
use std::ffi::CString;
use sys::*;

/// An Embree device and committed scene holding a copy of a coray scene.
pub struct EmbreeScene {
    device: RTCDevice,
    scene: RTCScene,
    /// Bytes Embree's device holds (allocations less releases) and the
    /// most it held, as its memory monitor reports them.
    memory: Box<Memory>,
    /// Seconds `rtcCommitScene` took: the build alone (device creation and
    /// the copies of the scene's arrays into Embree's buffers excluded).
    commit_secs: f64,
    /// Bytes the device held just before the commit (the scene's copies).
    before_commit: i64,
}

/// What the memory monitor saw.
#[derive(Default)]
struct Memory {
    now: std::sync::atomic::AtomicI64,
    peak: std::sync::atomic::AtomicI64,
}

/// Embree's memory monitor: adds every allocation and release.
///
/// # Safety
/// `user` is the `Memory` the device was given, alive as long as the device.
unsafe extern "C" fn monitor(user: *mut core::ffi::c_void, bytes: isize, post: bool) -> bool {
    use std::sync::atomic::Ordering::Relaxed;
    // Releases are reported after the fact (post = true), allocations before.
    let _ = post;
    // SAFETY: the caller's contract: `user` points to the live Memory.
    let m = unsafe { &*(user as *const Memory) };
    let now = m.now.fetch_add(bytes as i64, Relaxed) + bytes as i64;
    m.peak.fetch_max(now, Relaxed);
    true
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
        let memory = Box::<Memory>::default();
        unsafe {
            let device = rtcNewDevice(config.as_ptr());
            assert!(
                !device.is_null(),
                "rtcNewDevice failed (error {})",
                rtcGetDeviceError(std::ptr::null_mut())
            );
            let user = &*memory as *const Memory as *mut core::ffi::c_void;
            rtcSetDeviceMemoryMonitorFunction(device, Some(monitor), user);
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
            let before_commit = memory.now.load(std::sync::atomic::Ordering::Relaxed);
            let t = std::time::Instant::now();
            rtcCommitScene(scene);
            let commit_secs = t.elapsed().as_secs_f64();
            EmbreeScene {
                device,
                scene,
                memory,
                commit_secs,
                before_commit,
            }
        }
    }

    /// Bytes the device holds once the scene is built (allocations less
    /// releases, the geometry buffers' copies of the scene included), and
    /// the most it held during the build.
    pub fn memory_bytes(&self) -> (u64, u64) {
        use std::sync::atomic::Ordering::Relaxed;
        let m = &self.memory;
        (
            m.now.load(Relaxed).max(0) as u64,
            m.peak.load(Relaxed).max(0) as u64,
        )
    }

    /// The build as `rtcCommitScene` did it: (seconds, bytes the device
    /// holds for the hierarchy once built, the most it held above the
    /// scene's copies during the build), per the memory monitor.
    pub fn build_cost(&self) -> (f64, u64, u64) {
        use std::sync::atomic::Ordering::Relaxed;
        let m = &self.memory;
        let (now, peak) = (m.now.load(Relaxed), m.peak.load(Relaxed));
        (
            self.commit_secs,
            (now - self.before_commit).max(0) as u64,
            (peak - self.before_commit).max(0) as u64,
        )
    }

    fn context() -> RTCIntersectContext {
        RTCIntersectContext {
            flags: RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT,
            filter: std::ptr::null(),
            instID: [RTC_INVALID_GEOMETRY_ID],
        }
    }

    fn coherent() -> RTCIntersectContext {
        RTCIntersectContext {
            flags: RTC_INTERSECT_CONTEXT_FLAG_COHERENT,
            ..Self::context()
        }
    }

    /// Fills lanes `0..rays.len()` (at most 8) of a packet and its valid
    /// mask; the rest stay invalid.
    fn packet(rays: &[Ray]) -> (Valid8, RTCRay8) {
        let mut valid = Valid8([0; 8]);
        let mut p = RTCRay8 {
            mask: [u32::MAX; 8],
            ..RTCRay8::default()
        };
        for (i, r) in rays.iter().enumerate().take(8) {
            valid.0[i] = -1;
            p.org_x[i] = r.origin.x;
            p.org_y[i] = r.origin.y;
            p.org_z[i] = r.origin.z;
            p.tnear[i] = r.t_min;
            p.dir_x[i] = r.dir.x;
            p.dir_y[i] = r.dir.y;
            p.dir_z[i] = r.dir.z;
            p.tfar[i] = r.t_max;
        }
        (valid, p)
    }

    /// Closest hits with `rtcIntersect8`, rays taken 8 at a time in order
    /// (the caller orders coherent rays into packets: 4 x 2 pixel blocks).
    pub fn intersect8(&self, rays: &[Ray], out: &mut [Hit]) {
        let mut ctx = Self::coherent();
        for (chunk, hits) in rays.chunks(8).zip(out.chunks_mut(8)) {
            let (valid, ray) = Self::packet(chunk);
            let mut rh = RTCRayHit8 {
                ray,
                hit: RTCHit8 {
                    geomID: [RTC_INVALID_GEOMETRY_ID; 8],
                    primID: [RTC_INVALID_GEOMETRY_ID; 8],
                    ..RTCHit8::default()
                },
            };
            // SAFETY: a committed scene; the 32-byte aligned valid mask and
            // ray-hit packet and the context live on our stack.
            unsafe { rtcIntersect8(valid.0.as_ptr(), self.scene, &mut ctx, &mut rh) };
            for (i, h) in hits.iter_mut().enumerate() {
                let g = rh.hit.geomID[i];
                *h = if g == RTC_INVALID_GEOMETRY_ID {
                    Hit::MISS
                } else {
                    Hit {
                        t: rh.ray.tfar[i],
                        u: rh.hit.u[i],
                        v: rh.hit.v[i],
                        ng: Vec3::new(rh.hit.Ng_x[i], rh.hit.Ng_y[i], rh.hit.Ng_z[i]),
                        geom_id: g,
                        prim_id: rh.hit.primID[i],
                    }
                };
            }
        }
    }

    /// Any hits with `rtcOccluded8`, rays taken 8 at a time in order.
    pub fn occluded8(&self, rays: &[Ray], out: &mut [bool]) {
        let mut ctx = Self::coherent();
        for (chunk, occ) in rays.chunks(8).zip(out.chunks_mut(8)) {
            let (valid, mut ray) = Self::packet(chunk);
            // SAFETY: as in intersect8.
            unsafe { rtcOccluded8(valid.0.as_ptr(), self.scene, &mut ctx, &mut ray) };
            for (i, o) in occ.iter_mut().enumerate() {
                *o = ray.tfar[i] == f32::NEG_INFINITY;
            }
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
        // SAFETY: handles from new(), released once; the memory monitor's
        // Memory outlives the device (it is dropped after this).
        unsafe {
            rtcReleaseScene(self.scene);
            rtcReleaseDevice(self.device);
        }
    }
}

/// The tie rules of every comparison with Embree: one table, in the core
/// (`coray::tolerance`), shared by the cross-checks, `coray compare` and
/// `coray bench`.
pub use coray::tolerance::{classify, classify_occluded, grazing, t_tolerance, Agreement};

/// The valid mask of an 8-wide call: Embree loads it with an aligned
/// 32-byte load (`vmovdqa`), so a plain `[i32; 8]` (4-byte aligned) made
/// rtcOccluded8 fault whenever the stack put it at an odd 16 bytes.
#[repr(C, align(32))]
struct Valid8([i32; 8]);
const _: () = assert!(core::mem::align_of::<Valid8>() == 32);
