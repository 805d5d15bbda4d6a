//! Plain C structs of the ABI and their defaults.

use coray::{Hit, Ray, TraceStats, Vec3};

/// Build with SAH-driven termination (depth bound from N). Default.
pub const CORAY_KD_PRESET_AUTO: u32 = 0;
/// Build with the LCTS paper's settings: depth 16, leaves of at most 2.
pub const CORAY_KD_PRESET_PAPER: u32 = 1;

/// Hierarchical (stack) traversal, Havran's TA_B^rec.
pub const CORAY_TRAVERSAL_HIERARCHICAL: u32 = 0;
/// Rope traversal, leaf to leaf.
pub const CORAY_TRAVERSAL_ROPES: u32 = 1;

/// `geom_id` of the triangle mesh in a hit.
pub const CORAY_GEOM_TRIANGLES: u32 = 0;
/// `geom_id` of the spheres in a hit.
pub const CORAY_GEOM_SPHERES: u32 = 1;
/// `geom_id` of the cones in a hit.
pub const CORAY_GEOM_CONES: u32 = 2;
/// `geom_id` and `prim_id` of a miss.
pub const CORAY_INVALID_ID: u32 = 0xFFFF_FFFF;

/// Alignment, in bytes, of every arena passed to coray.
pub const CORAY_ARENA_ALIGN: usize = 16;

/// The primitives, borrowed for the duration of each call (coray keeps no
/// pointer). A tree stores primitive indices, not copies: pass the same
/// scene, unchanged, to every trace call on that tree.
///
/// Arrays may be NULL when their count is 0. Degenerate primitives (zero
/// area, zero or negative radius, NaN or infinite coordinates) are allowed
/// and never hit.
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
    /// Number of triangles (geometry id 0).
    pub triangle_count: usize,
    /// `4 * sphere_count` floats: x y z radius (Embree's sphere points).
    pub spheres: *const f32,
    /// Number of spheres (geometry id 1).
    pub sphere_count: usize,
    /// `8 * cone_count` floats: base x y z, base radius, apex x y z, apex
    /// radius; open cones and cylinders, no caps (NFF's `c`).
    pub cones: *const f32,
    /// Number of cones (geometry id 2).
    pub cone_count: usize,
}

/// Parameters of a kd-tree build. Get them from [`coray_kd_params_default`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CorayKdParams {
    /// `sizeof(CorayKdParams)`.
    pub struct_size: usize,
    /// Deepest leaf; 0 derives it from N as round(8 + 1.3 log2 N). At most 60.
    pub max_depth: u32,
    /// A node with at most this many primitives becomes a leaf.
    pub leaf_size: u32,
    /// 1: stop where no split beats the leaf by the SAH; 0: split down to
    /// `leaf_size` or `max_depth`.
    pub sah_termination: u32,
    /// Ideal references per primitive (1 to 64): sets the ideal arena size.
    pub refs_per_prim: u32,
    /// SAH cost of a traversal step (> 0; Wald and Havran: 15).
    pub cost_traversal: f32,
    /// SAH cost of a ray-primitive test (> 0; Wald and Havran: 20).
    pub cost_intersection: f32,
    /// Cost factor of a split with an empty side, in (0, 1] (0.8).
    pub empty_bonus: f32,
}

/// Arena sizes for a kd build, from [`coray_kdtree_requirements`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayKdRequirements {
    /// Smallest tree arena a build accepts (the tree is then one leaf).
    pub tree_min_bytes: usize,
    /// Tree arena with room for `refs_per_prim` references per primitive
    /// (4 by default): most scenes build without being cut short; one that
    /// needs more stops splitting evenly and says so (`truncated`).
    pub tree_bytes: usize,
    /// Smallest scratch arena a build accepts.
    pub scratch_min_bytes: usize,
    /// Scratch arena that goes with `tree_bytes`.
    pub scratch_bytes: usize,
}

/// What a built tree holds (read from its arena header, O(1)).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayKdTreeInfo {
    /// Nodes, interior and leaf.
    pub node_count: u32,
    /// Leaves.
    pub leaf_count: u32,
    /// Primitive references in leaves.
    pub ref_count: u32,
    /// Depth of the deepest leaf.
    pub depth: u32,
    /// Primitives in the tree (not degenerate).
    pub valid_prim_count: u32,
    /// 1 when room ran out and the build stopped splitting early.
    pub truncated: u32,
    /// Bytes of the arena the tree's layout covers.
    pub arena_bytes_used: usize,
    /// Lower corner of the scene box.
    pub bounds_min: [f32; 3],
    /// Upper corner of the scene box.
    pub bounds_max: [f32; 3],
}

