//! `coray_proj_*`: projection hierarchies (Bezerianos 2001) for a camera or
//! a light plane: planes, requirements, build, info, validate, intersect,
//! occluded. One hierarchy per arena; a light cube is six arenas.

use crate::bvh::{scene_counts, stack, too_small, CorayBvhParams, CorayBvhStats, Kind, MAX_PRIMS};
use crate::carve::{self, check_arena, slice_mut, slice_ref};
use crate::lcts::{camera, CorayCamera};
use crate::types::{CorayHit, CorayRay, CorayScene};
use crate::{guard, CorayStatus};
use coray::arena::{
    BvhScratchLayout, ProjArenaHeader, ProjArenaLayout, PROJ_HEADER_BYTES, PROJ_MAGIC, PROJ_VERSION,
};
use coray::bvh::{self, Bvh, BvhNode, BvhScratch, BvhStackItem};
use coray::proj::lights::{Light, LightPlanes};
use coray::proj::{
    build_proj, proj_requirements, Criteria, ProjBuilder, ProjHierarchy, ProjPlane, ProjScheme,
    ProjScratch, ProjStats, ProjStorage, Rect,
};
use coray::{Aabb, Ray, Scene, Vec3};
use core::ffi::c_void;
use core::mem::size_of;

/// Structure built on the primitives' rectangles on the plane.
pub const CORAY_PROJ_CRITERIA_2D: u32 = 0;
/// "Dummy": a 3D structure whose nodes carry their children's rectangles.
pub const CORAY_PROJ_CRITERIA_DUMMY: u32 = 1;

/// Nodes tested by the ray's point in their rectangle (4 comparisons).
pub const CORAY_PROJ_SCHEME_2D: u32 = 0;
/// Nodes tested by the ray against their 3D box.
pub const CORAY_PROJ_SCHEME_3D: u32 = 1;
/// The rectangle first, the 3D box when the rectangle holds the point.
pub const CORAY_PROJ_SCHEME_COMBINATION: u32 = 2;

/// A central projection.
pub const CORAY_PLANE_PERSPECTIVE: u32 = 0;
/// A parallel projection.
pub const CORAY_PLANE_ORTHOGRAPHIC: u32 = 1;

/// A point light.
pub const CORAY_LIGHT_POINT: u32 = 0;
/// A directional light.
pub const CORAY_LIGHT_DIRECTIONAL: u32 = 1;

/// A projection plane. Get one from [`coray_proj_plane_camera`] or
/// [`coray_proj_light_planes`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayProjPlane {
    /// `CORAY_PLANE_PERSPECTIVE` or `CORAY_PLANE_ORTHOGRAPHIC`.
    pub kind: u32,
    /// Centre of projection (perspective).
    pub eye: [f32; 3],
    /// First plane axis.
    pub right: [f32; 3],
    /// Second plane axis.
    pub up: [f32; 3],
    /// Direction of view (perspective) or of projection (orthographic).
    pub forward: [f32; 3],
}

/// A light: a point light at `v`, or a directional light shining along `v`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayLight {
    /// `CORAY_LIGHT_POINT` or `CORAY_LIGHT_DIRECTIONAL`.
    pub kind: u32,
    /// Position or direction.
    pub v: [f32; 3],
}

/// Parameters of a projection build. Get them from [`coray_proj_params_default`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CorayProjParams {
    /// `sizeof(CorayProjParams)`.
    pub struct_size: usize,
    /// `CORAY_PROJ_CRITERIA_2D` or `CORAY_PROJ_CRITERIA_DUMMY`.
    pub criteria: u32,
    /// The builder and its settings (`leaf_size` is 1 here; `start_empty`
    /// must be 0).
    pub bvh: CorayBvhParams,
}

/// Arena sizes for a projection hierarchy, from [`coray_proj_requirements`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayProjRequirements {
    /// The hierarchy's arena.
    pub proj_bytes: usize,
    /// Build scratch.
    pub scratch_bytes: usize,
}

/// What a projection hierarchy holds (read from its arena header, O(1)).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayProjInfo {
    /// `CORAY_BVH_*`.
    pub builder: u32,
    /// `CORAY_PROJ_CRITERIA_*`.
    pub criteria: u32,
    /// Nodes in use.
    pub node_count: u32,
    /// Primitives in the hierarchy (2D criteria leave out those that
    /// project to nothing).
    pub object_count: u32,
    /// Levels below the root.
    pub depth: u32,
    /// Bytes of traversal stack the trace calls need (4-byte aligned).
    pub stack_bytes: usize,
    /// Bytes of the arena the layout covers.
    pub arena_bytes_used: usize,
    /// The plane.
    pub plane: CorayProjPlane,
}

