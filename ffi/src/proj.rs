//! `coray_proj_*`: projection hierarchies (Bezerianos 2001) for a camera or
//! a light plane: planes, parameters, requirements, build, open, info,
//! validate, intersect, occluded. One hierarchy per arena; a light cube is
//! six arenas.

use crate::abi::*;
use crate::bvh::{check_scene, scene_counts, CorayBvhBuilder, CorayBvhParams, Kind};
use crate::carve::{self, check_arena, Out, OutValue, Regions, Versioned};
use crate::cast::{camera, CorayCamera};
use crate::handle::{self, Handle, Sealed, KIND_PROJ};
use crate::one_ray::one_ray;
use crate::tracer::{self, CorayTracer};
use crate::{guard, CorayProj, CorayStatus};
use coray::bvh::layout::code;
use coray::bvh::{Bvh, BvhNode, BvhScratch, BvhStackItem};
use coray::limits::MAX_PRIMS;
use coray::proj::layout::{
    ProjArenaHeader, ProjArenaLayout, ProjScratchLayout, PROJ_HEADER_BYTES, PROJ_MAGIC,
    PROJ_VERSION,
};
use coray::proj::lights::{Light, LightPlanes};
use coray::proj::{
    Criteria, ProjBuilder, ProjHierarchy, ProjPlane, ProjScheme, ProjScratch, ProjStorage, Rect,
};
use coray::{Aabb, Accel, Ray, Scene, TraceStats, Vec3};
use core::ffi::c_void;
use core::mem::size_of;

/// What a projection hierarchy's structure is built on: `CORAY_PROJ_CRITERIA_*`.
pub type CorayProjCriteria = u32;
/// The primitives' rectangles on the plane.
pub const CORAY_PROJ_CRITERIA_2D: CorayProjCriteria = 0;
/// "Dummy": a 3D structure whose nodes carry their children's rectangles.
pub const CORAY_PROJ_CRITERIA_DUMMY: CorayProjCriteria = 1;

/// How a ray is tested against the nodes: `CORAY_PROJ_SCHEME_*`.
pub type CorayProjScheme = u32;
/// The ray's point in the node's rectangle (4 comparisons).
pub const CORAY_PROJ_SCHEME_2D: CorayProjScheme = 0;
/// The ray against the node's 3D box.
pub const CORAY_PROJ_SCHEME_3D: CorayProjScheme = 1;
/// The rectangle first, the 3D box when the rectangle holds the point.
pub const CORAY_PROJ_SCHEME_COMBINATION: CorayProjScheme = 2;

/// A projection: `CORAY_PLANE_PERSPECTIVE` or `CORAY_PLANE_ORTHOGRAPHIC`.
pub type CorayPlaneKind = u32;
/// A central projection.
pub const CORAY_PLANE_PERSPECTIVE: CorayPlaneKind = 0;
/// A parallel projection.
pub const CORAY_PLANE_ORTHOGRAPHIC: CorayPlaneKind = 1;

/// A light: `CORAY_LIGHT_POINT` or `CORAY_LIGHT_DIRECTIONAL`.
pub type CorayLightKind = u32;
/// A point light.
pub const CORAY_LIGHT_POINT: CorayLightKind = 0;
/// A directional light.
pub const CORAY_LIGHT_DIRECTIONAL: CorayLightKind = 1;

/// A projection plane. Get one from `coray_proj_camera_plane` or
/// `coray_proj_light_planes`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayProjPlane {
    /// `sizeof(CorayProjPlane)`.
    pub struct_size: usize,
    /// `CORAY_PLANE_*`.
    pub kind: CorayPlaneKind,
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
    /// `sizeof(CorayLight)`.
    pub struct_size: usize,
    /// `CORAY_LIGHT_*`.
    pub kind: CorayLightKind,
    /// Position or direction.
    pub v: [f32; 3],
}

/// Parameters of a projection build. Get them from `coray_proj_params_default`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayProjParams {
    /// `sizeof(CorayProjParams)`.
    pub struct_size: usize,
    /// `CORAY_PROJ_CRITERIA_*`.
    pub criteria: CorayProjCriteria,
    /// The builder and its settings (`leaf_size` is 1 here; `start_empty`
    /// must be 0); its own `struct_size` is set too.
    pub bvh: CorayBvhParams,
}

