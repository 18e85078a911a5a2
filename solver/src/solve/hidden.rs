//! Hidden receivers: mesh vertices whose receiving point lies inside or under
//! another object, where no eye and no light can reach it.
//!
//! Scenes are built of overlapping polygons: the Cornell box's floor is one
//! quad that runs under both blocks (which have no bottom face), and its light
//! hangs 0.1 mm below a ceiling quad that runs above it. A vertex of the floor
//! under a block receives nothing and goes dark. That darkness is not wrong
//! where it is (nobody sees it), but it leaks twice:
//!
//! * Gouraud interpolation across an element that straddles the contact line
//!   spreads it into the visible floor next to the block (the dark rims of
//!   docs/lab/hidden-receivers.md's heat maps);
//! * the gather into patches averages it into the patch's unshot radiance, and
//!   the shot that follows loses the hidden part a second time, since its
//!   visibility rays to samples under the block are blocked as well. A floor
//!   patch half under a block then shoots about a quarter of its visible
//!   half's power instead of a half.
//!
//! So a hidden vertex is treated as hidden rather than as a dark receiver: the
//! gather leaves it out (the patch shoots the mean radiance of its visible
//! part, and the shot's visibility rays remove the hidden part once), and the
//! displayed radiance at it is extended from its visible neighbours, so no
//! visible element interpolates toward it ([`fill_hidden`]).
//!
//! A receiving point is hidden when every probe ray over its hemisphere meets
//! the back of a surface ([`is_hidden`]): it is enclosed by an object's inside,
//! as under a block or between the ceiling and the light's back. A point in
//! the open, in a narrow gap between two objects or in a room's corner sees
//! front faces or nothing along some probe, and stays a receiver.

use crate::geometry::visibility::Occluder;
use glam::DVec3;
use std::ops::Range;

/// Probe directions: rings of (polar angle from the normal in degrees, rays).
/// Three rings reach 75° from the normal: a point under the light's back,
/// 0.1 mm below the ceiling, escapes along the most grazing probe only within
/// 0.1 mm · tan 75° = 0.37 mm of the light's edge.
const RINGS: [(f64, u32); 3] = [(0.0, 1), (40.0, 6), (75.0, 12)];

/// Whether the receiving point `q` with unit normal `n` is enclosed by back
/// faces: every probe ray from `q` (lifted the occluder's epsilon along `n`)
/// meets a surface, and meets it from behind.
pub fn is_hidden(occluder: &Occluder, q: DVec3, n: DVec3) -> bool {
    let origin = q + n * occluder.scene_epsilon();
    let t = n.any_orthonormal_vector();
    let b = n.cross(t);
    for (ring, &(polar, count)) in RINGS.iter().enumerate() {
        let (sin, cos) = polar.to_radians().sin_cos();
        for k in 0..count {
            // Successive rings are rotated by half a step so their rays interleave.
            let phi = (k as f64 + 0.5 * ring as f64) * std::f64::consts::TAU / count as f64;
            let dir = n * cos + (t * phi.cos() + b * phi.sin()) * sin;
            match occluder.closest_hit(origin, dir, f64::INFINITY) {
                Some(hit) if !hit.front => {}
                _ => return false,
            }
        }
    }
    true
}

/// Per vertex `v`, the block `3v..3v + 3` of a flat array: one RGB value a
/// vertex (the diffuse output's radiance, the E/π of textured surfaces), the
/// layout [`fill_hidden`] and `seams.rs` take for those.
pub(crate) fn rgb(v: usize) -> Range<usize> {
    3 * v..3 * v + 3
}

