//! `coray_bvh_*`: bounding volume hierarchies built six ways (TDBS, TDBS
//! by the SAH, bottom-up matching quadratic or by a chain, R-tree,
//! R*-tree), one arena format: parameters, requirements, build, open,
//! info, validate, intersect, occluded, and the R-trees' insert and delete.

use crate::abi::*;
use crate::carve::{self, check_arena, Out, OutValue, Regions, Versioned};
use crate::handle::{self, Handle, Sealed, KIND_BVH};
use crate::one_ray::one_ray;
use crate::tracer::{self, CorayTracer};
use crate::{guard, CorayBvh, CorayStatus};
use coray::bvh::layout::{
    code, BvhArenaHeader, BvhArenaLayout, BvhScratchLayout, BVH_HEADER_BYTES, BVH_MAGIC,
    BVH_VERSION,
};
use coray::bvh::{
    self, Builder, Bvh, BvhNode, BvhStackItem, InsertOrder, RTree, RTreeParams, Split,
};
use coray::limits::MAX_PRIMS;
use coray::{Aabb, Scene, TraceStats};
use core::ffi::c_void;
use core::mem::size_of;

/// How a hierarchy is built: one of the `CORAY_BVH_BUILDER_*`.
pub type CorayBvhBuilder = u32;
/// Top-down binary splitting, children of most nearly equal surface area (the thesis' TDBS).
pub const CORAY_BVH_BUILDER_TDBS: CorayBvhBuilder = 0;
/// Top-down binary splitting by the surface area heuristic.
pub const CORAY_BVH_BUILDER_TDBS_SAH: CorayBvhBuilder = 1;
/// Bottom-up matching: join the pair with the smallest joint box, repeatedly.
pub const CORAY_BVH_BUILDER_NN: CorayBvhBuilder = 2;
/// Guttman's R-tree (quadratic split); dynamic.
pub const CORAY_BVH_BUILDER_RTREE: CorayBvhBuilder = 3;
/// The R*-tree; dynamic.
pub const CORAY_BVH_BUILDER_RSTAR: CorayBvhBuilder = 4;
/// Bottom-up matching by a nearest-neighbour chain: the joins of
/// `CORAY_BVH_BUILDER_NN` (exact ties aside) in sub-quadratic time.
pub const CORAY_BVH_BUILDER_NN_CHAIN: CorayBvhBuilder = 5;

/// The order an R-tree build inserts the primitives in: `CORAY_BVH_ORDER_*`.
pub type CorayBvhOrder = u32;
// The numbers are the arena header's (cbindgen needs literals).
const _: () = assert!(
    CORAY_BVH_BUILDER_TDBS == code::TDBS
        && CORAY_BVH_BUILDER_TDBS_SAH == code::TDBS_SAH
        && CORAY_BVH_BUILDER_NN == code::NN
        && CORAY_BVH_BUILDER_RTREE == code::RTREE
        && CORAY_BVH_BUILDER_RSTAR == code::RSTAR
        && CORAY_BVH_BUILDER_NN_CHAIN == code::NN_CHAIN
);

/// Scene order.
pub const CORAY_BVH_ORDER_SCENE: CorayBvhOrder = 0;
/// A shuffled order (`seed`).
pub const CORAY_BVH_ORDER_SHUFFLED: CorayBvhOrder = 1;
/// Morton order of the box centres.
pub const CORAY_BVH_ORDER_SORTED: CorayBvhOrder = 2;

/// Parameters of a hierarchy build. Get them from `coray_bvh_params_default`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayBvhParams {
    /// `sizeof(CorayBvhParams)`.
    pub struct_size: usize,
    /// R-trees: the shuffle's seed with `CORAY_BVH_ORDER_SHUFFLED`.
    pub seed: u64,
    /// `CORAY_BVH_BUILDER_*`.
    pub builder: CorayBvhBuilder,
    /// TDBS builders: most primitives per leaf (at least 1; the thesis: 1).
    /// Bottom-up matching always makes leaves of 1.
    pub leaf_size: u32,
    /// R-trees: M, most entries per node, 4 to 32 (default 8).
    pub max_children: u32,
    /// R-trees: m, fewest entries per node but the root, 2 to M / 2 (default 3).
    pub min_children: u32,
    /// R-trees: `CORAY_BVH_ORDER_*`, the order a build inserts the primitives.
    pub insert_order: CorayBvhOrder,
    /// R-trees: 1 to build an empty tree (objects then enter by
    /// `coray_bvh_insert`); 0 to insert every primitive.
    pub start_empty: u32,
    /// R-trees: 1 for the R*-tree's forced reinsertion (the first overflow
    /// at a level during an insert reinserts 30% of the node's entries
    /// instead of splitting); 0, the default and the thesis' setting, splits.
    pub forced_reinsert: u32,
}

