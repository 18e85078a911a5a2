//! The daylit families (issue 41): the atrium's counts, open roof, two
//! storeys and columns standing flush on the floor and slab and meeting the
//! arches; the window room's shell closed but for the window; and the
//! `[sun]` and `[sky]` tables their configs carry. (tests.rs checks them for
//! closed, outward, non-degenerate solids with the other families.)

use crate::atrium::{self, Storey};
use crate::mesh::{add, dot, length, scale, sub, Mesh, Object, Vec3};
use crate::scene::{lights_text, toml_number, toml_text, Lights};
use crate::window_room::{self, SIDE, WINDOW_X, WINDOW_Y};
use crate::{generate, Family, COUNT_TOLERANCE};
use std::collections::HashMap;

/// Smallest and largest corner of an object's vertices.
fn bounds(mesh: &Mesh, object: &Object) -> (Vec3, Vec3) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for c in object.triangles.iter().flatten() {
        let p = mesh.positions[c.position as usize];
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    (lo, hi)
}

fn objects<'a>(mesh: &'a Mesh, prefix: &str) -> Vec<&'a Object> {
    mesh.objects
        .iter()
        .filter(|o| o.name.starts_with(prefix))
        .collect()
}

#[test]
fn atrium_counts_land_within_tolerance_and_the_default_is_sponzas() {
    for n in [2_000usize, 5_000, 10_000, 65_000, 100_000, 1_000_000] {
        let count = atrium::Params::for_triangles(n).triangle_count();
        let error = (count as f64 - n as f64).abs() / n as f64;
        assert!(error <= COUNT_TOLERANCE, "{count} for {n}");
    }
    // The mesh has exactly the predicted count, and the 60–70k at
    // the family's default.
    for n in [5_000, Family::Atrium.default_triangles()] {
        let p = atrium::Params::for_triangles(n);
        assert_eq!(
            atrium::generate(p).mesh.triangle_count(),
            p.triangle_count()
        );
    }
    let sponza = generate(Family::Atrium, Family::Atrium.default_triangles(), 1).unwrap();
    let count = sponza.mesh.triangle_count();
    assert!((60_000..=70_000).contains(&count), "{count}");
    // Below its fixed part (walls, slabs, 4 bays) the request is an error.
    let e = generate(Family::Atrium, 1_000, 1).unwrap_err().to_string();
    assert!(e.contains("more than 20%"), "{e}");
}

#[test]
fn the_atrium_court_is_open_to_the_sky() {
    // No triangle reaches over the court's footprint above the fountain: the
    // bounding box of every triangle that overlaps the court's interior (1 mm
    // in from the arcades' faces and the end walls) stays below the
    // fountain's top. The attics reach 16 m beside it, so the roof height
    // exists, only not over the court.
    let scene = atrium::generate(atrium::Params::for_triangles(5_000));
    let mesh = &scene.mesh;
    let [z0, z1] = atrium::COURT_Z;
    let mut highest = f64::NEG_INFINITY;
    for object in &mesh.objects {
        for t in &object.triangles {
            let p = t.map(|c| mesh.positions[c.position as usize]);
            let lo = |a: usize| p.iter().map(|q| q[a]).fold(f64::INFINITY, f64::min);
            let hi = |a: usize| p.iter().map(|q| q[a]).fold(f64::NEG_INFINITY, f64::max);
            highest = highest.max(hi(1));
            let over_court =
                hi(0) > 1.0 && lo(0) < atrium::LENGTH - 1.0 && hi(2) > z0 + 1.0 && lo(2) < z1 - 1.0;
            if over_court {
                assert!(
                    hi(1) <= atrium::COURT_OBJECTS_TOP,
                    "{} covers the court at y = {}",
                    object.name,
                    hi(1)
                );
            }
        }
    }
    assert_eq!(highest, atrium::HEIGHT);
    // The court is the 35 m long, 8.3 m wide strip between the arcades.
    assert!(z1 - z0 > 8_000.0);
}

