//! `coray_bvh_*`: bounding volume hierarchies built four ways (TDBS, TDBS
//! with the SAH, bottom-up matching, R-tree and R*-tree), one arena format:
//! requirements, build, info, validate, insert, delete, intersect, occluded.

use crate::carve::{self, check_arena, slice_mut, slice_ref};
use crate::types::{CorayHit, CorayRay, CorayScene, CorayTraceStats};
use crate::{guard, CorayStatus};
use coray::arena::{
    BvhArenaHeader, BvhArenaLayout, BvhScratchLayout, BVH_FLAG_REINSERT, BVH_FLAG_RSTAR,
    BVH_HEADER_BYTES, BVH_MAGIC, BVH_VERSION,
};
use coray::bvh::{
    self, Builder, Bvh, BvhNode, BvhStackItem, BvhStats, InsertOrder, RTree, RTreeParams, Split,
};
use coray::{Aabb, Scene};
use core::ffi::c_void;
use core::mem::size_of;

/// Top-down binary splitting, children of most nearly equal surface area (the thesis' TDBS).
pub const CORAY_BVH_TDBS: u32 = 0;
/// Top-down binary splitting by the surface area heuristic.
pub const CORAY_BVH_TDBS_SAH: u32 = 1;
/// Bottom-up matching: join the pair with the smallest joint box, repeatedly.
pub const CORAY_BVH_NN: u32 = 2;
/// Guttman's R-tree (quadratic split); dynamic.
pub const CORAY_BVH_RTREE: u32 = 3;
/// The R*-tree (no forced reinsertion); dynamic.
pub const CORAY_BVH_RSTAR: u32 = 4;
/// Bottom-up matching by a nearest-neighbour chain: the joins of
/// `CORAY_BVH_NN` (exact ties aside) in sub-quadratic time.
pub const CORAY_BVH_NN_CHAIN: u32 = 5;

/// R-trees insert in scene order.
pub const CORAY_BVH_ORDER_SCENE: u32 = 0;
/// R-trees insert in a shuffled order (`seed`).
pub const CORAY_BVH_ORDER_SHUFFLED: u32 = 1;
/// R-trees insert in Morton order of the box centres.
pub const CORAY_BVH_ORDER_SORTED: u32 = 2;

/// Parameters of a hierarchy build. Get them from [`coray_bvh_params_default`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CorayBvhParams {
    /// `sizeof(CorayBvhParams)`.
    pub struct_size: usize,
    /// R-trees: the shuffle's seed with `CORAY_BVH_ORDER_SHUFFLED`.
    pub seed: u64,
    /// `CORAY_BVH_TDBS`, `_TDBS_SAH`, `_NN`, `_NN_CHAIN`, `_RTREE` or `_RSTAR`.
    pub builder: u32,
    /// TDBS builders: most primitives per leaf (at least 1; the thesis: 1).
    /// Bottom-up matching always makes leaves of 1.
    pub leaf_size: u32,
    /// R-trees: M, most entries per node, 4 to 32 (default 8).
    pub max_children: u32,
    /// R-trees: m, fewest entries per node but the root, 2 to M / 2 (default 3).
    pub min_children: u32,
    /// R-trees: `CORAY_BVH_ORDER_*`, the order a build inserts the primitives.
    pub insert_order: u32,
    /// R-trees: 1 to build an empty tree (objects then enter by
    /// [`coray_bvh_insert`]); 0 to insert every primitive.
    pub start_empty: u32,
    /// R-trees: 1 for the R*-tree's forced reinsertion (the first overflow
    /// at a level during an insert reinserts 30% of the node's entries
    /// instead of splitting); 0, the default and the thesis' setting, splits.
    pub forced_reinsert: u32,
}

/// Arena sizes for a hierarchy, from [`coray_bvh_requirements`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayBvhRequirements {
    /// The hierarchy arena. Static builders need exactly this; an R-tree's
    /// arena of this size holds up to `prim_count` objects, and a larger one
    /// proportionally more.
    pub bvh_bytes: usize,
    /// Scratch for a build, and for an R-tree's deletes.
    pub scratch_bytes: usize,
}

