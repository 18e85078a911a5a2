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

/// The radiance to display: `radiance`, except at hidden vertices, which take
/// the mean of their already-known neighbours along the display `triangles`,
/// ring by ring outward from the visible ones (a vertex with no path to a
/// visible one keeps its own value). An element that straddles a contact line
/// then interpolates between visible radiance and its extension, not toward
/// the dark inside; the extension is constant across one element, so the
/// error left on the visible side is the radiance's change over one element
/// there, which adaptive subdivision keeps small.
pub fn fill_hidden(triangles: &[[u32; 3]], hidden: &[bool], radiance: &[DVec3]) -> Vec<DVec3> {
    let mut value = radiance.to_vec();
    if !hidden.iter().any(|&h| h) {
        return value;
    }
    let mut known: Vec<bool> = hidden.iter().map(|&h| !h).collect();
    known.resize(radiance.len(), true);
    let mut sum = vec![DVec3::ZERO; radiance.len()];
    let mut count = vec![0u32; radiance.len()];
    loop {
        for t in triangles {
            for (i, &a) in t.iter().enumerate() {
                if known[a as usize] {
                    continue;
                }
                for &b in [t[(i + 1) % 3], t[(i + 2) % 3]].iter() {
                    if known[b as usize] {
                        sum[a as usize] += value[b as usize];
                        count[a as usize] += 1;
                    }
                }
            }
        }
        let mut filled = false;
        for v in 0..value.len() {
            if count[v] > 0 {
                value[v] = sum[v] / count[v] as f64;
                known[v] = true;
                sum[v] = DVec3::ZERO;
                count[v] = 0;
                filled = true;
            }
        }
        if !filled {
            return value;
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

    #[test]
    fn fill_extends_visible_radiance_ring_by_ring() {
        // A strip of vertices 0–1–2–3 (0 visible, the rest hidden) as two
        // triangles each: the hidden ones take their known neighbours' mean,
        // outward from the visible one.
        //   0 - 1 - 2 - 3
        //   |   |   |   |
        //   4 - 5 - 6 - 7   (4 visible at 2, 5 hidden)
        let tris = [
            [0, 4, 5],
            [0, 5, 1],
            [1, 5, 6],
            [1, 6, 2],
            [2, 6, 7],
            [2, 7, 3],
        ];
        let hidden = [false, true, true, true, false, true, true, true];
        let l = |x: f64| DVec3::splat(x);
        let radiance = [
            l(1.0),
            l(0.0),
            l(0.0),
            l(0.0),
            l(2.0),
            l(0.0),
            l(0.0),
            l(0.0),
        ];
        let shown = fill_hidden(&tris, &hidden, &radiance);
        assert_eq!(shown[0], l(1.0));
        assert_eq!(shown[4], l(2.0));
        // Ring 1: vertex 1 sees 0 once; vertex 5 sees 0 twice and 4 once.
        assert_eq!(shown[1], l(1.0));
        assert!((shown[5].x - 4.0 / 3.0).abs() < 1e-12);
        // Later rings average what the earlier ones filled.
        for v in [2, 3, 6, 7] {
            assert!(
                shown[v].x >= 1.0 && shown[v].x <= 4.0 / 3.0,
                "{v}: {}",
                shown[v]
            );
        }
        // Nothing hidden: unchanged.
        assert_eq!(
            fill_hidden(&tris, &[false; 8], &radiance),
            radiance.to_vec()
        );
    }
}