/// What a projection hierarchy holds, from `coray_proj_info` (O(1)).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayProjInfo {
    /// `sizeof(CorayProjInfo)`.
    pub struct_size: usize,
    /// `CORAY_BVH_BUILDER_*`.
    pub builder: CorayBvhBuilder,
    /// `CORAY_PROJ_CRITERIA_*`.
    pub criteria: CorayProjCriteria,
    /// Nodes in use.
    pub node_count: u32,
    /// Primitives in the hierarchy (2D criteria leave out those that
    /// project to nothing).
    pub ref_count: u32,
    /// Levels below the root.
    pub depth: u32,
    /// Bytes of the arena the layout covers.
    pub arena_bytes_used: usize,
    /// Bytes of traversal stack every trace and validate call needs.
    pub stack_bytes: usize,
    /// The plane (its `struct_size` set).
    pub plane: CorayProjPlane,
}

// SAFETY (all): repr(C), size_t struct_size first, integer and float
// fields (and nested structs of them) only; as first published.
unsafe impl Versioned for CorayProjPlane {
    const SIZE_1_0: usize = size_of::<Self>();
}
unsafe impl Versioned for CorayLight {
    const SIZE_1_0: usize = size_of::<Self>();
}
unsafe impl Versioned for CorayProjParams {
    const SIZE_1_0: usize = size_of::<Self>();
}
unsafe impl Versioned for CorayProjInfo {
    const SIZE_1_0: usize = size_of::<Self>();
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
        struct_size: size_of::<CorayProjPlane>(),
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

fn bounds(lo: &[f32; 3], hi: &[f32; 3]) -> Result<Aabb, CorayStatus> {
    let b = Aabb {
        min: v3(*lo),
        max: v3(*hi),
    };
    if !(b.min.is_finite() && b.max.is_finite()) {
        return Err(CorayStatus::InvalidParameter);
    }
    Ok(b)
}

/// The image plane of `camera` (a camera as `coray_kdtree_cast_image` takes it).
///
/// Safety: `camera` and `out` are NULL or valid pointers to their types.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_camera_plane(
    camera_in: *const CorayCamera,
    out: *mut CorayProjPlane,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: the caller passes valid pointers or NULL.
        let (cam, out) = unsafe {
            (
                camera(&carve::read(camera_in)?)?,
                Out::new(out, false, &mut regions)?,
            )
        };
        out.write(plane_to_c(&ProjPlane::camera(&cam)));
        Ok(())
    })
}

/// The planes of `light` for a scene inside `[bounds_min, bounds_max]`:
/// `*count` is 6 (a cube: the point light lies inside the box; face `k`
/// looks along +x, -x, +y, -y, +z, -z) or 1 (a point light outside it, a
/// directional light). `planes` holds 6 entries, each with `struct_size` set.
///
/// Safety: `light`, `bounds_min`, `bounds_max` are NULL or readable;
/// `planes` (6 entries) and `count` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_light_planes(
    light: *const CorayLight,
    bounds_min: *const [f32; 3],
    bounds_max: *const [f32; 3],
    planes: *mut CorayProjPlane,
    count: *mut u32,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract for each pointer.
        let (l, b) = unsafe {
            let lo = carve::input(bounds_min, 1)?;
            let hi = carve::input(bounds_max, 1)?;
            (
                light_from_c(&carve::read(light)?)?,
                bounds(
                    lo.first().ok_or(CorayStatus::NullPointer)?,
                    hi.first().ok_or(CorayStatus::NullPointer)?,
                )?,
            )
        };
        // SAFETY: the caller passes 6 writable planes or NULL.
        let out = unsafe { carve::output(planes, 6)? };
        regions.add(out.as_ptr(), size_of_val(out), true);
        let count = OutValue::new(count, false, &mut regions)?;
        regions.check()?;
        let lp = LightPlanes::new(l, &b);
        for (o, p) in out.iter_mut().zip(lp.planes.iter()) {
            *o = plane_to_c(p);
        }
        count.write(lp.count as u32);
        Ok(())
    })
}

