//! Polygons to triangles by ear clipping, so that concave polygons (the
//! gears' 144-gons) are covered exactly; a plain fan would cover the wrong area.

/// Newell's normal of a polygon (not normalised; zero when degenerate).
pub fn newell_normal(p: &[[f32; 3]]) -> [f64; 3] {
    let mut n = [0.0f64; 3];
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        let (a, b) = (a.map(f64::from), b.map(f64::from));
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    n
}

/// The largest `n * r` (vertices times reflex corners) of a polygon the
/// NFF reader accepts: ear clipping tests each candidate ear against the
/// reflex corners only, so it takes about `n * r` steps (convex polygons:
/// `n`). 2^30 is about a second; real files stay far below (the SPD
/// gears' 144-gons: 144 * 72).
pub const MAX_CLIP_WORK: u64 = 1 << 30;

/// A polygon in the plane that drops its normal's largest axis, wound
/// counter-clockwise; `None` when it has no area.
fn planar(p: &[[f32; 3]]) -> Option<Vec<[f64; 2]>> {
    let normal = newell_normal(p);
    let ax = (0..3).max_by(|&a, &b| normal[a].abs().total_cmp(&normal[b].abs()))?;
    if normal[ax] == 0.0 || !normal[ax].is_finite() {
        return None;
    }
    let (u, v) = ((ax + 1) % 3, (ax + 2) % 3);
    let flip = normal[ax] < 0.0;
    Some(
        p.iter()
            .map(|x| {
                let (a, b) = (x[u] as f64, x[v] as f64);
                if flip {
                    [b, a]
                } else {
                    [a, b]
                }
            })
            .collect(),
    )
}

fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Reflex (concave, or straight) corners of a polygon: with its vertex
/// count, what [`ear_clip`] will cost (see [`MAX_CLIP_WORK`]).
pub fn reflex_count(p: &[[f32; 3]]) -> usize {
    let n = p.len();
    match planar(p) {
        Some(q) if n > 3 => (0..n)
            .filter(|&i| cross(q[(i + n - 1) % n], q[i], q[(i + 1) % n]) <= 0.0)
            .count(),
        _ => 0,
    }
}

