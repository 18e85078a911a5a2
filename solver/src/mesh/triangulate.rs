//! Triangulation of a leaf element together with the T-vertices on its edges
//! (Remington 1992, §3.4), so that the displayed mesh has no cracks and no pixel drop.
//!
//! A leaf element is convex; the finer neighbours' vertices that lie on its edges
//! ("hanging" vertices) make some boundary points collinear. The output must use
//! every boundary point as a triangle corner (otherwise the neighbour's vertex
//! stays a T-junction) and must not contain zero-area triangles. A fan from a
//! corner fails when that corner's own edges carry hanging points, so this is an
//! ear-clipping of the convex point sequence in exact integer parametric
//! coordinates: clip a strictly convex point whose removal leaves a polygon of
//! non-zero area, preferring well-shaped ears. No point is added, so the
//! triangles use only real, solved vertices.

/// Appends triangles (indices into `points`, counter-clockwise like the input)
/// covering the convex polygon `points` (parametric integer coordinates,
/// counter-clockwise, collinear points allowed, no repeated points).
///
/// Every point is a corner of at least one triangle and no triangle has zero
/// area, provided the polygon has non-zero area; a degenerate input yields
/// nothing. `work` is scratch space, reused between calls to avoid allocating.
pub fn triangulate_convex(points: &[[i64; 2]], work: &mut Vec<usize>, out: &mut Vec<[usize; 3]>) {
    let n = points.len();
    if n < 3 {
        return;
    }
    let cross = |a: usize, b: usize, c: usize| -> i128 {
        let (pa, pb, pc) = (points[a], points[b], points[c]);
        let (ux, uy) = ((pb[0] - pa[0]) as i128, (pb[1] - pa[1]) as i128);
        let (vx, vy) = ((pc[0] - pa[0]) as i128, (pc[1] - pa[1]) as i128);
        ux * vy - uy * vx
    };
    let mut area2: i128 = 0;
    for i in 1..n - 1 {
        area2 += cross(0, i, i + 1);
    }
    if area2 <= 0 {
        return;
    }
    work.clear();
    work.extend(0..n);
    while work.len() > 3 {
        let m = work.len();
        let mut best: Option<(usize, i128, f64)> = None;
        for k in 0..m {
            let (a, c, b) = (work[(k + m - 1) % m], work[k], work[(k + 1) % m]);
            let ear = cross(a, c, b);
            // Collinear points are not ears; clipping an ear that leaves only
            // collinear points would strand them as T-junctions.
            if ear <= 0 || area2 - ear == 0 {
                continue;
            }
            let score = shape(points[a], points[c], points[b], ear);
            if best.is_none_or(|(_, _, s)| score > s) {
                best = Some((k, ear, score));
            }
        }
        let Some((k, ear, _)) = best else {
            // Unreachable for a convex polygon of non-zero area (a corner next to
            // a collinear run always qualifies); fan from the first strictly
            // convex point rather than loop.
            fan_fallback(work, &cross, out);
            return;
        };
        out.push([work[(k + m - 1) % m], work[k], work[(k + 1) % m]]);
        area2 -= ear;
        work.remove(k);
    }
    out.push([work[0], work[1], work[2]]);
}

/// Twice the area over the longest edge squared: 1 for a right isosceles ear,
/// small for slivers.
fn shape(a: [i64; 2], c: [i64; 2], b: [i64; 2], ear: i128) -> f64 {
    let len2 = |p: [i64; 2], q: [i64; 2]| {
        let (dx, dy) = ((q[0] - p[0]) as f64, (q[1] - p[1]) as f64);
        dx * dx + dy * dy
    };
    let longest = len2(a, c).max(len2(c, b)).max(len2(b, a));
    ear as f64 / longest
}