/// Which of `light`'s planes (from `coray_proj_light_planes` with the same
/// bounds) the shadow ray `ray` uses; `CORAY_STATUS_INVALID_PARAMETER` when
/// the ray does not run towards the light (ending at it or before).
///
/// Safety: pointers NULL or valid for their types.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_light_plane_for(
    light: *const CorayLight,
    bounds_min: *const [f32; 3],
    bounds_max: *const [f32; 3],
    ray: *const CorayRay,
    plane_index: *mut u32,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract for each pointer.
        let (l, b, r) = unsafe {
            let lo = carve::input(bounds_min, 1)?;
            let hi = carve::input(bounds_max, 1)?;
            let r = carve::input(ray, 1)?;
            (
                light_from_c(&carve::read(light)?)?,
                bounds(
                    lo.first().ok_or(CorayStatus::NullPointer)?,
                    hi.first().ok_or(CorayStatus::NullPointer)?,
                )?,
                Ray::from(r.first().ok_or(CorayStatus::NullPointer)?),
            )
        };
        let out = OutValue::new(plane_index, false, &mut regions)?;
        let lp = LightPlanes::new(l, &b);
        let k = lp.plane_for(&r).ok_or(CorayStatus::InvalidParameter)?;
        out.write(k as u32);
        Ok(())
    })
}

/// Default parameters: `criteria` with `builder` and its defaults; unknown
/// values give `struct_size` 0, which every call refuses.
#[no_mangle]
pub extern "C" fn coray_proj_params_default(
    criteria: CorayProjCriteria,
    builder: CorayBvhBuilder,
) -> CorayProjParams {
    let bvh = crate::bvh::coray_bvh_params_default(builder);
    let ok = criteria <= CORAY_PROJ_CRITERIA_DUMMY && bvh.struct_size != 0;
    CorayProjParams {
        struct_size: if ok { size_of::<CorayProjParams>() } else { 0 },
        criteria,
        bvh,
    }
}

/// A `CorayProjInfo` to fill, `struct_size` set.
#[no_mangle]
pub extern "C" fn coray_proj_info_default() -> CorayProjInfo {
    CorayProjInfo {
        struct_size: size_of::<CorayProjInfo>(),
        ..Default::default()
    }
}

/// A `CorayProjPlane` to fill or set, `struct_size` set (the rest zero).
#[no_mangle]
pub extern "C" fn coray_proj_plane_default() -> CorayProjPlane {
    CorayProjPlane {
        struct_size: size_of::<CorayProjPlane>(),
        ..Default::default()
    }
}

/// A point light at the origin, `struct_size` set.
#[no_mangle]
pub extern "C" fn coray_light_default() -> CorayLight {
    CorayLight {
        struct_size: size_of::<CorayLight>(),
        ..Default::default()
    }
}

impl CorayProjParams {
    fn to_core(self) -> Result<(ProjBuilder, Criteria), CorayStatus> {
        if self.bvh.start_empty != 0 || self.bvh.struct_size < CorayBvhParams::SIZE_1_0 {
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
        Ok((b, criteria))
    }
}

/// Arena and scratch layouts for `n` primitives.
fn layouts(n: usize, b: &ProjBuilder) -> Result<(ProjArenaLayout, ProjScratchLayout), CorayStatus> {
    let too_many = CorayStatus::TooManyPrimitives;
    if n >= MAX_PRIMS {
        return Err(too_many);
    }
    let r = coray::proj::requirements(n, b);
    Ok((
        ProjArenaLayout::of_requirements(&r).ok_or(too_many)?,
        ProjScratchLayout::of(&r).ok_or(too_many)?,
    ))
}

/// Arena, scratch and stack sizes for a projection hierarchy over
/// `prim_count` primitives (the arena exactly).
///
/// Safety: `params` and `out` are NULL or valid pointers to their types.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_requirements(
    prim_count: usize,
    params: *const CorayProjParams,
    out: *mut CorayRequirements,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: the caller passes valid pointers or NULL.
        let ((b, _), out) = unsafe {
            (
                carve::read(params)?.to_core()?,
                Out::new(out, false, &mut regions)?,
            )
        };
        let (a, s) = layouts(prim_count, &b)?;
        let mut bvh_req = CorayRequirements {
            struct_size: size_of::<CorayRequirements>(),
            ..Default::default()
        };
        // SAFETY: the parameters were read above; bvh_req is a local.
        let st = unsafe {
            crate::bvh::coray_bvh_requirements(prim_count, &carve::read(params)?.bvh, &mut bvh_req)
        };
        if st != CorayStatus::Ok {
            return Err(st);
        }
        out.write(CorayRequirements {
            struct_size: 0,
            arena_min_bytes: a.total_bytes,
            arena_bytes: a.total_bytes,
            scratch_min_bytes: s.total_bytes,
            scratch_bytes: s.total_bytes,
            stack_bytes: bvh_req.stack_bytes,
        });
        Ok(())
    })
}

