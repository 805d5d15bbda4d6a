//! Placing the leaves' reference runs so that few straddle a block of
//! [`TRI_LANES`] slots and the blocks cover only the runs that need them:
//! a leaf's triangles are tested one block at a time
//! ([`super::corners`]), so a run of two that starts at slot 3 costs two
//! block tests where one would do, and a run of spheres and cones needs
//! no block at all. Runs holding a triangle come first, the others after
//! (the blocks then end where the first part does). Runs are not padded
//! (the references stay one per primitive); within each part they are
//! ordered so that each fills the hole the one before left: a run of
//! `4m + c` slots (`c` in 1..=4) that starts `4 - f` slots into a block
//! spans its fewest blocks exactly when `c <= f`, so the next run is one
//! with `c == f` if any (the block is then full), else the largest `c`
//! below `f`, else any.

use super::node::{WideNode, EMPTY_SLOT, LEAF_BIT, WIDTH};
use crate::geom::TRI_LANES;

/// Set in a leaf entry's count while packing once its run is placed.
const PLACED: u32 = 1 << 31;

/// A run's class: its length modulo the block, 4 for whole blocks.
fn class_of(len: u32) -> usize {
    (len as usize - 1) % TRI_LANES + 1
}

/// Walks the unplaced leaf entries of one class in node order.
struct Cursor {
    node: usize,
    slot: usize,
}

impl Cursor {
    /// The next unplaced leaf entry of class `c` whose run holds a
    /// triangle (a reference below `triangles`) or not, as `with`, at or
    /// after the cursor, as (node, slot); the cursor stays on it. `None`
    /// also for a run past `refs` (corrupt entries).
    fn peek(
        &mut self,
        nodes: &[WideNode],
        refs: &[u32],
        (c, with, triangles): (usize, bool, usize),
    ) -> Option<(usize, usize)> {
        while self.node < nodes.len() {
            let n = &nodes[self.node];
            while self.slot < WIDTH {
                let (child, len) = (n.child[self.slot], n.count[self.slot]);
                if child != EMPTY_SLOT
                    && child & LEAF_BIT != 0
                    && len & PLACED == 0
                    && len > 0
                    && class_of(len) == c
                {
                    let first = (child & !LEAF_BIT) as usize;
                    let run = refs.get(first..first + len as usize)?;
                    if run.iter().any(|&p| (p as usize) < triangles) == with {
                        return Some((self.node, self.slot));
                    }
                }
                self.slot += 1;
            }
            self.node += 1;
            self.slot = 0;
        }
        None
    }
}

/// Places into `tmp` from `pos` the unplaced runs that hold a triangle
/// (`with`) or hold none, as the module says; returns where they end.
fn place(
    nodes: &mut [WideNode],
    refs: &[u32],
    tmp: &mut [u32],
    mut pos: usize,
    (with, triangles): (bool, usize),
) -> Option<usize> {
    let mut cursors: [Cursor; TRI_LANES + 1] =
        core::array::from_fn(|_| Cursor { node: 0, slot: 0 });
    loop {
        let free = TRI_LANES - pos % TRI_LANES;
        let mut pick = None;
        let order = [
            free,
            free - 1,
            free.saturating_sub(2),
            free.saturating_sub(3),
        ];
        for c in order
            .into_iter()
            .filter(|&c| c >= 1)
            .chain((1..=TRI_LANES).rev())
        {
            if let Some(at) = cursors[c].peek(nodes, refs, (c, with, triangles)) {
                pick = Some((c, at));
                break;
            }
        }
        let Some((c, (k, i))) = pick else {
            return Some(pos);
        };
        let (first, len) = (
            (nodes[k].child[i] & !LEAF_BIT) as usize,
            nodes[k].count[i] as usize,
        );
        let dst = tmp.get_mut(pos..pos + len)?;
        dst.copy_from_slice(&refs[first..first + len]);
        nodes[k].child[i] = LEAF_BIT | pos as u32;
        nodes[k].count[i] |= PLACED;
        cursors[c].slot += 1;
        pos += len;
    }
}

