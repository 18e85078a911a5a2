//! Non-uniform directional shooters: a source patch shoots, from each part
//! of its area, the radiance function its elements there hold, instead of
//! the patch's area mean from every point (accuracy issue, "uniform
//! shooters"; `solve/regions.rs` is the diffuse solver's four-quadrant form).
//!
//! Why it matters more for glossy surfaces than for diffuse ones: a glossy
//! patch's radiance differs across it in direction, not only in level. The
//! floor of the glossy Cornell box reflects the light back up in a lobe
//! about the mirror direction of each point, so the light it reflects lands
//! on the ceiling round the light (and on the light, which reflects none).
//! The patch's mean radiance function holds every point's lobe; shot from
//! every point it spreads that light over the whole ceiling, where the white
//! surfaces reflect it again: measured against the path-traced truth, the
//! ceiling and floor seen from the standard camera were +12% and +20% at
//! `draft` (patches 0.15 of the diagonal) and +4% and +9% with patches half
//! that size (docs/accuracy.md, "Glossy: non-uniform shooters").
//!
//! The shape is the patch's element tree, down to [`MAX_DEPTH`] levels below
//! the patch: each node of the cut holds the mean of its corner vertices'
//! radiance coefficients (hidden vertices left out), and a source sample
//! takes the coefficients of the node it falls in. As in `regions.rs`, the
//! vertices' *received* radiance stands in for the shape of the *unshot*
//! radiance (the two agree for a patch's first shot, which carries its
//! direct light), and a scale per channel keeps the shot's nominal power
//! that of the uniform shot: the patch-area mean of the shape, scaled, has
//! the unshot coefficients' hemispherical power.
//!
//! Emitting surfaces (whose radiance includes their emission) and textured
//! surfaces (whose slot also holds E/π) shoot uniformly.

use glam::DVec3;

/// Levels of the element tree the shape follows below the patch: at most
/// 4⁴ = 256 nodes, 256 × 3 (L+1)² coefficients (4 MB at L = 25, for one
/// shot; freed after it).
pub const MAX_DEPTH: u32 = 4;

/// One node of the cut through a patch's element tree.
struct Node {
    corners: [DVec3; 4],
    corner_count: usize,
    /// Its four children's node indices, or `None` at the cut.
    children: Option<[usize; 4]>,
    /// Where its coefficients start in `coefficients` (cut nodes only).
    at: usize,
}

/// The unshot radiance of one source patch as it varies over its area.
pub struct SourceShape {
    nodes: Vec<Node>,
    normal: DVec3,
    width: usize,
    coefficients: Vec<f64>,
}

/// What [`SourceShape::build`] reads of the solver's state.
pub struct ShapeInput<'a> {
    /// An element of the mesh.
    pub element: &'a dyn Fn(u32) -> ElementView,
    /// A vertex's radiance coefficients, or `None` when it is hidden.
    pub vertex: &'a dyn Fn(u32) -> Option<&'a [f64]>,
    /// Per channel: the hemispherical unshot radiance of some coefficients.
    pub power: &'a dyn Fn(&[f64]) -> DVec3,
}

/// One element as the shape sees it.
#[derive(Clone, Copy)]
pub struct ElementView {
    pub corners: [u32; 4],
    pub positions: [DVec3; 4],
    pub corner_count: usize,
    /// The first of its four consecutive children.
    pub first_child: Option<u32>,
    pub area: f64,
}

impl SourceShape {
    /// The shape of the patch whose root element is `root` (normal
    /// `normal`, area `area`), scaled so that its area mean has the
    /// hemispherical power of `unshot` per channel. `None` when the patch is
    /// a single element (nothing varies) or its radiance is dark in a channel
    /// whose unshot is not (the stand-in has no shape to give).
    pub fn build(
        input: &ShapeInput,
        root: u32,
        normal: DVec3,
        area: f64,
        unshot: &[f64],
    ) -> Option<SourceShape> {
        let width = unshot.len();
        let mut shape = SourceShape {
            nodes: Vec::new(),
            normal,
            width,
            coefficients: Vec::new(),
        };
        let mut mean = vec![0.0; width];
        shape.add(input, root, 0, &mut mean);
        if shape.nodes.len() == 1 || area <= 0.0 {
            return None;
        }
        mean.iter_mut().for_each(|m| *m /= area);
        let (want, have) = ((input.power)(unshot), (input.power)(&mean));
        let mut scale = DVec3::ZERO;
        for c in 0..3 {
            if want[c] > 0.0 && have[c] <= 0.0 {
                return None;
            }
            scale[c] = if have[c] > 0.0 {
                want[c] / have[c]
            } else {
                0.0
            };
        }
        for block in shape.coefficients.chunks_exact_mut(3) {
            for c in 0..3 {
                block[c] *= scale[c];
            }
        }
        Some(shape)
    }