/// What a hierarchy holds, from `coray_bvh_info` (O(1)).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayBvhInfo {
    /// `sizeof(CorayBvhInfo)`.
    pub struct_size: usize,
    /// The builder, `CORAY_BVH_BUILDER_*`.
    pub builder: CorayBvhBuilder,
    /// Nodes in use, interior and leaf.
    pub node_count: u32,
    /// Leaves in use.
    pub leaf_count: u32,
    /// Primitives in the hierarchy.
    pub ref_count: u32,
    /// Levels below the root.
    pub depth: u32,
    /// Most children a node may have (2, or the R-tree's M).
    pub max_children: u32,
    /// Most objects the hierarchy may hold: for an R-tree, what its arena
    /// holds whatever the order of inserts and deletes (inserts beyond it
    /// get `CORAY_STATUS_ARENA_TOO_SMALL`); static builders: `ref_count`.
    pub capacity: u32,
    /// Bytes of the arena the layout covers.
    pub arena_bytes_used: usize,
    /// Bytes of traversal stack every trace and validate call needs.
    /// Inserts can deepen an R-tree: read it again after them.
    pub stack_bytes: usize,
    /// Lower corner of the root box (empty hierarchy: +inf).
    pub bounds_min: [f32; 3],
    /// Upper corner of the root box (empty hierarchy: -inf).
    pub bounds_max: [f32; 3],
}

// SAFETY (both): repr(C), size_t struct_size first, integer and float
// fields only; as first published.
unsafe impl Versioned for CorayBvhParams {
    const SIZE_1_0: usize = size_of::<Self>();
}
unsafe impl Versioned for CorayBvhInfo {
    const SIZE_1_0: usize = size_of::<Self>();
}

/// Default parameters for `builder` with `struct_size` set; an unknown
/// builder gives `struct_size` 0, which every call refuses.
#[no_mangle]
pub extern "C" fn coray_bvh_params_default(builder: CorayBvhBuilder) -> CorayBvhParams {
    let r = RTreeParams::rtree();
    let known = code::to_static(builder).is_some() || code::is_rtree(builder);
    CorayBvhParams {
        struct_size: if known {
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

/// A `CorayBvhInfo` to fill, `struct_size` set.
#[no_mangle]
pub extern "C" fn coray_bvh_info_default() -> CorayBvhInfo {
    CorayBvhInfo {
        struct_size: size_of::<CorayBvhInfo>(),
        ..Default::default()
    }
}

/// A checked copy of the caller's parameters.
#[derive(Clone, Copy)]
pub(crate) enum Kind {
    Static(Builder, u32),
    RTree(RTreeParams),
}

impl CorayBvhParams {
    pub(crate) fn to_core(self) -> Result<Kind, CorayStatus> {
        if self.start_empty > 1 || self.forced_reinsert > 1 {
            return Err(CorayStatus::InvalidParameter);
        }
        if let Some(b) = code::to_static(self.builder) {
            let leaf = if matches!(b, Builder::Tdbs | Builder::TdbsSah) {
                self.leaf_size
            } else {
                1
            };
            if leaf == 0 || self.start_empty != 0 {
                return Err(CorayStatus::InvalidParameter);
            }
            return Ok(Kind::Static(b, leaf));
        }
        if !code::is_rtree(self.builder) {
            return Err(CorayStatus::InvalidParameter);
        }
        let order = match self.insert_order {
            CORAY_BVH_ORDER_SCENE => InsertOrder::Scene,
            CORAY_BVH_ORDER_SHUFFLED => InsertOrder::Shuffled(self.seed),
            CORAY_BVH_ORDER_SORTED => InsertOrder::Sorted,
            _ => return Err(CorayStatus::InvalidParameter),
        };
        let p = RTreeParams {
            split: if self.builder == CORAY_BVH_BUILDER_RSTAR {
                Split::RStar
            } else {
                Split::Quadratic
            },
            max_children: self.max_children,
            min_children: self.min_children,
            order,
            forced_reinsert: self.forced_reinsert == 1,
        };
        p.check()?;
        Ok(Kind::RTree(p))
    }
}

/// Hierarchy and scratch layouts for `n` primitives (an R-tree's capacity).
fn layouts(n: usize, k: &Kind) -> Result<(BvhArenaLayout, BvhScratchLayout), CorayStatus> {
    let too_many = CorayStatus::TooManyPrimitives;
    if n >= MAX_PRIMS {
        return Err(too_many);
    }
    match k {
        Kind::Static(b, _) => {
            let r = bvh::requirements(n, *b);
            Ok((
                BvhArenaLayout::of(r.nodes, r.refs).ok_or(too_many)?,
                BvhScratchLayout::of(&r).ok_or(too_many)?,
            ))
        }
        Kind::RTree(p) => {
            // The arena for `n` may hold a few more (the formula moves in
            // steps): scratch for deletes covers all the arena will take.
            let arena = BvhArenaLayout::rtree(n, p).ok_or(too_many)?;
            let links = bvh::BvhRequirements {
                links: BvhArenaLayout::rtree_fit(arena.total_bytes, n, p).unwrap_or(n),
                ..Default::default()
            };
            Ok((arena, BvhScratchLayout::of(&links).ok_or(too_many)?))
        }
    }
}

/// Stack entries a hierarchy of `n` primitives may need: a binary one is
/// at most `n - 1` deep, an R-tree at most `log_m(n) + 1`.
fn stack_bound(n: usize, k: &Kind) -> usize {
    match k {
        Kind::Static(..) => n.max(1),
        Kind::RTree(p) => {
            let (m, big) = (p.min_children.max(2) as usize, p.max_children as usize);
            let mut levels = 1;
            let mut reach = 1usize;
            while reach < n {
                reach = reach.saturating_mul(m);
                levels += 1;
            }
            levels * (big - 1) + 1
        }
    }
}

/// Arena, scratch and stack sizes for a hierarchy over `prim_count`
/// primitives with `params` (for an R-tree, `prim_count` is the most
/// objects it will hold). Static builders need exactly `arena_bytes`.
///
/// Safety: `params` and `out` are NULL or valid pointers to their types.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_requirements(
    prim_count: usize,
    params: *const CorayBvhParams,
    out: *mut CorayRequirements,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: the caller passes valid pointers or NULL.
        let (k, out) = unsafe {
            (
                carve::read(params)?.to_core()?,
                Out::new(out, false, &mut regions)?,
            )
        };
        let (a, s) = layouts(prim_count, &k)?;
        out.write(CorayRequirements {
            struct_size: 0,
            arena_min_bytes: a.total_bytes,
            arena_bytes: a.total_bytes,
            scratch_min_bytes: s.total_bytes,
            scratch_bytes: s.total_bytes,
            stack_bytes: stack_bound(prim_count, &k) * size_of::<BvhStackItem>(),
        });
        Ok(())
    })
}