/// Work done by one projection trace call.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayProjStats {
    /// Rays, nodes, primitives and the thesis' costs (a 2D test costs 4).
    pub bvh: CorayBvhStats,
    /// How many of `bvh.box_tests` were point-in-rectangle tests.
    pub rect_tests: u64,
}

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from(a)
}

fn plane_to_c(p: &ProjPlane) -> CorayProjPlane {
    let (r, u, f) = p.axes();
    let (kind, eye) = match *p {
        ProjPlane::Perspective { eye, .. } => (CORAY_PLANE_PERSPECTIVE, eye),
        ProjPlane::Orthographic { .. } => (CORAY_PLANE_ORTHOGRAPHIC, Vec3::ZERO),
    };
    CorayProjPlane {
        kind,
        eye: eye.into(),
        right: r.into(),
        up: u.into(),
        forward: f.into(),
    }
}

fn plane_from_c(p: &CorayProjPlane) -> Result<ProjPlane, CorayStatus> {
    let all = [p.eye, p.right, p.up, p.forward];
    if !all.iter().all(|v| v3(*v).is_finite()) || v3(p.forward).length_squared() == 0.0 {
        return Err(CorayStatus::InvalidParameter);
    }
    match p.kind {
        CORAY_PLANE_PERSPECTIVE => Ok(ProjPlane::Perspective {
            eye: v3(p.eye),
            right: v3(p.right),
            up: v3(p.up),
            forward: v3(p.forward),
        }),
        CORAY_PLANE_ORTHOGRAPHIC => Ok(ProjPlane::Orthographic {
            right: v3(p.right),
            up: v3(p.up),
            forward: v3(p.forward),
        }),
        _ => Err(CorayStatus::InvalidParameter),
    }
}

fn light_from_c(l: &CorayLight) -> Result<Light, CorayStatus> {
    let v = v3(l.v);
    if !v.is_finite() {
        return Err(CorayStatus::InvalidParameter);
    }
    match l.kind {
        CORAY_LIGHT_POINT => Ok(Light::Point(v)),
        CORAY_LIGHT_DIRECTIONAL if v.length_squared() > 0.0 => Ok(Light::Directional(v)),
        _ => Err(CorayStatus::InvalidParameter),
    }
}

/// Writes one value to a caller's out pointer.
fn put<T>(out: *mut T, v: T) -> Result<(), CorayStatus> {
    // SAFETY: the caller passes NULL or a valid, writable pointer.
    *unsafe { carve::output(out, 1)? }
        .first_mut()
        .ok_or(CorayStatus::NullPointer)? = v;
    Ok(())
}

/// The image plane of `camera`.
///
/// # Safety
/// `camera` and `out` are NULL or valid pointers to their types.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_plane_camera(
    camera_in: *const CorayCamera,
    out: *mut CorayProjPlane,
) -> CorayStatus {
    guard(|| {
        // SAFETY: the caller passes a valid camera pointer or NULL.
        let cam = camera(unsafe { carve::input_ref(camera_in)? })?;
        put(out, plane_to_c(&ProjPlane::camera(&cam)))
    })
}

/// The planes of `light` for a scene inside `[bounds_min, bounds_max]`:
/// `*count` is 6 (a cube: the point light lies inside the box; face `k`
/// looks along +x, -x, +y, -y, +z, -z) or 1 (a point light outside it, a
/// directional light). `planes` holds 6 entries.
///
/// # Safety
/// `light`, `bounds_min`, `bounds_max` are NULL or readable; `planes`
/// (6 entries) and `count` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_light_planes(
    light: *const CorayLight,
    bounds_min: *const [f32; 3],
    bounds_max: *const [f32; 3],
    planes: *mut CorayProjPlane,
    count: *mut u32,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract for each pointer.
        let (l, lo, hi) = unsafe {
            (
                light_from_c(carve::input_ref(light)?)?,
                *carve::input_ref(bounds_min)?,
                *carve::input_ref(bounds_max)?,
            )
        };
        let b = Aabb {
            min: v3(lo),
            max: v3(hi),
        };
        let lp = LightPlanes::new(l, &b);
        // SAFETY: the caller passes 6 writable planes or NULL.
        let out = unsafe { carve::output(planes, 6)? };
        for (o, p) in out.iter_mut().zip(lp.planes.iter()) {
            *o = plane_to_c(p);
        }
        put(count, lp.count as u32)
    })
}