/// What a hierarchy holds (read from its arena header, O(1)).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayBvhInfo {
    /// The builder, `CORAY_BVH_*`.
    pub builder: u32,
    /// Nodes in use, interior and leaf.
    pub node_count: u32,
    /// Leaves in use.
    pub leaf_count: u32,
    /// Primitives in the hierarchy.
    pub object_count: u32,
    /// Levels below the root.
    pub depth: u32,
    /// Most children a node may have (2, or the R-tree's M).
    pub max_children: u32,
    /// Most objects the hierarchy may hold: for an R-tree, what its arena
    /// holds whatever the order of inserts and deletes (inserts beyond it
    /// get `CORAY_STATUS_ARENA_TOO_SMALL`); static builders: `object_count`.
    pub capacity: u32,
    /// Bytes of the arena the layout covers.
    pub arena_bytes_used: usize,
    /// Bytes of traversal stack that [`coray_bvh_intersect`] and
    /// [`coray_bvh_occluded`] need (4-byte aligned). Inserts can deepen an
    /// R-tree: read it again after them.
    pub stack_bytes: usize,
    /// Lower corner of the root box (empty hierarchy: +inf).
    pub bounds_min: [f32; 3],
    /// Upper corner of the root box (empty hierarchy: -inf).
    pub bounds_max: [f32; 3],
}

/// Figures of a validated hierarchy, from [`coray_bvh_validate`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayBvhTreeStats {
    /// Nodes reached from the root.
    pub node_count: u32,
    /// Leaves reached.
    pub leaf_count: u32,
    /// References in them.
    pub ref_count: u32,
    /// Deepest leaf.
    pub depth: u32,
}

/// Work done by one hierarchy trace call, in the thesis' terms.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayBvhStats {
    /// Rays, nodes visited, primitive tests.
    pub trace: CorayTraceStats,
    /// Hierarchy objects (boxes) tested.
    pub box_tests: u64,
    /// Their cost in the thesis' units (a box test costs 2 to 51).
    pub box_cost: u64,
    /// Cost of the actual objects (primitives) tested, in the same units.
    pub prim_cost: u64,
}

/// Default parameters for `builder` (`CORAY_BVH_*`) with `struct_size`
/// set. An unknown builder gives `struct_size` 0, which every call rejects.
#[no_mangle]
pub extern "C" fn coray_bvh_params_default(builder: u32) -> CorayBvhParams {
    let r = RTreeParams::rtree();
    CorayBvhParams {
        struct_size: if builder <= CORAY_BVH_NN_CHAIN {
            size_of::<CorayBvhParams>()
        } else {
            0
        },
        seed: 0,
        builder,
        leaf_size: 1,
        max_children: r.max_children,
        min_children: r.min_children,
        insert_order: CORAY_BVH_ORDER_SCENE,
        start_empty: 0,
        forced_reinsert: 0,
    }
}

/// A checked copy of the caller's parameters.
pub(crate) enum Kind {
    Static(Builder, u32),
    RTree(RTreeParams),
}

impl CorayBvhParams {
    pub(crate) fn to_core(self) -> Result<Kind, CorayStatus> {
        if self.struct_size != size_of::<CorayBvhParams>()
            || self.start_empty > 1
            || self.forced_reinsert > 1
        {
            return Err(CorayStatus::InvalidParameter);
        }
        let order = match self.insert_order {
            CORAY_BVH_ORDER_SCENE => InsertOrder::Scene,
            CORAY_BVH_ORDER_SHUFFLED => InsertOrder::Shuffled(self.seed),
            CORAY_BVH_ORDER_SORTED => InsertOrder::Sorted,
            _ => return Err(CorayStatus::InvalidParameter),
        };
        let rtree = |split| {
            let p = RTreeParams {
                split,
                max_children: self.max_children,
                min_children: self.min_children,
                order,
                forced_reinsert: self.forced_reinsert == 1,
            };
            // Same rule as the core's: a zero-capacity requirement checks it.
            let bad = !(4..=bvh::MAX_CHILDREN).contains(&p.max_children)
                || p.min_children < 2
                || p.min_children > p.max_children / 2;
            if bad {
                Err(CorayStatus::InvalidParameter)
            } else {
                Ok(Kind::RTree(p))
            }
        };
        let leaf = |b| {
            if self.leaf_size == 0 {
                Err(CorayStatus::InvalidParameter)
            } else {
                Ok(Kind::Static(b, self.leaf_size))
            }
        };
        match self.builder {
            CORAY_BVH_TDBS => leaf(Builder::Tdbs),
            CORAY_BVH_TDBS_SAH => leaf(Builder::TdbsSah),
            CORAY_BVH_NN => Ok(Kind::Static(Builder::Nn, 1)),
            CORAY_BVH_NN_CHAIN => Ok(Kind::Static(Builder::NnChain, 1)),
            CORAY_BVH_RTREE => rtree(Split::Quadratic),
            CORAY_BVH_RSTAR => rtree(Split::RStar),
            _ => Err(CorayStatus::InvalidParameter),
        }
    }
}