    /// Adds element `e` (at `depth` below the patch) and, above the cut, its
    /// children; accumulates area × coefficients of the cut into `mean`.
    /// Returns the node's index.
    fn add(&mut self, input: &ShapeInput, e: u32, depth: u32, mean: &mut [f64]) -> usize {
        let view = (input.element)(e);
        let index = self.nodes.len();
        self.nodes.push(Node {
            corners: view.positions,
            corner_count: view.corner_count,
            children: None,
            at: 0,
        });
        match view.first_child {
            Some(first) if depth < MAX_DEPTH => {
                let children =
                    std::array::from_fn(|k| self.add(input, first + k as u32, depth + 1, mean));
                self.nodes[index].children = Some(children);
            }
            _ => {
                let at = self.coefficients.len();
                self.coefficients.resize(at + self.width, 0.0);
                let block = &mut self.coefficients[at..];
                let mut known = 0;
                for &v in &view.corners[..view.corner_count] {
                    if let Some(c) = (input.vertex)(v) {
                        known += 1;
                        for (o, x) in block.iter_mut().zip(c) {
                            *o += x;
                        }
                    }
                }
                if known > 0 {
                    block.iter_mut().for_each(|x| *x /= known as f64);
                    for (m, x) in mean.iter_mut().zip(block.iter()) {
                        *m += view.area * x;
                    }
                }
                self.nodes[index].at = at;
            }
        }
        index
    }

    /// The (scaled) radiance coefficients where source point `p` lies: the
    /// cut node containing it, or, where rounding puts `p` on no child,
    /// the child whose corner average is nearest.
    pub fn at(&self, p: DVec3) -> &[f64] {
        let mut n = 0;
        while let Some(children) = self.nodes[n].children {
            n = children
                .iter()
                .copied()
                .find(|&c| self.contains(c, p))
                .unwrap_or_else(|| self.nearest(&children, p));
        }
        let at = self.nodes[n].at;
        &self.coefficients[at..at + self.width]
    }

    /// Whether `p` (on the patch's plane) lies in node `n`'s convex polygon,
    /// its boundary included, whichever way its corners wind.
    fn contains(&self, n: usize, p: DVec3) -> bool {
        let node = &self.nodes[n];
        let corners = &node.corners[..node.corner_count];
        let size = (corners[0] - corners[corners.len() / 2]).length_squared();
        let tolerance = 1e-9 * size;
        let (mut above, mut below) = (false, false);
        for k in 0..corners.len() {
            let (a, b) = (corners[k], corners[(k + 1) % corners.len()]);
            let side = (b - a).cross(p - a).dot(self.normal);
            above |= side > tolerance;
            below |= side < -tolerance;
        }
        !(above && below)
    }