/// Builds a hierarchy over `scene` into `arena`, with `scratch` as scratch
/// (free again when this returns).
///
/// Both are 16-byte aligned and overlap neither each other nor the scene.
/// Static builders need `arena_bytes` of the requirements; an R-tree takes
/// any arena from the size for the scene's primitive count up and uses the
/// rest as room for later inserts. On `CORAY_STATUS_ARENA_TOO_SMALL`,
/// `*needed_bytes` (if not NULL) receives the size the arena or scratch
/// that was too small needs. Degenerate primitives stay out (never hit).
/// The part of the arena the layout covers is written entirely; bytes past
/// it are not touched.
///
/// Safety: every pointer is NULL or valid for its documented size; the
/// arenas are not read or written by anyone else during the call.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_build(
    scene: *const CorayScene,
    params: *const CorayBvhParams,
    arena: *mut c_void,
    arena_bytes: usize,
    scratch: *mut c_void,
    scratch_bytes: usize,
    needed_bytes: *mut usize,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: the caller passes valid scene and params pointers or NULL.
        let (scene, p) = unsafe { (carve::scene(scene, &mut regions)?, carve::read(params)?) };
        let kind = p.to_core()?;
        let needed = OutValue::new(needed_bytes, true, &mut regions)?;
        let (base, sbase) = (arena.cast::<u8>(), scratch.cast::<u8>());
        check_arena(base)?;
        check_arena(sbase)?;
        let n = scene.prim_count();
        // An R-tree that starts empty needs room for no object yet.
        let n_min = if p.start_empty == 1 { 0 } else { n };
        let (min_arena, scratch_l) = layouts(n_min, &kind)?;
        let (arena_l, capacity) = match &kind {
            Kind::Static(..) if arena_bytes < min_arena.total_bytes => {
                needed.write(min_arena.total_bytes);
                return Err(CorayStatus::ArenaTooSmall);
            }
            Kind::Static(..) => (min_arena, n),
            Kind::RTree(rp) => {
                let bytes = arena_bytes.min(coray::limits::MAX_ARENA_BYTES);
                let Some(cap) = BvhArenaLayout::rtree_fit(bytes, n_min, rp) else {
                    needed.write(min_arena.total_bytes);
                    return Err(CorayStatus::ArenaTooSmall);
                };
                let l = BvhArenaLayout::rtree(cap, rp).ok_or(CorayStatus::TooManyPrimitives)?;
                (l, cap)
            }
        };
        if scratch_bytes < scratch_l.total_bytes {
            needed.write(scratch_l.total_bytes);
            return Err(CorayStatus::ArenaTooSmall);
        }
        regions
            .add(base, arena_l.total_bytes, true)
            .add(sbase, scratch_l.total_bytes, true)
            .check()?;
        scene.check()?;
        let c = &scratch_l.counts;
        // SAFETY: both arenas passed check_arena; each layout lies within
        // its arena (checked above), its parts do not overlap (layout
        // formulas) and the arenas overlap neither each other nor the
        // scene (Regions); the caller lends both exclusively for the call.
        let (header, nodes, refs, boxes, keys, links, clusters) = unsafe {
            carve::zero(base, arena_l.total_bytes);
            (
                carve::arena_mut::<BvhArenaHeader>(base, 0, 1),
                carve::arena_mut::<BvhNode>(base, arena_l.nodes_offset, arena_l.nodes),
                carve::arena_mut::<u32>(base, arena_l.refs_offset, arena_l.refs),
                carve::arena_mut::<Aabb>(sbase, 0, c.boxes),
                carve::arena_mut::<f32>(sbase, scratch_l.keys_offset, c.keys),
                carve::arena_mut::<u32>(sbase, scratch_l.links_offset, c.links),
                carve::arena_mut::<BvhNode>(sbase, scratch_l.clusters_offset, c.clusters),
            )
        };
        let mut h = BvhArenaHeader {
            magic: BVH_MAGIC,
            version: BVH_VERSION,
            scene_counts: scene_counts(&scene),
            layout_bytes: arena_l.total_bytes as u32,
            nodes_cap: arena_l.nodes as u32,
            refs_cap: arena_l.refs as u32,
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
                h.builder = code::of_static(b);
                h.info = *t.info();
            }
            Kind::RTree(rp) => {
                let t = if p.start_empty == 1 {
                    RTree::new(&scene, rp, nodes, refs)?
                } else {
                    RTree::build(&scene, rp, nodes, refs, links)?
                };
                h.builder = code::of_rtree(&rp);
                h.set_rtree(&rp, t.state(), *t.bvh().info());
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

/// Errors unless `scene` has the counts the arena was built on.
pub(crate) fn check_scene(counts: [u32; 3], scene: &Scene) -> Result<(), CorayStatus> {
    let n = |x: usize| u32::try_from(x).ok();
    let have = [
        n(scene.triangles.len()),
        n(scene.spheres.len()),
        n(scene.cones.len()),
    ];
    if have != counts.map(Some) {
        return Err(CorayStatus::SceneMismatch);
    }
    Ok(())
}

/// The header of a hierarchy arena, checked in O(1).
///
/// Safety: `base` is NULL or readable for `bytes` bytes.
unsafe fn header(
    base: *const u8,
    bytes: usize,
) -> Result<(BvhArenaHeader, BvhArenaLayout), CorayStatus> {
    check_arena(base)?;
    if bytes < BVH_HEADER_BYTES {
        return Err(CorayStatus::CorruptArena);
    }
    // SAFETY: aligned, readable for bytes >= BVH_HEADER_BYTES >= one header.
    let h = unsafe { carve::arena_ref::<BvhArenaHeader>(base, 0, 1)[0] };
    let l = h.layout(bytes)?;
    h.rtree_params()?;
    if code::to_static(h.builder).is_none() && !code::is_rtree(h.builder) {
        return Err(CorayStatus::CorruptArena);
    }
    Ok((h, l))
}

/// Opens the hierarchy in `arena` with the scene it was built on: O(1)
/// checks, then `*out` is the handle every trace, info and validate call
/// takes. The arena and the scene's arrays stay in place and unchanged
/// while the handle is used (an R-tree's own inserts and deletes aside).
/// Validate an arena from untrusted storage once, as for a kd-tree.
///
/// Safety: `arena` is NULL or readable for `arena_bytes`; `scene` and `out`
/// NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_open(
    arena: *const c_void,
    arena_bytes: usize,
    scene: *const CorayScene,
    out: *mut CorayBvh,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let scene = unsafe { carve::scene(scene, &mut regions)? };
        carve::check_array(out, 1)?;
        regions.add(out, size_of::<CorayBvh>(), true);
        let base = arena.cast::<u8>();
        // SAFETY: forwarded contract.
        let (h, l) = unsafe { header(base, arena_bytes)? };
        regions.add(base, arena_bytes, false).check()?;
        check_scene(h.scene_counts, &scene)?;
        let mut hd = Handle::new(KIND_BVH, base as usize, l.total_bytes, &scene);
        hd.set_part::<BvhArenaHeader>(0, 0, 1)?;
        hd.set_part::<BvhNode>(1, l.nodes_offset, l.nodes)?;
        hd.set_part::<u32>(2, l.refs_offset, l.refs)?;
        let words = hd.words();
        // SAFETY: the handle describes the arena just checked, readable.
        unsafe { view_of(Sealed::new(&words, KIND_BVH)?, scene)? };
        // SAFETY: out checked non-null, aligned, disjoint from the arena.
        unsafe { out.write(CorayBvh { opaque: words }) };
        Ok(())
    })
}