/// Most primitives a hierarchy indexes, as for the kd-tree.
pub(crate) const MAX_PRIMS: usize = 1 << 30;

/// The arena layout of an R-tree for `capacity` objects.
fn rtree_layout(capacity: usize, p: &RTreeParams) -> BvhArenaLayout {
    let r = bvh::rtree_requirements(capacity, p);
    BvhArenaLayout::of(r.nodes, r.refs)
}

/// The largest R-tree capacity whose layout fits in `bytes`, if any reaches `min`.
fn rtree_fit(bytes: usize, min: usize, p: &RTreeParams) -> Option<usize> {
    if rtree_layout(min, p).total_bytes > bytes {
        return None;
    }
    let (mut lo, mut hi) = (min, MAX_PRIMS);
    while lo < hi {
        let mid = lo + (hi - lo).div_ceil(2);
        if rtree_layout(mid, p).total_bytes <= bytes {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    Some(lo)
}

/// Hierarchy and scratch layouts for `n` primitives (an R-tree's capacity).
fn layouts(n: usize, k: &Kind) -> Result<(BvhArenaLayout, BvhScratchLayout), CorayStatus> {
    if n >= MAX_PRIMS {
        return Err(CorayStatus::TooManyPrimitives);
    }
    let (arena, scratch) = match k {
        Kind::Static(b, _) => {
            let r = bvh::requirements(n, *b);
            (
                BvhArenaLayout::of(r.nodes, r.refs),
                BvhScratchLayout::of(&r),
            )
        }
        Kind::RTree(p) => {
            // The arena for `n` may hold a few more (the formula moves in
            // steps): scratch for deletes covers all the arena will take.
            let arena = rtree_layout(n, p);
            let links = bvh::BvhRequirements {
                links: rtree_fit(arena.total_bytes, n, p).unwrap_or(n),
                ..Default::default()
            };
            (arena, BvhScratchLayout::of(&links))
        }
    };
    if arena.total_bytes > u32::MAX as usize {
        return Err(CorayStatus::TooManyPrimitives);
    }
    Ok((arena, scratch))
}

/// Arena sizes for a hierarchy over `prim_count` primitives with `params`
/// (for an R-tree, `prim_count` is the most objects it will hold).
///
/// # Safety
/// `params` and `out` are NULL or valid pointers to their types.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_requirements(
    prim_count: usize,
    params: *const CorayBvhParams,
    out: *mut CorayBvhRequirements,
) -> CorayStatus {
    guard(|| {
        // SAFETY: the caller passes a valid params pointer or NULL.
        let k = unsafe { carve::input_ref(params)? }.to_core()?;
        let (a, s) = layouts(prim_count, &k)?;
        // SAFETY: the caller passes a valid, writable out pointer or NULL.
        *unsafe { carve::output(out, 1)? }
            .first_mut()
            .ok_or(CorayStatus::NullPointer)? = CorayBvhRequirements {
            bvh_bytes: a.total_bytes,
            scratch_bytes: s.total_bytes.max(1),
        };
        Ok(())
    })
}

/// Writes `bytes` to `*needed` when it is a usable pointer; the status.
pub(crate) fn too_small(needed: *mut usize, bytes: usize) -> Result<(), CorayStatus> {
    if !needed.is_null() && (needed as usize).is_multiple_of(core::mem::align_of::<usize>()) {
        // SAFETY: non-null and aligned; the caller promises it writable.
        unsafe { *needed = bytes };
    }
    Err(CorayStatus::ArenaTooSmall)
}

/// Builds a hierarchy over `scene` into `bvh_arena`, with `scratch_arena`
/// as scratch (free again when this returns).
///
/// Both arenas are 16-byte aligned and do not overlap. Static builders need
/// `bvh_bytes` from [`coray_bvh_requirements`]; an R-tree takes any arena
/// from the size for the scene's primitive count up, and uses the rest as
/// room for later inserts. On `CORAY_STATUS_ARENA_TOO_SMALL`,
/// `*needed_bytes` (if not NULL) receives the size the arena that was too
/// small needs. Degenerate primitives stay out of the hierarchy (never hit).
///
/// # Safety
/// Every pointer is NULL or valid for its documented size; the arenas are
/// not read or written by anyone else during the call.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_build(
    scene: *const CorayScene,
    params: *const CorayBvhParams,
    bvh_arena: *mut c_void,
    bvh_bytes: usize,
    scratch_arena: *mut c_void,
    scratch_bytes: usize,
    needed_bytes: *mut usize,
) -> CorayStatus {
    guard(|| {
        // SAFETY: the caller passes valid scene and params pointers or NULL.
        let (scene, p) = unsafe { (carve::scene(scene)?, carve::input_ref(params)?) };
        let kind = p.to_core()?;
        let (base, sbase) = (bvh_arena.cast::<u8>(), scratch_arena.cast::<u8>());
        check_arena(base)?;
        check_arena(sbase)?;
        let n = scene.prim_count();
        // An R-tree that starts empty needs room for no object yet.
        let n_min = if p.start_empty == 1 { 0 } else { n };
        let (min_arena, scratch) = layouts(n_min, &kind)?;
        let (arena, capacity) = match &kind {
            Kind::Static(..) if bvh_bytes < min_arena.total_bytes => {
                return too_small(needed_bytes, min_arena.total_bytes)
            }
            Kind::Static(..) => (min_arena, n),
            Kind::RTree(rp) => {
                let bytes = bvh_bytes.min(u32::MAX as usize);
                let Some(cap) = rtree_fit(bytes, n_min, rp) else {
                    return too_small(needed_bytes, min_arena.total_bytes);
                };
                (rtree_layout(cap, rp), cap)
            }
        };
        if scratch_bytes < scratch.total_bytes {
            return too_small(needed_bytes, scratch.total_bytes);
        }
        let (a0, s0) = (base as usize, sbase as usize);
        if a0 < s0 + scratch.total_bytes && s0 < a0 + arena.total_bytes {
            return Err(CorayStatus::InvalidParameter);
        }
        scene.check()?;
        let c = &scratch.counts;
        // SAFETY: both arenas passed check_arena; each layout lies within its
        // arena (checked above), its parts do not overlap (layout formulas)
        // and the arenas do not overlap each other (checked above); the
        // caller gives us both exclusively for the call.
        let (header, nodes, refs, boxes, keys, links, clusters) = unsafe {
            (
                slice_mut::<BvhArenaHeader>(base, 0, 1),
                slice_mut::<BvhNode>(base, arena.nodes_offset, arena.nodes),
                slice_mut::<u32>(base, arena.refs_offset, arena.refs),
                slice_mut::<Aabb>(sbase, 0, c.boxes),
                slice_mut::<f32>(sbase, scratch.keys_offset, c.keys),
                slice_mut::<u32>(sbase, scratch.links_offset, c.links),
                slice_mut::<BvhNode>(sbase, scratch.clusters_offset, c.clusters),
            )
        };
        let mut h = BvhArenaHeader {
            magic: BVH_MAGIC,
            version: BVH_VERSION,
            builder: p.builder,
            scene_counts: scene_counts(&scene),
            layout_bytes: arena.total_bytes as u32,
            nodes_cap: arena.nodes as u32,
            refs_cap: arena.refs as u32,
            capacity: capacity as u32,
            ..Default::default()
        };
        match kind {
            Kind::Static(b, leaf_size) => {
                let storage = bvh::BvhStorage { nodes, refs };
                let scratch = bvh::BvhScratch {
                    boxes,
                    keys,
                    links,
                    clusters,
                };
                let t = bvh::build(&scene, b, leaf_size, storage, scratch)?;
                h.info = t.info;
            }
            Kind::RTree(rp) => {
                let t = if p.start_empty == 1 {
                    RTree::new(&scene, rp, nodes, refs)?
                } else {
                    RTree::build(&scene, rp, nodes, refs, links)?
                };
                put_rtree(&mut h, &t);
            }
        }
        header[0] = h;
        Ok(())
    })
}

