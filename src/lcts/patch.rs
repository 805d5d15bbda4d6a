//! Patch-to-patch visibility (section 5.1): the segments between two convex
//! patches form a shaft whose boundary rays are the segments between their
//! vertices. One HLCTS built from those starts every segment between the
//! patches: along its leading leaves, then by ropes guided by the boundary
//! segment nearest to it (the one between the sample points' nearest
//! vertices). The visible fraction is the share of sample segments that
//! meet nothing.

use super::history::{trace_recorded_on, History, HistoryRecord};
use super::hlcts::{self, Boundary, HlctsEntry, Source, MAX_RAYS};
use crate::geom::{Hit, Ray, Vec3};
use crate::kd::{KdStackItem, KdTree, KD_STACK_LEN};
use crate::limits::MAX_PATCH_SAMPLES_PER_SIDE;
use crate::{Error, TraceStats};

/// Most vertices of a patch (a convex polygon): 4, so that the vertex pairs
/// fit [`MAX_RAYS`].
pub const MAX_PATCH_VERTICES: usize = 4;

/// Caller memory for [`patch_visibility`].
pub struct PatchScratch<'b> {
    /// Histories of the boundary segments: `a.len() * b.len()` slots of equal size.
    pub records: &'b mut [HistoryRecord],
    /// The cut: `MAX_RAYS` times a history slot's records never runs out.
    pub hlcts: &'b mut [HlctsEntry],
    /// The boundary segments' paths past the cut's leading leaves: as many
    /// `u32` as `records` has records (fewer only guides less).
    pub paths: &'b mut [u32],
    /// The traversal stack, [`KD_STACK_LEN`] entries.
    pub stack: &'b mut [KdStackItem],
}

/// What a visibility query found and did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PatchVisibility {
    /// Sample segments that meet nothing.
    pub visible: u32,
    /// Sample segments cast.
    pub samples: u32,
    /// Entries of the cut.
    pub cut_len: u32,
    /// Work of the boundary segments (tracing them to build the cut).
    pub boundary: TraceStats,
    /// Work of the sample segments.
    pub trace: TraceStats,
}

impl PatchVisibility {
    /// The visible fraction.
    pub fn fraction(&self) -> f64 {
        if self.samples == 0 {
            0.0
        } else {
            self.visible as f64 / self.samples as f64
        }
    }
}

/// The segment from `p` to `q`, without its ends (`eps` of its length
/// trimmed at each end, so the patches themselves do not occlude it).
pub fn segment(p: Vec3, q: Vec3, eps: f32) -> Ray {
    Ray::new(p, q - p, eps, 1.0 - eps)
}

/// The point of convex polygon `poly` at barycentric-like weights: `u`
/// along the first edge fan, `v` across (a bilinear map for quads, the
/// triangle map for triangles). Inside the polygon for u, v in [0, 1].
pub fn patch_point(poly: &[Vec3], u: f32, v: f32) -> Vec3 {
    match poly.len() {
        3 => poly[0] + (poly[1] - poly[0]) * (u * (1.0 - v)) + (poly[2] - poly[0]) * (u * v),
        _ => {
            let a = poly[0].lerp(poly[1], u);
            let b = poly[3].lerp(poly[2], u);
            a.lerp(b, v)
        }
    }
}

/// The vertex of a polygon of `n` vertices nearest (in [`patch_point`]'s
/// parameters) to the point at `u`, `v`.
fn nearest_vertex(n: usize, u: f32, v: f32) -> usize {
    match (n, u < 0.5, v < 0.5) {
        (3, true, _) => 0,
        (3, false, true) => 1,
        (3, false, false) => 2,
        (_, true, true) => 0,
        (_, false, true) => 1,
        (_, false, false) => 2,
        (_, true, false) => 3,
    }
}

