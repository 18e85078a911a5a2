//! Finding sky portals in the geometry (`portal_detect.rs`): the openings
//! of closed rooms are found, with their exact corners and facing into the
//! room; outer rims, covered loops and bent loops are not.
//!
//! Tolerances: a portal's corners are the loop's points (2 units from the
//! origin at most) moved into 2-D and back by one orthonormal basis, a few
//! rounding errors of 1.1e-16 each: 1e-9 of the room's size bounds them
//! with a margin of six orders and still tells one vertex from another.
//! Areas, sums of a few products of such coordinates, get 1e-12.

use super::portal::Portal;
use super::portal_detect::{detect_portals, Detection, MAX_DETECTED_PORTALS};
use glam::DVec3;

/// The rooms' side.
const S: f64 = 2.0;

/// A point on the plane `axis` = `at`, at (u, v) along the other two axes
/// in order.
fn on(axis: usize, at: f64, u: f64, v: f64) -> DVec3 {
    let mut p = [0.0; 3];
    p[axis] = at;
    p[(axis + 1) % 3] = u;
    p[(axis + 2) % 3] = v;
    DVec3::from(p)
}

/// The rectangle [u0, u1] × [v0, v1] on `axis` = `at`, counter-clockwise
/// seen from the room's centre; none when it is empty.
fn panel(axis: usize, at: f64, u: [f64; 2], v: [f64; 2]) -> Option<Vec<DVec3>> {
    if u[1] <= u[0] || v[1] <= v[0] {
        return None;
    }
    Some(facing_in(vec![
        on(axis, at, u[0], v[0]),
        on(axis, at, u[1], v[0]),
        on(axis, at, u[1], v[1]),
        on(axis, at, u[0], v[1]),
    ]))
}

/// `ring` counter-clockwise seen from the room's centre.
fn facing_in(mut ring: Vec<DVec3>) -> Vec<DVec3> {
    let normal = crate::geometry::polygon::newell_normal(&ring);
    if normal.dot(DVec3::splat(0.5 * S) - ring[0]) < 0.0 {
        ring.reverse();
    }
    ring
}