pub(crate) fn scene_counts(s: &Scene) -> [u32; 3] {
    [
        s.triangles.len() as u32,
        s.spheres.len() as u32,
        s.cones.len() as u32,
    ]
}

/// Records an R-tree's parameters, state and shape in its header.
fn put_rtree(h: &mut BvhArenaHeader, t: &RTree) {
    let p = t.params();
    h.max_children = p.max_children;
    h.min_children = p.min_children;
    h.rtree_flags = if p.split == Split::RStar {
        BVH_FLAG_RSTAR
    } else {
        0
    } | if p.forced_reinsert {
        BVH_FLAG_REINSERT
    } else {
        0
    };
    h.rtree = t.state();
    h.info = t.bvh().info;
}

/// The header of the arena, checked in O(1) (magic, version, layout).
///
/// # Safety
/// `base` is NULL or valid for reads of `bytes` bytes.
unsafe fn header(
    base: *const u8,
    bytes: usize,
) -> Result<(BvhArenaHeader, BvhArenaLayout), CorayStatus> {
    check_arena(base)?;
    if bytes < BVH_HEADER_BYTES {
        return Err(CorayStatus::CorruptArena);
    }
    // SAFETY: aligned, readable for bytes >= BVH_HEADER_BYTES >= one header.
    let h = unsafe { slice_ref::<BvhArenaHeader>(base, 0, 1)[0] };
    let l = h.layout(bytes)?;
    Ok((h, l))
}

