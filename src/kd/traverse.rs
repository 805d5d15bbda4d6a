//! Hierarchical traversal after Havran's TA_B^rec and rope traversal, for
//! closest hit and any hit. The method is chosen once per call, outside the
//! ray loop; each walk is generic over what a leaf visit does, so closest
//! and any hit share one walk without a branch on the query kind.

use super::node::{KdNode, KD_MAX_DEPTH, NO_NODE};
use super::KdTree;
use crate::geom::{Hit, PreparedRay, Ray, Scene, Vec3};
use crate::TraceStats;

/// How a ray walks the tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Traversal {
    /// Stack traversal with signed entry and exit distances (Havran's
    /// TA_B^rec). The stack lives on the call stack and holds
    /// `2 * KD_MAX_DEPTH + 4` exit points: enough for any tree.
    Hierarchical,
    /// Leaf to leaf through the six ropes of each leaf; no stack. A ray
    /// that lies exactly in a split plane it must cross falls back to
    /// hierarchical traversal (both sides of the plane hold its hits).
    Ropes,
}

/// What happens at a leaf: test its primitives; return true to stop.
trait LeafVisitor {
    fn ray(&self) -> &PreparedRay;
    fn visit(&mut self, scene: &Scene, refs: &[u32], exit_t: f32) -> bool;
}

struct Closest {
    ray: PreparedRay,
    best: Hit,
    tests: u64,
}

impl LeafVisitor for Closest {
    fn ray(&self) -> &PreparedRay {
        &self.ray
    }
    #[inline]
    fn visit(&mut self, scene: &Scene, refs: &[u32], exit_t: f32) -> bool {
        for &p in refs {
            self.tests += 1;
            let t_max = if self.best.is_hit() {
                self.best.t
            } else {
                self.ray.t_max
            };
            if let Some(h) = scene.intersect_prim(p as usize, &self.ray, t_max) {
                self.best = h;
            }
        }
        self.best.is_hit() && self.best.t <= exit_t
    }
}

struct Any {
    ray: PreparedRay,
    hit: bool,
    tests: u64,
}

impl LeafVisitor for Any {
    fn ray(&self) -> &PreparedRay {
        &self.ray
    }
    #[inline]
    fn visit(&mut self, scene: &Scene, refs: &[u32], _exit_t: f32) -> bool {
        for &p in refs {
            self.tests += 1;
            if scene
                .intersect_prim(p as usize, &self.ray, self.ray.t_max)
                .is_some()
            {
                self.hit = true;
                return true;
            }
        }
        false
    }
}

/// An exit point of TA_B^rec: the node to visit after the current segment,
/// the signed distance and the point where the segment ends.
#[derive(Clone, Copy)]
struct ExitPoint {
    node: u32,
    t: f32,
    p: Vec3,
}

/// Marks an exit point pushed only to end a segment that is then
/// restarted (a ray lying in a split plane visits both children).
const SKIP: u32 = NO_NODE - 1;
const STACK_SIZE: usize = 2 * KD_MAX_DEPTH as usize + 4;

impl<'a> KdTree<'a> {
    /// Closest hit of `ray`, or [`Hit::MISS`]. Adds its work to `stats`.
    pub fn intersect(&self, ray: &Ray, method: Traversal, stats: &mut TraceStats) -> Hit {
        stats.rays += 1;
        if !ray.is_valid() {
            return Hit::MISS;
        }
        let mut v = Closest {
            ray: PreparedRay::new(ray),
            best: Hit::MISS,
            tests: 0,
        };
        match method {
            Traversal::Hierarchical => self.walk_hierarchical(&mut v, stats),
            Traversal::Ropes => self.walk_ropes(&mut v, stats),
        }
        stats.prim_tests += v.tests;
        v.best
    }

    /// True when anything lies on `ray` within `[t_min, t_max]`.
    pub fn occluded(&self, ray: &Ray, method: Traversal, stats: &mut TraceStats) -> bool {
        stats.rays += 1;
        if !ray.is_valid() {
            return false;
        }
        let mut v = Any {
            ray: PreparedRay::new(ray),
            hit: false,
            tests: 0,
        };
        match method {
            Traversal::Hierarchical => self.walk_hierarchical(&mut v, stats),
            Traversal::Ropes => self.walk_ropes(&mut v, stats),
        }
        stats.prim_tests += v.tests;
        v.hit
    }

    /// Closest hits of many rays; `hits` must be as long as `rays`.
    pub fn intersect_many(
        &self,
        rays: &[Ray],
        hits: &mut [Hit],
        method: Traversal,
        stats: &mut TraceStats,
    ) {
        for (r, h) in rays.iter().zip(hits.iter_mut()) {
            *h = self.intersect(r, method, stats);
        }
    }