/// Which of `light`'s planes (from [`coray_proj_light_planes`] with the
/// same bounds) the shadow ray `ray` uses; `CORAY_STATUS_INVALID_PARAMETER`
/// when the ray does not run towards the light (ending at it or before).
///
/// # Safety
/// Pointers NULL or valid for their types.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_light_plane_for(
    light: *const CorayLight,
    bounds_min: *const [f32; 3],
    bounds_max: *const [f32; 3],
    ray: *const CorayRay,
    plane_index: *mut u32,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract for each pointer.
        let (l, lo, hi, r) = unsafe {
            (
                light_from_c(carve::input_ref(light)?)?,
                *carve::input_ref(bounds_min)?,
                *carve::input_ref(bounds_max)?,
                Ray::from(carve::input_ref(ray)?),
            )
        };
        let lp = LightPlanes::new(
            l,
            &Aabb {
                min: v3(lo),
                max: v3(hi),
            },
        );
        let k = lp.plane_for(&r).ok_or(CorayStatus::InvalidParameter)?;
        put(plane_index, k as u32)
    })
}

/// Default parameters: `criteria` (`CORAY_PROJ_CRITERIA_*`) with `builder`
/// (`CORAY_BVH_*`) and its defaults. Unknown values give `struct_size` 0.
#[no_mangle]
pub extern "C" fn coray_proj_params_default(criteria: u32, builder: u32) -> CorayProjParams {
    let bvh = crate::bvh::coray_bvh_params_default(builder);
    let ok = criteria <= CORAY_PROJ_CRITERIA_DUMMY && bvh.struct_size != 0;
    CorayProjParams {
        struct_size: if ok { size_of::<CorayProjParams>() } else { 0 },
        criteria,
        bvh,
    }
}

impl CorayProjParams {
    fn to_core(self) -> Result<(ProjBuilder, Criteria, u32), CorayStatus> {
        if self.struct_size != size_of::<CorayProjParams>() || self.bvh.start_empty != 0 {
            return Err(CorayStatus::InvalidParameter);
        }
        let criteria = match self.criteria {
            CORAY_PROJ_CRITERIA_2D => Criteria::TwoD,
            CORAY_PROJ_CRITERIA_DUMMY => Criteria::Dummy,
            _ => return Err(CorayStatus::InvalidParameter),
        };
        let b = match self.bvh.to_core()? {
            Kind::Static(b, _) => ProjBuilder::Static(b),
            Kind::RTree(p) => ProjBuilder::RTree(p),
        };
        Ok((b, criteria, self.bvh.builder))
    }
}

/// Arena and scratch layouts for `n` primitives.
struct Layouts {
    arena: ProjArenaLayout,
    bvh: BvhScratchLayout,
    source_offset: usize,
    stack_offset: usize,
    stack: usize,
    scratch_bytes: usize,
}

fn layouts(n: usize, b: &ProjBuilder) -> Result<Layouts, CorayStatus> {
    if n >= MAX_PRIMS {
        return Err(CorayStatus::TooManyPrimitives);
    }
    let r = proj_requirements(n, b);
    let arena = ProjArenaLayout::of(r.nodes, r.refs, r.prim_rects);
    if arena.total_bytes > u32::MAX as usize {
        return Err(CorayStatus::TooManyPrimitives);
    }
    let bvh = BvhScratchLayout::of(&r.bvh_scratch);
    let source_offset = coray::arena::align_up(bvh.total_bytes);
    let stack_offset = coray::arena::align_up(source_offset + r.source * size_of::<Aabb>());
    Ok(Layouts {
        arena,
        bvh,
        source_offset,
        stack_offset,
        stack: r.stack,
        scratch_bytes: stack_offset + r.stack * 4,
    })
}