/// Errors unless `scene` has the counts the hierarchy was built on.
fn check_scene(h: &BvhArenaHeader, scene: &Scene) -> Result<(), CorayStatus> {
    if scene_counts(scene) != h.scene_counts || scene.prim_count() > u32::MAX as usize {
        return Err(CorayStatus::SceneMismatch);
    }
    Ok(())
}

/// The hierarchy in an arena, for reading.
///
/// # Safety
/// `arena` is NULL or valid for reads of `bytes` bytes that nobody writes
/// during `'a`.
unsafe fn view<'a>(
    arena: *const c_void,
    bytes: usize,
    scene: Scene<'a>,
) -> Result<(BvhArenaHeader, Bvh<'a>), CorayStatus> {
    let base = arena.cast::<u8>();
    // SAFETY: forwarded contract.
    let (h, l) = unsafe { header(base, bytes)? };
    check_scene(&h, &scene)?;
    // SAFETY: the layout lies within `bytes` (checked by layout()), its
    // offsets are multiples of 16, and the arena is only read.
    let (nodes, refs) = unsafe {
        (
            slice_ref::<BvhNode>(base, l.nodes_offset, l.nodes),
            slice_ref::<u32>(base, l.refs_offset, l.refs),
        )
    };
    Ok((
        h,
        Bvh {
            scene,
            nodes,
            refs,
            info: h.info,
        },
    ))
}

/// The R-tree parameters a header records, or `InvalidParameter` for a
/// static hierarchy (which cannot change).
fn rtree_params(h: &BvhArenaHeader) -> Result<RTreeParams, CorayStatus> {
    if h.builder != CORAY_BVH_RTREE && h.builder != CORAY_BVH_RSTAR {
        return Err(CorayStatus::InvalidParameter);
    }
    Ok(RTreeParams {
        split: if h.rtree_flags & BVH_FLAG_RSTAR != 0 {
            Split::RStar
        } else {
            Split::Quadratic
        },
        max_children: h.max_children,
        min_children: h.min_children,
        order: InsertOrder::Scene,
        forced_reinsert: h.rtree_flags & BVH_FLAG_REINSERT != 0,
    })
}

