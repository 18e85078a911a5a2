use super::*;
use crate::geometry::sampling::Rng;
use crate::scene::{Material, Polygon, Scene};
use solution::camera::UpAxis;

fn scene_of(polygons: Vec<Vec<DVec3>>, patches: u32) -> Scene {
    Scene {
        lights: Default::default(),
        polygons: polygons
            .into_iter()
            .map(|vertices| Polygon {
                vertices,
                vertex_normals: None,
                material: 0,
                patches,
                sizes: Default::default(),
                source: SourceRef::default(),
                uv_map: None,
            })
            .collect(),
        materials: vec![Material {
            name: "grey".into(),
            kd: DVec3::splat(0.5),
            ks: DVec3::ZERO,
            alpha: 1.0,
            emission: DVec3::ZERO,
            diffuse_texture: None,
            emission_texture: None,
            folded_texture: None,
        }],
        units_per_metre: 1.0,
        up_axis: UpAxis::PosY,
        camera: None,
        recentre_offset: DVec3::ZERO,
        warnings: Vec::new(),
    }
}

fn square() -> Vec<DVec3> {
    vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(2.0, 2.0, 0.0),
        DVec3::new(0.0, 2.0, 0.0),
    ]
}

fn pentagon() -> Vec<DVec3> {
    (0..5)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 5.0;
            DVec3::new(a.cos(), 0.3, -a.sin())
        })
        .collect()
}

/// An L-shaped (non-convex) hexagon, counter-clockwise about +z.
fn ell() -> Vec<DVec3> {
    [
        (0.0, 0.0),
        (3.0, 0.0),
        (3.0, 1.0),
        (1.0, 1.0),
        (1.0, 2.0),
        (0.0, 2.0),
    ]
    .iter()
    .map(|&(x, y)| DVec3::new(x, y, 0.5))
    .collect()
}

#[test]
fn patches_share_vertices_on_grids_and_across_fan_diagonals() {
    let mesh = Mesh::new(&scene_of(vec![square()], 2), DVec3::ZERO, 4).unwrap();
    assert_eq!(mesh.patches.len(), 4);
    assert_eq!(mesh.vertices.len(), 9, "a 2×2 grid has 3×3 shared vertices");
    let s = &mesh.surfaces[0];
    assert_eq!(s.normal, DVec3::Z);
    assert_eq!(s.tangent, DVec3::X);
    assert_eq!(s.bitangent, DVec3::Y);

    let tri = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
    let mesh = Mesh::new(&scene_of(vec![tri], 3), DVec3::ZERO, 4).unwrap();
    assert_eq!(mesh.patches.len(), 9, "a triangle splits into N² patches");
    assert_eq!(mesh.vertices.len(), 10, "(N+1)(N+2)/2 grid points");

    // A pentagon is fanned into 3 triangles; with N = 2 each has 6 grid points
    // and the two diagonals share 3 each.
    let mesh = Mesh::new(&scene_of(vec![pentagon()], 2), DVec3::ZERO, 4).unwrap();
    assert_eq!(mesh.patches.len(), 12);
    assert_eq!(mesh.vertices.len(), 18 - 6);

    // Polygons with `patches = 0` take the default.
    let mesh = Mesh::new(&scene_of(vec![square()], 0), DVec3::ZERO, 3).unwrap();
    assert_eq!(mesh.patches.len(), 9);
}

#[test]
fn patch_areas_sum_to_the_polygon_area() {
    for poly in [square(), pentagon(), ell()] {
        let area = polygon::area(&poly);
        let mesh = Mesh::new(&scene_of(vec![poly], 3), DVec3::ZERO, 4).unwrap();
        let sum: f64 = mesh.patches.iter().map(|p| p.area).sum();
        // Rounding of O(patches) f64 terms.
        assert!((sum - area).abs() < 1e-12 * area, "{sum} vs {area}");
    }
}

#[test]
fn degenerate_polygons_are_skipped_and_bad_counts_refused() {
    let line = vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
    let mesh = Mesh::new(&scene_of(vec![line, square()], 1), DVec3::ZERO, 1).unwrap();
    assert_eq!(mesh.skipped, vec![0]);
    assert_eq!(mesh.surfaces.len(), 1);
    let err = Mesh::new(&scene_of(vec![square()], 5000), DVec3::ZERO, 1).unwrap_err();
    assert!(matches!(
        err,
        MeshError::TooManyPatches { patches: 5000, .. }
    ));
}