/// Triangles `[i, j, k]` (indices into `p`) covering the simple polygon
/// `p`, always `p.len() - 2` of them, in the polygon's winding. Works in
/// the plane that drops the normal's largest axis; a degenerate polygon
/// (no area) gets a fan, whose zero-area triangles no ray hits. Takes
/// about `n * r` steps for `n` vertices of which `r` are reflex.
pub fn ear_clip(p: &[[f32; 3]]) -> Vec<[u32; 3]> {
    let n = p.len();
    let mut out = Vec::with_capacity(n.saturating_sub(2));
    if n < 3 {
        return out;
    }
    let q = match planar(p) {
        Some(q) if n > 3 => q,
        _ => {
            for i in 1..n - 1 {
                out.push([0, i as u32, i as u32 + 1]);
            }
            return out;
        }
    };
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    let reflex =
        |i: usize, prev: &[usize], next: &[usize]| cross(q[prev[i]], q[i], q[next[i]]) <= 0.0;
    // The reflex corners as a set with O(1) insert and remove: the only
    // vertices that can lie inside a convex corner's triangle.
    const NONE: usize = usize::MAX;
    let mut slot = vec![NONE; n];
    let mut reflexes: Vec<usize> = Vec::new();
    let set = |i: usize, on: bool, slot: &mut [usize], reflexes: &mut Vec<usize>| {
        if on && slot[i] == NONE {
            slot[i] = reflexes.len();
            reflexes.push(i);
        } else if !on && slot[i] != NONE {
            let at = slot[i];
            reflexes.swap_remove(at);
            if let Some(&moved) = reflexes.get(at) {
                slot[moved] = at;
            }
            slot[i] = NONE;
        }
    };
    for i in 0..n {
        let r = reflex(i, &prev, &next);
        set(i, r, &mut slot, &mut reflexes);
    }
    let inside = |x: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        cross(a, b, x) >= 0.0 && cross(b, c, x) >= 0.0 && cross(c, a, x) >= 0.0
    };
    let mut left = n;
    let mut i = 0;
    let mut misses = 0;
    while left > 3 {
        let (a, c) = (prev[i], next[i]);
        let ear = slot[i] == NONE
            && !reflexes.iter().any(|&k| {
                k != a
                    && k != c
                    && q[k] != q[a]
                    && q[k] != q[i]
                    && q[k] != q[c]
                    && inside(q[k], q[a], q[i], q[c])
            });
        // After a full round without an ear (rounding in a nearly
        // degenerate polygon), clip anyway: the count stays n - 2.
        if ear || misses > left {
            out.push([a as u32, i as u32, c as u32]);
            next[a] = c;
            prev[c] = a;
            left -= 1;
            set(i, false, &mut slot, &mut reflexes);
            let (ra, rc) = (reflex(a, &prev, &next), reflex(c, &prev, &next));
            set(a, ra, &mut slot, &mut reflexes);
            set(c, rc, &mut slot, &mut reflexes);
            misses = 0;
            i = c;
        } else {
            misses += 1;
            i = next[i];
        }
    }
    out.push([prev[i] as u32, i as u32, next[i] as u32]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area2(p: &[[f32; 3]], t: &[[u32; 3]]) -> f64 {
        t.iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| p[i as usize]);
                let e1 = [b[0] - a[0], b[1] - a[1]];
                let e2 = [c[0] - a[0], c[1] - a[1]];
                (e1[0] * e2[1] - e1[1] * e2[0]) as f64
            })
            .sum()
    }

    #[test]
    fn concave_star_keeps_its_area_and_winding() {
        // A 10-point star in the z = 0 plane, counter-clockwise.
        let p: Vec<[f32; 3]> = (0..10)
            .map(|i| {
                let r = if i % 2 == 0 { 2.0 } else { 0.7 };
                let a = i as f32 * std::f32::consts::PI / 5.0;
                [r * a.cos(), r * a.sin(), 0.0]
            })
            .collect();
        let t = ear_clip(&p);
        assert_eq!(t.len(), 8);
        let polygon_area2 = newell_normal(&p)[2];
        // Every triangle has the polygon's winding, and together they cover it exactly.
        assert!(
            (area2(&p, &t) - polygon_area2).abs() < 1e-4,
            "{} vs {}",
            area2(&p, &t),
            polygon_area2
        );
        assert!(t.iter().all(|t| area2(&p, &[*t]) > 0.0));
        // A fan from vertex 0 would not: some of its triangles wind backwards.
        let fan: Vec<[u32; 3]> = (1..9).map(|i| [0, i, i + 1]).collect();
        assert!(fan.iter().any(|t| area2(&p, &[*t]) < 0.0));
    }

    #[test]
    fn clockwise_and_degenerate_polygons() {
        let sq = [
            [0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [1.0, 0.0, 0.0f32],
        ];
        let t = ear_clip(&sq);
        assert_eq!(t.len(), 2);
        assert!((area2(&sq, &t) - newell_normal(&sq)[2]).abs() < 1e-9);
        let line = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [3.0, 0.0, 0.0f32],
        ];
        assert_eq!(ear_clip(&line).len(), 2);
        assert_eq!(reflex_count(&line), 0);
    }

    /// A convex polygon of 8,193 vertices (points of a parabola, exact
    /// in f32): no reflex corner, so each ear is found at once; its
    /// triangles cover its area. A 2^20-gon circle, whose f32 corners are
    /// partly concave by rounding, is past the reader's bound instead.
    #[test]
    fn convex_polygon_has_no_reflex_work() {
        let k = 1i64 << 12;
        let p: Vec<[f32; 3]> = (-k..=k).map(|x| [x as f32, (x * x) as f32, 0.0]).collect();
        assert_eq!(reflex_count(&p), 0);
        let tris = ear_clip(&p);
        assert_eq!(tris.len(), p.len() - 2);
        let want = newell_normal(&p)[2];
        assert!(
            (area2(&p, &tris) - want).abs() < 1e-4 * want.abs(),
            "{want}"
        );
        let n = 1 << 20;
        let circle: Vec<[f32; 3]> = (0..n)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / n as f64;
                [a.cos() as f32 * 100.0, a.sin() as f32 * 100.0, 0.0]
            })
            .collect();
        assert!(n as u64 * reflex_count(&circle) as u64 > MAX_CLIP_WORK);
    }

    /// The star of the first test, and a comb with many reflex corners:
    /// reflex corners are counted, and clipping keeps the area.
    #[test]
    fn reflex_corners_are_counted() {
        let star: Vec<[f32; 3]> = (0..10)
            .map(|i| {
                let r = if i % 2 == 0 { 2.0 } else { 0.7 };
                let a = i as f32 * std::f32::consts::PI / 5.0;
                [r * a.cos(), r * a.sin(), 0.0]
            })
            .collect();
        assert_eq!(reflex_count(&star), 5);
        // A comb: teeth up from a base, clockwise order reversed by the
        // normal's sign.
        let teeth = 200;
        let mut comb = vec![[0.0, 0.0, 0.0f32]];
        for k in 0..teeth {
            let x = k as f32 * 2.0;
            comb.extend([[x, 1.0, 0.0], [x + 0.5, 3.0, 0.0], [x + 1.0, 1.0, 0.0]]);
        }
        comb.push([teeth as f32 * 2.0, 0.0, 0.0]);
        let t = ear_clip(&comb);
        assert_eq!(t.len(), comb.len() - 2);
        assert!(reflex_count(&comb) >= teeth - 1);
        assert!((area2(&comb, &t).abs() - newell_normal(&comb)[2].abs()).abs() < 1e-2);
        assert!(t
            .iter()
            .all(|t| area2(&comb, &[*t]) * newell_normal(&comb)[2] >= 0.0));
    }
}
