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

/// Triangles `[i, j, k]` (indices into `p`) covering the simple polygon
/// `p`, always `p.len() - 2` of them, in the polygon's winding. Works in
/// the plane that drops the normal's largest axis; a degenerate polygon
/// (no area) gets a fan, whose zero-area triangles no ray hits.
pub fn ear_clip(p: &[[f32; 3]]) -> Vec<[u32; 3]> {
    let n = p.len();
    let mut out = Vec::with_capacity(n.saturating_sub(2));
    if n < 3 {
        return out;
    }
    let normal = newell_normal(p);
    let ax = (0..3)
        .max_by(|&a, &b| normal[a].abs().total_cmp(&normal[b].abs()))
        .unwrap();
    if normal[ax] == 0.0 || n == 3 {
        for i in 1..n - 1 {
            out.push([0, i as u32, i as u32 + 1]);
        }
        return out;
    }
    // 2D coordinates, oriented so that the polygon winds counter-clockwise.
    let (u, v) = ((ax + 1) % 3, (ax + 2) % 3);
    let flip = normal[ax] < 0.0;
    let q: Vec<[f64; 2]> = p
        .iter()
        .map(|x| {
            let (a, b) = (x[u] as f64, x[v] as f64);
            if flip {
                [b, a]
            } else {
                [a, b]
            }
        })
        .collect();
    let cross = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    let reflex =
        |i: usize, prev: &[usize], next: &[usize]| cross(q[prev[i]], q[i], q[next[i]]) <= 0.0;
    let mut is_reflex: Vec<bool> = (0..n).map(|i| reflex(i, &prev, &next)).collect();
    let inside = |x: [f64; 2], a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        cross(a, b, x) >= 0.0 && cross(b, c, x) >= 0.0 && cross(c, a, x) >= 0.0
    };
    let mut left = n;
    let mut i = 0;
    let mut misses = 0;
    while left > 3 {
        let (a, c) = (prev[i], next[i]);
        let mut ear = !is_reflex[i];
        if ear {
            // Only reflex vertices can lie inside a convex corner's triangle.
            let mut k = next[c];
            while k != a {
                if is_reflex[k]
                    && q[k] != q[a]
                    && q[k] != q[i]
                    && q[k] != q[c]
                    && inside(q[k], q[a], q[i], q[c])
                {
                    ear = false;
                    break;
                }
                k = next[k];
            }
        }
        // After a full round without an ear (rounding in a nearly
        // degenerate polygon), clip anyway: the count stays n - 2.
        if ear || misses > left {
            out.push([a as u32, i as u32, c as u32]);
            next[a] = c;
            prev[c] = a;
            left -= 1;
            is_reflex[a] = reflex(a, &prev, &next);
            is_reflex[c] = reflex(c, &prev, &next);
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
    }
}