/// The header and hierarchy a handle describes, over `scene`.
///
/// Safety: the handle's arena is readable and unchanged during `'a`.
#[inline(always)]
unsafe fn view_of<'a>(
    h: Sealed,
    scene: Scene<'a>,
) -> Result<(&'a BvhArenaHeader, Bvh<'a>), CorayStatus> {
    // SAFETY: the handle's parts lie within its arena (Handle::set_part
    // at open), readable by the caller's contract.
    unsafe {
        let header: &'a BvhArenaHeader = &h.part::<BvhArenaHeader>(0)[0];
        let b = Bvh::from_parts(scene, h.part::<BvhNode>(1), h.part::<u32>(2), header.info)?;
        Ok((header, b))
    }
}

/// The hierarchy behind a caller's handle, its buffers noted in `regions`.
///
/// Safety: `t` is NULL or a handle `coray_bvh_open` filled, whose arena
/// and scene are still in place and unchanged during `'a`.
unsafe fn open<'a>(
    t: *const CorayBvh,
    regions: &mut Regions,
) -> Result<(&'a BvhArenaHeader, Bvh<'a>), CorayStatus> {
    // SAFETY: forwarded contract.
    unsafe {
        let h = handle::read(t.cast(), KIND_BVH, regions)?;
        regions.add(h.arena() as *const u8, h.arena_bytes(), false);
        let scene = h.scene();
        regions.add_scene(&scene);
        view_of(h, scene)
    }
}