/// Builds the projection hierarchy of `scene` on `plane` into `arena`
/// (`arena_bytes` of the requirements, or more), with `scratch` as scratch.
/// Both 16-byte aligned, overlapping neither each other nor the scene;
/// `CORAY_STATUS_ARENA_TOO_SMALL` reports the bytes needed. The part of
/// the arena the layout covers is written entirely.
///
/// Safety: every pointer is NULL or valid for its documented size; the
/// arenas are not touched by anyone else during the call.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_build(
    scene: *const CorayScene,
    params: *const CorayProjParams,
    plane: *const CorayProjPlane,
    arena: *mut c_void,
    arena_bytes: usize,
    scratch: *mut c_void,
    scratch_bytes: usize,
    needed_bytes: *mut usize,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: the caller passes valid pointers or NULL.
        let (scene, p, pl) = unsafe {
            (
                carve::scene(scene, &mut regions)?,
                carve::read(params)?,
                plane_from_c(&carve::read(plane)?)?,
            )
        };
        let (builder, criteria) = p.to_core()?;
        let needed = OutValue::new(needed_bytes, true, &mut regions)?;
        let (base, sbase) = (arena.cast::<u8>(), scratch.cast::<u8>());
        check_arena(base)?;
        check_arena(sbase)?;
        let (a, sl) = layouts(scene.prim_count(), &builder)?;
        if arena_bytes < a.total_bytes {
            needed.write(a.total_bytes);
            return Err(CorayStatus::ArenaTooSmall);
        }
        if scratch_bytes < sl.total_bytes {
            needed.write(sl.total_bytes);
            return Err(CorayStatus::ArenaTooSmall);
        }
        regions
            .add(base, a.total_bytes, true)
            .add(sbase, sl.total_bytes, true)
            .check()?;
        scene.check()?;
        let c = &sl.bvh.counts;
        // SAFETY: both arenas passed check_arena; each layout lies within
        // its arena (checked above); parts are disjoint (layout formulas,
        // 16-aligned offsets) and the arenas overlap neither each other nor
        // the scene (Regions); the caller lends both exclusively.
        let (header, storage, scratch) = unsafe {
            carve::zero(base, a.total_bytes);
            (
                carve::arena_mut::<ProjArenaHeader>(base, 0, 1),
                ProjStorage {
                    nodes: carve::arena_mut::<BvhNode>(base, a.nodes_offset, a.nodes),
                    refs: carve::arena_mut::<u32>(base, a.refs_offset, a.refs),
                    rects: carve::arena_mut::<Rect>(base, a.rects_offset, a.nodes),
                    prim_rects: carve::arena_mut::<Rect>(base, a.prim_rects_offset, a.prim_rects),
                },
                ProjScratch {
                    bvh: BvhScratch {
                        boxes: carve::arena_mut::<Aabb>(sbase, 0, c.boxes),
                        keys: carve::arena_mut::<f32>(sbase, sl.bvh.keys_offset, c.keys),
                        links: carve::arena_mut::<u32>(sbase, sl.bvh.links_offset, c.links),
                        clusters: carve::arena_mut::<BvhNode>(
                            sbase,
                            sl.bvh.clusters_offset,
                            c.clusters,
                        ),
                    },
                    source: carve::arena_mut::<Aabb>(sbase, sl.source_offset, sl.source),
                    stack: carve::arena_mut::<u32>(sbase, sl.stack_offset, sl.stack),
                },
            )
        };
        let h = coray::proj::build(&scene, pl, builder, criteria, storage, scratch)?;
        let mut hd = ProjArenaHeader {
            magic: PROJ_MAGIC,
            version: PROJ_VERSION,
            builder: match builder {
                ProjBuilder::Static(b) => code::of_static(b),
                ProjBuilder::RTree(r) => code::of_rtree(&r),
            },
            criteria: p.criteria,
            scene_counts: scene_counts(&scene),
            info: *h.bvh().info(),
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

/// Opens the projection hierarchy in `arena` with the scene it was built
/// on: O(1) checks, then `*out` is the handle every other call takes. The
/// arena and the scene's arrays stay in place and unchanged while the
/// handle is used. Validate an arena from untrusted storage once.
///
/// Safety: `arena` is NULL or readable for `arena_bytes`; `scene` and
/// `out` NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_open(
    arena: *const c_void,
    arena_bytes: usize,
    scene: *const CorayScene,
    out: *mut CorayProj,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let scene = unsafe { carve::scene(scene, &mut regions)? };
        carve::check_array(out, 1)?;
        regions.add(out, size_of::<CorayProj>(), true);
        let base = arena.cast::<u8>();
        check_arena(base)?;
        if arena_bytes < PROJ_HEADER_BYTES {
            return Err(CorayStatus::CorruptArena);
        }
        regions.add(base, arena_bytes, false).check()?;
        // SAFETY: aligned, readable for at least one header.
        let h = unsafe { carve::arena_ref::<ProjArenaHeader>(base, 0, 1)[0] };
        let l = h.layout(arena_bytes)?;
        check_scene(h.scene_counts, &scene)?;
        if code::to_static(h.builder).is_none() && !code::is_rtree(h.builder) {
            return Err(CorayStatus::CorruptArena);
        }
        let mut hd = Handle::new(KIND_PROJ, base as usize, l.total_bytes, &scene);
        hd.set_part::<ProjArenaHeader>(0, 0, 1)?;
        hd.set_part::<BvhNode>(1, l.nodes_offset, l.nodes)?;
        hd.set_part::<u32>(2, l.refs_offset, l.refs)?;
        hd.set_part::<Rect>(3, l.rects_offset, l.nodes)?;
        hd.set_part::<Rect>(4, l.prim_rects_offset, l.prim_rects)?;
        let words = hd.words();
        // SAFETY: the handle describes the arena just checked, readable.
        unsafe { view_of(Sealed::new(&words, KIND_PROJ)?, scene)? };
        // SAFETY: out checked non-null, aligned, disjoint from the arena.
        unsafe { out.write(CorayProj { opaque: words }) };
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
) -> Result<(&'a ProjArenaHeader, ProjHierarchy<'a>), CorayStatus> {
    // SAFETY: the handle's parts lie within its arena (Handle::set_part
    // at open), readable by the caller's contract.
    unsafe {
        let header: &'a ProjArenaHeader = &h.part::<ProjArenaHeader>(0)[0];
        if header.plane_kind > 1 || !header.plane.iter().all(|x| x.is_finite()) {
            return Err(CorayStatus::CorruptArena);
        }
        let b = Bvh::from_parts(scene, h.part::<BvhNode>(1), h.part::<u32>(2), header.info)?;
        let p = ProjHierarchy::from_parts(b, h.part::<Rect>(3), h.part::<Rect>(4), header.plane())?;
        Ok((header, p))
    }
}