/// Arena sizes for a projection hierarchy over `prim_count` primitives.
///
/// # Safety
/// `params` and `out` are NULL or valid pointers to their types.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_requirements(
    prim_count: usize,
    params: *const CorayProjParams,
    out: *mut CorayProjRequirements,
) -> CorayStatus {
    guard(|| {
        // SAFETY: the caller passes a valid params pointer or NULL.
        let (b, _, _) = unsafe { carve::input_ref(params)? }.to_core()?;
        let l = layouts(prim_count, &b)?;
        put(
            out,
            CorayProjRequirements {
                proj_bytes: l.arena.total_bytes,
                scratch_bytes: l.scratch_bytes,
            },
        )
    })
}

/// Builds the projection hierarchy of `scene` on `plane` into
/// `proj_arena` (exactly `proj_bytes` from [`coray_proj_requirements`] or
/// more), with `scratch_arena` as scratch. Arenas 16-byte aligned, not
/// overlapping; `CORAY_STATUS_ARENA_TOO_SMALL` reports the bytes needed.
///
/// # Safety
/// Every pointer is NULL or valid for its documented size; the arenas are
/// not touched by anyone else during the call.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_build(
    scene: *const CorayScene,
    params: *const CorayProjParams,
    plane: *const CorayProjPlane,
    proj_arena: *mut c_void,
    proj_bytes: usize,
    scratch_arena: *mut c_void,
    scratch_bytes: usize,
    needed_bytes: *mut usize,
) -> CorayStatus {
    guard(|| {
        // SAFETY: the caller passes valid pointers or NULL.
        let (scene, p, pl) = unsafe {
            (
                carve::scene(scene)?,
                *carve::input_ref(params)?,
                plane_from_c(carve::input_ref(plane)?)?,
            )
        };
        let (builder, criteria, builder_id) = p.to_core()?;
        let (base, sbase) = (proj_arena.cast::<u8>(), scratch_arena.cast::<u8>());
        check_arena(base)?;
        check_arena(sbase)?;
        let l = layouts(scene.prim_count(), &builder)?;
        if proj_bytes < l.arena.total_bytes {
            return too_small(needed_bytes, l.arena.total_bytes);
        }
        if scratch_bytes < l.scratch_bytes {
            return too_small(needed_bytes, l.scratch_bytes);
        }
        let (a0, s0) = (base as usize, sbase as usize);
        if a0 < s0 + l.scratch_bytes && s0 < a0 + l.arena.total_bytes {
            return Err(CorayStatus::InvalidParameter);
        }
        scene.check()?;
        let (a, c) = (&l.arena, &l.bvh.counts);
        // SAFETY: both arenas passed check_arena; each layout lies within
        // its arena (checked above); parts are disjoint (layout formulas,
        // 16-aligned offsets) and the arenas do not overlap (checked); the
        // caller lends both exclusively for the call.
        let (header, storage, scratch) = unsafe {
            (
                slice_mut::<ProjArenaHeader>(base, 0, 1),
                ProjStorage {
                    nodes: slice_mut::<BvhNode>(base, a.nodes_offset, a.nodes),
                    refs: slice_mut::<u32>(base, a.refs_offset, a.refs),
                    rects: slice_mut::<Rect>(base, a.rects_offset, a.nodes),
                    prim_rects: slice_mut::<Rect>(base, a.prim_rects_offset, a.prim_rects),
                },
                ProjScratch {
                    bvh: BvhScratch {
                        boxes: slice_mut::<Aabb>(sbase, 0, c.boxes),
                        keys: slice_mut::<f32>(sbase, l.bvh.keys_offset, c.keys),
                        links: slice_mut::<u32>(sbase, l.bvh.links_offset, c.links),
                        clusters: slice_mut::<BvhNode>(sbase, l.bvh.clusters_offset, c.clusters),
                    },
                    source: slice_mut::<Aabb>(sbase, l.source_offset, scene.prim_count()),
                    stack: slice_mut::<u32>(sbase, l.stack_offset, l.stack),
                },
            )
        };
        let h = build_proj(&scene, pl, builder, criteria, storage, scratch)?;
        let mut hd = ProjArenaHeader {
            magic: PROJ_MAGIC,
            version: PROJ_VERSION,
            builder: builder_id,
            criteria: p.criteria,
            scene_counts: scene_counts(&scene),
            info: h.bvh.info,
            layout_bytes: a.total_bytes as u32,
            nodes_cap: a.nodes as u32,
            refs_cap: a.refs as u32,
            prim_rects_cap: a.prim_rects as u32,
            ..Default::default()
        };
        hd.set_plane(&pl);
        header[0] = hd;
        Ok(())
    })
}