/// Reorders the runs of `refs` (every leaf entry of `nodes` names one, and
/// together they cover `refs`) as the module says, using `tmp` (at least
/// `refs.len()`), and points the entries at their new runs; references
/// below `triangles` name triangles. Returns how many slots the runs
/// holding a triangle take (they come first). `None` when `tmp` is short
/// or the entries do not cover `refs` (a corrupt hierarchy: entries may
/// then be partly rewritten).
pub(super) fn pack_leaves(
    nodes: &mut [WideNode],
    refs: &mut [u32],
    tmp: &mut [u32],
    triangles: usize,
) -> Option<usize> {
    let tmp = tmp.get_mut(..refs.len())?;
    let with = place(nodes, refs, tmp, 0, (true, triangles))?;
    let end = place(nodes, refs, tmp, with, (false, triangles))?;
    for n in nodes.iter_mut() {
        for count in n.count.iter_mut() {
            *count &= !PLACED;
        }
    }
    if end != refs.len() {
        return None;
    }
    refs.copy_from_slice(tmp);
    Some(with)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Nodes holding leaf entries of `lens` (four a node, in order) over
    /// consecutive references `0..`.
    fn leaves(lens: &[u32]) -> ([WideNode; 8], usize) {
        let mut nodes = [WideNode::default(); 8];
        let mut first = 0;
        for (e, &len) in lens.iter().enumerate() {
            let n = &mut nodes[e / WIDTH];
            n.child[e % WIDTH] = LEAF_BIT | first;
            n.count[e % WIDTH] = len;
            first += len;
        }
        (nodes, first as usize)
    }

    /// Each entry's run after packing: the same references as before.
    fn runs(nodes: &[WideNode], refs: &[u32]) -> [[u32; 8]; 32] {
        let mut out = [[u32::MAX; 8]; 32];
        for (k, n) in nodes.iter().enumerate() {
            for i in 0..WIDTH {
                if n.child[i] != EMPTY_SLOT {
                    let f = (n.child[i] & !LEAF_BIT) as usize;
                    for (j, &r) in refs[f..f + n.count[i] as usize].iter().enumerate() {
                        out[k * WIDTH + i][j] = r;
                    }
                }
            }
        }
        out
    }

    /// Blocks the runs span beyond their fewest.
    fn extra_blocks(nodes: &[WideNode]) -> usize {
        let mut extra = 0;
        for n in nodes {
            for i in 0..WIDTH {
                if n.child[i] != EMPTY_SLOT {
                    let (f, len) = ((n.child[i] & !LEAF_BIT) as usize, n.count[i] as usize);
                    let spans = (f + len).div_ceil(TRI_LANES) - f / TRI_LANES;
                    extra += spans - len.div_ceil(TRI_LANES);
                }
            }
        }
        extra
    }

    #[test]
    fn runs_fill_the_holes_the_ones_before_left() {
        // Packable: 3 + 1, 2 + 2, 5 + 3, 2 + 1 + 1, 6 + 2, 4; unpacked
        // they straddle.
        for lens in [
            &[3u32, 2, 1, 2, 5, 3, 2, 1, 1, 6, 2, 4][..],
            &[1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1][..],
            &[2, 3, 2, 1, 7, 1, 2, 2][..],
        ] {
            let (mut nodes, n) = leaves(lens);
            let mut refs = [0u32; 64];
            for (i, r) in refs.iter_mut().enumerate() {
                *r = 1000 + i as u32;
            }
            let before = runs(&nodes, &refs);
            assert_eq!(extra_blocks(&nodes) > 0, lens[0] != 1, "{lens:?}");
            let mut tmp = [0u32; 64];
            assert!(pack_leaves(&mut nodes, &mut refs[..n], &mut tmp, usize::MAX).is_some());
            assert_eq!(runs(&nodes, &refs), before, "{lens:?}");
            assert_eq!(extra_blocks(&nodes), 0, "{lens:?}");
        }
        // Three runs of 3 back to back: the second and third must straddle.
        let (mut nodes, n) = leaves(&[3, 3, 3]);
        let mut refs = [0u32; 9];
        for (i, r) in refs.iter_mut().enumerate() {
            *r = i as u32;
        }
        let before = runs(&nodes, &refs);
        assert!(pack_leaves(&mut nodes, &mut refs[..n], &mut [0; 9], usize::MAX).is_some());
        assert_eq!(runs(&nodes, &refs), before);
        assert_eq!(extra_blocks(&nodes), 2);
    }

    #[test]
    fn short_scratch_or_runs_that_miss_references_are_refused() {
        let (mut nodes, n) = leaves(&[2, 3]);
        let mut refs = [0u32; 5];
        assert!(pack_leaves(&mut nodes, &mut refs[..n], &mut [0; 4], 9).is_none());
        // Runs covering 5 of 6 references.
        let (mut nodes, _) = leaves(&[2, 3]);
        assert!(pack_leaves(&mut nodes, &mut [0; 6], &mut [0; 6], 9).is_none());
        // A run past the references.
        let (mut nodes, _) = leaves(&[2, 3]);
        assert!(pack_leaves(&mut nodes, &mut [0; 4], &mut [0; 4], 9).is_none());
    }

    /// Runs holding a triangle come first (their slots are what the
    /// return value counts), runs of spheres and cones after them.
    #[test]
    fn runs_with_triangles_come_first() {
        // References below 100 are triangles: runs of 2 (spheres), 3
        // (one triangle), 1 (sphere), 2 (triangles), 4 (spheres).
        let (mut nodes, n) = leaves(&[2, 3, 1, 2, 4]);
        let mut refs = [200, 201, 202, 7, 203, 204, 8, 9, 205, 206, 207, 208];
        let before = runs(&nodes, &refs);
        let mut tmp = [0u32; 12];
        assert_eq!(
            pack_leaves(&mut nodes, &mut refs[..n], &mut tmp, 100),
            Some(5)
        );
        assert_eq!(runs(&nodes, &refs), before);
        assert!(refs[..5].iter().filter(|&&p| p < 100).count() == 3);
        assert!(refs[5..].iter().all(|&p| p >= 100));
        // Every count is a plain count again.
        assert!(nodes.iter().all(|nd| nd.count.iter().all(|&c| c < 100)));
        // A scene of spheres: no slot needs a block.
        let (mut nodes, n) = leaves(&[2, 3]);
        let mut refs = [5u32; 5];
        assert_eq!(
            pack_leaves(&mut nodes, &mut refs[..n], &mut [0; 5], 0),
            Some(0)
        );
    }
}