/// Splits random leaves of every polygon, then checks the displayed
/// triangulation of each polygon: every triangle counter-clockwise with positive
/// area, the areas summing to the polygon's area within 1e-12 relative (f64
/// rounding of a few thousand terms of similar size), every edge used by at most
/// two triangles, and every edge used once lying on the polygon's boundary. An
/// edge used once in the interior would be a crack (a T-junction).
#[test]
fn random_refinement_leaves_no_cracks() {
    let tri = vec![
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(3.0, 0.0, 1.0),
        DVec3::new(0.0, 2.0, 2.0),
    ];
    for (case, poly) in [square(), pentagon(), ell(), tri].into_iter().enumerate() {
        let mut mesh = Mesh::new(&scene_of(vec![poly.clone()], 2), DVec3::ZERO, 2).unwrap();
        let mut rng = Rng::new(7, case as u64);
        let mut created = Vec::new();
        for _ in 0..150 {
            let leaves: Vec<u32> = mesh
                .leaves()
                .filter(|&e| mesh.elements[e as usize].depth < 5)
                .collect();
            let pick = leaves[(rng.next_u32() as usize) % leaves.len()];
            created.clear();
            mesh.split(pick, &mut created).unwrap();
            for v in &created {
                // Interpolation parents are the element corners of the split.
                assert!(v.parents().iter().all(|&p| p < v.id));
            }
        }
        let tris = mesh.triangles();
        let normal = polygon::newell_normal(&poly).normalize();
        let mut area = 0.0;
        // Undirected edge -> (uses, sum of orientations).
        let mut edges: HashMap<(u32, u32), (i32, i32)> = HashMap::new();
        for t in &tris {
            let p = |i: usize| mesh.vertices[t[i] as usize].position;
            let twice = (p(1) - p(0)).cross(p(2) - p(0)).dot(normal);
            assert!(twice > 0.0, "case {case}: flipped or empty triangle {t:?}");
            area += 0.5 * twice;
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let entry = edges.entry((a.min(b), a.max(b))).or_default();
                entry.0 += 1;
                entry.1 += if a < b { 1 } else { -1 };
            }
        }
        let exact = polygon::area(&poly);
        assert!(
            (area - exact).abs() <= 1e-12 * exact,
            "case {case}: {area} vs {exact}"
        );
        let on_edge = |i: usize, v: u32| {
            let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
            let x = mesh.vertices[v as usize].position;
            (b - a).cross(x - a).length() <= 1e-12 * (b - a).length_squared()
        };
        let mut boundary_length = 0.0;
        for (&(a, b), &(uses, orientation)) in &edges {
            match uses {
                // Interior edges are shared by two triangles, traversed once in
                // each direction.
                2 => assert_eq!(
                    orientation, 0,
                    "case {case}: edge {a}-{b} not shared consistently"
                ),
                1 => {
                    assert!(
                        (0..poly.len()).any(|i| on_edge(i, a) && on_edge(i, b)),
                        "case {case}: interior edge {a}-{b} used once (a crack)"
                    );
                    boundary_length += (mesh.vertices[a as usize].position
                        - mesh.vertices[b as usize].position)
                        .length();
                }
                _ => panic!("case {case}: edge {a}-{b} used {uses} times"),
            }
        }
        let perimeter: f64 = (0..poly.len())
            .map(|i| (poly[(i + 1) % poly.len()] - poly[i]).length())
            .sum();
        assert!(
            (boundary_length - perimeter).abs() < 1e-12 * perimeter,
            "case {case}"
        );
    }
}

#[test]
fn replaying_the_split_log_rebuilds_the_same_mesh() {
    let mut mesh = Mesh::new(&scene_of(vec![square(), pentagon()], 2), DVec3::ZERO, 2).unwrap();
    let mut created = Vec::new();
    for e in [0u32, 9, 3, 20, 21, 12, 40] {
        if mesh.elements.get(e as usize).is_some_and(|el| el.is_leaf()) {
            mesh.split(e, &mut created).unwrap();
        }
    }
    let mut again = Mesh::new(&scene_of(vec![square(), pentagon()], 2), DVec3::ZERO, 2).unwrap();
    again.replay(&mesh.split_log).unwrap();
    assert_eq!(again.vertices, mesh.vertices);
    assert_eq!(again.elements, mesh.elements);
    assert_eq!(again.triangles(), mesh.triangles());
    // Splitting an inner node is refused, not a panic.
    assert_eq!(again.split(0, &mut created), Err(MeshError::BadSplit(0)));
}