/// The hierarchy in an arena, for reading (O(1) checks).
///
/// # Safety
/// `arena` is NULL or valid for reads of `bytes` bytes nobody writes during `'a`.
unsafe fn view<'a>(
    arena: *const c_void,
    bytes: usize,
    scene: Scene<'a>,
) -> Result<(ProjArenaHeader, ProjHierarchy<'a>), CorayStatus> {
    let base = arena.cast::<u8>();
    check_arena(base)?;
    if bytes < PROJ_HEADER_BYTES {
        return Err(CorayStatus::CorruptArena);
    }
    // SAFETY: aligned, readable for at least one header.
    let h = unsafe { slice_ref::<ProjArenaHeader>(base, 0, 1)[0] };
    let l = h.layout(bytes)?;
    if scene_counts(&scene) != h.scene_counts || l.prim_rects < scene.prim_count() {
        return Err(CorayStatus::SceneMismatch);
    }
    // SAFETY: the layout lies within `bytes` (checked by layout()), offsets
    // are multiples of 16, and the arena is only read.
    let (nodes, refs, rects, prim_rects) = unsafe {
        (
            slice_ref::<BvhNode>(base, l.nodes_offset, l.nodes),
            slice_ref::<u32>(base, l.refs_offset, l.refs),
            slice_ref::<Rect>(base, l.rects_offset, l.nodes),
            slice_ref::<Rect>(base, l.prim_rects_offset, l.prim_rects),
        )
    };
    Ok((
        h,
        ProjHierarchy {
            bvh: Bvh {
                scene,
                nodes,
                refs,
                info: h.info,
            },
            rects,
            prim_rects,
            plane: h.plane(),
        },
    ))
}

/// What the hierarchy in `proj_arena` holds (O(1)).
///
/// # Safety
/// `proj_arena` is valid for reads of `proj_bytes`; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_info(
    proj_arena: *const c_void,
    proj_bytes: usize,
    out: *mut CorayProjInfo,
) -> CorayStatus {
    guard(|| {
        let base = proj_arena.cast::<u8>();
        check_arena(base)?;
        if proj_bytes < PROJ_HEADER_BYTES {
            return Err(CorayStatus::CorruptArena);
        }
        // SAFETY: aligned, readable for at least one header.
        let h = unsafe { slice_ref::<ProjArenaHeader>(base, 0, 1)[0] };
        let l = h.layout(proj_bytes)?;
        let i = &h.info;
        let stack = Bvh {
            scene: Scene::default(),
            nodes: &[],
            refs: &[],
            info: *i,
        }
        .stack_len();
        put(
            out,
            CorayProjInfo {
                builder: h.builder,
                criteria: h.criteria,
                node_count: i.node_count,
                object_count: i.ref_count,
                depth: i.depth,
                stack_bytes: stack * size_of::<bvh::BvhStackItem>(),
                arena_bytes_used: l.total_bytes,
                plane: plane_to_c(&h.plane()),
            },
        )
    })
}

/// Checks the hierarchy against `scene` (O(size)): the 3D side as
/// [`crate::coray_bvh_validate`] does, every rectangle the union of its
/// entries', every primitive's the projection of its box.
///
/// # Safety
/// As [`coray_proj_info`]; `scene` is valid.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_validate(
    proj_arena: *const c_void,
    proj_bytes: usize,
    scene: *const CorayScene,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract.
        let (_, t) = unsafe { view(proj_arena, proj_bytes, carve::scene(scene)?)? };
        // An R-tree's fill rule is not checked here: its m is not kept in
        // the arena, and tracing relies on the structure, boxes and
        // rectangles only.
        t.validate(None)?;
        Ok(())
    })
}

fn scheme(s: u32) -> Result<ProjScheme, CorayStatus> {
    match s {
        CORAY_PROJ_SCHEME_2D => Ok(ProjScheme::TwoD),
        CORAY_PROJ_SCHEME_3D => Ok(ProjScheme::ThreeD),
        CORAY_PROJ_SCHEME_COMBINATION => Ok(ProjScheme::Combination),
        _ => Err(CorayStatus::InvalidParameter),
    }
}