/// The R-tree in an arena, for changing, with its header to write back.
///
/// # Safety
/// `arena` is NULL or valid for reads and writes of `bytes` bytes that
/// nobody else touches during `'a`.
unsafe fn rtree_mut<'a>(
    arena: *mut c_void,
    bytes: usize,
    scene: Scene<'a>,
) -> Result<(&'a mut BvhArenaHeader, RTree<'a>), CorayStatus> {
    let base = arena.cast::<u8>();
    // SAFETY: forwarded contract.
    let (h, l) = unsafe { header(base, bytes)? };
    check_scene(&h, &scene)?;
    let p = rtree_params(&h)?;
    // SAFETY: header, nodes and refs are disjoint parts of the checked
    // layout (header below BVH_HEADER_BYTES, then 16-aligned parts), all
    // within `bytes`; the caller gives us the arena exclusively.
    let (hd, nodes, refs) = unsafe {
        (
            &mut slice_mut::<BvhArenaHeader>(base, 0, 1)[0],
            slice_mut::<BvhNode>(base, l.nodes_offset, l.nodes),
            slice_mut::<u32>(base, l.refs_offset, l.refs),
        )
    };
    let t = RTree::resume(&scene, p, nodes, refs, h.rtree)?;
    Ok((hd, t))
}

/// What the hierarchy in `bvh_arena` holds, from its header (O(1)).
///
/// # Safety
/// `bvh_arena` is valid for reads of `bvh_bytes`; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_info(
    bvh_arena: *const c_void,
    bvh_bytes: usize,
    out: *mut CorayBvhInfo,
) -> CorayStatus {
    guard(|| {
        let base = bvh_arena.cast::<u8>();
        // SAFETY: forwarded contract.
        let (h, l) = unsafe { header(base, bvh_bytes)? };
        let i = &h.info;
        // SAFETY: root < nodes_cap (checked by layout()); read only.
        let root = unsafe { slice_ref::<BvhNode>(base, l.nodes_offset, l.nodes)[i.root as usize] };
        let stack = Bvh {
            scene: Scene::default(),
            nodes: &[],
            refs: &[],
            info: *i,
        }
        .stack_len();
        let info = CorayBvhInfo {
            builder: h.builder,
            node_count: i.node_count,
            leaf_count: i.leaf_count,
            object_count: i.ref_count,
            depth: i.depth,
            max_children: i.max_children,
            capacity: h.capacity,
            arena_bytes_used: l.total_bytes,
            stack_bytes: stack * size_of::<BvhStackItem>(),
            bounds_min: root.min,
            bounds_max: root.max,
        };
        // SAFETY: out is NULL or writable (caller's contract).
        *unsafe { carve::output(out, 1)? }
            .first_mut()
            .ok_or(CorayStatus::NullPointer)? = info;
        Ok(())
    })
}

/// Checks every structural invariant of the hierarchy against `scene`
/// (O(size)): boxes are exact unions, indices in range, counts and depth as
/// recorded; for R-trees also the fill rules and free lists. Run it on an
/// arena loaded from untrusted storage before tracing or changing it.
/// `CORAY_STATUS_CORRUPT_ARENA` when anything is wrong; `out` may be NULL.
///
/// # Safety
/// As [`coray_bvh_info`]; `scene` is valid.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_validate(
    bvh_arena: *const c_void,
    bvh_bytes: usize,
    scene: *const CorayScene,
    out: *mut CorayBvhTreeStats,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract.
        let (h, t) = unsafe { view(bvh_arena, bvh_bytes, carve::scene(scene)?)? };
        let s = match rtree_params(&h) {
            Ok(p) => {
                let l = rtree_layout(h.capacity as usize, &p);
                if (l.nodes, l.refs) != (h.nodes_cap as usize, h.refs_cap as usize) {
                    return Err(CorayStatus::CorruptArena);
                }
                bvh::validate_rtree(&t, &p, &h.rtree)?
            }
            Err(_) if h.capacity != t.info.ref_count => return Err(CorayStatus::CorruptArena),
            Err(_) if t.info.max_children != 2 => return Err(CorayStatus::CorruptArena),
            Err(_) => t.validate(None)?,
        };
        if !out.is_null() {
            // SAFETY: non-null; writable by the caller's contract.
            *unsafe { carve::output(out, 1)? }
                .first_mut()
                .ok_or(CorayStatus::NullPointer)? = CorayBvhTreeStats {
                node_count: s.nodes,
                leaf_count: s.leaves,
                ref_count: s.refs,
                depth: s.depth,
            };
        }
        Ok(())
    })
}