/// Figures of a validated tree, from [`coray_kdtree_validate`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayKdTreeStats {
    /// Nodes, interior and leaf.
    pub node_count: u32,
    /// Leaves.
    pub leaf_count: u32,
    /// Leaves with no primitive.
    pub empty_leaf_count: u32,
    /// Primitive references.
    pub ref_count: u32,
    /// Depth of the deepest leaf.
    pub depth: u32,
    /// SAH cost with the default constants, relative to the root's area.
    pub sah_cost: f32,
}

/// A ray segment `org + t * dir`, `t` in `[tnear, tfar]` (Embree's layout of
/// the same fields). `dir` need not be normalised. A NaN or zero direction hits nothing.
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
    /// Triangle: barycentric weight of vertex 1; cone: position along the axis in [0, 1].
    pub u: f32,
    /// Triangle: barycentric weight of vertex 2.
    pub v: f32,
    /// Geometric normal, not normalised.
    pub ng: [f32; 3],
    /// `CORAY_GEOM_TRIANGLES`, `_SPHERES`, `_CONES` or `CORAY_INVALID_ID`.
    pub geom_id: u32,
    /// Index within the geometry, or `CORAY_INVALID_ID`.
    pub prim_id: u32,
}

/// Work done by one trace call.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayTraceStats {
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
}

impl From<&CorayRay> for Ray {
    fn from(r: &CorayRay) -> Ray {
        Ray::new(Vec3::from(r.org), Vec3::from(r.dir), r.tnear, r.tfar)
    }
}

impl From<Hit> for CorayHit {
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

impl From<TraceStats> for CorayTraceStats {
    fn from(s: TraceStats) -> CorayTraceStats {
        CorayTraceStats {
            rays: s.rays,
            traversal_steps: s.traversal_steps,
            interior_steps: s.interior_steps,
            leaf_steps: s.leaf_steps,
            empty_leaf_steps: s.empty_leaf_steps,
            prim_tests: s.prim_tests,
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

/// Default kd parameters of a preset (`CORAY_KD_PRESET_AUTO` or
/// `CORAY_KD_PRESET_PAPER`) with `struct_size` set. An unknown preset gives
/// the auto preset with `struct_size` 0, which every build rejects.
#[no_mangle]
pub extern "C" fn coray_kd_params_default(preset: u32) -> CorayKdParams {
    let (p, size) = match preset {
        CORAY_KD_PRESET_AUTO => (
            coray::kd::KdParams::auto(),
            core::mem::size_of::<CorayKdParams>(),
        ),
        CORAY_KD_PRESET_PAPER => (
            coray::kd::KdParams::paper(),
            core::mem::size_of::<CorayKdParams>(),
        ),
        _ => (coray::kd::KdParams::auto(), 0),
    };
    CorayKdParams {
        struct_size: size,
        max_depth: p.max_depth,
        leaf_size: p.leaf_size,
        sah_termination: p.sah_termination as u32,
        refs_per_prim: p.refs_per_prim,
        cost_traversal: p.cost_traversal,
        cost_intersection: p.cost_intersection,
        empty_bonus: p.empty_bonus,
    }
}

impl CorayKdParams {
    /// The core's parameters, or `InvalidParameter`.
    pub(crate) fn to_core(self) -> Result<coray::kd::KdParams, crate::CorayStatus> {
        if self.struct_size != core::mem::size_of::<CorayKdParams>() || self.sah_termination > 1 {
            return Err(crate::CorayStatus::InvalidParameter);
        }
        let p = coray::kd::KdParams {
            max_depth: self.max_depth,
            leaf_size: self.leaf_size,
            sah_termination: self.sah_termination == 1,
            cost_traversal: self.cost_traversal,
            cost_intersection: self.cost_intersection,
            empty_bonus: self.empty_bonus,
            refs_per_prim: self.refs_per_prim,
        };
        p.check()?;
        Ok(p)
    }
}
