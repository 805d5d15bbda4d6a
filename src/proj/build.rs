//! Building a projection hierarchy in caller memory: project every
//! primitive's box, build the structure (on the rectangles or on the 3D
//! boxes), then refit so that every node holds both the union of its
//! entries' 3D boxes and the union of their rectangles.

use super::{Criteria, ProjBuilder, ProjHierarchy, ProjPlane, Rect};
use crate::bvh::{self, Bvh, BvhNode, BvhScratch, BvhStorage, RTree};
use crate::geom::{Aabb, Scene};
use crate::Error;

/// Slices a projection hierarchy over `prim_count` primitives needs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProjRequirements {
    /// [`BvhNode`] slots (kept).
    pub nodes: usize,
    /// References (kept).
    pub refs: usize,
    /// Node rectangles (kept): one per node slot.
    pub rects: usize,
    /// Primitive rectangles (kept): one per primitive.
    pub prim_rects: usize,
    /// Scratch of the builder ([`bvh::requirements`]; empty for R-trees).
    pub bvh_scratch: bvh::BvhRequirements,
    /// Scratch: a box per primitive (the flat boxes of 2D criteria).
    pub source: usize,
    /// Scratch `u32`s: the refit's stack, an R-tree's insertion order.
    pub stack: usize,
}

/// Room for a projection hierarchy over `prim_count` primitives.
pub fn requirements(prim_count: usize, builder: &ProjBuilder) -> ProjRequirements {
    let (nodes, refs, bvh_scratch, order) = match builder {
        ProjBuilder::Static(b) => {
            let r = bvh::requirements(prim_count, *b);
            (r.nodes, r.refs, r, 0)
        }
        ProjBuilder::RTree(p) => {
            let r = bvh::RTree::requirements(prim_count, p);
            (r.nodes, r.refs, bvh::BvhRequirements::default(), r.scratch)
        }
    };
    ProjRequirements {
        nodes,
        refs,
        rects: nodes,
        prim_rects: prim_count,
        bvh_scratch,
        source: prim_count,
        stack: (2 * nodes).max(order),
    }
}

/// Where a projection hierarchy lives.
pub struct ProjStorage<'a> {
    /// At least [`ProjRequirements::nodes`].
    pub nodes: &'a mut [BvhNode],
    /// At least [`ProjRequirements::refs`].
    pub refs: &'a mut [u32],
    /// At least [`ProjRequirements::rects`].
    pub rects: &'a mut [Rect],
    /// At least [`ProjRequirements::prim_rects`].
    pub prim_rects: &'a mut [Rect],
}

/// Build scratch; free to reuse once the build returns.
pub struct ProjScratch<'s> {
    /// The builder's scratch (at least [`ProjRequirements::bvh_scratch`]).
    pub bvh: BvhScratch<'s>,
    /// At least [`ProjRequirements::source`].
    pub source: &'s mut [Aabb],
    /// At least [`ProjRequirements::stack`].
    pub stack: &'s mut [u32],
}

fn need(slice: &'static str, needed: usize, got: usize) -> Result<(), Error> {
    if got < needed {
        return Err(Error::SliceTooSmall { slice, needed, got });
    }
    Ok(())
}

/// Builds a projection hierarchy of `scene` on `plane` with `builder`
/// over `criteria`.
pub fn build<'a>(
    scene: &Scene<'a>,
    plane: ProjPlane,
    builder: ProjBuilder,
    criteria: Criteria,
    storage: ProjStorage<'a>,
    scratch: ProjScratch,
) -> Result<ProjHierarchy<'a>, Error> {
    let n = scene.prim_count();
    let req = requirements(n, &builder);
    need("rects", req.rects, storage.rects.len())?;
    need("prim_rects", req.prim_rects, storage.prim_rects.len())?;
    need("source", req.source, scratch.source.len())?;
    need("stack", req.stack, scratch.stack.len())?;
    let ProjStorage {
        nodes,
        refs,
        rects,
        prim_rects,
    } = storage;
    let ProjScratch { bvh, source, stack } = scratch;
    for p in 0..n {
        let b = scene.prim_bounds(p);
        prim_rects[p] = b.map_or(Rect::EMPTY, |b| plane.project_box(&b));
        source[p] = match b {
            Some(_) => prim_rects[p].as_flat_box(),
            None => Aabb::EMPTY,
        };
    }
    let source = (criteria == Criteria::TwoD).then_some(&source[..n]);
    let info = match builder {
        ProjBuilder::Static(b) => {
            let storage = BvhStorage {
                nodes: &mut nodes[..],
                refs: &mut refs[..],
            };
            bvh::build_over(scene, source, b, 1, storage, bvh)?.info
        }
        ProjBuilder::RTree(p) => {
            let t = RTree::build_over(scene, source, p, &mut nodes[..], &mut refs[..], stack)?;
            t.bvh().info
        }
    };
    refit(scene, nodes, refs, rects, prim_rects, info.root, stack);
    Ok(ProjHierarchy {
        bvh: Bvh {
            scene: *scene,
            nodes,
            refs,
            info,
        },
        rects,
        prim_rects,
        plane,
    })
}

