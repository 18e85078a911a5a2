//! A solution's radiance on one horizontal plane (a floor, a slab top), as the
//! renderers draw it: the vertex luminance interpolated over the triangle that
//! holds a point (Gouraud). It answers "what does the floor look like right
//! beside this column" without a camera, and lists the vertices on a contact
//! ring, where a leak shows first.

/// The plane's up-facing triangles: corners (x, z) and their luminances.
#[derive(Clone, Debug, Default)]
pub struct Plane {
    pub triangles: Vec<([[f64; 2]; 3], [f64; 3])>,
}

impl Plane {
    /// The luminance drawn at (x, z), or `None` off the plane's triangles. Where
    /// coplanar pieces overlap (a covered piece under an object), the first
    /// triangle found wins: callers probe outside footprints.
    pub fn drawn_at(&self, x: f64, z: f64) -> Option<f64> {
        self.triangles.iter().find_map(|(p, v)| {
            let e1 = [p[1][0] - p[0][0], p[1][1] - p[0][1]];
            let e2 = [p[2][0] - p[0][0], p[2][1] - p[0][1]];
            let det = e1[0] * e2[1] - e2[0] * e1[1];
            if det == 0.0 {
                return None;
            }
            let d = [x - p[0][0], z - p[0][1]];
            let b1 = (d[0] * e2[1] - e2[0] * d[1]) / det;
            let b2 = (e1[0] * d[1] - d[0] * e1[1]) / det;
            let inside = b1 >= -1e-9 && b2 >= -1e-9 && b1 + b2 <= 1.0 + 1e-9;
            inside.then(|| v[0] * (1.0 - b1 - b2) + v[1] * b1 + v[2] * b2)
        })
    }

    /// The triangles' corners within `tolerance` of the circle of `radius`
    /// about `centre` whose triangle lies outside it (the visible side of a
    /// contact), as (angle in degrees from +x toward +z, luminance), by angle.
    pub fn ring(&self, centre: [f64; 2], radius: f64, tolerance: f64) -> Vec<(f64, f64)> {
        let r = |q: [f64; 2]| (q[0] - centre[0]).hypot(q[1] - centre[1]);
        let mut out: Vec<(f64, f64)> = Vec::new();
        for (p, v) in &self.triangles {
            let centroid = [0, 1].map(|k| (p[0][k] + p[1][k] + p[2][k]) / 3.0);
            if r(centroid) <= radius {
                continue;
            }
            for (q, &value) in p.iter().zip(v) {
                if (r(*q) - radius).abs() <= tolerance {
                    let angle = (q[1] - centre[1]).atan2(q[0] - centre[0]).to_degrees();
                    out.push((angle, value));
                }
            }
        }
        out.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        out.dedup();
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_is_drawn_as_the_linear_blend_of_its_triangles_corners() {
        // One unit square in two triangles, luminance x + 2z at the corners:
        // linear, so the drawn value anywhere inside is exactly x + 2z.
        let f = |q: [f64; 2]| q[0] + 2.0 * q[1];
        let tri = |p: [[f64; 2]; 3]| (p, p.map(f));
        let plane = Plane {
            triangles: vec![
                tri([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]),
                tri([[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
            ],
        };
        for (x, z) in [(0.25, 0.1), (0.9, 0.8), (0.1, 0.9), (0.5, 0.5)] {
            let value = plane.drawn_at(x, z).unwrap();
            assert!((value - f([x, z])).abs() < 1e-12, "({x}, {z}): {value}");
        }
        assert_eq!(plane.drawn_at(1.5, 0.5), None);
    }

    #[test]
    fn the_ring_keeps_the_corners_on_the_circle_of_outside_triangles() {
        // A triangle outside the unit circle with two corners on it, and one
        // inside it (a covered piece) with a corner on it too: only the outside
        // triangle's two corners are listed, by angle.
        let plane = Plane {
            triangles: vec![
                ([[1.0, 0.0], [0.0, 1.0], [2.0, 2.0]], [5.0, 7.0, 9.0]),
                ([[0.0, 0.0], [1.0, 0.0], [0.0, 0.5]], [0.0, 1.0, 0.0]),
            ],
        };
        assert_eq!(
            plane.ring([0.0, 0.0], 1.0, 1e-9),
            vec![(0.0, 5.0), (90.0, 7.0)]
        );
    }
}