#[test]
fn new_vertices_interpolate_from_their_edge_or_element_corners() {
    let mut mesh = Mesh::new(&scene_of(vec![square()], 1), DVec3::ZERO, 1).unwrap();
    let mut created = Vec::new();
    mesh.split(0, &mut created).unwrap();
    assert_eq!(created.len(), 5, "four midpoints and the centre");
    for v in &created {
        let mean = v
            .parents()
            .iter()
            .map(|&p| mesh.vertices[p as usize].position)
            .sum::<DVec3>()
            / v.parent_count as f64;
        assert_eq!(mesh.vertices[v.id as usize].position, mean);
    }
    // The neighbouring-leaf case: split child 0 again, then its sibling finds the
    // existing midpoint instead of creating a duplicate.
    created.clear();
    let first = mesh.elements[0].first_child;
    mesh.split(first, &mut created).unwrap();
    created.clear();
    mesh.split(first + 1, &mut created).unwrap();
    assert_eq!(
        created.len(),
        4,
        "the shared edge's midpoint already exists"
    );
}

#[test]
fn patches_at_finds_every_patch_a_point_touches() {
    let step = 1u32 << SUBDIVISION_BITS;
    let mesh = Mesh::new(&scene_of(vec![square()], 4), DVec3::ZERO, 4).unwrap();
    let at = |uv: [u32; 2]| {
        let mut out = Vec::new();
        mesh.patches_at(0, uv, &mut out);
        out.sort();
        out
    };
    assert_eq!(
        at([step + step / 2, step / 2]),
        vec![1],
        "inside patch (1, 0)"
    );
    assert_eq!(at([step, step / 2]), vec![0, 1], "on the edge between two");
    assert_eq!(at([step, step]), vec![0, 1, 4, 5], "at a grid corner");
    assert_eq!(at([0, 0]), vec![0], "a polygon corner");

    let tri = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
    let mesh = Mesh::new(&scene_of(vec![tri], 3), DVec3::ZERO, 3).unwrap();
    let mut out = Vec::new();
    mesh.patches_at(0, [step, step], &mut out);
    assert_eq!(
        out.len(),
        6,
        "an inner grid point of a triangle touches six patches"
    );
    for &p in &out {
        let corners = mesh.elements[mesh.patches[p as usize].root as usize].uv;
        assert!(
            corners.contains(&[step, step]),
            "patch {p} does not touch it"
        );
    }
    // A point on the shared diagonal of a fanned pentagon may touch patches of
    // the other piece: every patch of the surface is reported.
    let mesh = Mesh::new(&scene_of(vec![pentagon()], 2), DVec3::ZERO, 2).unwrap();
    out.clear();
    mesh.patches_at(0, [0, step / 2], &mut out);
    assert_eq!(out.len(), mesh.patches.len());
}

/// A rectangle `w` × `h` in the z = 0 plane, counter-clockwise about +z.
fn rectangle(w: f64, h: f64) -> Vec<DVec3> {
    vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(w, 0.0, 0.0),
        DVec3::new(w, h, 0.0),
        DVec3::new(0.0, h, 0.0),
    ]
}

fn sized(patch: f64, min_element: Option<f64>) -> Sizing {
    Sizing {
        patches: PatchRule::Size(patch),
        min_element_size: min_element,
        units_per_metre: 1.0,
    }
}

#[test]
fn a_triangle_smaller_than_the_target_is_one_patch_as_it_is() {
    // Edges 0.1, 0.1 and 0.14 against a target of 1: N = ⌈0.14 / 1⌉ = 1.
    let tri = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(0.1, 0.0, 0.0),
        DVec3::new(0.0, 0.1, 0.0),
    ];
    let mesh = Mesh::with_sizing(
        &scene_of(vec![tri.clone()], 0),
        DVec3::ZERO,
        &sized(1.0, None),
    )
    .unwrap();
    assert_eq!(mesh.surfaces[0].patches_per_side, 1);
    assert_eq!(mesh.patches.len(), 1);
    assert_eq!(mesh.elements.len(), 1);
    // The patch is the input triangle itself: its corners are the input
    // vertices exactly (the one-patch grid puts its nodes at the corners).
    let mut corners: Vec<[f64; 3]> = mesh.patches[0]
        .polygon()
        .iter()
        .map(|p| p.to_array())
        .collect();
    let mut input: Vec<[f64; 3]> = tri.iter().map(|p| p.to_array()).collect();
    corners.sort_by(|a, b| a.partial_cmp(b).unwrap());
    input.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert_eq!(corners, input);
}