/// Inserts primitive `prim_index` (0-based over triangles, then spheres,
/// then cones) into the R-tree in `bvh_arena`. A degenerate primitive is
/// accepted and not stored. `CORAY_STATUS_ARENA_TOO_SMALL` when the arena
/// holds `CorayBvhInfo.capacity` objects: the tree is then unchanged
/// (build again in a larger arena). `CORAY_STATUS_INVALID_PARAMETER` for a
/// static hierarchy or an index past the scene. Inserting an object that the
/// tree holds already stores it twice.
///
/// # Safety
/// `bvh_arena` is valid for reads and writes of `bvh_bytes` bytes that
/// nobody else touches during the call; `scene` is valid.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_insert(
    bvh_arena: *mut c_void,
    bvh_bytes: usize,
    scene: *const CorayScene,
    prim_index: u32,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract.
        let (hd, mut t) = unsafe { rtree_mut(bvh_arena, bvh_bytes, carve::scene(scene)?)? };
        if t.len() >= hd.capacity && (prim_index as usize) < t.bvh().scene.prim_count() {
            return Err(CorayStatus::ArenaTooSmall);
        }
        t.insert(prim_index)?;
        put_rtree(hd, &t);
        Ok(())
    })
}

/// Removes primitive `prim_index` from the R-tree in `bvh_arena`;
/// `*deleted` (if not NULL) receives 1 when it was there, else 0. Nodes left
/// underfull are dissolved and their objects inserted again, which needs
/// `scratch_bytes` from [`coray_bvh_requirements`] in `scratch_arena`
/// (16-byte aligned, not overlapping the tree).
///
/// # Safety
/// As [`coray_bvh_insert`]; `scratch_arena` is valid for writes of
/// `scratch_bytes`; `deleted` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_delete(
    bvh_arena: *mut c_void,
    bvh_bytes: usize,
    scene: *const CorayScene,
    prim_index: u32,
    scratch_arena: *mut c_void,
    scratch_bytes: usize,
    deleted: *mut u8,
) -> CorayStatus {
    guard(|| {
        let sbase = scratch_arena.cast::<u8>();
        check_arena(sbase)?;
        // SAFETY: forwarded caller contract.
        let (hd, mut t) = unsafe { rtree_mut(bvh_arena, bvh_bytes, carve::scene(scene)?)? };
        let need = t.len() as usize;
        if scratch_bytes < need * 4 {
            return Err(CorayStatus::ArenaTooSmall);
        }
        let (a0, s0) = (bvh_arena as usize, sbase as usize);
        if a0 < s0 + need * 4 && s0 < a0 + bvh_bytes {
            return Err(CorayStatus::InvalidParameter);
        }
        // SAFETY: aligned (checked), `need * 4 <= scratch_bytes` bytes the
        // caller lends exclusively, disjoint from the tree arena (checked).
        let orphans = unsafe { slice_mut::<u32>(sbase, 0, need) };
        let was = t.delete(prim_index, orphans)?;
        put_rtree(hd, &t);
        if !deleted.is_null() {
            // SAFETY: non-null; writable by the caller's contract.
            unsafe { *deleted = was as u8 };
        }
        Ok(())
    })
}

/// The caller's traversal stack, at least the hierarchy's `stack_bytes`.
///
/// # Safety
/// `stack` is NULL or valid for writes of `bytes` bytes during `'a`.
pub(crate) unsafe fn stack<'a>(
    t: &Bvh,
    stack: *mut c_void,
    bytes: usize,
) -> Result<&'a mut [BvhStackItem], CorayStatus> {
    let need = t.stack_len();
    if bytes < need * size_of::<BvhStackItem>() {
        return Err(CorayStatus::ArenaTooSmall);
    }
    // SAFETY: forwarded contract; output() checks null and alignment.
    unsafe { carve::output(stack.cast::<BvhStackItem>(), need) }
}

