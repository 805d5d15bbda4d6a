//! The plain C types every object shares: the scene, rays and hits, the
//! one requirements shape, the one statistics type, the one validation
//! result, and the named enumerations.

use crate::carve::Versioned;
use coray::{Hit, Ray, TraceStats, Vec3};

/// A geometry of the scene: `CORAY_GEOM_TRIANGLES`, `CORAY_GEOM_SPHERES`
/// or `CORAY_GEOM_CONES` (`CORAY_INVALID_ID` in a miss).
pub type CorayGeomId = u32;
/// The scene's triangle mesh.
pub const CORAY_GEOM_TRIANGLES: CorayGeomId = 0;
/// The scene's spheres.
pub const CORAY_GEOM_SPHERES: CorayGeomId = 1;
/// The scene's cones and cylinders.
pub const CORAY_GEOM_CONES: CorayGeomId = 2;
/// `geom_id` and `prim_id` of a miss.
pub const CORAY_INVALID_ID: u32 = 0xFFFF_FFFF;

/// Alignment, in bytes, of every arena, scratch and stack passed to coray.
pub const CORAY_ARENA_ALIGN: usize = 16;

/// Two libraries' hits on one primitive agree when their t differ by at
/// most this times max(1, |t|) (`coray::tolerance::SAME_T_REL`). The
/// `CORAY_TOL_*` are the cross-check rules of `coray::tolerance`, written
/// as double literals: compare as coray does, in float
/// (`(float)CORAY_TOL_EDGE_BARY`). Since 1.8.
pub const CORAY_TOL_SAME_T_REL: f32 = 1e-4;
/// A triangle hit whose smallest barycentric weight is below this lies on
/// an edge, where rounding may move it (`coray::tolerance::EDGE_BARY`).
/// Since 1.8.
pub const CORAY_TOL_EDGE_BARY: f32 = 1e-4;
/// A cone hit this close to either rim, in `u` (`coray::tolerance::RIM_U`).
/// Since 1.8.
pub const CORAY_TOL_RIM_U: f32 = 1e-3;
/// A hit where the ray meets the surface at a cosine below this is tangent
/// (`coray::tolerance::GRAZE_COS`). Since 1.8.
pub const CORAY_TOL_GRAZE_COS: f32 = 2e-2;
const _: () = {
    use coray::tolerance as t;
    assert!(CORAY_TOL_SAME_T_REL.to_bits() == t::SAME_T_REL.to_bits());
    assert!(CORAY_TOL_EDGE_BARY.to_bits() == t::EDGE_BARY.to_bits());
    assert!(CORAY_TOL_RIM_U.to_bits() == t::RIM_U.to_bits());
    assert!(CORAY_TOL_GRAZE_COS.to_bits() == t::GRAZE_COS.to_bits());
};

/// The primitives, borrowed for the duration of each call (coray keeps no
/// pointer but inside the handles of the open calls). A structure stores
/// primitive indices, not copies: pass the same scene, unchanged, to every
/// call on it.
///
/// Arrays may be NULL when their count is 0. Degenerate primitives (zero
/// area, zero or negative radius, NaN or infinite coordinates) are allowed
/// and never hit. A primitive is named by its geometry and its index in
/// that geometry's array, in hits and everywhere else.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CorayScene {
    /// `sizeof(CorayScene)`.
    pub struct_size: usize,
    /// `3 * vertex_count` floats: x y z per vertex (4-byte aligned).
    pub vertices: *const f32,
    /// Number of vertices.
    pub vertex_count: usize,
    /// `3 * triangle_count` vertex indices.
    pub indices: *const u32,
    /// Number of triangles (`CORAY_GEOM_TRIANGLES`).
    pub triangle_count: usize,
    /// `4 * sphere_count` floats: x y z radius (Embree's sphere points).
    pub spheres: *const f32,
    /// Number of spheres (`CORAY_GEOM_SPHERES`).
    pub sphere_count: usize,
    /// `8 * cone_count` floats: base x y z, base radius, apex x y z, apex
    /// radius; open cones and cylinders, no caps (NFF's `c`).
    pub cones: *const f32,
    /// Number of cones (`CORAY_GEOM_CONES`).
    pub cone_count: usize,
}