/// What the hierarchy holds, from its header (O(1)).
///
/// Safety: `bvh` is a handle `coray_bvh_open` filled; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_info(
    bvh: *const CorayBvh,
    out: *mut CorayBvhInfo,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let ((h, b), out) = unsafe {
            (
                open(bvh, &mut regions)?,
                Out::new(out, false, &mut regions)?,
            )
        };
        regions.check()?;
        let i = b.info();
        let root = b
            .parts()
            .0
            .get(i.root as usize)
            .copied()
            .unwrap_or_default();
        out.write(CorayBvhInfo {
            struct_size: 0,
            builder: h.builder,
            node_count: i.node_count,
            leaf_count: i.leaf_count,
            ref_count: i.ref_count,
            depth: i.depth,
            max_children: i.max_children,
            capacity: h.capacity,
            arena_bytes_used: h.layout_bytes as usize,
            stack_bytes: b.stack_len().saturating_mul(size_of::<BvhStackItem>()),
            bounds_min: root.min,
            bounds_max: root.max,
        });
        Ok(())
    })
}

/// Checks every structural invariant of the hierarchy against its scene,
/// in time linear in the hierarchy, never crashing on any bytes: boxes are
/// exact unions, indices in range, counts, depth and reference digest as
/// recorded; for the static builders the leaves holding exactly the
/// scene's non-degenerate primitives, for R-trees the fill rules and free
/// lists.
/// `CORAY_STATUS_CORRUPT_ARENA` when anything is wrong. Once it accepts an
/// arena, every call on it gives the results of a clean build. `stack` is
/// the traversal stack (`stack_bytes` of the info); `out` may be NULL.
///
/// Safety: as `coray_bvh_info`; `stack` writable for `stack_bytes`.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_validate(
    bvh: *const CorayBvh,
    stack: *mut c_void,
    stack_bytes: usize,
    out: *mut CorayShape,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let ((h, b), out) =
            unsafe { (open(bvh, &mut regions)?, Out::new(out, true, &mut regions)?) };
        // SAFETY: forwarded caller contract: a writable stack.
        let stk = unsafe {
            carve::stack::<BvhStackItem>(stack, stack_bytes, b.stack_len(), &mut regions)?
        };
        regions.check()?;
        let s = match h.rtree_params()? {
            Some(p) => {
                let l = BvhArenaLayout::rtree(h.capacity as usize, &p);
                if l.is_none_or(|l| {
                    (l.nodes, l.refs) != (h.nodes_cap as usize, h.refs_cap as usize)
                }) {
                    return Err(CorayStatus::CorruptArena);
                }
                bvh::validate_rtree(&b, &p, &h.rtree, stk)?
            }
            None => {
                // A static build's capacity is its scene's primitive
                // count; degenerate ones stay out of the references.
                let i = b.info();
                let prims: u64 = h.scene_counts.iter().map(|&c| c as u64).sum();
                if h.capacity as u64 != prims || i.max_children != 2 {
                    return Err(CorayStatus::CorruptArena);
                }
                b.validate(None, stk)?
            }
        };
        out.write(CorayShape {
            struct_size: 0,
            node_count: s.nodes,
            leaf_count: s.leaves,
            empty_leaf_count: 0,
            ref_count: s.refs,
            depth: s.depth,
        });
        Ok(())
    })
}