fn put_stats(out: *mut CorayBvhStats, s: &BvhStats) -> Result<(), CorayStatus> {
    if !out.is_null() {
        // SAFETY: non-null; the caller promises a writable CorayBvhStats.
        if let Some(o) = unsafe { carve::output(out, 1)? }.first_mut() {
            *o = CorayBvhStats {
                trace: s.trace.into(),
                box_tests: s.box_tests,
                box_cost: s.box_cost,
                prim_cost: s.prim_cost,
            };
        }
    }
    Ok(())
}

/// Closest hits of `count` rays: `hits[i]` for `rays[i]`. `stack` is the
/// caller's traversal stack of `stack_bytes` (at least
/// `CorayBvhInfo.stack_bytes`, 4-byte aligned; one per thread). `stats` may
/// be NULL. Many threads may trace one hierarchy at once, each with its
/// own stack, while nobody changes it.
///
/// # Safety
/// `rays` and `hits` hold `count` elements (may be NULL when `count` is 0);
/// the arena and scene as in [`coray_bvh_validate`]; `stack` is writable
/// for `stack_bytes`.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_intersect(
    bvh_arena: *const c_void,
    bvh_bytes: usize,
    scene: *const CorayScene,
    rays: *const CorayRay,
    hits: *mut CorayHit,
    count: usize,
    stack_mem: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayBvhStats,
) -> CorayStatus {
    // SAFETY: forwarded caller contract.
    unsafe {
        batch(
            bvh_arena,
            bvh_bytes,
            scene,
            rays,
            hits,
            count,
            stack_mem,
            stack_bytes,
            stats,
            |t, r, stk, st| t.intersect(r, stk, st).into(),
        )
    }
}

/// Any-hit queries (shadow rays): `occluded[i]` is 1 when something lies on
/// `rays[i]` within `[tnear, tfar]`, else 0. Otherwise as [`coray_bvh_intersect`].
///
/// # Safety
/// As [`coray_bvh_intersect`], with `occluded` holding `count` bytes.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_occluded(
    bvh_arena: *const c_void,
    bvh_bytes: usize,
    scene: *const CorayScene,
    rays: *const CorayRay,
    occluded: *mut u8,
    count: usize,
    stack_mem: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayBvhStats,
) -> CorayStatus {
    // SAFETY: forwarded caller contract.
    unsafe {
        batch(
            bvh_arena,
            bvh_bytes,
            scene,
            rays,
            occluded,
            count,
            stack_mem,
            stack_bytes,
            stats,
            |t, r, stk, st| t.occluded(r, stk, st) as u8,
        )
    }
}

/// The body of [`coray_bvh_intersect`] and [`coray_bvh_occluded`]: views
/// the arena, carves rays, answers, stack and statistics, and writes
/// `answer` for each ray.
///
/// # Safety
/// As [`coray_bvh_intersect`], with `out` holding `count` elements.
#[allow(clippy::too_many_arguments)]
unsafe fn batch<O>(
    bvh_arena: *const c_void,
    bvh_bytes: usize,
    scene: *const CorayScene,
    rays: *const CorayRay,
    out: *mut O,
    count: usize,
    stack_mem: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayBvhStats,
    answer: impl Fn(&Bvh, &coray::Ray, &mut [BvhStackItem], &mut BvhStats) -> O,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract for every pointer.
        let (t, rays, out) = unsafe {
            (
                view(bvh_arena, bvh_bytes, carve::scene(scene)?)?.1,
                carve::input(rays, count)?,
                carve::output(out, count)?,
            )
        };
        // SAFETY: forwarded caller contract.
        let stk = unsafe { stack(&t, stack_mem, stack_bytes)? };
        let mut st = BvhStats::default();
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = answer(&t, &r.into(), stk, &mut st);
        }
        put_stats(stats, &st)
    })
}
