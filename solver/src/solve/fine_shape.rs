//! The received radiance across a quad source at a finer grain than its
//! quadrants, for directional shots (issue 14, "uniform shooters").
//!
//! A glossy receiver close to a source reflects an image of it, and a
//! quadrant is coarser than that image: on the glossy Cornell box at `final`
//! a quadrant of a 72 mm floor patch is 36 mm across, while an α = 0.1 lobe
//! seen from 50–100 mm covers about 10 mm of the floor. A quadrant
//! straddling a shadow's edge (a step from about 0.005 to 0.8 in front of the
//! short block) shot its lit part's light from its dark part too. Shaping
//! each quadrant by its vertices moved the floor camera's error against the
//! 0.5%-noise truth from 4.11% / HDR-FLIP 0.0811 to 3.90% / 0.0777 and left
//! the standard camera as it was (2.03% / 0.0475 → 2.05% / 0.0481;
//! docs/lab/glossy-quadrants.md, "Glossy: shots shaped inside quadrants").
//!
//! The shape is kept on a grid of (N + 1)² nodes in the quad's bilinear
//! coordinates (u, v), N = [`FINE_CELLS`]: each visible vertex adds its
//! received radiance, times its gather weight, to the four nodes of its cell
//! with bilinear weights; nodes no vertex reached take the mean of their
//! reached neighbours, ring by ring. A point's value is the bilinear
//! interpolation of its cell's nodes (Gouraud shading of the grid, as the
//! elements are shaded), divided by its quadrant's mean of that
//! interpolation, so that the quadrants' scales, and with them the exact
//! quadrant factors of [`super::regions::QuadrantScale::sample_scales`], stay
//! as they were: the fine shape only moves light within a quadrant.

use crate::geometry::polygon::inverse_bilinear;
use glam::DVec3;

/// Cells per side of the fine grid. Even, so that the quadrants' dividing lines
/// (u = ½, v = ½) are cell edges; 8 puts a node every 9 mm on the Cornell
/// box's 72 mm patches, about the spacing of a 32-sample shot's points on the
/// patch (72 / √32 = 13 mm), so finer cells would be resolved by no sample.
pub const FINE_CELLS: usize = 8;

/// Nodes whose value differs from the mean by less than this fraction of the
/// mean's brightest channel leave the shape flat (as
/// [`super::regions::UNIFORM_TOLERANCE`] for the quadrants).
pub const FLAT_TOLERANCE: f64 = 0.02;

/// A quad source's received radiance relative to each quadrant's mean.
pub struct FineShape {
    corners: [DVec3; 4],
    /// Per node, row-major in v then u: the shape over its quadrant's mean,
    /// per channel. Nodes on a dividing line hold one value per side, so the
    /// grid is stored per quadrant: `(N/2 + 1)²` nodes each.
    relative: [Vec<DVec3>; 4],
}

const HALF: usize = FINE_CELLS / 2;
const SIDE: usize = FINE_CELLS + 1;

impl FineShape {
    /// The shape of quad `c` (corners in bilinear order: (0,0), (1,0), (1,1),
    /// (0,1)) from `samples` (position, gather weight, received radiance) of
    /// its visible vertices; `None` when no sample lies inside a quadrant
    /// ([`refined_inside_a_quadrant`]) or the shape is flat within
    /// [`FLAT_TOLERANCE`].
    pub fn new(c: &[DVec3; 4], samples: impl Iterator<Item = (DVec3, f64, DVec3)>) -> Option<Self> {
        // Each weighted sample in bilinear coordinates, inverted once.
        let samples: Vec<_> = samples
            .filter(|s| s.1 > 0.0)
            .map(|(x, w, l)| (inverse_bilinear(c, x), w, l))
            .collect();
        if !refined_inside_a_quadrant(&samples) {
            return None;
        }
        let nodes = splat(&samples);
        let mean = nodes.iter().copied().sum::<DVec3>() / nodes.len() as f64;
        let limit = FLAT_TOLERANCE * mean.max_element();
        if limit <= 0.0
            || nodes
                .iter()
                .all(|v| (*v - mean).abs().max_element() <= limit)
        {
            return None;
        }
        Some(Self {
            corners: *c,
            relative: std::array::from_fn(|q| relative_to_mean(&nodes, q)),
        })
    }