    /// Any-hit answers for many rays; `out` must be as long as `rays`.
    pub fn occluded_many(
        &self,
        rays: &[Ray],
        out: &mut [bool],
        method: Traversal,
        stats: &mut TraceStats,
    ) {
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = self.occluded(r, method, stats);
        }
    }

    #[inline]
    fn leaf_refs(&self, node: KdNode) -> &[u32] {
        let l = self.leaves[node.index() as usize];
        &self.refs[l.first_ref as usize..(l.first_ref + l.ref_count) as usize]
    }

    fn walk_hierarchical<V: LeafVisitor>(&self, v: &mut V, stats: &mut TraceStats) {
        let r = *v.ray();
        let Some((t0, t1)) = self
            .info
            .bounds()
            .clip_ray(r.origin, r.inv_dir, r.t_min, r.t_max)
        else {
            return;
        };
        let mut stack = [ExitPoint {
            node: NO_NODE,
            t: 0.0,
            p: Vec3::ZERO,
        }; STACK_SIZE];
        stack[0] = ExitPoint {
            node: NO_NODE,
            t: t1,
            p: r.at(t1),
        };
        let mut ex = 0usize;
        let mut en_p = r.at(t0);
        let mut node = 0u32;
        let (mut interior, mut leaves, mut empty) = (0u64, 0u64, 0u64);
        'outer: loop {
            let mut nd = self.nodes[node as usize];
            while !nd.is_leaf() {
                interior += 1;
                let (a, s, left) = (nd.axis(), nd.split(), nd.index());
                let ex_pa = stack[ex].p[a];
                let far;
                if en_p[a] <= s {
                    if ex_pa <= s {
                        if en_p[a] == s && ex_pa == s {
                            // The segment lies in the plane: left, then right again.
                            let x = stack[ex];
                            stack[ex + 1] = ExitPoint {
                                node: left + 1,
                                t: 0.0,
                                p: en_p,
                            };
                            stack[ex + 2] = ExitPoint { node: SKIP, ..x };
                            ex += 2;
                        }
                        nd = self.nodes[left as usize];
                        continue;
                    }
                    if en_p[a] == s {
                        nd = self.nodes[left as usize + 1];
                        continue;
                    }
                    far = left + 1;
                    nd = self.nodes[left as usize];
                } else {
                    if s < ex_pa {
                        nd = self.nodes[left as usize + 1];
                        continue;
                    }
                    far = left;
                    nd = self.nodes[left as usize + 1];
                }
                let t = (s - r.origin[a]) * r.inv_dir[a];
                let mut p = r.at(t);
                p[a] = s;
                ex += 1;
                stack[ex] = ExitPoint { node: far, t, p };
            }
            leaves += 1;
            let refs = self.leaf_refs(nd);
            empty += refs.is_empty() as u64;
            if v.visit(&self.scene, refs, stack[ex].t) {
                break 'outer;
            }
            loop {
                let e = stack[ex];
                if e.node == NO_NODE {
                    break 'outer;
                }
                ex -= 1;
                en_p = e.p;
                node = e.node;
                if node != SKIP {
                    break;
                }
            }
        }
        stats.interior_steps += interior;
        stats.leaf_steps += leaves;
        stats.empty_leaf_steps += empty;
        stats.traversal_steps += interior + leaves;
    }

    /// Descends from `node` to the leaf holding `p`; a point on a split
    /// plane goes where the ray heads. `None` when the ray lies in the plane.
    #[inline]
    fn locate(&self, mut node: u32, p: Vec3, d: Vec3, interior: &mut u64) -> Option<KdNode> {
        loop {
            let nd = self.nodes[node as usize];
            if nd.is_leaf() {
                return Some(nd);
            }
            *interior += 1;
            let (a, s, left) = (nd.axis(), nd.split(), nd.index());
            node = if p[a] < s || (p[a] == s && d[a] < 0.0) {
                left
            } else if p[a] > s || d[a] > 0.0 {
                left + 1
            } else {
                return None;
            };
        }
    }

    fn walk_ropes<V: LeafVisitor>(&self, v: &mut V, stats: &mut TraceStats) {
        let r = *v.ray();
        let Some((t0, t1)) = self
            .info
            .bounds()
            .clip_ray(r.origin, r.inv_dir, r.t_min, r.t_max)
        else {
            return;
        };
        let (mut interior, mut leaves, mut empty) = (0u64, 0u64, 0u64);
        let mut found = self.locate(0, r.at(t0), r.dir, &mut interior);
        // A rope walk crosses each leaf at most once; the bound only guards
        // against a corrupt arena.
        let mut budget = self.leaves.len() + 1;
        let mut fallback = found.is_none();
        while let Some(nd) = found {
            leaves += 1;
            let refs = self.leaf_refs(nd);
            empty += refs.is_empty() as u64;
            let rp = &self.ropes[nd.index() as usize];
            let mut t_exit = f32::INFINITY;
            let mut face = 0;
            for a in 0..3 {
                let (bound, f) = if r.dir[a] > 0.0 {
                    (rp.max[a], 2 * a + 1)
                } else if r.dir[a] < 0.0 {
                    (rp.min[a], 2 * a)
                } else {
                    continue;
                };
                let t = (bound - r.origin[a]) * r.inv_dir[a];
                if t < t_exit {
                    t_exit = t;
                    face = f;
                }
            }
            if v.visit(&self.scene, refs, t_exit.min(t1)) || t_exit >= t1 {
                break;
            }
            let next = rp.neighbor[face];
            budget -= 1;
            if next == NO_NODE || budget == 0 {
                fallback = budget == 0;
                break;
            }
            let mut p = r.at(t_exit);
            p[face / 2] = if face % 2 == 1 {
                rp.max[face / 2]
            } else {
                rp.min[face / 2]
            };
            found = self.locate(next, p, r.dir, &mut interior);
            fallback = found.is_none();
        }
        stats.interior_steps += interior;
        stats.leaf_steps += leaves;
        stats.empty_leaf_steps += empty;
        stats.traversal_steps += interior + leaves;
        if fallback {
            self.walk_hierarchical(v, stats);
        }
    }
}