/// The hierarchy behind a caller's handle, its buffers noted in `regions`.
///
/// Safety: `t` is NULL or a handle `coray_proj_open` filled, whose arena
/// and scene are still in place and unchanged during `'a`.
unsafe fn open<'a>(
    t: *const CorayProj,
    regions: &mut Regions,
) -> Result<(&'a ProjArenaHeader, ProjHierarchy<'a>), CorayStatus> {
    // SAFETY: forwarded contract.
    unsafe {
        let h = handle::read(t.cast(), KIND_PROJ, regions)?;
        regions.add(h.arena() as *const u8, h.arena_bytes(), false);
        let scene = h.scene();
        regions.add_scene(&scene);
        view_of(h, scene)
    }
}

/// What the hierarchy holds (O(1)).
///
/// Safety: `proj` is a handle `coray_proj_open` filled; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_info(
    proj: *const CorayProj,
    out: *mut CorayProjInfo,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let ((h, p), out) = unsafe {
            (
                open(proj, &mut regions)?,
                Out::new(out, false, &mut regions)?,
            )
        };
        regions.check()?;
        let i = p.bvh().info();
        out.write(CorayProjInfo {
            struct_size: 0,
            builder: h.builder,
            criteria: h.criteria,
            node_count: i.node_count,
            ref_count: i.ref_count,
            depth: i.depth,
            arena_bytes_used: h.layout_bytes as usize,
            stack_bytes: p.stack_len().saturating_mul(size_of::<BvhStackItem>()),
            plane: plane_to_c(p.plane()),
        });
        Ok(())
    })
}