/// The values to display, in place: per vertex `v` the block `range(v)` of
/// `values` (an RGB radiance, or a vector of SH coefficients per channel),
/// unchanged except at hidden vertices, which take the mean of their
/// already-known neighbours' blocks along the display `triangles`, ring by
/// ring outward from the visible ones (a vertex with no path to a visible one
/// keeps its own value). An element that straddles a contact line then
/// interpolates between visible values and their extension, not toward the
/// dark inside; the extension is constant across one element, so the error
/// left on the visible side is the value's change over one element there,
/// which adaptive subdivision keeps small.
///
/// Averaging SH coefficient vectors averages the radiance functions they
/// stand for (SH evaluation is linear), which is meaningful only within one
/// frame: a display triangle lies in one polygon, and every vertex of a
/// polygon shares its surface's order and frame (`directional.rs`, "Frames
/// on smooth surfaces"), so neighbours along the display triangles always
/// agree; a neighbour whose block has another length is skipped all the
/// same, so that no two frames are ever mixed.
pub fn fill_hidden(
    triangles: &[[u32; 3]],
    hidden: &[bool],
    vertex_count: usize,
    range: impl Fn(usize) -> Range<usize>,
    values: &mut [f64],
) {
    if !hidden.iter().any(|&h| h) {
        return;
    }
    let mut known: Vec<bool> = (0..vertex_count)
        .map(|v| !hidden.get(v).copied().unwrap_or(false))
        .collect();
    let mut sum = vec![0.0; values.len()];
    let mut count = vec![0u32; vertex_count];
    loop {
        for t in triangles {
            for (i, &a) in t.iter().enumerate() {
                let a = a as usize;
                if known[a] {
                    continue;
                }
                let into = range(a);
                for &b in [t[(i + 1) % 3], t[(i + 2) % 3]].iter() {
                    let b = b as usize;
                    let from = range(b);
                    if !known[b] || from.len() != into.len() {
                        continue;
                    }
                    for (s, x) in sum[into.clone()].iter_mut().zip(&values[from]) {
                        *s += x;
                    }
                    count[a] += 1;
                }
            }
        }
        let mut filled = false;
        for v in 0..vertex_count {
            if count[v] == 0 {
                continue;
            }
            let n = count[v] as f64;
            let block = range(v);
            for (x, s) in values[block.clone()].iter_mut().zip(&mut sum[block]) {
                *x = *s / n;
                *s = 0.0;
            }
            known[v] = true;
            count[v] = 0;
            filled = true;
        }
        if !filled {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box [0, 1]³ without a bottom face (faces wound to face outward) on a
    /// floor [−2, 3]² at y = 0 facing up: the Cornell box's blocks.
    fn box_on_floor() -> Occluder {
        let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let floor = vec![
            p(-2., 0., -2.),
            p(-2., 0., 3.),
            p(3., 0., 3.),
            p(3., 0., -2.),
        ];
        let top = vec![p(0., 1., 0.), p(0., 1., 1.), p(1., 1., 1.), p(1., 1., 0.)];
        let front = vec![p(0., 0., 0.), p(0., 1., 0.), p(1., 1., 0.), p(1., 0., 0.)];
        let back = vec![p(0., 0., 1.), p(1., 0., 1.), p(1., 1., 1.), p(0., 1., 1.)];
        let left = vec![p(0., 0., 0.), p(0., 0., 1.), p(0., 1., 1.), p(0., 1., 0.)];
        let right = vec![p(1., 0., 0.), p(1., 1., 0.), p(1., 1., 1.), p(1., 0., 1.)];
        Occluder::new(&[floor, top, front, back, left, right])
    }

    #[test]
    fn floor_under_a_box_is_hidden_and_beside_it_is_not() {
        let occluder = box_on_floor();
        let up = DVec3::Y;
        for (x, z, hidden) in [
            (0.5, 0.5, true),
            (0.001, 0.5, true),
            (0.999, 0.999, true),
            (-0.001, 0.5, false),
            (1.001, 0.5, false),
            (0.5, -0.001, false),
            (2.0, 2.0, false),
        ] {
            let q = DVec3::new(x, 0.0, z);
            assert_eq!(is_hidden(&occluder, q, up), hidden, "floor at ({x}, {z})");
        }
        // The box's own faces look outward into the open: never hidden.
        assert!(!is_hidden(&occluder, DVec3::new(0.5, 0.01, 0.0), -DVec3::Z));
        assert!(!is_hidden(&occluder, DVec3::new(0.5, 1.0, 0.5), DVec3::Y));
    }

    #[test]
    fn ceiling_above_a_hanging_light_is_hidden() {
        // A ceiling at y = 1 facing down, and a light 1e-4 below it facing
        // down, as in the Cornell box (0.1 mm under a 549 mm ceiling).
        let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let ceiling = vec![
            p(-1., 1., -1.),
            p(2., 1., -1.),
            p(2., 1., 2.),
            p(-1., 1., 2.),
        ];
        let light = vec![
            p(0., 0.9999, 0.),
            p(1., 0.9999, 0.),
            p(1., 0.9999, 1.),
            p(0., 0.9999, 1.),
        ];
        let floor = vec![
            p(-1., 0., -1.),
            p(-1., 0., 2.),
            p(2., 0., 2.),
            p(2., 0., -1.),
        ];
        let occluder = Occluder::new(&[ceiling, light, floor]);
        let down = -DVec3::Y;
        assert!(is_hidden(&occluder, p(0.5, 1.0, 0.5), down));
        assert!(is_hidden(&occluder, p(0.01, 1.0, 0.99), down));
        assert!(!is_hidden(&occluder, p(-0.01, 1.0, 0.5), down));
        // The light itself shines into the room.
        assert!(!is_hidden(&occluder, p(0.5, 0.9999, 0.5), down));
    }

    #[test]
    fn a_closed_room_has_no_hidden_point() {
        // Inside a room every probe meets a wall's front: nothing is hidden,
        // so scenes without overlaps solve exactly as before.
        let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let floor = vec![p(0., 0., 0.), p(0., 0., 1.), p(1., 0., 1.), p(1., 0., 0.)];
        let ceiling = vec![p(0., 1., 0.), p(1., 1., 0.), p(1., 1., 1.), p(0., 1., 1.)];
        let walls = [
            vec![p(0., 0., 0.), p(1., 0., 0.), p(1., 1., 0.), p(0., 1., 0.)],
            vec![p(0., 0., 1.), p(0., 1., 1.), p(1., 1., 1.), p(1., 0., 1.)],
            vec![p(0., 0., 0.), p(0., 1., 0.), p(0., 1., 1.), p(0., 0., 1.)],
            vec![p(1., 0., 0.), p(1., 0., 1.), p(1., 1., 1.), p(1., 1., 0.)],
        ];
        let mut all = vec![floor, ceiling];
        all.extend(walls);
        let occluder = Occluder::new(&all);
        for (q, n) in [
            (p(0.5, 0.0, 0.5), DVec3::Y),
            (p(0.001, 0.0, 0.001), DVec3::Y),
            (p(0.5, 1.0, 0.5), -DVec3::Y),
            (p(0.0, 0.5, 0.5), DVec3::X),
        ] {
            assert!(!is_hidden(&occluder, q, n), "{q}");
        }
    }

    /// A strip of vertices as two triangles a square:
    ///   0 - 1 - 2 - 3
    ///   |   |   |   |
    ///   4 - 5 - 6 - 7   (0 and 4 visible, the rest hidden)
    const TRIS: [[u32; 3]; 6] = [
        [0, 4, 5],
        [0, 5, 1],
        [1, 5, 6],
        [1, 6, 2],
        [2, 6, 7],
        [2, 7, 3],
    ];
    const HIDDEN: [bool; 8] = [false, true, true, true, false, true, true, true];

    /// `values` with the hidden vertices of [`TRIS`] filled, per vertex `v` the
    /// block `range(v)`.
    fn filled(hidden: &[bool], range: impl Fn(usize) -> Range<usize>, values: &[f64]) -> Vec<f64> {
        let mut shown = values.to_vec();
        fill_hidden(&TRIS, hidden, 8, range, &mut shown);
        shown
    }

    #[test]
    fn fill_extends_visible_radiance_ring_by_ring() {
        // RGB radiance (the diffuse output): vertex 0 at 1, vertex 4 at 2,
        // the hidden ones at 0; the hidden ones take their known neighbours'
        // mean, outward from the visible ones.
        let mut radiance = [0.0; 24];
        radiance[rgb(0)].fill(1.0);
        radiance[rgb(4)].fill(2.0);
        let shown = filled(&HIDDEN, rgb, &radiance);
        let at = |v: usize| DVec3::from_slice(&shown[rgb(v)]);
        assert_eq!(at(0), DVec3::splat(1.0));
        assert_eq!(at(4), DVec3::splat(2.0));
        // Ring 1: vertex 1 sees 0 once; vertex 5 sees 0 twice and 4 once.
        assert_eq!(at(1), DVec3::splat(1.0));
        assert!((at(5) - DVec3::splat(4.0 / 3.0)).abs().max_element() < 1e-12);
        // Later rings average what the earlier ones filled.
        for v in [2, 3, 6, 7] {
            assert!(at(v).x >= 1.0 && at(v).x <= 4.0 / 3.0, "{v}: {}", at(v));
        }
        // Nothing hidden: unchanged.
        assert_eq!(filled(&[false; 8], rgb, &radiance), radiance.to_vec());
    }

    #[test]
    fn higher_order_blocks_average_every_coefficient() {
        // Blocks of 12 values (order 1, RGB; the directional output): the
        // visible vertices carry distinct functions; each hidden vertex's
        // block is the same mean of them for every coefficient, so evaluating
        // it in any direction gives the mean of the neighbours' radiance in
        // that direction.
        let block = |v: usize| 12 * v..12 * v + 12;
        let mut values = vec![0.0; 96];
        for k in 0..12 {
            values[k] = 1.0 + k as f64; // vertex 0
            values[48 + k] = 2.0 * k as f64 - 3.0; // vertex 4
        }
        let shown = filled(&HIDDEN, block, &values);
        for k in 0..12 {
            let (a, b) = (values[k], values[48 + k]);
            // Ring 1: vertex 1 sees only 0; vertex 5 sees 0 twice and 4 once.
            assert_eq!(shown[12 + k], a);
            assert!((shown[60 + k] - (2.0 * a + b) / 3.0).abs() < 1e-12);
            // Visible blocks are untouched.
            assert_eq!(shown[k], a);
            assert_eq!(shown[48 + k], b);
        }
    }

    #[test]
    fn neighbours_of_another_order_are_skipped() {
        // Vertex 1 (hidden, order 1) touches 0 (order 0) and 5 (hidden,
        // order 1), which touches 4 (order 1, visible): it must take 4's
        // block through 5, never a 3-value block read as 12.
        let ranges = [0..3, 3..15, 15..18, 18..21, 21..33, 33..45, 45..48, 48..51];
        let mut values = vec![7.0; 51];
        values[3..15].fill(0.0);
        values[33..45].fill(0.0);
        for (k, x) in values[21..33].iter_mut().enumerate() {
            *x = k as f64;
        }
        let hidden = [false, true, false, false, false, true, false, false];
        let shown = filled(&hidden, |v| ranges[v].clone(), &values);
        assert_eq!(&shown[33..45], &values[21..33]);
        assert_eq!(&shown[3..15], &values[21..33]);
    }
}