fn put_stats(out: *mut CorayProjStats, s: &ProjStats) -> Result<(), CorayStatus> {
    if out.is_null() {
        return Ok(());
    }
    let b = &s.bvh;
    put(
        out,
        CorayProjStats {
            bvh: CorayBvhStats {
                trace: b.trace.into(),
                box_tests: b.box_tests,
                box_cost: b.box_cost,
                prim_cost: b.prim_cost,
            },
            rect_tests: s.rect_tests,
        },
    )
}

/// Closest hits of `count` rays by `scheme_id` (`CORAY_PROJ_SCHEME_*`).
/// Every ray must lie on a line through the plane's eye: a camera ray that
/// starts at the eye, or a ray towards the eye that ends at it or before
/// (for an orthographic plane: against its direction). Otherwise nothing is
/// written and the status is `CORAY_STATUS_INVALID_PARAMETER`: trace such
/// rays through a 3D hierarchy. `stack` as for [`crate::coray_bvh_intersect`].
///
/// # Safety
/// As [`crate::coray_bvh_intersect`].
#[no_mangle]
pub unsafe extern "C" fn coray_proj_intersect(
    proj_arena: *const c_void,
    proj_bytes: usize,
    scene: *const CorayScene,
    scheme_id: u32,
    rays: *const CorayRay,
    hits: *mut CorayHit,
    count: usize,
    stack_mem: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayProjStats,
) -> CorayStatus {
    // SAFETY: forwarded caller contract.
    unsafe {
        batch(
            proj_arena,
            proj_bytes,
            scene,
            scheme_id,
            rays,
            hits,
            count,
            stack_mem,
            stack_bytes,
            stats,
            |t, r, sch, stk, st| t.intersect(r, sch, stk, st).map(Into::into),
        )
    }
}

/// Any-hit queries (shadow rays towards the plane's light), as
/// [`coray_proj_intersect`]: `occluded[i]` is 1 when something lies on
/// `rays[i]` within `[tnear, tfar]`.
///
/// # Safety
/// As [`coray_proj_intersect`], with `occluded` holding `count` bytes.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_occluded(
    proj_arena: *const c_void,
    proj_bytes: usize,
    scene: *const CorayScene,
    scheme_id: u32,
    rays: *const CorayRay,
    occluded: *mut u8,
    count: usize,
    stack_mem: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayProjStats,
) -> CorayStatus {
    // SAFETY: forwarded caller contract.
    unsafe {
        batch(
            proj_arena,
            proj_bytes,
            scene,
            scheme_id,
            rays,
            occluded,
            count,
            stack_mem,
            stack_bytes,
            stats,
            |t, r, sch, stk, st| t.occluded(r, sch, stk, st).map(u8::from),
        )
    }
}

/// The body of [`coray_proj_intersect`] and [`coray_proj_occluded`]: views
/// the arena, carves rays, answers, stack and statistics, refuses the
/// batch (writing nothing) when a ray does not pass the plane's eye, and
/// writes `answer` for each ray.
///
/// # Safety
/// As [`coray_proj_intersect`], with `out` holding `count` elements.
#[allow(clippy::too_many_arguments)]
unsafe fn batch<O>(
    proj_arena: *const c_void,
    proj_bytes: usize,
    scene: *const CorayScene,
    scheme_id: u32,
    rays: *const CorayRay,
    out: *mut O,
    count: usize,
    stack_mem: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayProjStats,
    answer: impl Fn(&ProjHierarchy, &Ray, ProjScheme, &mut [BvhStackItem], &mut ProjStats) -> Option<O>,
) -> CorayStatus {
    guard(|| {
        let s = scheme(scheme_id)?;
        // SAFETY: forwarded caller contract for every pointer.
        let (t, rays, out) = unsafe {
            (
                view(proj_arena, proj_bytes, carve::scene(scene)?)?.1,
                carve::input(rays, count)?,
                carve::output(out, count)?,
            )
        };
        // SAFETY: forwarded caller contract.
        let stk = unsafe { stack(&t.bvh, stack_mem, stack_bytes)? };
        if rays.iter().any(|r| t.project(&r.into()).is_none()) {
            return Err(CorayStatus::InvalidParameter);
        }
        let mut st = ProjStats::default();
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            // The rays were checked: a refusal here is a defect.
            *o = answer(&t, &r.into(), s, stk, &mut st).ok_or(CorayStatus::InternalError)?;
        }
        put_stats(stats, &st)
    })
}