    /// The shape at point `p` of the quad's plane over its quadrant's mean.
    pub fn at(&self, p: DVec3) -> DVec3 {
        // inverse_bilinear's (u, v) lie in [0, 1]².
        let (u, v) = inverse_bilinear(&self.corners, p);
        let (x, y) = (u * FINE_CELLS as f64, v * FINE_CELLS as f64);
        let q = quadrant_of(x, y);
        // Coordinates within the quadrant's own (HALF + 1)² nodes.
        let (ox, oy) = quadrant_origin(q);
        let (lx, ly) = (
            (x - ox as f64).clamp(0.0, HALF as f64),
            (y - oy as f64).clamp(0.0, HALF as f64),
        );
        let (i, j) = ((lx as usize).min(HALF - 1), (ly as usize).min(HALF - 1));
        let (fx, fy) = (lx - i as f64, ly - j as f64);
        let n = &self.relative[q];
        let at = |i: usize, j: usize| n[j * (HALF + 1) + i];
        at(i, j) * ((1.0 - fx) * (1.0 - fy))
            + at(i + 1, j) * (fx * (1.0 - fy))
            + at(i + 1, j + 1) * (fx * fy)
            + at(i, j + 1) * ((1.0 - fx) * fy)
    }
}

/// Whether a sample lies off the quadrants' own 3 × 3 lattice (corners, edge
/// midpoints, centre): only a patch that adaptive subdivision split inside
/// a quadrant knows more of its light than the quadrants hold. An unsplit
/// patch's corners, or a once-split patch's nine vertices, give each
/// quadrant a bilinear ramp at most, which the quadrants' exact factors
/// already shoot as its mean; shaping them would invent a profile between
/// vertices that no split found.
fn refined_inside_a_quadrant(samples: &[((f64, f64), f64, DVec3)]) -> bool {
    samples.iter().any(|&((u, v), _, _)| {
        let off = |t: f64| {
            let half = 2.0 * t;
            (half - half.round()).abs() > 1e-6
        };
        off(u) || off(v)
    })
}

/// The quadrant (as in [`super::regions::quadrants`]: 0 at corner (0,0), 1 at
/// (1,0), 2 at (1,1), 3 at (0,1)) of grid point (x, y), x and y in cells.
fn quadrant_of(x: f64, y: f64) -> usize {
    let h = HALF as f64;
    match (x >= h, y >= h) {
        (false, false) => 0,
        (true, false) => 1,
        (true, true) => 2,
        (false, true) => 3,
    }
}

/// The grid node at quadrant `q`'s (0, 0) corner of its own nodes.
fn quadrant_origin(q: usize) -> (usize, usize) {
    match q {
        0 => (0, 0),
        1 => (HALF, 0),
        2 => (HALF, HALF),
        _ => (0, HALF),
    }
}

/// The grid's node values from samples ((u, v), gather weight > 0, value):
/// each sample's weighted value spread bilinearly over its cell's four
/// nodes, unreached nodes filled from their neighbours. At least one sample
/// is given ([`FineShape::new`] returns before otherwise), so every node
/// gets a value.
fn splat(samples: &[((f64, f64), f64, DVec3)]) -> Vec<DVec3> {
    let mut sum = vec![DVec3::ZERO; SIDE * SIDE];
    let mut weight = vec![0.0f64; SIDE * SIDE];
    for &((u, v), w, l) in samples {
        let (gx, gy) = (u * FINE_CELLS as f64, v * FINE_CELLS as f64);
        let (i, j) = (
            (gx as usize).min(FINE_CELLS - 1),
            (gy as usize).min(FINE_CELLS - 1),
        );
        let (fx, fy) = (gx - i as f64, gy - j as f64);
        for (di, dj, b) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (1, 1, fx * fy),
            (0, 1, (1.0 - fx) * fy),
        ] {
            let k = (j + dj) * SIDE + i + di;
            sum[k] += l * (w * b);
            weight[k] += w * b;
        }
    }
    let mut nodes: Vec<Option<DVec3>> = sum
        .iter()
        .zip(&weight)
        .map(|(s, &w)| (w > 0.0).then(|| *s / w))
        .collect();
    fill_from_neighbours(&mut nodes);
    nodes
        .into_iter()
        .map(|n| n.unwrap_or(DVec3::ZERO))
        .collect()
}