#[test]
fn a_large_quad_gets_ceil_longest_edge_over_target_per_side() {
    // 5.5 × 3 against a target of 1: N = ⌈5.5⌉ = 6, 36 patches, each at most
    // 5.5 / 6 ≈ 0.917 long; an edge that is an exact multiple (4 × 2 against
    // 1) gets exactly that many, not one more.
    for (w, h, n) in [(5.5, 3.0, 6u32), (4.0, 2.0, 4), (0.5, 0.5, 1)] {
        let mesh = Mesh::with_sizing(
            &scene_of(vec![rectangle(w, h)], 0),
            DVec3::ZERO,
            &sized(1.0, None),
        )
        .unwrap();
        assert_eq!(mesh.surfaces[0].patches_per_side, n, "{w} × {h}");
        assert_eq!(mesh.patches.len(), (n * n) as usize);
        for p in &mesh.patches {
            let c = p.polygon();
            let longest = (0..c.len())
                .map(|k| (c[(k + 1) % c.len()] - c[k]).length())
                .fold(0.0, f64::max);
            // Rounding of the bilinear positions only (1e-12 of a unit).
            assert!(longest <= 1.0 + 1e-12, "{longest}");
        }
    }
}

#[test]
fn an_explicit_patch_count_wins_and_an_oversized_request_is_clamped() {
    let scene = scene_of(vec![rectangle(10.0, 10.0)], 3);
    let mesh = Mesh::with_sizing(&scene, DVec3::ZERO, &sized(1.0, None)).unwrap();
    assert_eq!(mesh.surfaces[0].patches_per_side, 3);
    // 10 / 0.002 = 5000 per side asked: clamped to the most the parametric
    // keys can hold (1024), and reported for the command line to warn.
    let scene = scene_of(vec![rectangle(10.0, 10.0), rectangle(1.0, 1.0)], 0);
    let sizing = sized(0.002, None);
    assert_eq!(
        sizing::clamped_polygons(&scene, &sizing),
        vec![(0usize, 5000u64)]
    );
    let polygon = &scene.polygons[0];
    assert_eq!(sizing.patches_per_side(polygon), MAX_PATCHES_PER_SIDE);
    assert_eq!(sizing.patches_per_side(&scene.polygons[1]), 500);
}

#[test]
fn the_flat_rule_gives_n_squared_patches_whatever_the_size() {
    // Today's (per-polygon) rule: N × N on a quad, N² triangles on a triangle,
    // N² per fan triangle of other polygons (a pentagon fans into 3), for a
    // tiny and a huge polygon alike. `Mesh::new` and an explicit flat sizing agree.
    for scale in [1e-3, 1.0, 1e3] {
        let s = |v: Vec<DVec3>| v.into_iter().map(|p| p * scale).collect::<Vec<_>>();
        let tri = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        let scene = scene_of(vec![s(square()), s(tri), s(pentagon())], 0);
        let a = Mesh::new(&scene, DVec3::ZERO, 3).unwrap();
        let b = Mesh::with_sizing(&scene, DVec3::ZERO, &Sizing::flat(3)).unwrap();
        let per_surface = |m: &Mesh| {
            (0..m.surfaces.len())
                .map(|s| m.patches.iter().filter(|p| p.surface == s as u32).count())
                .collect::<Vec<_>>()
        };
        assert_eq!(per_surface(&a), vec![9, 9, 27], "scale {scale}");
        assert_eq!(per_surface(&a), per_surface(&b));
        assert!(a.surfaces.iter().all(|s| s.min_element_size.is_none()));
    }
}

#[test]
fn per_polygon_sizes_in_metres_and_scene_units_override_the_rule() {
    use crate::scene::{Length, MeshSizes};
    // 1000 scene units per metre (millimetres): "0.25 m" is 250 units.
    let mut scene = scene_of(vec![rectangle(1000.0, 500.0), rectangle(1000.0, 500.0)], 0);
    scene.units_per_metre = 1000.0;
    scene.polygons[0].sizes = MeshSizes {
        patch_size: Some(Length::Metres(0.25)),
        min_element_size: Some(Length::Metres(0.01)),
    };
    scene.polygons[1].sizes = MeshSizes {
        patch_size: Some(Length::SceneUnits(100.0)),
        min_element_size: None,
    };
    let sizing = Sizing {
        patches: PatchRule::Size(1000.0),
        min_element_size: Some(50.0),
        units_per_metre: scene.units_per_metre,
    };
    let mesh = Mesh::with_sizing(&scene, DVec3::ZERO, &sizing).unwrap();
    assert_eq!(mesh.surfaces[0].patches_per_side, 4); // ⌈1000 / 250⌉
    assert_eq!(mesh.surfaces[1].patches_per_side, 10); // ⌈1000 / 100⌉
    assert_eq!(mesh.surfaces[0].min_element_size, Some(10.0));
    assert_eq!(mesh.surfaces[1].min_element_size, Some(50.0));
}