/// The R-tree in an arena, for changing, with its header to write back.
///
/// Safety: `arena` is NULL or valid for reads and writes of `bytes` bytes
/// that nobody else touches during `'a`.
unsafe fn rtree_mut<'a>(
    arena: *mut c_void,
    bytes: usize,
    scene: Scene<'a>,
    regions: &mut Regions,
) -> Result<(&'a mut BvhArenaHeader, RTree<'a>), CorayStatus> {
    let base = arena.cast::<u8>();
    // SAFETY: forwarded contract.
    let (h, l) = unsafe { header(base, bytes)? };
    check_scene(h.scene_counts, &scene)?;
    let p = h.rtree_params()?.ok_or(CorayStatus::InvalidParameter)?;
    regions.add(base, l.total_bytes, true).check()?;
    // SAFETY: header, nodes and refs are disjoint parts of the checked
    // layout (header below BVH_HEADER_BYTES, then 16-aligned parts), all
    // within `bytes`, apart from the call's other buffers (Regions); the
    // caller gives us the arena exclusively.
    let (hd, nodes, refs) = unsafe {
        (
            &mut carve::arena_mut::<BvhArenaHeader>(base, 0, 1)[0],
            carve::arena_mut::<BvhNode>(base, l.nodes_offset, l.nodes),
            carve::arena_mut::<u32>(base, l.refs_offset, l.refs),
        )
    };
    let t = RTree::resume(&scene, p, nodes, refs, h.rtree)?;
    Ok((hd, t))
}

/// Inserts primitive `prim_id` of geometry `geom_id` into the R-tree in
/// `arena`. A degenerate primitive is accepted and not stored.
/// `CORAY_STATUS_ARENA_TOO_SMALL` when the arena holds
/// `CorayBvhInfo.capacity` objects: the tree is then unchanged (build
/// again in a larger arena). `CORAY_STATUS_INVALID_PARAMETER` for a static
/// hierarchy or a primitive the scene lacks. Inserting an object that the
/// tree holds already stores it twice. On a tree that validates, an insert
/// either completes or changes nothing; on a broken one it may stop with
/// `CORAY_STATUS_CORRUPT_ARENA`. No trace may run on the arena meanwhile.
///
/// Safety: `arena` is valid for reads and writes of `arena_bytes` bytes
/// that nobody else touches during the call; `scene` is valid.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_insert(
    arena: *mut c_void,
    arena_bytes: usize,
    scene: *const CorayScene,
    geom_id: CorayGeomId,
    prim_id: u32,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let scene = unsafe { carve::scene(scene, &mut regions)? };
        let prim = global_prim(&scene, geom_id, prim_id).ok_or(CorayStatus::InvalidParameter)?;
        // SAFETY: forwarded caller contract.
        let (hd, mut t) = unsafe { rtree_mut(arena, arena_bytes, scene, &mut regions)? };
        if t.len() >= hd.capacity {
            return Err(CorayStatus::ArenaTooSmall);
        }
        t.insert(prim)?;
        let p = t.params();
        hd.set_rtree(&p, t.state(), *t.bvh().info());
        Ok(())
    })
}

/// Removes primitive `prim_id` of geometry `geom_id` from the R-tree in
/// `arena`; `*deleted` (if not NULL) receives 1 when it was there, else 0.
/// Nodes left underfull are dissolved and their objects inserted again,
/// which needs the requirements' `scratch_bytes` in `scratch` (16-byte
/// aligned, not overlapping the tree). Otherwise as `coray_bvh_insert`.
///
/// Safety: as `coray_bvh_insert`; `scratch` is writable for
/// `scratch_bytes`; `deleted` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_delete(
    arena: *mut c_void,
    arena_bytes: usize,
    scene: *const CorayScene,
    geom_id: CorayGeomId,
    prim_id: u32,
    scratch: *mut c_void,
    scratch_bytes: usize,
    deleted: *mut u8,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let scene = unsafe { carve::scene(scene, &mut regions)? };
        let prim = global_prim(&scene, geom_id, prim_id).ok_or(CorayStatus::InvalidParameter)?;
        let deleted = OutValue::new(deleted, true, &mut regions)?;
        let sbase = scratch.cast::<u8>();
        check_arena(sbase)?;
        // SAFETY: forwarded caller contract.
        let (hd, mut t) = unsafe { rtree_mut(arena, arena_bytes, scene, &mut regions)? };
        let need = t.len() as usize;
        if scratch_bytes < need * 4 {
            return Err(CorayStatus::ArenaTooSmall);
        }
        regions.add(sbase, need * 4, true).check()?;
        // SAFETY: aligned (checked), `need * 4 <= scratch_bytes` bytes the
        // caller lends exclusively, disjoint from the tree (Regions).
        let orphans = unsafe { carve::arena_mut::<u32>(sbase, 0, need) };
        let was = t.delete(prim, orphans)?;
        let p = t.params();
        hd.set_rtree(&p, t.state(), *t.bvh().info());
        deleted.write(was as u8);
        Ok(())
    })
}