/// The wall `axis` = `at` of the room without the hole [u0, u1] × [v0,
/// v1]: a strip below and above it across the wall and one on either side
/// of it, so that the hole's corners are T-vertices on the strips' edges.
fn wall_with_hole(axis: usize, at: f64, u: [f64; 2], v: [f64; 2]) -> Vec<Vec<DVec3>> {
    [
        panel(axis, at, [0.0, S], [0.0, v[0]]),
        panel(axis, at, [0.0, S], [v[1], S]),
        panel(axis, at, [0.0, u[0]], v),
        panel(axis, at, [u[1], S], v),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// The room's six faces less those `open` names (axis, at): whole walls.
fn room(open: &[(usize, f64)]) -> Vec<Vec<DVec3>> {
    let mut faces = Vec::new();
    for axis in 0..3 {
        for at in [0.0, S] {
            if !open.contains(&(axis, at)) {
                faces.extend(panel(axis, at, [0.0, S], [0.0, S]));
            }
        }
    }
    faces
}

fn detect(polygons: &[Vec<DVec3>]) -> Detection {
    let rings: Vec<&[DVec3]> = polygons.iter().map(Vec::as_slice).collect();
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for p in polygons.iter().flatten() {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    detect_portals(&rings, (hi - lo).length())
}

/// Whether the portal's corners are `expected`'s, in the same cyclic order
/// (either way round), each within 1e-9 of the room's size.
fn same_corners(portal: &Portal, expected: &[DVec3]) -> bool {
    let k = portal.corners();
    let n = expected.len();
    let close = |a: DVec3, b: DVec3| (a - b).length() <= 1e-9 * S;
    k.len() == n
        && (0..n).any(|shift| {
            (0..n).all(|i| close(k[i], expected[(i + shift) % n]))
                || (0..n).all(|i| close(k[i], expected[(n - i + shift) % n]))
        })
}

/// The portal's normal points into the room: toward its centre.
fn faces_the_room(portal: &Portal) -> bool {
    portal.normal().dot(DVec3::splat(0.5 * S) - portal.centre()) > 0.0
}

#[test]
fn a_hole_in_a_wall_of_a_closed_room_is_its_one_portal() {
    // The back wall (z = S) has a window; every other face is whole. The
    // window's corners are T-vertices of the strips around it.
    let (u, v) = ([0.5, 1.25], [0.625, 1.5]);
    let mut polygons = room(&[(2, S)]);
    polygons.extend(wall_with_hole(2, S, u, v));
    let found = detect(&polygons);
    assert_eq!(found.portals.len(), 1, "{found:?}");
    assert_eq!(found.note, None);
    let portal = &found.portals[0];
    let hole =
        [(u[0], v[0]), (u[1], v[0]), (u[1], v[1]), (u[0], v[1])].map(|(x, y)| on(2, S, x, y));
    assert!(same_corners(portal, &hole), "{:?}", portal.corners());
    assert!((portal.area() - 0.75 * 0.875).abs() < 1e-12);
    assert!(portal.is_detected() && faces_the_room(portal));
}

#[test]
fn an_open_ground_plane_has_no_portal() {
    // A 4 × 4 grid of quads facing up: its one boundary loop is the outer
    // rim, and the surface in its plane lies inside it.
    let mut ground = Vec::new();
    for i in 0..4 {
        for j in 0..4 {
            let (x, z) = (i as f64 * 0.5, j as f64 * 0.5);
            ground.push(vec![
                DVec3::new(x, 0.0, z),
                DVec3::new(x, 0.0, z + 0.5),
                DVec3::new(x + 0.5, 0.0, z + 0.5),
                DVec3::new(x + 0.5, 0.0, z),
            ]);
        }
    }
    assert_eq!(detect(&ground), Detection::default());
}

#[test]
fn an_open_bottomed_box_standing_on_a_floor_is_no_opening() {
    // A column modelled without its bottom face stands on the floor: its
    // bottom rim is a hole of the column, but the floor covers it. Lifted
    // off the floor, the same rim is an opening.
    let column = |base: f64| {
        let mut polygons = room(&[]);
        let (a, b, top) = (0.75, 1.25, 1.0);
        let corners = [(a, a), (b, a), (b, b), (a, b)];
        for k in 0..4 {
            let ((x0, z0), (x1, z1)) = (corners[k], corners[(k + 1) % 4]);
            polygons.push(vec![
                DVec3::new(x0, base, z0),
                DVec3::new(x0, top, z0),
                DVec3::new(x1, top, z1),
                DVec3::new(x1, base, z1),
            ]);
        }
        polygons.push(
            [(a, a), (a, b), (b, b), (b, a)]
                .map(|(x, z)| DVec3::new(x, top, z))
                .to_vec(),
        );
        (
            detect(&polygons),
            corners.map(|(x, z)| DVec3::new(x, base, z)),
        )
    };
    let (found, _) = column(0.0);
    assert!(found.portals.is_empty(), "{found:?}");
    let (found, rim) = column(0.25);
    assert_eq!(found.portals.len(), 1, "{found:?}");
    assert!(same_corners(&found.portals[0], &rim));
}

#[test]
fn a_room_without_a_roof_has_the_roof_opening_as_its_portal() {
    // The walls meet the missing roof across its plane: the loop is the
    // rim at y = S, and the room lies below it.
    let found = detect(&room(&[(1, S)]));
    assert_eq!(found.portals.len(), 1, "{found:?}");
    let portal = &found.portals[0];
    let roof = [(0.0, 0.0), (S, 0.0), (S, S), (0.0, S)].map(|(x, z)| DVec3::new(x, S, z));
    assert!(same_corners(portal, &roof), "{:?}", portal.corners());
    assert!(faces_the_room(portal) && portal.normal().y < 0.0);
}

#[test]
fn a_hole_around_a_corner_is_not_planar_and_gives_no_portal() {
    // The opening wraps the vertical corner at x = z = S: it is cut from
    // both walls, so its loop bends by 90° (off its best plane by about a
    // fifth of its size, far above the 1e-3 tolerance).
    let (y, w) = ([0.5, 1.5], [1.25, S]);
    let mut polygons = room(&[(0, S), (2, S)]);
    // Wall x = S: u is y, v is z. Wall z = S: u is x, v is y.
    polygons.extend(wall_with_hole(0, S, y, w));
    polygons.extend(wall_with_hole(2, S, w, y));
    let found = detect(&polygons);
    assert!(found.portals.is_empty(), "{found:?}");
}

#[test]
fn a_round_window_gets_the_square_around_it() {
    // A regular octagon of width 0.8 between opposite sides, in the back
    // wall: the smallest rectangle around it is the 0.8 square whose sides
    // lie on four of its sides.
    let (cx, cy, half) = (1.0, 1.0, 0.4);
    let r = half / (std::f64::consts::PI / 8.0).cos();
    let octagon: Vec<(f64, f64)> = (0..8)
        .map(|k| {
            let a = std::f64::consts::PI / 8.0 + k as f64 * std::f64::consts::PI / 4.0;
            (cx + r * a.cos(), cy + r * a.sin())
        })
        .collect();
    // The wall as a fan of quads from the octagon to the wall's corners.
    let mut polygons = room(&[(2, S)]);
    let corners = [(S, S), (0.0, S), (0.0, 0.0), (S, 0.0)];
    for k in 0..8 {
        let (p, q) = (octagon[k], octagon[(k + 1) % 8]);
        let c = corners[k / 2];
        let mut ring = vec![on(2, S, p.0, p.1), on(2, S, c.0, c.1), on(2, S, q.0, q.1)];
        if k % 2 == 1 {
            let next = corners[(k / 2 + 1) % 4];
            ring.insert(2, on(2, S, next.0, next.1));
        }
        polygons.push(facing_in(ring));
    }
    let found = detect(&polygons);
    assert_eq!(found.portals.len(), 1, "{found:?}");
    let square = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(x, y)| on(2, S, cx + half * x, cy + half * y));
    assert!(
        same_corners(&found.portals[0], &square),
        "{:?}",
        found.portals[0].corners()
    );
}

#[test]
fn only_the_largest_openings_become_portals_with_a_note() {
    // A floor (y = 0) with 20 square holes of growing size in a 5 × 4
    // grid of cells, each hole in its own cell's middle, the cell's rest
    // as four strips: the 16 largest are kept and the note says so.
    let mut polygons = room(&[(1, 0.0)]);
    let cell = S / 5.0;
    let mut sizes = Vec::new();
    for i in 0..5 {
        for j in 0..4 {
            let (x0, z0) = (i as f64 * cell, j as f64 * 0.5);
            let h = 0.05 + 0.005 * (i * 4 + j) as f64;
            sizes.push(h * h);
            let (u, v) = ([x0 + 0.1, x0 + 0.1 + h], [z0 + 0.1, z0 + 0.1 + h]);
            for (a, b) in [
                ([x0, x0 + cell], [z0, v[0]]),
                ([x0, x0 + cell], [v[1], z0 + 0.5]),
                ([x0, u[0]], v),
                ([u[1], x0 + cell], v),
            ] {
                // The floor's u is z and v is x.
                polygons.extend(panel(1, 0.0, b, a));
            }
        }
    }
    let found = detect(&polygons);
    assert_eq!(found.portals.len(), MAX_DETECTED_PORTALS, "{found:?}");
    sizes.sort_by(|a, b| b.total_cmp(a));
    for (portal, area) in found.portals.iter().zip(&sizes) {
        assert!(
            (portal.area() - area).abs() < 1e-12,
            "{} {area}",
            portal.area()
        );
        assert!(faces_the_room(portal));
    }
    let note = found.note.unwrap_or_default();
    assert!(
        note.contains("20 openings") && note.contains("4 smaller"),
        "{note}"
    );
}

/// Writes the room with a window in its back wall as an OBJ of triangles
/// (the importer welds them back into quads) and a config with `body`, and
/// imports it; the window's corners, in the file's coordinates.
fn import_window_room(body: &str) -> (Result<crate::scene::Scene, String>, [DVec3; 4]) {
    let (u, v) = ([0.5, 1.25], [0.625, 1.5]);
    let mut polygons = room(&[(2, S)]);
    polygons.extend(wall_with_hole(2, S, u, v));
    let mut obj = String::new();
    let mut count = 0;
    for q in &polygons {
        for p in q {
            obj.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
        }
        obj.push_str(&format!("f {} {} {}\n", count + 1, count + 2, count + 3));
        obj.push_str(&format!("f {} {} {}\n", count + 1, count + 3, count + 4));
        count += 4;
    }
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("room.obj"), obj).unwrap();
    let path = dir.path().join("room.toml");
    std::fs::write(&path, format!("geometry = [\"room.obj\"]\n{body}")).unwrap();
    let scene = crate::scene::load_scene(&path, &Default::default())
        .map(|l| l.scene)
        .map_err(|e| e.to_string());
    let hole =
        [(u[0], v[0]), (u[1], v[0]), (u[1], v[1]), (u[0], v[1])].map(|(x, y)| on(2, S, x, y));
    (scene, hole)
}

const SKY: &str = "[sky]\nkind = \"uniform\"\nradiance = 1\n";

#[test]
fn an_imported_room_with_a_sky_gets_its_window_as_a_portal_unless_told_not_to() {
    // Detected after welding, in the polygons' re-centred frame: moved back
    // by the offset, the portal is the window in the file's coordinates.
    let (scene, hole) = import_window_room(SKY);
    let scene = scene.unwrap();
    let lights = scene.lights.recentred(-scene.recentre_offset);
    assert_eq!(lights.portals.len(), 1, "{:?}", lights.portals);
    assert!(same_corners(&lights.portals[0], &hole));
    assert!(faces_the_room(&lights.portals[0]));
    let lines = scene.lights.describe(scene.recentre_offset);
    assert!(
        lines.iter().any(
            |l| l.starts_with("portal (detected) at [0.875, 1.062, 2.000]")
                && l.ends_with("area 0.6562")
        ),
        "{lines:?}"
    );
    // Turned off, or without a sky: none.
    let (off, _) = import_window_room(&format!("{SKY}portals = \"none\"\n"));
    assert!(off.unwrap().lights.portals.is_empty());
    let sun = "[sun]\ndirection = [0, 1, 1]\nirradiance = 100\n";
    let (sunlit, _) = import_window_room(sun);
    assert!(sunlit.unwrap().lights.portals.is_empty());
    // Declared portals win, and are not detected.
    let declared = "[[portals]]\ncorners = [[0, 0, 2], [1, 0, 2], [1, 1, 2]]\n";
    let (scene, _) = import_window_room(&format!("{SKY}{declared}"));
    let portals = scene.unwrap().lights.portals;
    assert_eq!(portals.len(), 1);
    assert!(!portals[0].is_detected());
}

#[test]
fn a_bad_portals_value_names_the_file_line_and_value() {
    let (scene, _) = import_window_room(&format!("{SKY}portals = \"always\"\n"));
    let message = scene.unwrap_err();
    assert!(
        message.contains("room.toml:5") && message.contains("\"always\""),
        "{message}"
    );
}

#[test]
fn rotating_calipers_find_the_smallest_rectangle_that_every_side_gives() {
    // Against the O(k²) search the calipers replace: for each side of the
    // hull, the rectangle on it spans the extreme projections along and
    // across it; the smallest of these is the answer (Freeman and Shapira
    // 1975). Random hulls of 3 to 40 points, thin ones included (y squashed
    // by up to 1,000): the areas agree to 1e-12 relative (sums of a few
    // products of coordinates of size 1), and every point lies inside.
    use super::portal_detect::min_area_rectangle;
    use crate::geometry::sampling::Rng;
    use crate::mesh::contact::convex_hull;
    use glam::DVec2;
    let mut rng = Rng::new(7, 1);
    for trial in 0..300 {
        let count = 3 + trial % 38;
        let squash = 10f64.powf(-3.0 * rng.next_f64());
        let points: Vec<DVec2> = (0..count)
            .map(|_| DVec2::new(rng.next_f64(), squash * rng.next_f64()))
            .collect();
        let hull = convex_hull(&points);
        let Some(r) = min_area_rectangle(&hull) else {
            assert!(hull.len() < 3);
            continue;
        };
        let area = |r: &[DVec2; 4]| (r[1] - r[0]).length() * (r[3] - r[0]).length();
        let brute = (0..hull.len())
            .map(|i| {
                let d = (hull[(i + 1) % hull.len()] - hull[i]).normalize();
                let along = hull.iter().map(|p| (*p - hull[i]).dot(d));
                let across = hull.iter().map(|p| (*p - hull[i]).dot(d.perp()));
                let (lo, hi) = along.fold((0.0f64, 0.0f64), |(l, h), x| (l.min(x), h.max(x)));
                (hi - lo) * across.fold(0.0f64, f64::max)
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            (area(&r) - brute).abs() <= 1e-12 * brute.max(squash),
            "{} against {brute}",
            area(&r)
        );
        for p in &points {
            let inside = (0..4).all(|k| {
                let (a, b) = (r[k], r[(k + 1) % 4]);
                (b - a).perp_dot(*p - a) >= -1e-12
            });
            assert!(inside, "{p} outside {r:?}");
        }
    }
}