/// Sets every node reachable from `root` to the union of its entries' 3D
/// boxes and of their rectangles (post-order on `stack`: a node is pushed
/// once to open it and once, marked, to close it).
fn refit(
    scene: &Scene,
    nodes: &mut [BvhNode],
    refs: &[u32],
    rects: &mut [Rect],
    prim_rects: &[Rect],
    root: u32,
    stack: &mut [u32],
) {
    const CLOSE: u32 = 1 << 31;
    stack[0] = root;
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let item = stack[sp];
        let i = (item & !CLOSE) as usize;
        let nd = nodes[i];
        if nd.is_leaf() {
            let mut b = Aabb::EMPTY;
            let mut r = Rect::EMPTY;
            for &p in &refs[nd.first as usize..(nd.first + nd.len()) as usize] {
                b = b.union(&scene.prim_bounds(p as usize).unwrap_or(Aabb::EMPTY));
                r = r.union(&prim_rects[p as usize]);
            }
            nodes[i].set_bounds(&b);
            rects[i] = r;
        } else if item & CLOSE != 0 {
            let mut b = Aabb::EMPTY;
            let mut r = Rect::EMPTY;
            for c in nd.first..nd.first + nd.len() {
                b = b.union(&nodes[c as usize].bounds());
                r = r.union(&rects[c as usize]);
            }
            nodes[i].set_bounds(&b);
            rects[i] = r;
        } else {
            stack[sp] = item | CLOSE;
            sp += 1;
            for c in nd.first..nd.first + nd.len() {
                stack[sp] = c;
                sp += 1;
            }
        }
    }
}

impl ProjHierarchy<'_> {
    /// [`Bvh::validate`] of the 3D side (`min_children` for R-trees) on
    /// the caller's `stack`, and every node's rectangle is the union of its
    /// entries' rectangles, each primitive's that of its box on the plane.
    /// Never panics; linear time.
    pub fn validate(
        &self,
        min_children: Option<u32>,
        stack: &mut [bvh::BvhStackItem],
    ) -> Result<bvh::BvhTreeStats, Error> {
        let corrupt = |what| Err(Error::Corrupt { what });
        let scene = &self.bvh.scene;
        if self.prim_rects.len() < scene.prim_count() || self.rects.len() < self.bvh.nodes.len() {
            return corrupt("rectangle slices");
        }
        for p in 0..scene.prim_count() {
            let want = scene
                .prim_bounds(p)
                .map_or(Rect::EMPTY, |b| self.plane.project_box(&b));
            if want != self.prim_rects[p] {
                return corrupt("primitive rectangle differs from its projection");
            }
        }
        let mismatch = Error::Corrupt {
            what: "node rectangle differs from the union of its entries'",
        };
        self.bvh.validate_with(min_children, stack, |i, nd| {
            let mut r = Rect::EMPTY;
            if nd.is_leaf() {
                for &p in self.bvh.leaf_refs(nd).ok_or(mismatch)? {
                    r = r.union(self.prim_rects.get(p as usize).ok_or(mismatch)?);
                }
            } else {
                for c in self.bvh.children(nd).ok_or(mismatch)? {
                    r = r.union(&self.rects[c as usize]);
                }
            }
            let own = &self.rects[i as usize];
            if r == *own || (r.is_empty() && own.is_empty()) {
                Ok(())
            } else {
                Err(mismatch)
            }
        })
    }
}
