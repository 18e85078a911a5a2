//! Clipping, fixed-point rasterization and the depth-tested write: the fixed
//! function part of the pipeline (module documentation of [`super`], steps 2–6).

use super::Image;
use crate::texture::MipChain;
use glam::DVec4;

/// Sub-pixel precision of snapped vertex positions, bits (1/256 pixel), as
/// Vulkan's `subPixelPrecisionBits` on common hardware and on lavapipe.
pub const SUBPIXEL_BITS: u32 = 8;
const SUBPIXEL: i64 = 1 << SUBPIXEL_BITS;
const HALF_PIXEL: i64 = SUBPIXEL / 2;

/// The guard band in NDC units: geometry is clipped to `|x|, |y| ≤ GUARD · w`.
/// With images of at most 16384 pixels a side, snapped coordinates stay below
/// 2^24 sub-pixel steps and edge functions (products of two differences) below
/// 2^50, exact in both i64 and the f64 they are converted to.
const GUARD: f64 = 4.0;

/// A vertex after the vertex stage: clip-space position and radiance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipVertex {
    pub position: DVec4,
    pub radiance: [f64; 3],
    /// Textured batches: u, v and the factor times E/π (zero otherwise),
    /// interpolated like the radiance.
    pub textured: [f64; 5],
}

impl ClipVertex {
    fn lerp(&self, other: &ClipVertex, t: f64) -> ClipVertex {
        ClipVertex {
            position: self.position + (other.position - self.position) * t,
            radiance: [0, 1, 2]
                .map(|c| self.radiance[c] + (other.radiance[c] - self.radiance[c]) * t),
            textured: [0, 1, 2, 3, 4]
                .map(|c| self.textured[c] + (other.textured[c] - self.textured[c]) * t),
        }
    }
}

/// A vertex in the framebuffer: snapped position, depth and what perspective
/// correction needs.
#[derive(Clone, Copy, Debug)]
struct ScreenVertex {
    x: i64,
    y: i64,
    depth: f64,
    inv_w: f64,
    radiance_over_w: [f64; 3],
    textured_over_w: [f64; 5],
}

/// A convex polygon of at most 3 + 6 vertices (a triangle clipped by six planes).
struct Polygon {
    vertices: [ClipVertex; 9],
    len: usize,
}

/// The six clip planes as signed distances, inside when ≥ 0: near, far and the
/// four guard-band planes.
fn plane_distance(plane: usize, p: DVec4) -> f64 {
    match plane {
        0 => p.z,
        1 => p.w - p.z,
        2 => GUARD * p.w - p.x,
        3 => GUARD * p.w + p.x,
        4 => GUARD * p.w - p.y,
        _ => GUARD * p.w + p.y,
    }
}

/// Sutherland–Hodgman clipping of `triangle` against the six planes. Returns the
/// visible convex polygon (empty when nothing is visible).
fn clip(triangle: [ClipVertex; 3]) -> Polygon {
    let mut poly = Polygon {
        vertices: [triangle[0]; 9],
        len: 3,
    };
    poly.vertices[..3].copy_from_slice(&triangle);
    for plane in 0..6 {
        let mut distances = [0.0; 9];
        let mut all_inside = true;
        for (distance, vertex) in distances.iter_mut().zip(&poly.vertices[..poly.len]) {
            *distance = plane_distance(plane, vertex.position);
            all_inside &= *distance >= 0.0;
        }
        if all_inside {
            continue;
        }
        let mut out = Polygon {
            vertices: poly.vertices,
            len: 0,
        };
        for k in 0..poly.len {
            let next = (k + 1) % poly.len;
            let (a, b) = (&poly.vertices[k], &poly.vertices[next]);
            let (da, db) = (distances[k], distances[next]);
            if da >= 0.0 {
                out.vertices[out.len] = *a;
                out.len += 1;
            }
            if (da >= 0.0) != (db >= 0.0) {
                // The crossing point, where the interpolated distance is 0. Always
                // computed from the inside vertex so that a shared edge of two
                // triangles gets the same point whichever way it is traversed.
                let point = if da >= 0.0 {
                    a.lerp(b, da / (da - db))
                } else {
                    b.lerp(a, db / (db - da))
                };
                out.vertices[out.len] = point;
                out.len += 1;
            }
        }
        // Convex polygon ∩ half-space: at most one more vertex per plane, so
        // `out.len ≤ 3 + plane + 1 ≤ 9`.
        poly = out;
        if poly.len < 3 {
            poly.len = 0;
            break;
        }
    }
    poly
}