/// Checks the hierarchy against its scene in linear time, never crashing:
/// the 3D side as `coray_bvh_validate` does (an R-tree's fill rule aside:
/// its m is not kept), every rectangle the union of its entries', every
/// primitive's the projection of its box. `stack` as for the trace calls;
/// `out` may be NULL.
///
/// Safety: as `coray_proj_info`; `stack` writable for `stack_bytes`.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_validate(
    proj: *const CorayProj,
    stack: *mut c_void,
    stack_bytes: usize,
    out: *mut CorayShape,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let ((_, p), out) = unsafe {
            (
                open(proj, &mut regions)?,
                Out::new(out, true, &mut regions)?,
            )
        };
        // SAFETY: forwarded caller contract: a writable stack.
        let stk = unsafe {
            carve::stack::<BvhStackItem>(stack, stack_bytes, p.stack_len(), &mut regions)?
        };
        regions.check()?;
        let s = Accel::validate(&p, stk)?;
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

fn scheme(s: CorayProjScheme) -> Result<ProjScheme, CorayStatus> {
    match s {
        CORAY_PROJ_SCHEME_2D => Ok(ProjScheme::TwoD),
        CORAY_PROJ_SCHEME_3D => Ok(ProjScheme::ThreeD),
        CORAY_PROJ_SCHEME_COMBINATION => Ok(ProjScheme::Combination),
        _ => Err(CorayStatus::InvalidParameter),
    }
}

/// The body of every trace entry point: checks the handle, the arrays, the
/// stack, the statistics and that every ray lies on a line through the
/// plane's eye, before anything is written; then writes `answer` per ray.
///
/// Safety: as `coray_proj_intersect`, with `out` holding `count` `O`s.
#[allow(clippy::too_many_arguments)]
unsafe fn batch<O>(
    proj: *const CorayProj,
    scheme_id: CorayProjScheme,
    rays: *const CorayRay,
    out: *mut O,
    count: usize,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
    answer: impl Fn(&ProjHierarchy, &Ray, ProjScheme, &mut [BvhStackItem], &mut TraceStats) -> Option<O>,
) -> CorayStatus {
    guard(|| {
        let s = scheme(scheme_id)?;
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract for every pointer.
        let (p, rays, out, stk, stats) = unsafe {
            let (_, p) = open(proj, &mut regions)?;
            let rays = carve::input(rays, count)?;
            regions.add(rays.as_ptr(), size_of_val(rays), false);
            let out = carve::output(out, count)?;
            regions.add(out.as_ptr(), size_of_val(out), true);
            let need = if count == 0 { 0 } else { p.stack_len() };
            let stk = carve::stack::<BvhStackItem>(stack, stack_bytes, need, &mut regions)?;
            (p, rays, out, stk, Out::new(stats, true, &mut regions)?)
        };
        regions.check()?;
        if rays.iter().any(|r| p.project(&r.into()).is_none()) {
            return Err(CorayStatus::InvalidParameter);
        }
        let mut st = TraceStats::default();
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            // Every ray was checked: a refusal here would be a defect.
            *o = answer(&p, &r.into(), s, stk, &mut st).ok_or(CorayStatus::InternalError)?;
            // A corrupt arena: the call stops at the first ray that met it.
            if st.faults > 0 {
                return Err(CorayStatus::CorruptArena);
            }
        }
        stats.write(CorayTraceStats::of(&st));
        Ok(())
    })
}