    fn nearest(&self, children: &[usize; 4], p: DVec3) -> usize {
        let distance = |c: usize| {
            let node = &self.nodes[c];
            let corners = &node.corners[..node.corner_count];
            let centre = corners.iter().copied().sum::<DVec3>() / corners.len() as f64;
            (centre - p).length_squared()
        };
        children
            .iter()
            .copied()
            .min_by(|&a, &b| distance(a).total_cmp(&distance(b)))
            .unwrap_or(children[0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square patch (element 0, vertices 0–3) split once at its
    /// midpoints (elements 1–4, corner vertex k, edge midpoints 4–7 and
    /// centre 8), and element 1 split once more (elements 5–8).
    struct Square {
        positions: Vec<DVec3>,
        elements: Vec<ElementView>,
    }

    fn square() -> Square {
        let p = |x: f64, y: f64| DVec3::new(x, y, 0.0);
        let mut positions = vec![p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)];
        positions.extend([
            p(0.5, 0.0),
            p(1.0, 0.5),
            p(0.5, 1.0),
            p(0.0, 0.5),
            p(0.5, 0.5),
        ]);
        // Element 1's own split: midpoints of its edges and its centre.
        positions.extend([
            p(0.25, 0.0),
            p(0.5, 0.25),
            p(0.25, 0.5),
            p(0.0, 0.25),
            p(0.25, 0.25),
        ]);
        let quad = |corners: [u32; 4], first_child: Option<u32>, positions: &[DVec3]| {
            let at = corners.map(|v| positions[v as usize]);
            ElementView {
                corners,
                positions: at,
                corner_count: 4,
                first_child,
                area: (at[2] - at[0]).x * (at[2] - at[0]).y,
            }
        };
        let elements = vec![
            quad([0, 1, 2, 3], Some(1), &positions),
            quad([0, 4, 8, 7], Some(5), &positions),
            quad([4, 1, 5, 8], None, &positions),
            quad([8, 5, 2, 6], None, &positions),
            quad([7, 8, 6, 3], None, &positions),
            quad([0, 9, 13, 12], None, &positions),
            quad([9, 4, 10, 13], None, &positions),
            quad([13, 10, 8, 11], None, &positions),
            quad([12, 13, 11, 7], None, &positions),
        ];
        Square {
            positions,
            elements,
        }
    }

    /// Order-0 coefficients (one RGB block): vertex v's radiance is its x
    /// coordinate in every channel (a patch lit from its right).
    fn shape_of(sq: &Square, hidden: &[u32], unshot: f64) -> Option<SourceShape> {
        let values: Vec<[f64; 3]> = sq.positions.iter().map(|p| [p.x; 3]).collect();
        let element = |e: u32| sq.elements[e as usize];
        let vertex = |v: u32| (!hidden.contains(&v)).then(|| &values[v as usize][..]);
        let power = |c: &[f64]| DVec3::from_slice(&c[..3]);
        SourceShape::build(
            &ShapeInput {
                element: &element,
                vertex: &vertex,
                power: &power,
            },
            0,
            DVec3::Z,
            1.0,
            &[unshot; 3],
        )
    }

    #[test]
    fn samples_take_the_leaf_they_fall_in_and_the_mean_keeps_the_power() {
        let sq = square();
        let shape = shape_of(&sq, &[], 2.0).unwrap();
        // Leaf means of x: element 2 (x in 0.5..1) 0.75, element 3 0.75,
        // element 4 0.25; element 1's children 0.125, 0.375, 0.375, 0.125.
        // Area mean: (0.75 + 0.75 + 0.25) / 4 + (0.125 + 0.375) × 2 / 16 = 0.5.
        // The unshot (2.0) over that mean scales every leaf by 4.
        let at = |x: f64, y: f64| shape.at(DVec3::new(x, y, 0.0))[0];
        assert!((at(0.8, 0.2) - 3.0).abs() < 1e-12);
        assert!((at(0.2, 0.8) - 1.0).abs() < 1e-12);
        assert!((at(0.1, 0.1) - 0.5).abs() < 1e-12);
        assert!((at(0.4, 0.1) - 1.5).abs() < 1e-12);
        // The area mean of the shape is the unshot radiance (the uniform
        // shot's power): integrate on a fine grid.
        let n = 200;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                sum += at((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
            }
        }
        assert!(
            (sum / (n * n) as f64 - 2.0).abs() < 1e-9,
            "{}",
            sum / (n * n) as f64
        );
    }

    #[test]
    fn points_on_lines_and_just_outside_find_a_leaf() {
        let sq = square();
        let shape = shape_of(&sq, &[], 1.0).unwrap();
        // The unshot (1.0) over the area mean of x (0.5) scales leaves by 2.
        // On the line between elements 3 (mean 0.75) and 4 (mean 0.25)
        // either side is right.
        let on_line = shape.at(DVec3::new(0.5, 0.7, 0.0))[0];
        assert!(on_line == 1.5 || on_line == 0.5, "{on_line}");
        // Rounding off the patch: the nearest child.
        let outside = shape.at(DVec3::new(1.0 + 1e-7, 0.9, 0.0))[0];
        assert!((outside - 0.75 / 0.5).abs() < 1e-12);
    }

    #[test]
    fn hidden_corners_are_left_out_and_a_whole_patch_is_uniform() {
        let sq = square();
        // Vertex 2 (x = 1) hidden: element 3's mean is that of 8, 5, 6 (x =
        // 0.5, 1, 0.5): 2/3.
        let shape = shape_of(&sq, &[2], 1.0).unwrap();
        let ratio = shape.at(DVec3::new(0.8, 0.8, 0.0))[0] / shape.at(DVec3::new(0.8, 0.2, 0.0))[0];
        assert!((ratio - (2.0 / 3.0) / 0.75).abs() < 1e-12);
        // A patch that is one element has no shape.
        let mut whole = square();
        whole.elements[0].first_child = None;
        assert!(shape_of(&whole, &[], 1.0).is_none());
        // A dark patch with unshot light cannot be shaped by its radiance.
        let dark = square();
        let values = vec![[0.0; 3]; dark.positions.len()];
        let element = |e: u32| dark.elements[e as usize];
        let vertex = |v: u32| Some(&values[v as usize][..]);
        let power = |c: &[f64]| DVec3::from_slice(&c[..3]);
        let input = ShapeInput {
            element: &element,
            vertex: &vertex,
            power: &power,
        };
        assert!(SourceShape::build(&input, 0, DVec3::Z, 1.0, &[1.0; 3]).is_none());
    }
}
