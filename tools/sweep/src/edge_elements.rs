//! How wide the mesh draws a shadow edge: the triangles that straddle a lit/unlit
//! boundary on a plane, and their sizes.
//!
//! A renderer interpolates vertex radiance linearly over each triangle, so a
//! shadow edge is drawn as a ramp as wide as the triangles it crosses, however
//! narrow the true penumbra. Classifying each vertex as lit (its luminance above
//! a threshold between the lit and the shaded level) and keeping the triangles
//! with both kinds of vertex gives exactly those ramps.

/// The straddling triangles on the plane and their sizes (scene units).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct EdgeElements {
    /// Triangles with all three vertices on the plane.
    pub plane_triangles: usize,
    /// Of those, the ones with a lit and an unlit vertex.
    pub straddling: usize,
    /// Each straddling triangle's longest edge: the minimum, median and maximum.
    /// The longest edge bounds the width of the ramp the triangle draws.
    pub longest_edge: [f64; 3],
    /// The shortest edge of any straddling triangle.
    pub shortest_edge: f64,
}

/// The triangles of `indices` whose vertices all satisfy `on_plane` and whose
/// vertices' luminances lie on both sides of `threshold`. `None` when none does.
pub fn straddling_triangles(
    positions: &[[f64; 3]],
    luminance: &[f64],
    indices: &[u32],
    on_plane: impl Fn([f64; 3]) -> bool,
    threshold: f64,
) -> Option<EdgeElements> {
    let length = |a: [f64; 3], b: [f64; 3]| {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    };
    let mut plane_triangles = 0;
    let mut longest = Vec::new();
    let mut shortest = f64::INFINITY;
    for tri in indices.chunks_exact(3) {
        let v = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        if !v.iter().all(|&i| on_plane(positions[i])) {
            continue;
        }
        plane_triangles += 1;
        let lit = v.iter().filter(|&&i| luminance[i] > threshold).count();
        if lit == 0 || lit == 3 {
            continue;
        }
        let edges = [(0, 1), (1, 2), (2, 0)].map(|(a, b)| length(positions[v[a]], positions[v[b]]));
        longest.push(edges.iter().copied().fold(0.0, f64::max));
        shortest = edges.iter().copied().fold(shortest, f64::min);
    }
    if longest.is_empty() {
        return None;
    }
    longest.sort_by(f64::total_cmp);
    Some(EdgeElements {
        plane_triangles,
        straddling: longest.len(),
        longest_edge: [
            longest[0],
            longest[longest.len() / 2],
            longest[longest.len() - 1],
        ],
        shortest_edge: shortest,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_straight_edge_through_a_grid_is_crossed_by_one_column_of_triangles() {
        // A 4 × 4 grid of unit squares on the plane y = 0, each split in two
        // triangles, lit where x < 1.5: the vertices at x ≤ 1 are lit, those at
        // x ≥ 2 are not, so exactly the 4 squares between x = 1 and x = 2 (8
        // triangles) straddle the edge; each has legs 1 and a diagonal √2. A
        // copy of the grid lifted to y = 1 is off the plane and not counted.
        let mut positions = Vec::new();
        for lift in [0.0, 1.0] {
            for z in 0..5 {
                for x in 0..5 {
                    positions.push([x as f64, lift, z as f64]);
                }
            }
        }
        let luminance: Vec<f64> = positions
            .iter()
            .map(|p| if p[0] < 1.5 { 10.0 } else { 1.0 })
            .collect();
        let mut indices = Vec::new();
        for base in [0u32, 25] {
            for z in 0..4u32 {
                for x in 0..4u32 {
                    let i = base + z * 5 + x;
                    indices.extend([i, i + 5, i + 1, i + 1, i + 5, i + 6]);
                }
            }
        }
        let on_floor = |p: [f64; 3]| p[1].abs() < 1e-9;
        let e = straddling_triangles(&positions, &luminance, &indices, on_floor, 3.0).unwrap();
        assert_eq!((e.plane_triangles, e.straddling), (32, 8));
        let diagonal = 2f64.sqrt();
        assert!(e.longest_edge.iter().all(|&l| (l - diagonal).abs() < 1e-12));
        assert_eq!(e.shortest_edge, 1.0);
        // A threshold above every vertex: nothing is lit, nothing straddles.
        assert_eq!(
            straddling_triangles(&positions, &luminance, &indices, on_floor, 20.0),
            None
        );
    }
}