/// The body of the one-ray entry points: [`one_ray`] on a projection
/// hierarchy, by `scheme_id`; the ray must lie on a line through the
/// plane's eye (checked after the buffers, as the array call does).
///
/// Safety: as `coray_proj_intersect1`, with `out` one writable `O`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
unsafe fn one<O>(
    proj: *const CorayProj,
    scheme_id: CorayProjScheme,
    ray: *const CorayRay,
    out: *mut O,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
    answer: impl FnOnce(
        &ProjHierarchy,
        &Ray,
        ProjScheme,
        &mut [BvhStackItem],
        &mut TraceStats,
    ) -> Option<O>,
) -> CorayStatus {
    guard(|| {
        let sc = scheme(scheme_id)?;
        // SAFETY: forwarded caller contract.
        unsafe {
            one_ray(
                proj.cast(),
                KIND_PROJ,
                |h, s| Ok(view_of(h, s)?.1),
                |p| p.stack_len(),
                ray,
                out,
                stack,
                stack_bytes,
                stats,
                |p, r, s, st| {
                    if p.project(r).is_none() {
                        return Err(CorayStatus::InvalidParameter);
                    }
                    // Checked above: a refusal here would be a defect.
                    answer(p, r, sc, s, st).ok_or(CorayStatus::InternalError)
                },
            )
        }
    })
}

/// Closest hits of `count` rays by `scheme`. Every ray must lie on a line
/// through the plane's eye: a camera ray that starts at the eye, or a ray
/// towards the eye that ends at it or before (for an orthographic plane:
/// against its direction). Otherwise nothing is written and the status is
/// `CORAY_STATUS_INVALID_PARAMETER`: trace such rays through a 3D
/// hierarchy. `stack` and `stats` as for `coray_bvh_intersect`.
///
/// Safety: as `coray_bvh_intersect`, with `proj` a handle `coray_proj_open` filled.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_intersect(
    proj: *const CorayProj,
    scheme: CorayProjScheme,
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
            proj,
            scheme,
            rays,
            hits,
            count,
            stack,
            stack_bytes,
            stats,
            |p, r, s, stk, st| p.intersect(r, s, stk, st).map(Into::into),
        )
    }
}

/// `coray_proj_intersect` for one ray, checked in full on every call. A thread
/// tracing one ray per call makes a tracer (`coray_proj_tracer`) and calls
/// `coray_proj_tracer_intersect1`: the same answer, the checks made once.
///
/// Safety: as `coray_proj_intersect` with `count` 1.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_intersect1(
    proj: *const CorayProj,
    scheme: CorayProjScheme,
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
        one(
            proj,
            scheme,
            ray,
            hit,
            stack,
            stack_bytes,
            stats,
            |p, r, sc, s, st| p.intersect(r, sc, s, st).map(Into::into),
        )
    }
}

/// Any-hit queries (shadow rays towards the plane's light), as
/// `coray_proj_intersect`: `occluded[i]` is 1 when something lies on
/// `rays[i]` within `[tnear, tfar]`.
///
/// Safety: as `coray_proj_intersect`, with `occluded` holding `count` bytes.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_occluded(
    proj: *const CorayProj,
    scheme: CorayProjScheme,
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
            proj,
            scheme,
            rays,
            occluded,
            count,
            stack,
            stack_bytes,
            stats,
            |p, r, s, stk, st| p.occluded(r, s, stk, st).map(u8::from),
        )
    }
}