/// Twice the signed area of (a, b, c) in sub-pixel units², positive when
/// (a, b, c) turns clockwise on screen (y down); equivalently the edge function of
/// edge a→b at c.
#[inline]
fn edge_function(ax: i64, ay: i64, bx: i64, by: i64, px: i64, py: i64) -> i64 {
    (bx - ax) * (py - ay) - (by - ay) * (px - ax)
}

/// One edge of a triangle oriented so that its inside is where the edge function
/// is positive, with the top-left tie rule folded into `bias`.
struct Edge {
    dx: i64,
    dy: i64,
    ax: i64,
    ay: i64,
    /// 0 for a top or left edge (a centre exactly on it is inside), −1 otherwise.
    bias: i64,
}

impl Edge {
    fn new(a: &ScreenVertex, b: &ScreenVertex) -> Edge {
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        // With the inside on the positive side and y down: a top edge is
        // horizontal with the inside below it (dx > 0); a left edge has the inside
        // to its right, i.e. it runs upward on screen (dy < 0).
        let top_left = dy < 0 || (dy == 0 && dx > 0);
        Edge {
            dx,
            dy,
            ax: a.x,
            ay: a.y,
            bias: if top_left { 0 } else { -1 },
        }
    }

    #[inline]
    fn at(&self, px: i64, py: i64) -> i64 {
        self.dx * (py - self.ay) - self.dy * (px - self.ax)
    }
}

/// Draws triangles into an [`Image`] with depth test LESS.
pub struct Rasterizer<'a> {
    image: &'a mut Image,
    cull_back_faces: bool,
    /// The texture of the triangles drawn next (`None`: untextured).
    texture: Option<&'a MipChain>,
    /// The emission texture of the triangles drawn next and its factor Ke
    /// (format 3's second slot; `None`: none).
    emission: Option<(&'a MipChain, [f64; 3])>,
}