impl Default for CorayScene {
    /// An empty scene with `struct_size` 0 (coray_scene_default sets it).
    fn default() -> CorayScene {
        CorayScene {
            struct_size: 0,
            ..coray_scene_default()
        }
    }
}

/// An empty scene with `struct_size` set.
#[no_mangle]
pub extern "C" fn coray_scene_default() -> CorayScene {
    CorayScene {
        struct_size: core::mem::size_of::<CorayScene>(),
        vertices: core::ptr::null(),
        vertex_count: 0,
        indices: core::ptr::null(),
        triangle_count: 0,
        spheres: core::ptr::null(),
        sphere_count: 0,
        cones: core::ptr::null(),
        cone_count: 0,
    }
}

/// A ray segment `org + t * dir`, `t` in `[tnear, tfar]` (Embree's layout
/// of the same fields). `dir` need not be normalised. A ray with a NaN or
/// infinite component, a zero direction or `tnear > tfar` hits nothing.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayRay {
    /// Origin.
    pub org: [f32; 3],
    /// Start of the segment.
    pub tnear: f32,
    /// Direction.
    pub dir: [f32; 3],
    /// End of the segment.
    pub tfar: f32,
}

/// The closest hit of a ray. On a miss `geom_id` and `prim_id` are
/// `CORAY_INVALID_ID` and `t` is infinity.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayHit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Triangle: barycentric weight of vertex 1; cone: position along the
    /// axis in [0, 1].
    pub u: f32,
    /// Triangle: barycentric weight of vertex 2.
    pub v: f32,
    /// Geometric normal, not normalised, not flipped towards the ray.
    pub ng: [f32; 3],
    /// The primitive's geometry (`CORAY_GEOM_*`), or `CORAY_INVALID_ID`.
    pub geom_id: CorayGeomId,
    /// Index within that geometry's array, or `CORAY_INVALID_ID`.
    pub prim_id: u32,
}

/// What one object needs, in bytes, from `coray_<object>_requirements`.
/// Fields an object has no use for are 0.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayRequirements {
    /// `sizeof(CorayRequirements)`.
    pub struct_size: usize,
    /// Smallest arena a build accepts.
    pub arena_min_bytes: usize,
    /// The arena to give it: enough that ordinary scenes build unhindered.
    pub arena_bytes: usize,
    /// Smallest scratch a build (or a cast, a query) accepts.
    pub scratch_min_bytes: usize,
    /// The scratch to give it with `arena_bytes`.
    pub scratch_bytes: usize,
    /// Traversal stack every trace and validate call on the result needs
    /// (an upper bound before the build; the info call gives the exact
    /// figure after it).
    pub stack_bytes: usize,
}

/// What a validate call found: the structure's shape.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayShape {
    /// `sizeof(CorayShape)`.
    pub struct_size: usize,
    /// Nodes reached from the root, interior and leaf.
    pub node_count: u32,
    /// Leaves reached.
    pub leaf_count: u32,
    /// Leaves holding no primitive.
    pub empty_leaf_count: u32,
    /// Primitive references in the leaves.
    pub ref_count: u32,
    /// Depth of the deepest leaf (root: 0).
    pub depth: u32,
}

/// Work done by one trace call, for every object. Fields an object has no
/// use for stay 0. Set `struct_size`; coray writes that many bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayTraceStats {
    /// `sizeof(CorayTraceStats)`.
    pub struct_size: usize,
    /// Rays traced.
    pub rays: u64,
    /// Nodes visited, interior plus leaf (TSPR = this / rays).
    pub traversal_steps: u64,
    /// Interior nodes visited.
    pub interior_steps: u64,
    /// Leaves visited.
    pub leaf_steps: u64,
    /// Empty leaves visited.
    pub empty_leaf_steps: u64,
    /// Ray-primitive tests.
    pub prim_tests: u64,
    /// Hierarchies: hierarchy objects (3D boxes, 2D rectangles) tested.
    pub box_tests: u64,
    /// Hierarchies: their cost in the thesis' units (a box test costs 2 to 51).
    pub box_cost: u64,
    /// Hierarchies: the primitives' cost in the same units.
    pub prim_cost: u64,
    /// Projection hierarchies: point-in-rectangle tests among `box_tests`.
    pub rect_tests: u64,
    /// LCTS casts: shafts (windows, intervals, rectangles) given a common sequence.
    pub windows: u64,
    /// Of those, shafts whose sequence starts with a shared leaf (gamma = this / windows).
    pub windows_shared: u64,
    /// Shafts with a termination object.
    pub windows_terminated: u64,
    /// SLCTS windows without a shared leaf whose rays started below the
    /// root, at their corners' deepest common node.
    pub windows_entered: u64,
}