/// Visibility between convex patches `a` and `b` (3 or 4 vertices each)
/// along `n x n` sample points on each (n^4 segments), every segment
/// trimmed by `eps` at its ends. The segments start from the HLCTS of the
/// vertex-to-vertex segments; each one's answer is exactly what
/// hierarchical traversal of that segment gives. The tree needs ropes
/// ([`Error::NoRopes`] otherwise).
pub fn patch_visibility(
    tree: &KdTree,
    a: &[Vec3],
    b: &[Vec3],
    n: u32,
    eps: f32,
    scratch: PatchScratch,
) -> Result<PatchVisibility, Error> {
    if !tree.info().has_ropes() {
        return Err(Error::NoRopes);
    }
    for p in [a, b] {
        if !(3..=MAX_PATCH_VERTICES).contains(&p.len()) || p.iter().any(|v| !v.is_finite()) {
            return Err(Error::InvalidParameter { name: "patch" });
        }
    }
    if !(0.0..0.5).contains(&eps) {
        return Err(Error::InvalidParameter { name: "eps" });
    }
    if n == 0 || n > MAX_PATCH_SAMPLES_PER_SIDE {
        return Err(Error::InvalidParameter {
            name: "samples_per_side",
        });
    }
    if scratch.stack.len() < KD_STACK_LEN {
        return Err(Error::SliceTooSmall {
            slice: "stack",
            needed: KD_STACK_LEN,
            got: scratch.stack.len(),
        });
    }
    let k = a.len() * b.len();
    let cap = scratch.records.len() / k;
    if cap == 0 {
        return Err(Error::SliceTooSmall {
            slice: "records",
            needed: k,
            got: scratch.records.len(),
        });
    }
    let mut out = PatchVisibility::default();
    let stack = scratch.stack;
    // The boundary segments, traced from the root with their histories.
    let mut lens = [(0usize, false, Hit::MISS); MAX_RAYS];
    let mut rays = [Ray::new(Vec3::ZERO, Vec3::X, 0.0, 1.0); MAX_RAYS];
    for (j, slot) in scratch.records.chunks_mut(cap).enumerate().take(k) {
        let (ia, ib) = (j / b.len(), j % b.len());
        rays[j] = segment(a[ia], b[ib], eps);
        let mut h = History::new(slot);
        trace_recorded_on(tree, &rays[j], &mut h, stack, &mut out.boundary, true);
        lens[j] = (h.len, h.overflow, h.hit);
    }
    let records: &[HistoryRecord] = scratch.records;
    let bounds: [Boundary; MAX_RAYS] = core::array::from_fn(|j| {
        let (len, overflow, hit) = lens[j];
        let recs = records
            .get(j * cap..j * cap + len)
            .filter(|_| !overflow && j < k);
        Boundary {
            ray: rays[j],
            records: recs,
            source: Source::Parent(j),
            hit,
        }
    });
    let root = [hlcts::root_entry(tree)];
    let cut = hlcts::build(tree, &root, &bounds[..k], scratch.hlcts);
    out.cut_len = cut.len as u32;
    let histories: [Option<&[HistoryRecord]>; MAX_RAYS] =
        core::array::from_fn(|j| bounds[j].records);
    let paths = cut.paths(&histories[..k], scratch.paths);
    let step = |i: u32| {
        if n <= 1 {
            0.5
        } else {
            i as f32 / (n - 1) as f32
        }
    };
    for ia in 0..n * n {
        let (ua, va) = (step(ia % n), step(ia / n));
        let p = patch_point(a, ua, va);
        for ib in 0..n * n {
            let (ub, vb) = (step(ib % n), step(ib / n));
            let q = patch_point(b, ub, vb);
            let nearest =
                nearest_vertex(a.len(), ua, va) * b.len() + nearest_vertex(b.len(), ub, vb);
            let hit = hlcts::trace_guided(
                tree,
                &cut,
                &paths,
                nearest,
                &segment(p, q, eps),
                stack,
                &mut out.trace,
            );
            out.samples += 1;
            out.visible += !hit.is_hit() as u32;
        }
    }
    Ok(out)
}