fn fan_fallback(
    work: &[usize],
    cross: &dyn Fn(usize, usize, usize) -> i128,
    out: &mut Vec<[usize; 3]>,
) {
    let m = work.len();
    for apex in 0..m {
        if cross(work[(apex + m - 1) % m], work[apex], work[(apex + 1) % m]) > 0 {
            for j in 1..m - 1 {
                let (p, q) = (work[(apex + j) % m], work[(apex + j + 1) % m]);
                if cross(work[apex], p, q) > 0 {
                    out.push([work[apex], p, q]);
                }
            }
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn twice_area(points: &[[i64; 2]], t: [usize; 3]) -> i128 {
        let (a, b, c) = (points[t[0]], points[t[1]], points[t[2]]);
        ((b[0] - a[0]) as i128) * ((c[1] - a[1]) as i128)
            - ((b[1] - a[1]) as i128) * ((c[0] - a[0]) as i128)
    }

    /// Checks the three properties the display needs: positive triangles, exact
    /// area, every point used, and every boundary segment used exactly once while
    /// every interior edge is shared by exactly two triangles (no T-junctions).
    fn check(points: &[[i64; 2]]) {
        let mut out = Vec::new();
        triangulate_convex(points, &mut Vec::new(), &mut out);
        assert_eq!(out.len(), points.len() - 2, "{points:?} -> {out:?}");
        let mut total = 0;
        let mut edges = std::collections::HashMap::new();
        for &t in &out {
            let a = twice_area(points, t);
            assert!(a > 0, "degenerate or flipped triangle {t:?}");
            total += a;
            for k in 0..3 {
                let (p, q) = (t[k], t[(k + 1) % 3]);
                *edges.entry((p.min(q), p.max(q))).or_insert(0) += 1;
            }
        }
        let n = points.len();
        let mut area2 = 0;
        for i in 1..n - 1 {
            area2 += twice_area(points, [0, i, i + 1]);
        }
        assert_eq!(total, area2);
        for (&(p, q), &count) in &edges {
            let boundary = (q - p == 1) || (p == 0 && q == n - 1);
            assert_eq!(count, if boundary { 1 } else { 2 }, "edge {p}-{q}");
        }
        for i in 0..n {
            assert!(out.iter().any(|t| t.contains(&i)), "point {i} unused");
        }
    }

    #[test]
    fn quads_with_hanging_points_on_any_edges_triangulate_without_t_junctions() {
        // A square of side 8 with hanging points at the halves and quarters of
        // every subset of edges.
        let corners = [[0, 0], [8, 0], [8, 8], [0, 8]];
        for mask in 0u32..256 {
            let mut pts = Vec::new();
            for e in 0..4 {
                let (a, b) = (corners[e], corners[(e + 1) % 4]);
                pts.push(a);
                let level = (mask >> (2 * e)) & 3;
                let divisions = [1, 2, 4, 8][level as usize];
                for k in 1..divisions {
                    pts.push([
                        a[0] + (b[0] - a[0]) * k / divisions,
                        a[1] + (b[1] - a[1]) * k / divisions,
                    ]);
                }
            }
            check(&pts);
        }
    }

    #[test]
    fn triangles_with_hanging_points_triangulate_without_t_junctions() {
        let corners = [[0, 0], [8, 0], [0, 8]];
        for mask in 0u32..64 {
            let mut pts = Vec::new();
            for e in 0..3 {
                let (a, b) = (corners[e], corners[(e + 1) % 3]);
                pts.push(a);
                let divisions = [1, 2, 4, 8][((mask >> (2 * e)) & 3) as usize];
                for k in 1..divisions {
                    pts.push([
                        a[0] + (b[0] - a[0]) * k / divisions,
                        a[1] + (b[1] - a[1]) * k / divisions,
                    ]);
                }
            }
            check(&pts);
        }
    }

    #[test]
    fn degenerate_input_gives_nothing() {
        let mut out = Vec::new();
        triangulate_convex(&[[0, 0], [1, 0], [2, 0]], &mut Vec::new(), &mut out);
        assert!(out.is_empty());
    }
}