/// `coray_proj_occluded` for one ray, checked in full on every call. A thread
/// tracing one ray per call makes a tracer (`coray_proj_tracer`) and calls
/// `coray_proj_tracer_occluded1`: the same answer, the checks made once.
///
/// Safety: as `coray_proj_occluded` with `count` 1.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_occluded1(
    proj: *const CorayProj,
    scheme: CorayProjScheme,
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
            proj,
            scheme,
            ray,
            occluded,
            stack,
            stack_bytes,
            stats,
            |p, r, sc, s, st| p.occluded(r, sc, s, st).map(u8::from),
        )
    }
}

/// Makes `tracer` trace `proj` by `scheme` with the caller's `stack` (at
/// least the info's `stack_bytes`, 16-byte aligned): one thread's
/// `coray_proj_tracer_intersect1` and `_occluded1` calls then skip the checks
/// this call makes; each ray must lie on a line through the plane's eye,
/// as for `coray_proj_intersect1`. Since 1.5.
///
/// Safety: `proj` as in `coray_proj_info`; `stack` NULL or writable for
/// `stack_bytes`, and used by nothing else while the tracer is; `tracer`
/// NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_tracer(
    proj: *const CorayProj,
    scheme_id: CorayProjScheme,
    stack: *mut c_void,
    stack_bytes: usize,
    tracer: *mut CorayTracer,
) -> CorayStatus {
    guard(|| {
        scheme(scheme_id)?;
        // SAFETY: forwarded caller contract.
        unsafe {
            tracer::make::<_, BvhStackItem>(
                tracer,
                proj.cast(),
                KIND_PROJ,
                scheme_id as u64,
                |h, s| Ok(view_of(h, s)?.1),
                |p| p.stack_len(),
                |_| [0; tracer::HINT_WORDS],
                stack,
                stack_bytes,
            )
        }
    })
}

/// `coray_proj_tracer_intersect1` and `_occluded1` on a projection
/// hierarchy's tracer: `answer` for the ray, which must lie on a line
/// through the plane's eye.
///
/// Safety: as `coray_proj_tracer_intersect1`, with `out` one writable `O`.
#[inline(always)]
unsafe fn traced<O>(
    tracer: *mut CorayTracer,
    ray: *const CorayRay,
    out: *mut O,
    answer: impl FnOnce(
        &ProjHierarchy,
        &Ray,
        ProjScheme,
        &mut [BvhStackItem],
        &mut TraceStats,
    ) -> Option<O>,
) -> Result<(), CorayStatus> {
    // SAFETY: forwarded caller contract.
    unsafe {
        tracer::trace(
            tracer,
            KIND_PROJ,
            #[inline(always)]
            |h, s, _| Ok(view_of(h, s)?.1),
            #[inline(always)]
            |p| p.stack_len(),
            ray,
            out,
            |_, _, _| None,
            #[inline(always)]
            |p, m, r, s, st| {
                let sc = scheme(m as CorayProjScheme)?;
                if p.project(r).is_none() {
                    return Err(CorayStatus::InvalidParameter);
                }
                // Checked above: a refusal here would be a defect.
                answer(p, r, sc, s, st).ok_or(CorayStatus::InternalError)
            },
        )
    }
}

/// The closest hit of `ray` by a tracer of this projection hierarchy (made by
/// `coray_proj_tracer`), into `hit`: `coray_proj_intersect1`'s answer, with
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
pub unsafe extern "C" fn coray_proj_tracer_intersect1(
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
                |p, r, sc, s, st| p.intersect(r, sc, s, st).map(Into::into),
            )
        }
    })
}

/// Whether something lies on `ray` within `[tnear, tfar]` (1) or not (0),
/// by a tracer of this projection hierarchy, into `occluded`: `coray_proj_occluded1`'s
/// answer. Otherwise as `coray_proj_tracer_intersect1`. Since 1.5.
///
/// Safety: as `coray_proj_tracer_intersect1`, with `occluded` one writable
/// byte.
#[no_mangle]
pub unsafe extern "C" fn coray_proj_tracer_occluded1(
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
                |p, r, sc, s, st| p.occluded(r, sc, s, st).map(u8::from),
            )
        }
    })
}