/// Gives each empty node the mean of its filled 4-neighbours, ring by ring
/// outward from the filled ones, until every node has a value (a grid with at
/// least one filled node fills in at most 2N passes).
fn fill_from_neighbours(nodes: &mut [Option<DVec3>]) {
    loop {
        let before = nodes.to_vec();
        let mut changed = false;
        for j in 0..SIDE {
            for i in 0..SIDE {
                if before[j * SIDE + i].is_some() {
                    continue;
                }
                let mut sum = DVec3::ZERO;
                let mut count = 0;
                let neighbours = [
                    (i.wrapping_sub(1), j),
                    (i + 1, j),
                    (i, j.wrapping_sub(1)),
                    (i, j + 1),
                ];
                for (ni, nj) in neighbours {
                    if ni < SIDE && nj < SIDE {
                        if let Some(v) = before[nj * SIDE + ni] {
                            sum += v;
                            count += 1;
                        }
                    }
                }
                if count > 0 {
                    nodes[j * SIDE + i] = Some(sum / count as f64);
                    changed = true;
                }
            }
        }
        if !changed {
            return;
        }
    }
}

/// Quadrant `q`'s nodes divided by the mean of their bilinear interpolation
/// over the quadrant (each cell's mean is its four nodes' mean), per channel;
/// a channel whose mean is 0 gets 1 (nothing to shape).
fn relative_to_mean(nodes: &[DVec3], q: usize) -> Vec<DVec3> {
    let (ox, oy) = quadrant_origin(q);
    let node = |i: usize, j: usize| nodes[(oy + j) * SIDE + ox + i];
    let mut mean = DVec3::ZERO;
    for j in 0..HALF {
        for i in 0..HALF {
            mean += (node(i, j) + node(i + 1, j) + node(i + 1, j + 1) + node(i, j + 1)) / 4.0;
        }
    }
    mean /= (HALF * HALF) as f64;
    let mut out = Vec::with_capacity((HALF + 1) * (HALF + 1));
    for j in 0..=HALF {
        for i in 0..=HALF {
            let v = node(i, j);
            out.push(DVec3::from_array(std::array::from_fn(|k| {
                if mean[k] > 0.0 {
                    v[k] / mean[k]
                } else {
                    1.0
                }
            })));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::regions::tests::square;
    use super::*;

    /// Samples on the node lattice of the square with value `f(x, y)`.
    fn lattice(f: impl Fn(f64, f64) -> f64) -> Vec<(DVec3, f64, DVec3)> {
        let mut out = Vec::new();
        for j in 0..SIDE {
            for i in 0..SIDE {
                let (x, y) = (
                    2.0 * i as f64 / FINE_CELLS as f64,
                    2.0 * j as f64 / FINE_CELLS as f64,
                );
                out.push((DVec3::new(x, y, 0.0), 1.0, DVec3::splat(f(x, y))));
            }
        }
        out
    }

    #[test]
    fn a_step_inside_a_quadrant_is_kept_and_each_quadrant_keeps_its_mean() {
        // Lit (1) for x < 0.5, dark (0.01) beyond: the step lies inside
        // quadrants 0 and 3 (x < 1). The shape must show it, and each
        // quadrant's mean of the relative shape must be 1 (to rounding), so
        // the quadrants' power is untouched.
        let f = |x: f64, _y: f64| if x < 0.5 { 1.0 } else { 0.01 };
        let shape = FineShape::new(&square(), lattice(f).into_iter()).expect("not flat");
        let lit = shape.at(DVec3::new(0.1, 0.4, 0.0));
        let dark = shape.at(DVec3::new(0.9, 0.4, 0.0));
        assert!(lit.x > 30.0 * dark.x, "lit {lit} dark {dark}");
        for q in 0..4 {
            let (ox, oy) = quadrant_origin(q);
            let n = 64;
            let mut mean = 0.0;
            for j in 0..n {
                for i in 0..n {
                    let x = (ox as f64 + HALF as f64 * (i as f64 + 0.5) / n as f64) * 2.0
                        / FINE_CELLS as f64;
                    let y = (oy as f64 + HALF as f64 * (j as f64 + 0.5) / n as f64) * 2.0
                        / FINE_CELLS as f64;
                    mean += shape.at(DVec3::new(x, y, 0.0)).x;
                }
            }
            mean /= (n * n) as f64;
            assert!((mean - 1.0).abs() < 1e-9, "quadrant {q}: mean {mean}");
        }
    }

    #[test]
    fn a_flat_or_empty_patch_has_no_shape() {
        assert!(FineShape::new(&square(), lattice(|_, _| 0.7).into_iter()).is_none());
        assert!(FineShape::new(&square(), std::iter::empty()).is_none());
    }

    #[test]
    fn an_unsplit_or_once_split_patch_has_no_shape() {
        // Corners, edge midpoints and centre only: nothing inside a quadrant.
        let c = square();
        let once: Vec<_> = (0..3)
            .flat_map(|j| (0..3).map(move |i| (i, j)))
            .map(|(i, j)| {
                (
                    DVec3::new(i as f64, j as f64, 0.0),
                    1.0,
                    DVec3::splat(0.1 + i as f64),
                )
            })
            .collect();
        assert!(FineShape::new(&c, once.into_iter()).is_none());
    }

    #[test]
    fn nodes_no_vertex_reached_take_their_neighbours_values() {
        // The corners (dark on the left, lit on the right) and one vertex
        // inside quadrant 1: the nodes between fill from them, so the
        // shape follows the gradient from dark to lit.
        let c = square();
        let values = [0.2, 1.0, 1.0, 0.2];
        let samples = (0..4)
            .map(|i| (c[i], 1.0, DVec3::splat(values[i])))
            .chain([(DVec3::new(1.5, 0.5, 0.0), 1.0, DVec3::splat(0.8))]);
        let shape = FineShape::new(&c, samples).expect("not flat");
        let left = shape.at(DVec3::new(0.05, 0.2, 0.0)).x;
        let right = shape.at(DVec3::new(0.95, 0.2, 0.0)).x;
        assert!(right > left, "left {left} right {right}");
    }

    #[test]
    fn a_refined_patch_shoots_its_gouraud_shaded_radiance() {
        // Vertices on the fine lattice with their gather weights (the
        // trapezoid rule's: a cell's area shared by its corners), shaded by a
        // shadow's step at x = 0.5 inside quadrants 0 and 3. The quadrants'
        // means ([`super::super::regions::regions`]) are then the exact area
        // means of the Gouraud-shaded field T, and the fine shape makes each
        // point's scale of the patch mean T(p) / mean(T) exactly (1e-12,
        // rounding): the shot's radiance at every point is the one the
        // solution shows there. Without it a point in the shadow shoots its
        // quadrant's mean, 10× and more its own radiance.
        use super::super::regions::{regions, QuadrantScale};
        let c = square();
        let h = 2.0 / FINE_CELLS as f64;
        let t = |x: f64| if x < 0.5 { 1.0 } else { 0.01 };
        let samples: Vec<_> = (0..SIDE)
            .flat_map(|j| (0..SIDE).map(move |i| (i, j)))
            .map(|(i, j)| {
                let edge = |k: usize| if k == 0 || k == FINE_CELLS { 0.5 } else { 1.0 };
                let (x, y) = (i as f64 * h, j as f64 * h);
                (
                    DVec3::new(x, y, 0.0),
                    h * h * edge(i) * edge(j),
                    DVec3::splat(t(x)),
                )
            })
            .collect();
        // T is bilinear between nodes: along x it ramps from 1 at 0.25 to
        // 0.01 at 0.5, and is constant in y.
        let shaded = |x: f64| {
            let i = ((x / h) as usize).min(FINE_CELLS - 1);
            let f = x / h - i as f64;
            t(i as f64 * h) * (1.0 - f) + t((i + 1) as f64 * h) * f
        };
        let mean_t = (0..4000)
            .map(|k| shaded((k as f64 + 0.5) * 2.0 / 4000.0))
            .sum::<f64>()
            / 4000.0;
        let fine = FineShape::new(&c, samples.iter().copied());
        assert!(fine.is_some());
        let scale = |fine| QuadrantScale {
            corners: c,
            normal: DVec3::Z,
            centre: DVec3::new(1.0, 1.0, 0.0),
            diameter: 8.0f64.sqrt(),
            regions: regions(&c, DVec3::Z, DVec3::ONE, samples.iter().copied()).expect("uneven"),
            fine,
        };
        let (shaped, flat) = (scale(fine), scale(None));
        for &(x, y) in &[
            (0.1, 0.3),
            (0.3, 1.7),
            (0.45, 0.2),
            (0.8, 0.6),
            (1.3, 0.4),
            (1.9, 1.9),
        ] {
            let p = DVec3::new(x, y, 0.0);
            let got = shaped.scale_at(p).x * mean_t;
            assert!(
                (got - shaded(x)).abs() < 1e-12,
                "({x}, {y}): {got} against {}",
                shaded(x)
            );
        }
        let dark = DVec3::new(0.8, 0.6, 0.0);
        assert!(flat.scale_at(dark).x * mean_t > 10.0 * shaded(0.8));
    }
}