/// The body of every trace entry point: checks the handle, the arrays, the
/// stack and the statistics first, then writes `answer` for each ray.
///
/// Safety: as `coray_bvh_intersect`, with `out` holding `count` `O`s.
#[allow(clippy::too_many_arguments)]
unsafe fn batch<O>(
    bvh: *const CorayBvh,
    rays: *const CorayRay,
    out: *mut O,
    count: usize,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
    answer: impl Fn(&Bvh, &coray::Ray, &mut [BvhStackItem], &mut TraceStats) -> O,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract for every pointer.
        let (b, rays, out, stk, stats) = unsafe {
            let (_, b) = open(bvh, &mut regions)?;
            let rays = carve::input(rays, count)?;
            regions.add(rays.as_ptr(), size_of_val(rays), false);
            let out = carve::output(out, count)?;
            regions.add(out.as_ptr(), size_of_val(out), true);
            let need = if count == 0 { 0 } else { b.stack_len() };
            let stk = carve::stack::<BvhStackItem>(stack, stack_bytes, need, &mut regions)?;
            (b, rays, out, stk, Out::new(stats, true, &mut regions)?)
        };
        regions.check()?;
        let mut st = TraceStats::default();
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = answer(&b, &r.into(), stk, &mut st);
            // A corrupt arena: the call stops at the first ray that met it.
            if st.faults > 0 {
                return Err(CorayStatus::CorruptArena);
            }
        }
        stats.write(CorayTraceStats::of(&st));
        Ok(())
    })
}

/// The body of the one-ray entry points: [`one_ray`] on a hierarchy,
/// writing `answer` for the ray.
///
/// Safety: as `coray_bvh_intersect1`, with `out` one writable `O`.
#[inline(always)]
unsafe fn one<O>(
    bvh: *const CorayBvh,
    ray: *const CorayRay,
    out: *mut O,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
    answer: impl FnOnce(&Bvh, &coray::Ray, &mut [BvhStackItem], &mut TraceStats) -> O,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract.
        unsafe {
            one_ray(
                bvh.cast(),
                KIND_BVH,
                |h, s| Ok(view_of(h, s)?.1),
                |b| b.stack_len(),
                ray,
                out,
                stack,
                stack_bytes,
                stats,
                |b, r, s, st| Ok(answer(b, r, s, st)),
            )
        }
    })
}

/// Closest hits of `count` rays: `hits[i]` for `rays[i]`. `stack` is the
/// caller's traversal stack of `stack_bytes` (at least the info's
/// `stack_bytes`, 16-byte aligned; one per thread). `stats` may be NULL.
/// Many threads may trace one hierarchy at once, each with its own stack,
/// while nobody changes it.
///
/// Safety: `bvh` as in `coray_bvh_info`; `rays` and `hits` hold `count`
/// elements (may be NULL when `count` is 0); `stack` is writable for
/// `stack_bytes`; `stats` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_intersect(
    bvh: *const CorayBvh,
    rays: *const CorayRay,
    hits: *mut CorayHit,
    count: usize,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    // SAFETY: forwarded caller contract.
    unsafe {
        batch(
            bvh,
            rays,
            hits,
            count,
            stack,
            stack_bytes,
            stats,
            |b, r, s, st| b.intersect(r, s, st).into(),
        )
    }
}

/// `coray_bvh_intersect` for one ray, checked in full on every call. A thread
/// tracing one ray per call makes a tracer (`coray_bvh_tracer`) and calls
/// `coray_bvh_tracer_intersect1`: the same answer, the checks made once.
///
/// Safety: as `coray_bvh_intersect` with `count` 1.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_intersect1(
    bvh: *const CorayBvh,
    ray: *const CorayRay,
    hit: *mut CorayHit,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    if ray.is_null() || hit.is_null() {
        return CorayStatus::NullPointer;
    }
    // SAFETY: forwarded caller contract.
    unsafe {
        one(bvh, ray, hit, stack, stack_bytes, stats, |b, r, s, st| {
            b.intersect(r, s, st).into()
        })
    }
}

/// Any-hit queries (shadow rays): `occluded[i]` is 1 when something lies
/// on `rays[i]` within `[tnear, tfar]`, else 0. Otherwise as
/// `coray_bvh_intersect`.
///
/// Safety: as `coray_bvh_intersect`, with `occluded` holding `count` bytes.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_occluded(
    bvh: *const CorayBvh,
    rays: *const CorayRay,
    occluded: *mut u8,
    count: usize,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    // SAFETY: forwarded caller contract.
    unsafe {
        batch(
            bvh,
            rays,
            occluded,
            count,
            stack,
            stack_bytes,
            stats,
            |b, r, s, st| b.occluded(r, s, st) as u8,
        )
    }
}