impl<'a> Rasterizer<'a> {
    pub fn new(image: &'a mut Image, cull_back_faces: bool) -> Rasterizer<'a> {
        Rasterizer {
            image,
            cull_back_faces,
            texture: None,
            emission: None,
        }
    }

    /// Draws the next triangles with `texture`: each fragment adds
    /// `ρ(u, v) · (factor · E/π)` from the vertices' `textured` values, ρ
    /// filtered trilinearly at the level of detail of the exact screen-space
    /// derivatives of (u, v) at the pixel centre.
    pub fn set_texture(&mut self, texture: Option<&'a MipChain>) {
        self.texture = texture;
    }

    /// Draws the next triangles with an emission texture too (only with a
    /// texture): each fragment adds `Ke ⊙ ρ_e(u, v)` at the same UV, filtered
    /// as [`Rasterizer::set_texture`]'s at its own level of detail.
    pub fn set_emission(&mut self, emission: Option<(&'a MipChain, [f64; 3])>) {
        self.emission = emission;
    }

    /// Clips, culls and rasterizes one triangle given in index order.
    pub fn draw_triangle(&mut self, triangle: [ClipVertex; 3]) {
        if triangle.iter().any(|v| !v.position.is_finite()) {
            // Corrupt positions: nothing sensible to draw, and NaN would defeat
            // the clipper's comparisons.
            return;
        }
        // Outcodes: bit p set when a vertex is outside plane p. Most triangles are
        // wholly inside (drawn unclipped) or wholly outside one plane (dropped).
        let outcode = |v: &ClipVertex| {
            (0..6).fold(0u8, |code, plane| {
                code | (((plane_distance(plane, v.position) < 0.0) as u8) << plane)
            })
        };
        let codes = triangle.each_ref().map(outcode);
        if codes[0] & codes[1] & codes[2] != 0 {
            return;
        }
        let polygon = if codes[0] | codes[1] | codes[2] == 0 {
            let mut p = Polygon {
                vertices: [triangle[0]; 9],
                len: 3,
            };
            p.vertices[..3].copy_from_slice(&triangle);
            p
        } else {
            clip(triangle)
        };
        if polygon.len < 3 {
            return;
        }
        let (width, height) = (self.image.width as f64, self.image.height as f64);
        let mut screen = [ScreenVertex {
            x: 0,
            y: 0,
            depth: 0.0,
            inv_w: 0.0,
            radiance_over_w: [0.0; 3],
            textured_over_w: [0.0; 5],
        }; 9];
        for (s, v) in screen.iter_mut().zip(&polygon.vertices[..polygon.len]) {
            // Clipping guarantees w ≥ near > 0 (z ≥ 0 and z = a·w − b with a, b > 0).
            let inv_w = 1.0 / v.position.w;
            let ndc = v.position.truncate() * inv_w;
            // Viewport transform, then snap to the sub-pixel grid.
            let fx = (ndc.x + 1.0) * 0.5 * width;
            let fy = (ndc.y + 1.0) * 0.5 * height;
            *s = ScreenVertex {
                x: (fx * SUBPIXEL as f64).round() as i64,
                y: (fy * SUBPIXEL as f64).round() as i64,
                depth: ndc.z,
                inv_w,
                radiance_over_w: v.radiance.map(|r| r * inv_w),
                textured_over_w: v.textured.map(|t| t * inv_w),
            };
        }
        let screen = &screen[..polygon.len];
        // Facing from the whole clipped polygon (clipping keeps orientation).
        // Front = counter-clockwise on screen in Vulkan's sense = negative here.
        let area: i64 = (1..screen.len() - 1)
            .map(|k| {
                let (a, b, c) = (&screen[0], &screen[k], &screen[k + 1]);
                edge_function(a.x, a.y, b.x, b.y, c.x, c.y)
            })
            .sum();
        if area == 0 || (self.cull_back_faces && area > 0) {
            return;
        }
        for k in 1..screen.len() - 1 {
            let (a, b, c) = (&screen[0], &screen[k], &screen[k + 1]);
            let sub_area = edge_function(a.x, a.y, b.x, b.y, c.x, c.y);
            // A fan piece whose orientation differs from the polygon's is a sliver
            // flipped by snapping; it covers no pixel centre of its own.
            if sub_area == 0 || (sub_area > 0) != (area > 0) {
                continue;
            }
            if sub_area > 0 {
                self.fill(a, b, c);
            } else {
                self.fill(a, c, b);
            }
        }
    }

    /// Fills a triangle whose edge functions are positive inside (clockwise on a
    /// y-down screen).
    fn fill(&mut self, a: &ScreenVertex, b: &ScreenVertex, c: &ScreenVertex) {
        let (w, h) = (self.image.width as i64, self.image.height as i64);
        let min_x = a.x.min(b.x).min(c.x);
        let max_x = a.x.max(b.x).max(c.x);
        let min_y = a.y.min(b.y).min(c.y);
        let max_y = a.y.max(b.y).max(c.y);
        // Pixels whose centres `SUBPIXEL · i + HALF_PIXEL` lie in the bounding box.
        let i0 = (min_x - HALF_PIXEL + SUBPIXEL - 1)
            .div_euclid(SUBPIXEL)
            .max(0);
        let i1 = (max_x - HALF_PIXEL).div_euclid(SUBPIXEL).min(w - 1);
        let j0 = (min_y - HALF_PIXEL + SUBPIXEL - 1)
            .div_euclid(SUBPIXEL)
            .max(0);
        let j1 = (max_y - HALF_PIXEL).div_euclid(SUBPIXEL).min(h - 1);
        if i0 > i1 || j0 > j1 {
            return;
        }
        // Edge opposite each vertex: λ_a ∝ E_bc, λ_b ∝ E_ca, λ_c ∝ E_ab.
        let edges = [Edge::new(b, c), Edge::new(c, a), Edge::new(a, b)];
        let area = edge_function(a.x, a.y, b.x, b.y, c.x, c.y) as f64;
        let vertices = [a, b, c];
        let step_x = edges.each_ref().map(|e| -e.dy * SUBPIXEL);
        // Screen-space derivatives of the barycentrics, per pixel (for the
        // texture's level of detail).
        let gradient = Gradient {
            x: step_x.map(|s| s as f64 / area),
            y: edges.each_ref().map(|e| (e.dx * SUBPIXEL) as f64 / area),
        };
        let x0 = SUBPIXEL * i0 + HALF_PIXEL;
        for j in j0..=j1 {
            let py = SUBPIXEL * j + HALF_PIXEL;
            let mut e = edges.each_ref().map(|edge| edge.at(x0, py));
            let row = (j * w) as usize;
            for i in i0..=i1 {
                if e[0] + edges[0].bias >= 0
                    && e[1] + edges[1].bias >= 0
                    && e[2] + edges[2].bias >= 0
                {
                    self.shade_fragment(
                        row + i as usize,
                        &vertices,
                        [e[0] as f64 / area, e[1] as f64 / area, e[2] as f64 / area],
                        &gradient,
                    );
                }
                for k in 0..3 {
                    e[k] += step_x[k];
                }
            }
        }
    }

    /// Depth test and write of one covered pixel with screen barycentrics `lambda`.
    #[inline]
    fn shade_fragment(
        &mut self,
        index: usize,
        v: &[&ScreenVertex; 3],
        lambda: [f64; 3],
        gradient: &Gradient,
    ) {
        // Depth is affine in screen space (Vulkan interpolates z/w linearly); the
        // viewport's depth range 0..1 clamps it.
        let depth = (lambda[0] * v[0].depth + lambda[1] * v[1].depth + lambda[2] * v[2].depth)
            .clamp(0.0, 1.0) as f32;
        if depth >= self.image.depth[index] {
            return;
        }
        // Perspective-correct: attributes divided by w are affine in screen space.
        let inv_w = lambda[0] * v[0].inv_w + lambda[1] * v[1].inv_w + lambda[2] * v[2].inv_w;
        let radiance = [0, 1, 2].map(|c| {
            ((lambda[0] * v[0].radiance_over_w[c]
                + lambda[1] * v[1].radiance_over_w[c]
                + lambda[2] * v[2].radiance_over_w[c])
                / inv_w) as f32
        });
        self.image.depth[index] = depth;
        self.image.pixels[index] = match self.texture {
            Some(texture) => {
                let at = TexturedAt::new(v, lambda, inv_w, gradient);
                let rho = at.sample(texture);
                let mut textured = [0, 1, 2].map(|c| rho[c] * at.factor_e[c]);
                if let Some((emission, ke)) = self.emission {
                    let rho_e = at.sample(emission);
                    for c in 0..3 {
                        textured[c] += ke[c] * rho_e[c];
                    }
                }
                [0, 1, 2].map(|c| (f64::from(radiance[c]) + textured[c]) as f32)
            }
            None => radiance,
        };
    }
}

/// Per-pixel derivatives of the three screen barycentrics along x and y.
struct Gradient {
    x: [f64; 3],
    y: [f64; 3],
}

/// The textured attributes at a fragment: the perspective-correct
/// `a = (Σ λ a/w) / (Σ λ/w)` of u, v and factor · E/π, and the exact
/// derivatives of (u, v), `∂a = (∂(Σ λ a/w) − a · ∂(Σ λ/w)) / Σ λ/w`, for the
/// level of detail (Vulkan takes them from differences across a 2 × 2 quad:
/// equal for an affine mapping, within the curvature of the perspective over
/// one pixel otherwise).
struct TexturedAt {
    uv: [f64; 2],
    /// ∂u/∂x, ∂v/∂x, ∂u/∂y, ∂v/∂y.
    derivatives: [f64; 4],
    factor_e: [f64; 3],
}

impl TexturedAt {
    fn new(v: &[&ScreenVertex; 3], lambda: [f64; 3], inv_w: f64, gradient: &Gradient) -> Self {
        let sum = |weights: [f64; 3], attribute: usize| -> f64 {
            (0..3)
                .map(|k| weights[k] * v[k].textured_over_w[attribute])
                .sum()
        };
        let sum_inv_w =
            |weights: [f64; 3]| -> f64 { (0..3).map(|k| weights[k] * v[k].inv_w).sum() };
        let value = |attribute: usize| sum(lambda, attribute) / inv_w;
        let derivative = |attribute: usize, weights: [f64; 3]| {
            (sum(weights, attribute) - value(attribute) * sum_inv_w(weights)) / inv_w
        };
        TexturedAt {
            uv: [value(0), value(1)],
            derivatives: [
                derivative(0, gradient.x),
                derivative(1, gradient.x),
                derivative(0, gradient.y),
                derivative(1, gradient.y),
            ],
            factor_e: [2, 3, 4].map(value),
        }
    }

    /// The texture's trilinear sample here, at its own level of detail.
    fn sample(&self, texture: &MipChain) -> [f64; 3] {
        let [a, b, c, d] = self.derivatives;
        let lod = texture.lod(a, b, c, d);
        texture.sample_trilinear(self.uv[0], self.uv[1], lod)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(x: f64, y: f64, z: f64, w: f64) -> ClipVertex {
        ClipVertex {
            position: DVec4::new(x, y, z, w),
            radiance: [1.0, 0.0, 0.0],
            textured: [0.0; 5],
        }
    }

    /// Clip-space vertex (w = 1, z = 0.5) at framebuffer position (fx, fy).
    fn at_pixel(fx: f64, fy: f64, width: u32, height: u32) -> ClipVertex {
        vertex(
            fx / width as f64 * 2.0 - 1.0,
            fy / height as f64 * 2.0 - 1.0,
            0.5,
            1.0,
        )
    }

    #[test]
    fn shared_edges_cover_every_pixel_exactly_once() {
        // A 40x30-pixel rectangle cut into a fan and a grid of triangles whose
        // edges pass exactly through pixel centres and corners in many directions.
        // Counting coverage with culling off (one extra draw per fragment) shows
        // the top-left rule: no pixel counted twice, none missed.
        let (w, h) = (64, 48);
        let mut points = Vec::new();
        // Grid vertices at pixel centres, corners and odd sub-pixel offsets.
        let xs = [5.5, 12.0, 17.5, 23.25, 30.5, 38.0, 45.5];
        let ys = [6.5, 11.0, 19.5, 27.75, 36.5];
        for &y in &ys {
            for &x in &xs {
                points.push((x, y));
            }
        }
        let nx = xs.len();
        let mut triangles = Vec::new();
        for r in 0..ys.len() - 1 {
            for c in 0..nx - 1 {
                let (p00, p10, p01, p11) = (
                    r * nx + c,
                    r * nx + c + 1,
                    (r + 1) * nx + c,
                    (r + 1) * nx + c + 1,
                );
                // Alternate diagonals so that both directions are exercised.
                if (r + c) % 2 == 0 {
                    triangles.push([p00, p01, p11]);
                    triangles.push([p00, p11, p10]);
                } else {
                    triangles.push([p00, p01, p10]);
                    triangles.push([p10, p01, p11]);
                }
            }
        }
        let mut count = vec![0u32; (w * h) as usize];
        for t in &triangles {
            let mut image = Image::new(w, h);
            let mut r = Rasterizer::new(&mut image, false);
            r.draw_triangle(t.map(|k| at_pixel(points[k].0, points[k].1, w, h)));
            for (n, d) in count.iter_mut().zip(&image.depth) {
                *n += (*d < 1.0) as u32;
            }
        }
        for j in 0..h {
            for i in 0..w {
                let (cx, cy) = (i as f64 + 0.5, j as f64 + 0.5);
                // Half-open rectangle [5.5, 45.5) × [6.5, 36.5): the left and top
                // borders are left/top edges, the right and bottom ones are not.
                let inside = (5.5..45.5).contains(&cx) && (6.5..36.5).contains(&cy);
                assert_eq!(
                    count[(j * w + i) as usize],
                    inside as u32,
                    "pixel ({i}, {j})"
                );
            }
        }
    }

    #[test]
    fn clipping_keeps_the_part_in_front_of_the_near_plane() {
        // A triangle with one vertex behind the eye (w < 0, z < 0): the clipped
        // polygon has four vertices, all with z ≥ 0, and the radiance there is the
        // clip-space linear interpolation.
        let mut a = vertex(0.0, 0.0, 0.5, 1.0);
        a.radiance = [0.0; 3];
        let mut b = vertex(0.5, 0.0, 0.5, 1.0);
        b.radiance = [1.0; 3];
        let mut c = vertex(0.0, 0.5, -1.0, -1.0);
        c.radiance = [3.0; 3];
        let poly = clip([a, b, c]);
        assert_eq!(poly.len, 4);
        for v in &poly.vertices[..poly.len] {
            assert!(v.position.z >= -1e-15 && v.position.w > 0.0, "{v:?}");
        }
        // The crossing on edge a–c is at t = 0.5 / 1.5 = 1/3 from a.
        let crossing = poly.vertices[..poly.len]
            .iter()
            .find(|v| v.position.z.abs() < 1e-12 && v.position.x.abs() < 1e-12)
            .expect("crossing on edge a-c");
        assert!((crossing.radiance[0] - 1.0).abs() < 1e-12);
        assert!((crossing.position.w - 1.0 / 3.0).abs() < 1e-12);
        // Entirely behind: nothing.
        let behind = [
            vertex(0.0, 0.0, -1.0, -1.0),
            vertex(1.0, 0.0, -1.0, -1.0),
            vertex(0.0, 1.0, -2.0, -2.0),
        ];
        assert_eq!(clip(behind).len, 0);
    }
}