/// Checks one storey's columns: feet on `floor_y`, tops on the spring line,
/// and the arch blocks of the same storey and side covering each top disc.
fn check_storey(mesh: &Mesh, level: usize, storey: &Storey, columns_per_side: usize) {
    let r = atrium::COLUMN_RADIUS;
    for (side, line) in ["south", "north"].into_iter().zip(atrium::COLUMN_LINES) {
        let columns: Vec<_> = objects(mesh, &format!("column_{level}_{side}_"));
        assert_eq!(columns.len(), columns_per_side, "storey {level} {side}");
        let arches: Vec<_> = objects(mesh, &format!("arch_{level}_{side}_"))
            .into_iter()
            .map(|o| bounds(mesh, o))
            .collect();
        for column in columns {
            let (lo, hi) = bounds(mesh, column);
            assert!(
                (lo[1] - storey.base).abs() < 1e-6,
                "{} foot at {}",
                column.name,
                lo[1]
            );
            assert!(
                (hi[1] - storey.spring).abs() < 1e-6,
                "{} top at {}",
                column.name,
                hi[1]
            );
            let x = 0.5 * (lo[0] + hi[0]);
            // Each half of the top disc lies under the bottom strip of an arch
            // block that starts exactly on the spring line.
            for half in [[x - r, x], [x, x + r]] {
                let covered = arches.iter().any(|(a_lo, a_hi)| {
                    a_lo[1] == storey.spring
                        && a_lo[0] <= half[0] + 1e-6
                        && a_hi[0] >= half[1] - 1e-6
                        && a_lo[2] <= line - r
                        && a_hi[2] >= line + r
                });
                assert!(covered, "{}: no arch over x {half:?}", column.name);
            }
        }
        for (a_lo, a_hi) in &arches {
            assert_eq!(a_lo[1], storey.spring);
            assert_eq!(a_hi[1], storey.top);
        }
    }
}

#[test]
fn atrium_columns_stand_on_the_floor_and_slab_and_meet_the_arches() {
    for n in [5_000, 65_000] {
        let p = atrium::Params::for_triangles(n);
        let scene = atrium::generate(p);
        let mesh = &scene.mesh;
        let [ground, upper] = p.storeys();
        // Two storeys, one above the other, the upper standing on the slab
        // that the ground storey's arches carry.
        assert_eq!(ground.base, 0.0);
        assert!(ground.base < ground.spring && ground.spring < ground.top);
        assert!(ground.top < upper.base && upper.spring < upper.top);
        let floor = objects(mesh, "floor")[0];
        let (f_lo, f_hi) = bounds(mesh, floor);
        assert_eq!((f_lo[1], f_hi[1]), (0.0, 0.0));
        for slab in objects(mesh, "gallery_slab_") {
            let (lo, hi) = bounds(mesh, slab);
            assert_eq!((lo[1], hi[1]), (ground.top, upper.base), "{}", slab.name);
        }
        let per_side = p.bays as usize - 1;
        check_storey(mesh, 0, &ground, per_side);
        check_storey(mesh, 1, &upper, per_side);
        // The pilasters against the end walls stand and end the same way.
        for pilaster in objects(mesh, "pilaster_") {
            let storey = if pilaster.name.starts_with("pilaster_0") {
                ground
            } else {
                upper
            };
            let (lo, hi) = bounds(mesh, pilaster);
            assert_eq!(
                (lo[1], hi[1]),
                (storey.base, storey.spring),
                "{}",
                pilaster.name
            );
        }
    }
}

#[test]
fn atrium_walls_and_slabs_have_an_edge_at_every_contact() {
    // Where a slab meets a wall, or an arcade meets an end wall or a slab's
    // underside, the touched face has an edge along the contact: no triangle
    // reaches across it, so no element mixes the light of the two sides
    // (an aisle's wall top with the gallery above the slab, an end wall's
    // aisle part with the court, the gallery ceiling behind a drape with the
    // part in front of it).
    let p = atrium::Params::for_triangles(5_000);
    let mesh = &atrium::generate(p).mesh;
    let [ground, upper] = p.storeys();
    let slabs = vec![ground.top, upper.base, upper.top];
    let arcades: Vec<f64> = atrium::COLUMN_LINES
        .iter()
        .flat_map(|l| [l - atrium::ARCH_HALF_DEPTH, l + atrium::ARCH_HALF_DEPTH])
        .collect();
    let drapes: Vec<f64> = atrium::COLUMN_LINES
        .iter()
        .flat_map(|&l| atrium::drape_z(l))
        .chain(arcades.iter().copied())
        .collect();
    let cases = [
        ("back_wall_", 1, &slabs),
        ("end_wall_", 1, &slabs),
        ("end_wall_", 2, &arcades),
        ("gallery_slab_", 2, &arcades),
        ("roof_", 2, &drapes),
    ];
    for (prefix, axis, lines) in cases {
        let found = objects(mesh, prefix);
        assert!(!found.is_empty(), "{prefix}");
        for object in found {
            for t in &object.triangles {
                let values = t.map(|c| mesh.positions[c.position as usize][axis]);
                let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                for &c in lines {
                    assert!(
                        !(lo < c - 1e-6 && hi > c + 1e-6),
                        "{}: a triangle spans {lo}..{hi} across the contact at {c} (axis {axis})",
                        object.name
                    );
                }
            }
        }
    }
}