/// `coray_bvh_occluded` for one ray, checked in full on every call. A thread
/// tracing one ray per call makes a tracer (`coray_bvh_tracer`) and calls
/// `coray_bvh_tracer_occluded1`: the same answer, the checks made once.
///
/// Safety: as `coray_bvh_occluded` with `count` 1.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_occluded1(
    bvh: *const CorayBvh,
    ray: *const CorayRay,
    occluded: *mut u8,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    if ray.is_null() || occluded.is_null() {
        return CorayStatus::NullPointer;
    }
    // SAFETY: forwarded caller contract.
    unsafe {
        one(
            bvh,
            ray,
            occluded,
            stack,
            stack_bytes,
            stats,
            |b, r, s, st| b.occluded(r, s, st) as u8,
        )
    }
}

/// Makes `tracer` trace `bvh` with the caller's `stack` (at least the
/// info's `stack_bytes`, 16-byte aligned): one thread's
/// `coray_bvh_tracer_intersect1` and `_occluded1` calls then skip the checks
/// this call makes. An R-tree that `coray_bvh_insert` deepened past what
/// the stack holds gets `CORAY_STATUS_ARENA_TOO_SMALL` from them: make the
/// tracer again with the info's new `stack_bytes`. Since 1.5.
///
/// Safety: `bvh` as in `coray_bvh_info`; `stack` NULL or writable
/// for `stack_bytes`, and used by nothing else while the tracer is;
/// `tracer` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_tracer(
    bvh: *const CorayBvh,
    stack: *mut c_void,
    stack_bytes: usize,
    tracer: *mut CorayTracer,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract.
        unsafe {
            tracer::make::<_, BvhStackItem>(
                tracer,
                bvh.cast(),
                KIND_BVH,
                0,
                |h, s| Ok(view_of(h, s)?.1),
                |x| x.stack_len(),
                |_| [0; tracer::HINT_WORDS],
                stack,
                stack_bytes,
            )
        }
    })
}

/// `coray_bvh_tracer_intersect1` and `_occluded1` on a tracer of this family:
/// `answer` for the ray.
///
/// Safety: as `coray_bvh_tracer_intersect1`, with `out` one writable `O`.
#[inline(always)]
unsafe fn traced<O>(
    tracer: *mut CorayTracer,
    ray: *const CorayRay,
    out: *mut O,
    answer: impl FnOnce(&Bvh, &coray::Ray, &mut [BvhStackItem], &mut TraceStats) -> O,
) -> Result<(), CorayStatus> {
    // SAFETY: forwarded caller contract.
    unsafe {
        tracer::trace(
            tracer,
            KIND_BVH,
            #[inline(always)]
            |h, s, _| Ok(view_of(h, s)?.1),
            #[inline(always)]
            |x| x.stack_len(),
            ray,
            out,
            |_, _, _| None,
            #[inline(always)]
            |x, _, r, s, st| Ok(answer(x, r, s, st)),
        )
    }
}

/// The closest hit of `ray` by a tracer of this hierarchy (made by
/// `coray_bvh_tracer`), into `hit`: `coray_bvh_intersect1`'s answer, with
/// the checks made once when the tracer was made. Each call checks the
/// tracer (made by that call, not moved or copied since; of this family),
/// its handle's seal word, `ray` and `hit` (non-null, aligned, apart, and
/// `hit` over none of the tracer, its stack, handle, arena or scene, nor
/// the ray over the tracer or stack), and adds its statistics to the
/// tracer's (`coray_tracer_stats`). Since 1.5.
///
/// Safety: `tracer` NULL or a tracer its make call filled, used by one
/// thread at a time, whose handle, arena, scene and stack are in place and
/// (but the stack) unchanged; `ray` NULL or readable; `hit` NULL or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_tracer_intersect1(
    tracer: *mut CorayTracer,
    ray: *const CorayRay,
    hit: *mut CorayHit,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract.
        unsafe {
            traced(
                tracer,
                ray,
                hit,
                #[inline(always)]
                |x, r, s, st| x.intersect(r, s, st).into(),
            )
        }
    })
}

/// Whether something lies on `ray` within `[tnear, tfar]` (1) or not (0),
/// by a tracer of this hierarchy, into `occluded`: `coray_bvh_occluded1`'s
/// answer. Otherwise as `coray_bvh_tracer_intersect1`. Since 1.5.
///
/// Safety: as `coray_bvh_tracer_intersect1`, with `occluded` one writable
/// byte.
#[no_mangle]
pub unsafe extern "C" fn coray_bvh_tracer_occluded1(
    tracer: *mut CorayTracer,
    ray: *const CorayRay,
    occluded: *mut u8,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract.
        unsafe {
            traced(
                tracer,
                ray,
                occluded,
                #[inline(always)]
                |x, r, s, st| x.occluded(r, s, st) as u8,
            )
        }
    })
}