impl CorayTraceStats {
    /// The C view of the core's counters (LCTS counters left 0).
    pub(crate) fn of(s: &TraceStats) -> CorayTraceStats {
        CorayTraceStats {
            struct_size: core::mem::size_of::<CorayTraceStats>(),
            rays: s.rays,
            traversal_steps: s.traversal_steps,
            interior_steps: s.interior_steps,
            leaf_steps: s.leaf_steps,
            empty_leaf_steps: s.empty_leaf_steps,
            prim_tests: s.prim_tests,
            box_tests: s.box_tests,
            box_cost: s.box_cost,
            prim_cost: s.prim_cost,
            rect_tests: s.rect_tests,
            ..Default::default()
        }
    }
}

// SAFETY (all impls): repr(C) structs of usize, u32, u64, f32 and pointer
// fields, every bit pattern a valid value, `struct_size` first. In ABI 1.0
// every struct is as first published, so its 1.0 size is its size.
unsafe impl Versioned for CorayScene {
    const SIZE_1_0: usize = core::mem::size_of::<Self>();
}
unsafe impl Versioned for CorayRequirements {
    const SIZE_1_0: usize = core::mem::size_of::<Self>();
}
unsafe impl Versioned for CorayShape {
    const SIZE_1_0: usize = core::mem::size_of::<Self>();
}
unsafe impl Versioned for CorayTraceStats {
    const SIZE_1_0: usize = core::mem::size_of::<Self>();
}

// CorayRay and Ray, CorayHit and Hit: the same fields at the same offsets
// (repr(C), f32 and u32 throughout), so the caller's arrays are traced in
// place (`core_rays`, `core_hits`). Checked at compile time.
const _: () = {
    use core::mem::{align_of, offset_of, size_of};
    assert!(
        size_of::<CorayRay>() == size_of::<Ray>() && align_of::<CorayRay>() == align_of::<Ray>()
    );
    assert!(offset_of!(CorayRay, org) == offset_of!(Ray, origin));
    assert!(offset_of!(CorayRay, tnear) == offset_of!(Ray, t_min));
    assert!(offset_of!(CorayRay, dir) == offset_of!(Ray, dir));
    assert!(offset_of!(CorayRay, tfar) == offset_of!(Ray, t_max));
    assert!(
        size_of::<CorayHit>() == size_of::<Hit>() && align_of::<CorayHit>() == align_of::<Hit>()
    );
    assert!(offset_of!(CorayHit, t) == offset_of!(Hit, t));
    assert!(offset_of!(CorayHit, u) == offset_of!(Hit, u));
    assert!(offset_of!(CorayHit, v) == offset_of!(Hit, v));
    assert!(offset_of!(CorayHit, ng) == offset_of!(Hit, ng));
    assert!(offset_of!(CorayHit, geom_id) == offset_of!(Hit, geom_id));
    assert!(offset_of!(CorayHit, prim_id) == offset_of!(Hit, prim_id));
    assert!(size_of::<Vec3>() == 12 && align_of::<Vec3>() == 4);
};

/// The caller's rays as the core's, without a copy.
pub(crate) fn core_rays(r: &[CorayRay]) -> &[Ray] {
    // SAFETY: CorayRay and Ray have the same size, alignment and fields
    // (f32s at the same offsets, asserted above), and every bit pattern is
    // a valid f32: the same memory is a valid [Ray] of the same length,
    // borrowed for the same lifetime.
    unsafe { core::slice::from_raw_parts(r.as_ptr().cast::<Ray>(), r.len()) }
}

/// The caller's ray as the core's, without a copy. A copy would cost a
/// one-ray call a stall: the conversion stores the ray in three parts, and
/// the traversal's first 8-byte load of the direction spans two of them,
/// which a store cannot forward (measured: 17% of a tracer call's time).
pub(crate) fn core_ray(r: &CorayRay) -> &Ray {
    &core_rays(core::slice::from_ref(r))[0]
}