#[test]
fn atrium_materials_are_stone_and_nothing_emits() {
    let scene = atrium::generate(atrium::Params::for_triangles(5_000));
    for m in &scene.materials {
        assert_eq!(m.ke, [0.0; 3], "{}", m.name);
        if !m.name.starts_with("drape") {
            assert!(m.kd.iter().all(|&k| (0.4..=0.7).contains(&k)), "{}", m.name);
        }
    }
    // The camera stands in the court at eye height, looking along +x.
    let c = &scene.camera;
    assert!(c.eye[2] > atrium::COURT_Z[0] && c.eye[2] < atrium::COURT_Z[1]);
    assert!((1_500.0..=1_800.0).contains(&c.eye[1]));
    let view = sub(c.target, c.eye);
    assert!(view[0] > 0.9 * length(view));
}

/// Directed edges of the objects together: (a, b) → uses.
fn directed_edges<'a>(objects: impl Iterator<Item = &'a Object>) -> HashMap<(u32, u32), u32> {
    let mut edges = HashMap::new();
    for t in objects.flat_map(|o| &o.triangles) {
        for i in 0..3 {
            *edges
                .entry((t[i].position, t[(i + 1) % 3].position))
                .or_insert(0) += 1;
        }
    }
    edges
}

#[test]
fn the_window_room_is_closed_except_for_the_window() {
    for n in [100, 300, 5_000] {
        let p = window_room::Params::for_triangles(n);
        let scene = window_room::generate(p);
        assert_eq!(scene.mesh.triangle_count(), p.triangle_count());
        let mesh = &scene.mesh;
        let room: Vec<_> = mesh
            .objects
            .iter()
            .filter(|o| !o.name.starts_with("box"))
            .collect();
        assert_eq!(room.len(), 6);
        // Every directed edge once; an edge without its reverse is on the
        // rim, and the rim is exactly the window's outline in the back wall:
        // each such edge lies on it and together they are its perimeter.
        let edges = directed_edges(room.iter().copied());
        let on_rim = |p: Vec3| {
            let on = |v: f64, range: [f64; 2]| {
                (v - range[0]).abs() < 1e-9 || (v - range[1]).abs() < 1e-9
            };
            let within = |v: f64, range: [f64; 2]| v >= range[0] - 1e-9 && v <= range[1] + 1e-9;
            p[2] == SIDE
                && within(p[0], WINDOW_X)
                && within(p[1], WINDOW_Y)
                && (on(p[0], WINDOW_X) || on(p[1], WINDOW_Y))
        };
        let mut rim = 0.0;
        for (&(a, b), &uses) in &edges {
            assert_eq!(uses, 1, "{n}: edge {a} → {b} used {uses} times");
            if !edges.contains_key(&(b, a)) {
                let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
                let mid = scale(add(pa, pb), 0.5);
                assert!(
                    on_rim(pa) && on_rim(pb) && on_rim(mid),
                    "{n}: open edge {pa:?} → {pb:?}"
                );
                rim += length(sub(pb, pa));
            }
        }
        let width = WINDOW_X[1] - WINDOW_X[0];
        let height = WINDOW_Y[1] - WINDOW_Y[0];
        assert!(
            (rim - 2.0 * (width + height)).abs() < 1e-6,
            "{n}: rim {rim}"
        );
        // A closed surface's vector area Σ n·A is zero; the shell faces in,
        // so the back wall (facing −z) lacks exactly the window: Σ = +A_w ẑ.
        let mut vector_area = [0.0; 3];
        for t in room.iter().flat_map(|o| &o.triangles) {
            vector_area = add(vector_area, scale(mesh.geometric_normal(t), 0.5));
            // And every face looks into the room.
            let p = mesh.positions[t[0].position as usize];
            let centre = [0.5 * SIDE; 3];
            assert!(dot(mesh.geometric_normal(t), sub(centre, p)) > 0.0);
        }
        let expected = [0.0, 0.0, width * height];
        assert!(
            length(sub(vector_area, expected)) < 1e-6 * width * height,
            "{vector_area:?}"
        );
        // The boxes stand on the floor, inside the walls.
        for b in objects(mesh, "box_") {
            let (lo, hi) = bounds(mesh, b);
            assert!(lo[1].abs() < 1e-9, "{}", b.name);
            for a in [0, 2] {
                assert!(lo[a] > 0.0 && hi[a] < SIDE, "{}: {lo:?} {hi:?}", b.name);
            }
        }
    }
}

