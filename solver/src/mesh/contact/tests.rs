use super::*;
use crate::mesh::{Mesh, Sizing};
use crate::scene::{Material, MeshSizes, Polygon, SourceRef, PATCHES_UNSET};

fn p(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

fn scene_of(polygons: Vec<Vec<DVec3>>) -> Scene {
    let polygons = polygons
        .into_iter()
        .enumerate()
        .map(|(i, vertices)| Polygon {
            vertices,
            vertex_normals: None,
            material: 0,
            uv_map: None,
            patches: PATCHES_UNSET,
            sizes: MeshSizes::default(),
            source: SourceRef {
                item: format!("polygon {i}"),
                ..SourceRef::default()
            },
        })
        .collect();
    Scene {
        lights: Default::default(),
        polygons,
        materials: vec![Material {
            name: "white".into(),
            kd: DVec3::splat(0.5),
            ks: DVec3::ZERO,
            alpha: 0.0,
            emission: DVec3::ZERO,
            diffuse_texture: None,
            emission_texture: None,
            folded_texture: None,
        }],
        units_per_metre: 1.0,
        up_axis: solution::camera::UpAxis::PosY,
        camera: None,
        recentre_offset: DVec3::ZERO,
        warnings: Vec::new(),
    }
}

/// A floor [0, 2]² at y = 0 facing up, and a box of height 0.3 with no bottom
/// face standing on it, its base the square with corners `base`
/// (counter-clockwise seen from above), rotated so that its edges are not
/// parallel to the floor's.
fn box_on_floor() -> (Scene, [DVec3; 4]) {
    let base = [
        p(0.8, 0., 0.6),
        p(0.6, 0., 1.2),
        p(1.2, 0., 1.4),
        p(1.4, 0., 0.8),
    ];
    let floor = vec![p(0., 0., 0.), p(0., 0., 2.), p(2., 0., 2.), p(2., 0., 0.)];
    let up = DVec3::new(0.0, 0.3, 0.0);
    let mut polygons = vec![floor, base.iter().rev().map(|&b| b + up).collect()];
    for i in 0..4 {
        let (a, b) = (base[i], base[(i + 1) % 4]);
        // Facing out of the box.
        polygons.push(vec![a, a + up, b + up, b]);
    }
    (scene_of(polygons), base)
}

fn area3(v: &[DVec3]) -> f64 {
    crate::geometry::polygon::area(v)
}

/// Signed distances of `q` (in the floor's xz plane) to the base's edges,
/// positive inside: the point is inside when all are positive.
fn inside_base(base: &[DVec3; 4], q: DVec3) -> f64 {
    (0..4)
        .map(|i| {
            let (a, b) = (base[i], base[(i + 1) % 4]);
            // The base runs counter-clockwise seen from above (+y): inside is
            // to the left of a → b in the xz plane seen from above.
            let d = b - a;
            let r = q - a;
            (d.z * r.x - d.x * r.z) / d.length()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn a_box_cuts_the_floor_into_visible_parts_and_its_footprint() {
    let (scene, base) = box_on_floor();
    let parts = conform(&scene, Cuts::Contacts);
    let floor = parts[0].as_ref().expect("the floor is cut");
    // The parts tile the floor: their areas sum to its area (rounding only).
    let total: f64 = floor.iter().map(|q| area3(&q.vertices)).sum();
    assert!((total - 4.0).abs() < 1e-12, "{total}");
    // One covered part: the base itself (area 0.4 for this base).
    let covered: Vec<_> = floor.iter().filter(|q| q.covered).collect();
    assert_eq!(covered.len(), 1);
    assert!((area3(&covered[0].vertices) - area3(&base)).abs() < 1e-12);
    for v in &covered[0].vertices {
        assert!(base.iter().any(|b| (*b - *v).length() < 1e-12), "{v}");
    }
    // No visible part reaches into the base (1e-12: rounding of the cuts),
    // and none is flipped: each faces up like the floor.
    for part in floor.iter().filter(|q| !q.covered) {
        for &v in &part.vertices {
            assert!(inside_base(&base, v) <= 1e-12, "{v} is under the box");
            assert!(v.y == 0.0);
        }
        let n = crate::geometry::polygon::newell_normal(&part.vertices);
        assert!(n.y > 0.0);
    }
    // The box's own faces touch nothing.
    assert!(parts[1..].iter().all(|p| p.is_none()));
}

#[test]
fn a_light_just_under_a_ceiling_covers_it_and_one_further_down_does_not() {
    // The Cornell box's ceiling and light in millimetres: a ceiling 549 mm up
    // facing down, a 130 × 105 mm light facing down 0.1 mm under it, and a
    // floor so that the diagonal is about the box's.
    let ceiling_at = |drop: f64| {
        let y = 548.8 - drop;
        let ceiling = vec![
            p(0., 548.8, 0.),
            p(556., 548.8, 0.),
            p(556., 548.8, 559.),
            p(0., 548.8, 559.),
        ];
        let light = vec![
            p(213., y, 227.),
            p(343., y, 227.),
            p(343., y, 332.),
            p(213., y, 332.),
        ];
        let floor = vec![
            p(0., 0., 0.),
            p(0., 0., 559.),
            p(556., 0., 559.),
            p(556., 0., 0.),
        ];
        conform(&scene_of(vec![ceiling, light, floor]), Cuts::Contacts)
    };
    let parts = ceiling_at(0.1);
    let ceiling = parts[0].as_ref().expect("the light covers the ceiling");
    let covered: Vec<_> = ceiling.iter().filter(|q| q.covered).collect();
    assert_eq!(covered.len(), 1);
    assert!((area3(&covered[0].vertices) - 130.0 * 105.0).abs() < 1e-6);
    // The tolerance is 2e-4 of the diagonal (0.19 mm here): a light 1 mm
    // down hangs free.
    assert!(ceiling_at(1.0)[0].is_none());
}

#[test]
fn walls_on_the_floors_edges_and_a_lone_wall_cut_nothing() {
    // Walls standing on the floor's edges share its corners (a hull that is
    // the floor itself); a single wall inside it touches it along a segment,
    // which covers nothing.
    let floor = vec![p(0., 0., 0.), p(0., 0., 2.), p(2., 0., 2.), p(2., 0., 0.)];
    let back = vec![p(0., 0., 2.), p(0., 1., 2.), p(2., 1., 2.), p(2., 0., 2.)];
    let left = vec![p(0., 0., 0.), p(0., 1., 0.), p(0., 1., 2.), p(0., 0., 2.)];
    let lone = vec![
        p(0.5, 0., 1.),
        p(0.5, 1., 1.),
        p(1.5, 1., 1.),
        p(1.5, 0., 1.),
    ];
    let parts = conform(&scene_of(vec![floor, back, left, lone]), Cuts::Contacts);
    assert!(parts.iter().all(|p| p.is_none()));
}

/// Whether a leaf element of the floor has corners strictly on both sides of
/// the base's boundary (`margin` from it).
fn straddlers(mesh: &Mesh, base: &[DVec3; 4], margin: f64) -> usize {
    mesh.leaves()
        .filter(|&e| {
            let el = &mesh.elements[e as usize];
            let s = &mesh.surfaces[mesh.patches[el.patch as usize].surface as usize];
            if s.polygon != 0 {
                return false;
            }
            let d: Vec<f64> = el
                .corners()
                .iter()
                .map(|&c| inside_base(base, mesh.vertices[c as usize].position))
                .collect();
            d.iter().any(|&x| x > margin) && d.iter().any(|&x| x < -margin)
        })
        .count()
}

#[test]
fn no_floor_element_straddles_the_contact_line() {
    let (scene, base) = box_on_floor();
    let sizing = Sizing::flat(5);
    let mut conformed = Mesh::with_sizing(&scene, DVec3::ZERO, &sizing).unwrap();
    let mut whole = Mesh::with_contacts(
        &scene,
        DVec3::ZERO,
        &sizing,
        &conform(&scene, Cuts::None),
        &mut crate::progress::Quiet,
    )
    .unwrap();
    // Refine every floor element twice, as adaptive subdivision would near
    // the box: the quadtree stays inside its part.
    for mesh in [&mut conformed, &mut whole] {
        for _ in 0..2 {
            let floor: Vec<u32> = mesh
                .leaves()
                .filter(|&e| {
                    let patch = mesh.elements[e as usize].patch;
                    mesh.surfaces[mesh.patches[patch as usize].surface as usize].polygon == 0
                })
                .collect();
            let mut created = Vec::new();
            for e in floor {
                mesh.split(e, &mut created).unwrap();
            }
        }
    }
    // 1e-12: corners on the contact line are on it up to rounding.
    assert_eq!(straddlers(&conformed, &base, 1e-12), 0);
    // The whole floor's elements do straddle it (the test can fail).
    assert!(straddlers(&whole, &base, 1e-12) > 0);
    // The conformed floor's leaves cover its area exactly once.
    let area: f64 = conformed
        .leaves()
        .map(|e| &conformed.elements[e as usize])
        .filter(|el| {
            let patch = &conformed.patches[el.patch as usize];
            conformed.surfaces[patch.surface as usize].polygon == 0
        })
        .map(|el| el.area)
        .sum();
    assert!((area - 4.0).abs() < 1e-9, "{area}");
    // Visible parts are marked smooth (shared seams), the covered one flat,
    // all with the floor's frame.
    let floor: Vec<_> = conformed
        .surfaces
        .iter()
        .filter(|s| s.polygon == 0)
        .collect();
    assert!(floor.len() > 2);
    assert_eq!(
        floor.iter().filter(|s| s.corner_normals.is_none()).count(),
        1
    );
    for s in &floor {
        assert_eq!(s.normal, floor[0].normal);
        assert_eq!(s.tangent, floor[0].tangent);
    }
}

/// A floor [0, 10]² at y = 0 facing up with `n` separate boxes of side 0.2
/// and height 0.2 standing on it in rows of ten, each as its top and four
/// sides (no two boxes share a vertex, so each is an object of its own).
fn floor_with_boxes(n: usize) -> Scene {
    let floor = vec![
        p(0., 0., 0.),
        p(0., 0., 10.),
        p(10., 0., 10.),
        p(10., 0., 0.),
    ];
    let mut polygons = vec![floor];
    for i in 0..n {
        let (x, z) = (0.5 + (i % 10) as f64 * 0.9, 0.5 + (i / 10) as f64 * 0.9);
        let base = [
            p(x, 0., z),
            p(x, 0., z + 0.2),
            p(x + 0.2, 0., z + 0.2),
            p(x + 0.2, 0., z),
        ];
        let up = DVec3::new(0.0, 0.2, 0.0);
        polygons.push(base.iter().map(|&b| b + up).collect());
        for k in 0..4 {
            let (a, b) = (base[k], base[(k + 1) % 4]);
            polygons.push(vec![a, a + up, b + up, b]);
        }
    }
    scene_of(polygons)
}

#[test]
fn a_receiver_under_more_objects_than_the_cap_stays_whole() {
    // At the cap the floor is cut: one covered part per box.
    let parts = conform(&floor_with_boxes(MAX_FOOTPRINTS), Cuts::Contacts);
    let floor = parts[0].as_ref().expect("a floor under 64 boxes is cut");
    assert_eq!(floor.iter().filter(|p| p.covered).count(), MAX_FOOTPRINTS);
    // One more object and it stays whole (cutting is quadratic in the
    // footprints); the boxes' own faces are never cut by the floor.
    let parts = conform(&floor_with_boxes(MAX_FOOTPRINTS + 1), Cuts::Contacts);
    assert!(parts[0].is_none());
    assert!(parts.iter().all(Option::is_none));
}

/// [`box_on_floor`] under a 0.2-wide emitter 2 above the floor, over x in
/// [0.1, 0.3] and z in [1.6, 1.8]: up and to the left of the box's base as
/// seen from above, so that the shadow lines from the base's corners run
/// out over the floor on the far side.
fn box_on_floor_under_a_light() -> (Scene, [DVec3; 4], Vec<DVec3>) {
    let (mut scene, base) = box_on_floor();
    let light = vec![
        p(0.1, 2., 1.6),
        p(0.3, 2., 1.6),
        p(0.3, 2., 1.8),
        p(0.1, 2., 1.8),
    ];
    let mut polygon = scene.polygons[0].clone();
    polygon.vertices = light.clone();
    polygon.material = 1;
    scene.polygons.push(polygon);
    let mut emitter = scene.materials[0].clone();
    emitter.kd = DVec3::ZERO;
    emitter.emission = DVec3::ONE;
    scene.materials.push(emitter);
    (scene, base, light)
}

#[test]
fn shadow_lines_run_from_the_base_corners_away_from_each_light_vertex() {
    let (scene, base, light) = box_on_floor_under_a_light();
    // Contact cuts alone mark no apex.
    let plain = conform(&scene, Cuts::Contacts);
    let plain = plain[0].as_ref().expect("the floor is cut");
    assert!(plain.iter().all(|q| q.apexes.is_empty()));
    let parts = conform(&scene, Cuts::ShadowLines);
    let floor = parts[0].as_ref().expect("the floor is cut");
    // The parts still tile the floor, and one is still the covered base.
    let total: f64 = floor.iter().map(|q| area3(&q.vertices)).sum();
    assert!((total - 4.0).abs() < 1e-12, "{total}");
    assert_eq!(floor.iter().filter(|q| q.covered).count(), 1);
    assert!(
        floor.len() > plain.len(),
        "{} parts, {} before",
        floor.len(),
        plain.len()
    );
    let apexes: Vec<DVec3> = floor.iter().flat_map(|q| q.apexes.clone()).collect();
    assert!(!apexes.is_empty());
    for &c in &apexes {
        assert!(
            base.iter().any(|&b| (b - c).length() < 1e-12),
            "apex {c} is no corner"
        );
        // Every part listing the apex has it as a vertex, and is visible.
        for q in floor.iter().filter(|q| q.apexes.contains(&c)) {
            assert!(!q.covered);
            assert!(q.vertices.iter().any(|&v| (v - c).length() < 1e-12));
        }
        // From each light vertex, the ray from the corner directed away
        // from it (in the floor's plane) is an edge of a part that lists
        // the apex, unless it runs under the box.
        for &l in &light {
            let away = DVec3::new(c.x - l.x, 0.0, c.z - l.z).normalize();
            let under = inside_base(&base, c + away * 1e-6) > 0.0;
            let edge = floor.iter().filter(|q| q.apexes.contains(&c)).any(|q| {
                q.vertices.iter().any(|&v| {
                    let e = v - c;
                    e.length() > 1e-9 && e.normalize().dot(away) > 1.0 - 1e-12
                })
            });
            assert!(
                edge || under,
                "no edge from apex {c} away from light vertex {l}"
            );
        }
    }
    // The corner facing the light, (0.6, 1.2), is no apex: its lines run
    // under the box, and their other halves, toward the light, are no
    // shadow's edges and cut nothing (the parts touching it are the contact
    // cuts' own).
    let facing = base[1];
    assert!(!apexes.contains(&facing));
    let touching = |parts: &[Part]| {
        parts
            .iter()
            .filter(|q| q.vertices.iter().any(|&v| (v - facing).length() < 1e-12))
            .count()
    };
    assert_eq!(touching(floor), touching(plain));
}

#[test]
fn the_sun_cuts_shadow_lines_from_the_base_corners_away_from_it_in_both_modes() {
    // A box on a floor in the sun: its umbra's sides leave the footprint's
    // corners along the sun's direction projected on the floor, turned away
    // from it. Cut in diffuse mode too (a hard shadow a vertex-less umbra
    // would hide from refinement: docs/lab/lights-atrium.md, "Column
    // bases"), and not at all without a sun.
    let (mut scene, base) = box_on_floor();
    let plain = conform(&scene, Cuts::Contacts);
    let plain = plain[0].as_ref().expect("the floor is cut");
    let toward = DVec3::new(0.3, 0.8, -0.5).normalize();
    let position = crate::light::sun::SunPosition::from_direction(toward).unwrap();
    scene.lights.sun = Some(crate::light::sun::Sun::new(position, DVec3::ONE, 0.53).unwrap());
    let parts = conform(&scene, Cuts::Contacts);
    let floor = parts[0].as_ref().expect("the floor is cut");
    let total: f64 = floor.iter().map(|q| area3(&q.vertices)).sum();
    assert!(
        (total - 4.0).abs() < 1e-12,
        "the parts tile the floor: {total}"
    );
    assert!(
        floor.len() > plain.len(),
        "{} parts, {} before",
        floor.len(),
        plain.len()
    );
    let away = DVec3::new(-toward.x, 0.0, -toward.z).normalize();
    // Each part meeting an apex lists it: the distinct ones.
    let mut apexes: Vec<DVec3> = Vec::new();
    for &c in floor.iter().flat_map(|q| &q.apexes) {
        if !apexes.contains(&c) {
            apexes.push(c);
        }
    }
    // Two corners cast the umbra's sides, and the one between them, behind
    // the box, its own line: three of the four run into the floor.
    assert_eq!(apexes.len(), 3, "{apexes:?}");
    for &c in &apexes {
        assert!(
            base.iter().any(|&b| (b - c).length() < 1e-12),
            "apex {c} is no corner"
        );
        assert!(
            inside_base(&base, c + away * 1e-6) <= 0.0,
            "its line runs under the box"
        );
        let edge = floor.iter().filter(|q| q.apexes.contains(&c)).any(|q| {
            q.vertices.iter().any(|&v| {
                let e = v - c;
                e.length() > 1e-9 && e.normalize().dot(away) > 1.0 - 1e-12
            })
        });
        assert!(edge, "no edge from apex {c} away from the sun");
    }
}

#[test]
fn the_sun_cuts_a_round_base_along_its_shadow_sides_all_the_way_through() {
    // A 24-sided column on the floor: the contact cut splits the floor along
    // the footprint edges' lines, into wedges that fan out from the base and
    // cross the shadow's sides far from the corners. Each side of the shadow
    // (a line from a silhouette corner, away from the sun) must be an edge of
    // every part it crosses, so that no part spans umbra and light: no point
    // of the line strictly inside a part, from the corner to the floor's edge
    // (docs/lab/lights-atrium.md, "Column bases").
    let (centre, radius, segments) = (DVec2::new(1.0, 1.0), 0.15, 24);
    let at = |k: usize, y: f64| {
        let a = 2.0 * std::f64::consts::PI * k as f64 / segments as f64;
        p(centre.x + radius * a.cos(), y, centre.y + radius * a.sin())
    };
    let floor = vec![p(0., 0., 0.), p(0., 0., 2.), p(2., 0., 2.), p(2., 0., 0.)];
    let mut polygons = vec![floor];
    polygons.extend(
        (0..segments).map(|k| vec![at(k, 0.0), at(k, 1.0), at(k + 1, 1.0), at(k + 1, 0.0)]),
    );
    let mut scene = scene_of(polygons);
    let toward = DVec3::new(0.5, 0.8, -0.3).normalize();
    let position = crate::light::sun::SunPosition::from_direction(toward).unwrap();
    scene.lights.sun = Some(crate::light::sun::Sun::new(position, DVec3::ONE, 0.53).unwrap());
    let parts = conform(&scene, Cuts::Contacts);
    let floor = parts[0].as_ref().expect("the floor is cut");
    let away = DVec2::new(-toward.x, -toward.z).normalize();
    let side = DVec2::new(-away.y, away.x);
    // The tangent corners: the footprint's farthest on each side of the
    // shadow's axis.
    let corners: Vec<DVec2> = (0..segments)
        .map(|k| DVec2::new(at(k, 0.).x, at(k, 0.).z))
        .collect();
    let extreme = |sign: f64| {
        corners
            .iter()
            .copied()
            .max_by(|a, b| {
                (sign * side.dot(*a - centre)).total_cmp(&(sign * side.dot(*b - centre)))
            })
            .unwrap()
    };
    let inside = |ring: &[DVec3], q: DVec2| {
        let ring: Vec<DVec2> = ring.iter().map(|v| DVec2::new(v.x, v.z)).collect();
        let sign = (0..ring.len())
            .map(|i| (ring[(i + 1) % ring.len()] - ring[i]).perp_dot(q - ring[i]))
            .collect::<Vec<_>>();
        sign.iter().all(|&s| s > 1e-9) || sign.iter().all(|&s| s < -1e-9)
    };
    let mut crossed = 0;
    for sign in [-1.0, 1.0] {
        let c = extreme(sign);
        for k in 1..400 {
            let q = c + away * (k as f64 * 0.005);
            if !(0.0..=2.0).contains(&q.x) || !(0.0..=2.0).contains(&q.y) {
                break;
            }
            crossed += 1;
            let holder = floor.iter().find(|part| inside(&part.vertices, q));
            assert!(
                holder.is_none(),
                "the shadow's side runs through a part at {q}"
            );
        }
    }
    assert!(crossed > 100, "{crossed} points checked");
}