/// The caller's hit array as the core's, written in place.
pub(crate) fn core_hits(h: &mut [CorayHit]) -> &mut [Hit] {
    // SAFETY: as in core_rays (f32 and u32 fields at the same offsets, any
    // bit pattern valid), and the unique borrow passes on for its lifetime.
    unsafe { core::slice::from_raw_parts_mut(h.as_mut_ptr().cast::<Hit>(), h.len()) }
}

impl From<&CorayRay> for Ray {
    #[inline]
    fn from(r: &CorayRay) -> Ray {
        Ray::new(Vec3::from(r.org), Vec3::from(r.dir), r.tnear, r.tfar)
    }
}

impl From<Hit> for CorayHit {
    #[inline]
    fn from(h: Hit) -> CorayHit {
        CorayHit {
            t: h.t,
            u: h.u,
            v: h.v,
            ng: h.ng.into(),
            geom_id: h.geom_id,
            prim_id: h.prim_id,
        }
    }
}

/// The global primitive index (triangles, then spheres, then cones) of
/// `(geom, prim)`, or `None` when the scene has no such primitive.
pub(crate) fn global_prim(s: &coray::Scene, geom: CorayGeomId, prim: u32) -> Option<u32> {
    let p = prim as usize;
    let (nt, ns, nc) = (s.triangles.len(), s.spheres.len(), s.cones.len());
    let g = match geom {
        CORAY_GEOM_TRIANGLES if p < nt => p,
        CORAY_GEOM_SPHERES if p < ns => nt + p,
        CORAY_GEOM_CONES if p < nc => nt + ns + p,
        _ => return None,
    };
    u32::try_from(g).ok()
}

/// A `CorayRequirements` to fill, `struct_size` set.
#[no_mangle]
pub extern "C" fn coray_requirements_default() -> CorayRequirements {
    CorayRequirements {
        struct_size: core::mem::size_of::<CorayRequirements>(),
        ..Default::default()
    }
}

/// A `CorayShape` to fill, `struct_size` set.
#[no_mangle]
pub extern "C" fn coray_shape_default() -> CorayShape {
    CorayShape {
        struct_size: core::mem::size_of::<CorayShape>(),
        ..Default::default()
    }
}

/// A `CorayTraceStats` to fill, `struct_size` set.
#[no_mangle]
pub extern "C" fn coray_trace_stats_default() -> CorayTraceStats {
    CorayTraceStats {
        struct_size: core::mem::size_of::<CorayTraceStats>(),
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {

    #[test]
    fn caller_arrays_read_and_write_as_the_cores() {
        let r = CorayRay {
            org: [1.0, 2.0, 3.0],
            tnear: 0.5,
            dir: [4.0, 5.0, 6.0],
            tfar: 7.5,
        };
        let rays = [r, r];
        let core = core_rays(&rays);
        assert_eq!(core.len(), 2);
        assert_eq!(core[1], Ray::from(&r));
        let h = Hit {
            t: 2.0,
            u: 0.25,
            v: 0.5,
            ng: Vec3::new(0.0, 1.0, 0.0),
            geom_id: 1,
            prim_id: 7,
        };
        let mut hits = [CorayHit::default(); 3];
        core_hits(&mut hits)[2] = h;
        let c = hits[2];
        assert_eq!(
            (c.t, c.u, c.v, c.ng, c.geom_id, c.prim_id),
            (2.0, 0.25, 0.5, [0.0, 1.0, 0.0], 1, 7)
        );
        assert_eq!(hits[0].t, 0.0);
    }

    use super::*;
    use core::mem::size_of;

    #[test]
    fn sizes_of_abi_1_0_on_64_bit_targets() {
        assert_eq!(size_of::<CorayScene>(), 72);
        assert_eq!(size_of::<CorayRequirements>(), 48);
        assert_eq!(size_of::<CorayShape>(), 32);
        assert_eq!(size_of::<CorayTraceStats>(), 120);
        assert_eq!(size_of::<CorayRay>(), 32);
        assert_eq!(size_of::<CorayHit>(), 32);
    }
}