#[test]
fn the_sun_shines_through_the_window_onto_the_floor() {
    let scene = window_room::generate(window_room::Params::for_triangles(300));
    let sun = scene.lights.sun.as_ref().unwrap();
    let d = scale(sun.direction, 1.0 / length(sun.direction));
    let elevation = d[1].asin().to_degrees();
    assert!((elevation - window_room::SUN_ELEVATION_DEG).abs() < 1e-9);
    // Follow the sunlight from each window corner down to the floor (y = 0):
    // each lands inside the room, so the whole sun patch is on the floor.
    for x in WINDOW_X {
        for y in WINDOW_Y {
            let corner = [x, y, SIDE];
            let t = y / d[1];
            let floor = sub(corner, scale(d, t));
            assert!(floor[1].abs() < 1e-9);
            assert!(
                floor[0] > 0.0 && floor[0] < SIDE && floor[2] > 0.0 && floor[2] < SIDE,
                "{floor:?}"
            );
        }
    }
    for m in &scene.materials {
        assert_eq!(
            m.ke, [0.0; 3],
            "{}: lit only by the sun and the sky",
            m.name
        );
    }
}

#[test]
fn the_daylit_configs_state_the_sun_and_the_sky() {
    for family in [Family::Atrium, Family::WindowRoom] {
        let scene = generate(family, family.default_triangles(), 1).unwrap();
        let text = toml_text(&scene, "x.obj");
        let sun = scene.lights.sun.as_ref().unwrap();
        let direction = format!(
            "direction = [{}, {}, {}]\n",
            toml_number(sun.direction[0]),
            toml_number(sun.direction[1]),
            toml_number(sun.direction[2])
        );
        for expected in [
            "\n[sun]\n",
            direction.as_str(),
            "irradiance = [146.4, 146.4, 146.4]\n",
            "angular_diameter_deg = 0.53\n",
            "\n[sky]\nkind = \"uniform\"\nradiance = [3.0, 3.5, 4.5]\nbelow_horizon = \"black\"\n",
        ] {
            assert!(
                text.contains(expected),
                "{family:?}: no {expected:?} in\n{text}"
            );
        }
        // The tables follow the camera's, after every top-level key.
        assert!(text.find("[camera]").unwrap() < text.find("[sun]").unwrap());
    }
    // The atrium's sun stands 55° high; 100 klux of white is 100000/683.
    let atrium = generate(Family::Atrium, 5_000, 1).unwrap();
    let d = atrium.lights.sun.unwrap().direction;
    assert!(((d[1] / length(d)).asin().to_degrees() - 55.0).abs() < 1e-9);
    assert!((100_000.0 / 683.0 - 146.4_f64).abs() < 0.05);
    // The emitter-lit families write neither table.
    assert_eq!(lights_text(&Lights::default()), "");
    for family in Family::ALL {
        let text = toml_text(&generate(family, 1_000, 1).unwrap(), "x.obj");
        assert!(
            !text.contains("[sun]") && !text.contains("[sky]"),
            "{family:?}"
        );
    }
}

#[test]
fn toml_numbers_always_carry_a_decimal_point() {
    assert_eq!(toml_number(146.4), "146.4");
    assert_eq!(toml_number(3.0), "3.0");
    assert_eq!(toml_number(0.53), "0.53");
    assert_eq!(toml_number(-0.286_788_1), "-0.286788");
    assert_eq!(toml_number(-1e-9), "0.0");
    assert_eq!(toml_number(16_000.0), "16000.0");
}
