use super::*;
use crate::scene::{Material, Polygon, SourceRef};
use crate::settings::Preset;
use solution::camera::{Camera, UpAxis};
use solution::format::Representation;

pub(crate) fn material(name: &str, kd: f64, emission: f64) -> Material {
    Material {
        name: name.into(),
        kd: DVec3::splat(kd),
        ks: DVec3::ZERO,
        alpha: 1.0,
        emission: DVec3::splat(emission),
        diffuse_texture: None,
        emission_texture: None,
        folded_texture: None,
    }
}

pub(crate) fn scene_of(
    polygons: Vec<(Vec<DVec3>, usize)>,
    materials: Vec<Material>,
    patches: u32,
) -> Scene {
    Scene {
        lights: Default::default(),
        polygons: polygons
            .into_iter()
            .enumerate()
            .map(|(i, (vertices, material))| Polygon {
                vertices,
                vertex_normals: None,
                uv_map: None,
                material,
                patches,
                sizes: Default::default(),
                source: SourceRef {
                    item: format!("polygon {i}"),
                    ..Default::default()
                },
            })
            .collect(),
        materials,
        units_per_metre: 1.0,
        up_axis: UpAxis::PosY,
        camera: None,
        recentre_offset: DVec3::ZERO,
        warnings: Vec::new(),
    }
}

fn quad(a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) -> Vec<DVec3> {
    [a, b, c, d].map(DVec3::from_array).to_vec()
}

pub(crate) fn settings() -> SolverSettings {
    let mut s = SolverSettings::preset(Preset::Draft);
    s.adaptive = false;
    s.samples = 4;
    s
}

/// Howell's catalogue C-11: between parallel, directly opposed rectangles a × b
/// at distance c.
fn parallel_rectangles(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    2.0 / (PI * x * y)
        * (((1.0 + x * x) * (1.0 + y * y) / (1.0 + x * x + y * y))
            .sqrt()
            .ln()
            + x * sy * (x / sy).atan()
            + y * sx * (y / sx).atan()
            - x * x.atan()
            - y * y.atan())
}

/// Howell's catalogue C-14: from a rectangle w × l to a perpendicular one h × l
/// sharing the edge of length l.
fn perpendicular_rectangles(w: f64, h: f64, l: f64) -> f64 {
    let (h, w) = (h / l, w / l);
    let (h2, w2) = (h * h, w * w);
    let s = (h2 + w2).sqrt();
    let log = ((1.0 + w2) * (1.0 + h2) / (1.0 + w2 + h2)).ln()
        + w2 * (w2 * (1.0 + w2 + h2) / ((1.0 + w2) * (w2 + h2))).ln()
        + h2 * (h2 * (1.0 + h2 + w2) / ((1.0 + h2) * (h2 + w2))).ln();
    (w * (1.0 / w).atan() + h * (1.0 / h).atan() - s * (1.0 / s).atan() + 0.25 * log) / (PI * w)
}

/// Unit square at z = 0 facing +z (material 1, the emitter) and a receiver.
fn pair(receiver: Vec<DVec3>, patches: u32) -> Solver {
    let floor = quad(
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    );
    let scene = scene_of(
        vec![(floor, 1), (receiver, 0)],
        vec![material("grey", 0.5, 0.0), material("light", 0.5, 1.0)],
        patches,
    );
    Solver::new(&scene, &settings()).unwrap()
}

fn facing_square() -> Vec<DVec3> {
    quad(
        [0.0, 0.0, 1.0],
        [0.0, 1.0, 1.0],
        [1.0, 1.0, 1.0],
        [1.0, 0.0, 1.0],
    )
}

fn wall_square() -> Vec<DVec3> {
    // The plane x = 0, facing +x, sharing the edge x = z = 0 with the floor.
    quad(
        [0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 1.0, 1.0],
        [0.0, 0.0, 1.0],
    )
}

/// Σ over the patches of surface `s`.
fn patches_of(solver: &Solver, s: u32) -> Vec<u32> {
    (0..solver.mesh().patches.len() as u32)
        .filter(|&p| solver.mesh().patches[p as usize].surface == s)
        .collect()
}

/// A_I F_IJ between the coarse 4 × 4 patches of surfaces 0 and 1, computed on
/// a mesh with 4k × 4k patches (each coarse patch the union of k × k fine ones):
/// `[I][J]` from surface 0 to 1 and `[J][I]` the other way.
fn coarse_exchange(receiver: &[DVec3], k: u32) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let n = 4 * k;
    let solver = pair(receiver.to_vec(), n);
    let coarse = |p: u32| {
        let local = p % (n * n);
        ((local / n) / k * 4 + (local % n) / k) as usize
    };
    let (a, b) = (patches_of(&solver, 0), patches_of(&solver, 1));
    let mut ab = vec![vec![0.0; 16]; 16];
    let mut ba = vec![vec![0.0; 16]; 16];
    for (sources, receivers, out) in [(&b, &a, &mut ab), (&a, &b, &mut ba)] {
        for &j in sources.iter() {
            let f = solver.vertex_form_factors(j);
            for &i in receivers.iter() {
                let aij: f64 = solver
                    .patch_weights(i)
                    .iter()
                    .map(|&(v, w)| w * f[v as usize])
                    .sum();
                out[coarse(i)][coarse(j)] += aij;
            }
        }
    }
    (ab, ba)
}

#[test]
fn vertex_factors_integrate_to_the_exact_polygon_factors_and_are_reciprocal() {
    let exact_parallel = parallel_rectangles(1.0, 1.0, 1.0);
    let exact_perpendicular = perpendicular_rectangles(1.0, 1.0, 1.0);
    assert!((exact_parallel - 0.19982).abs() < 1e-5);
    assert!((exact_perpendicular - 0.20004).abs() < 1e-5);
    for (name, receiver, exact) in [
        ("parallel", facing_square(), exact_parallel),
        ("perpendicular", wall_square(), exact_perpendicular),
    ] {
        let mut total_errors = Vec::new();
        let mut pair_errors = Vec::new();
        for k in [1u32, 2, 4] {
            let (ab, ba) = coarse_exchange(&receiver, k);
            // Polygon level: A_A F_AB (unit areas) both ways.
            let (sum_ab, sum_ba): (f64, f64) =
                (ab.iter().flatten().sum(), ba.iter().flatten().sum());
            let total = (sum_ab - exact).abs().max((sum_ba - exact).abs()) / exact;
            // Patch level: the worst relative reciprocity error A_I F_IJ vs
            // A_J F_JI over the 256 coarse pairs.
            let mut worst: f64 = 0.0;
            for i in 0..16 {
                for j in 0..16 {
                    let (x, y) = (ab[i][j], ba[j][i]);
                    worst = worst.max((x - y).abs() / x.max(y));
                }
            }
            println!(
                "{name} {0}×{0} patches: A F_AB = {sum_ab:.6}, A F_BA = {sum_ba:.6}, exact {exact:.6}, \
                 rel err {total:.2e}; worst 4×4-pair reciprocity error {worst:.2e}",
                4 * k
            );
            total_errors.push(total);
            pair_errors.push(worst);
        }
        // The gather integrates the piecewise-linear interpolant of the vertex
        // factors, so the error of a factor is about (h²/12) · ∫ΔF / ∫F with h
        // the patch side: second order in h. For the polygons the relative
        // Laplacian of F over the receiver is ≈ 3.6 (parallel pair), i.e.
        // 0.30 h² (1.9% at h = 1/4): bound 0.5 h², and at least a factor 3 less
        // each time h halves.
        for (e, h) in total_errors.iter().zip([0.25, 0.125, 0.0625]) {
            assert!(*e < 0.5 * h * h, "{name}: {total_errors:?}");
        }
        assert!(
            total_errors[1] < total_errors[0] / 3.0,
            "{name}: {total_errors:?}"
        );
        // Patch pairs: for two 1/4-wide patches a distance d apart the relative
        // Laplacian scales like 1/d², so pairs at d ≈ h are not resolved by
        // their own corners (errors of tens of percent at 4 × 4; for pairs that
        // touch the shared edge the integrand even has a logarithmic
        // singularity at a corner). What the mesh guarantees is convergence:
        // the worst reciprocity error must fall by at least 1.6 each time the
        // mesh is refined by 2: first order (a factor 2; the O(h) part is the
        // step of boundary vertices into their element, and the worst pairs
        // touch the singular edge) less 20% for taking the maximum over pairs.
        assert!(
            pair_errors[1] < pair_errors[0] / 1.6,
            "{name}: {pair_errors:?}"
        );
        assert!(
            pair_errors[2] < pair_errors[1] / 1.6,
            "{name}: {pair_errors:?}"
        );
    }
}

#[test]
fn one_shot_delivers_kd_times_the_exactly_intercepted_power() {
    // Energy balance of the gather: the unshot power on the receiver after the
    // emitter's patches have shot equals Kd · Φ_emitted · F_AB (every patch of the
    // emitter shoots once, N² shots), within the O(h²) integration error bounded
    // above (0.5 h², 3.1% at N = 4).
    let solver_settings = settings();
    let floor = quad(
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    );
    let scene = scene_of(
        vec![(floor, 1), (facing_square(), 0)],
        vec![material("grey", 0.5, 0.0), material("light", 0.0, 2.0)],
        4,
    );
    let mut solver = Solver::new(&scene, &solver_settings).unwrap();
    let emitted = solver.progress().emitted_power;
    assert!(
        (emitted - PI * 1.0 * 6.0).abs() < 1e-12 * emitted,
        "π · A · ΣLe = 6π"
    );
    // In millimetres the same numbers are 1e-6 of the watts.
    let mut millimetres = scene.clone();
    millimetres.units_per_metre = 1000.0;
    let watts = Solver::new(&millimetres, &solver_settings)
        .unwrap()
        .progress()
        .emitted_power;
    assert!((watts - 6.0 * PI * 1e-6).abs() < 1e-12 * watts, "{watts}");
    // The light's 16 patches shoot first, alone or (grouped shooters, the
    // default) in recorded groups of emitters' first shots.
    while solver.emitter_first_shots().0 + solver.emitter_first_shots().1 < 16 {
        let report = solver.step().unwrap();
        assert!(solver.mesh().patches[report.source.unwrap() as usize].surface == 0);
    }
    let received = solver.progress().unshot_fraction * emitted;
    let expected = 0.5 * emitted * parallel_rectangles(1.0, 1.0, 1.0);
    println!("received {received:.6} W, expected {expected:.6} W");
    assert!((received - expected).abs() < 0.5 / 16.0 * expected);
}

#[test]
fn bad_scenes_are_refused_with_clear_errors() {
    let floor = quad(
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    );
    let mats = vec![material("grey", 0.5, 0.0), material("light", 0.5, 1.0)];
    let s = settings();
    let err = |scene: Scene| Solver::new(&scene, &s).err().unwrap();

    let e = err(scene_of(vec![], mats.clone(), 1));
    assert!(matches!(e, SolveError::EmptyScene), "{e}");
    let e = err(scene_of(vec![(floor.clone(), 1)], mats.clone(), 1));
    assert!(matches!(e, SolveError::SinglePolygon), "{e}");
    assert!(e.to_string().contains("single polygon"));
    let e = err(scene_of(
        vec![(floor.clone(), 0), (facing_square(), 0)],
        mats.clone(),
        1,
    ));
    assert!(matches!(e, SolveError::NoEmitter { .. }), "{e}");
    assert!(e.to_string().contains("no emitter"));
    // The fix in the scene's own format: a glTF's polygons are told about
    // `emissiveFactor`, not the MTL's `Ke` (issue 42), and every scene about
    // the sun and sky.
    let mut gltf = scene_of(
        vec![(floor.clone(), 0), (facing_square(), 0)],
        mats.clone(),
        1,
    );
    for polygon in &mut gltf.polygons {
        polygon.source.file = "car.gltf".into();
    }
    let message = err(gltf).to_string();
    for phrase in [
        "emissiveFactor",
        "KHR_lights_punctual",
        "[sun]",
        "--sun",
        "--sky",
    ] {
        assert!(message.contains(phrase), "{phrase:?} not in {message}");
    }
    assert!(!message.contains("Ke r g b"), "{message}");
    let e = err(scene_of(
        vec![(floor.clone(), 3), (facing_square(), 0)],
        mats.clone(),
        1,
    ));
    assert!(
        matches!(e, SolveError::Mesh(MeshError::BadMaterial { .. })),
        "{e}"
    );
    let e = err(scene_of(
        vec![(floor.clone(), 1), (facing_square(), 0)],
        vec![material("grey", 0.5, 0.0), material("light", 0.5, f64::NAN)],
        1,
    ));
    assert!(e.to_string().contains("material `light`"), "{e}");
    // A zero-area polygon does not count as a surface.
    let sliver = vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
    let e = err(scene_of(
        vec![(floor.clone(), 1), (sliver, 0)],
        mats.clone(),
        1,
    ));
    assert!(matches!(e, SolveError::SinglePolygon), "{e}");
    let mut directional = s.clone();
    directional.mode = SolveMode::Directional;
    let scene = scene_of(vec![(floor, 1), (facing_square(), 0)], mats, 1);
    // Directional mode is implemented (solve/directional.rs) and accepted.
    assert!(Solver::new(&scene, &directional).is_ok());
}

#[test]
fn solution_holds_sh_order_0_and_the_ambient_term_while_light_is_unshot() {
    let mut solver = pair(facing_square(), 2);
    // A solver that has not shot (as the Gauss–Seidel and cube gathers use it)
    // writes no ambient term in a final file, though all its emission is unshot.
    assert_eq!(solver.to_solution(false).header.stats.ambient, [0.0; 3]);
    solver.step().unwrap();
    let radiance = solver.vertex_radiance().to_vec();
    let with_ambient = solver.settings().clone();
    let mut off = with_ambient.clone();
    off.ambient = false;
    solver.settings = off;
    let full = solver.to_solution(false);
    solver.settings = with_ambient;
    let batch = &full.batches[0];
    assert_eq!(batch.representation, Representation::Sh { order: 0 });
    assert_eq!(batch.vertices.len(), solver.mesh().vertices.len());
    assert_eq!(batch.coefficients.len(), 3 * batch.vertices.len());
    assert!(batch
        .indices
        .iter()
        .all(|&i| (i as usize) < batch.vertices.len()));
    assert_eq!(
        batch.indices.len(),
        3 * 2 * 2 * 4,
        "two 2×2 quads, two triangles per patch"
    );
    // Without the ambient term, c00 = L · √(4π): evaluating Y00 = 1/(2√π)
    // gives L back (f32 rounding).
    for (v, l) in radiance.iter().enumerate() {
        for c in 0..3 {
            let back = batch.coefficients[3 * v + c] as f64 / (2.0 * PI.sqrt());
            assert!(
                (back - l[c]).abs() <= 1e-6 * l[c].abs().max(1e-30),
                "{back} vs {}",
                l[c]
            );
        }
    }
    assert_eq!(full.header.stats.ambient, [0.0; 3]);
    let ambient = solver.ambient();
    assert!(
        ambient.min_element() > 0.0,
        "light is left unshot after one shot"
    );
    // With it (the default), partial and final files alike carry the estimate
    // of the light still unshot: displayed = L + Kd · ambient · ε / ε̄, the
    // term weighted by the vertex's enclosure (`enclosure.rs`; the two
    // facing squares are open all round, so ε < 1 at a corner), and the
    // solver's own radiance is unchanged.
    let weighted = solver.enclosed_ambient(&[0], ambient)[0];
    assert!(
        weighted.x > 0.0 && weighted.x < ambient.x,
        "{weighted} {ambient}"
    );
    for partial in [true, false] {
        let file = solver.to_solution(partial);
        assert_eq!(file.header.partial, partial);
        assert_eq!(file.header.stats.ambient, ambient.as_vec3().to_array());
        let shown = file.batches[0].coefficients[0] as f64 / (2.0 * PI.sqrt());
        assert!((shown - (radiance[0].x + 0.5 * weighted.x)).abs() < 1e-6 * shown);
    }
    assert_eq!(solver.vertex_radiance(), &radiance[..]);
    // Header: the settings travel as JSON, and the re-centring offset is the
    // bounding-box centre the solver subtracted.
    assert!(full.header.settings_json.contains("\"samples\":4"));
    assert_eq!(full.header.recentre_offset, [0.5, 0.5, 0.5]);
    assert_eq!(full.header.bounds_min, [-0.5; 3]);
}

#[test]
fn ambient_term_matches_cohen_et_al_for_uniform_unshot() {
    // Before any shot only the emitter (area 1, Le = 1) holds unshot radiance;
    // both surfaces have ρ = 0.5, so R = 2 and ambient = 2 · (1 · 1) / 2 = 1.
    let solver = pair(facing_square(), 1);
    let ambient = solver.ambient();
    assert!(
        (ambient - DVec3::ONE).abs().max_element() < 1e-12,
        "{ambient}"
    );
}

/// Asserts that two directional solves hold the same bits at every vertex:
/// its diffuse proxy and its coefficients (the resume tests).
pub(crate) fn assert_same_directional_bits(a: &Solver, b: &Solver) {
    for v in 0..a.mesh.vertices.len() {
        let (x, y) = (a.directional_vertex(v), b.directional_vertex(v));
        assert_eq!(
            x.0.to_array().map(f64::to_bits),
            y.0.to_array().map(f64::to_bits),
            "{v}"
        );
        let same =
            x.1.iter()
                .zip(&y.1)
                .all(|(p, q)| p.to_bits() == q.to_bits());
        assert!(same && x.1.len() == y.1.len(), "vertex {v}");
    }
}

/// A closed 4 × 2.5 × 6 room (walls facing in, Kd 0.5) with a 1 m² ceiling
/// light facing down, re-centred by (100, 0, 0).
pub(crate) fn closed_room(camera: Option<Camera>) -> Scene {
    let face = |c: DVec3, e1: DVec3, e2: DVec3| vec![c, c + e1, c + e1 + e2, c + e2];
    let lo = DVec3::new(-2.0, 0.0, -3.0);
    let (x, y, z) = (DVec3::X * 4.0, DVec3::Y * 2.5, DVec3::Z * 6.0);
    let polygons = vec![
        (face(lo, z, x), 0),
        (face(lo + y, x, z), 0),
        (face(lo, y, z), 0),
        (face(lo + x, z, y), 0),
        (face(lo, x, y), 0),
        (face(lo + z, y, x), 0),
        (face(DVec3::new(0.5, 2.49, 1.0), DVec3::X, DVec3::Z), 1),
    ];
    let mut scene = scene_of(
        polygons,
        vec![material("wall", 0.5, 0.0), material("light", 0.5, 10.0)],
        2,
    );
    scene.recentre_offset = DVec3::new(100.0, 0.0, 0.0);
    scene.camera = camera;
    scene
}

#[test]
fn a_scene_without_a_camera_gets_an_eye_inside_and_an_authored_camera_is_kept() {
    let mut solver = Solver::new(&closed_room(None), &settings()).unwrap();
    solver.step().unwrap();
    let camera = solver.to_solution(false).header.camera;
    // The framing camera stood at z = 1.25 + 3.9 / sin 22.5° ≈ 11 m, outside the
    // room; the chosen eye is inside it (original coordinates: x offset by 100),
    // 1.6 m above the floor (the room is 2.5 m high: 0.7 × 2.5 > 1.6).
    let eye = DVec3::from_array(camera.eye);
    let (lo, hi) = (DVec3::new(98.0, 0.0, -3.0), DVec3::new(102.0, 2.5, 3.0));
    assert!(eye.cmpgt(lo).all() && eye.cmplt(hi).all(), "{camera:?}");
    assert!(
        (eye.y - solution::view::EYE_HEIGHT_M).abs() < 1e-5,
        "{camera:?}"
    );
    assert_eq!(camera.fov_y_deg, solution::view::FOV_Y_DEG);
    // Partial files choose the same way (the light seen differs only by the
    // ambient term, which adds to every wall alike).
    assert!(solver.to_solution(true).header.camera.validate().is_ok());

    let authored = Camera {
        eye: [100.0, 5.0, 20.0],
        target: [100.0, 1.0, 0.0],
        fov_y_deg: 30.0,
        ..Camera::default()
    };
    let mut solver = Solver::new(&closed_room(Some(authored)), &settings()).unwrap();
    solver.step().unwrap();
    assert_eq!(solver.to_solution(false).header.camera, authored);
    assert_eq!(solver.to_solution(true).header.camera, authored);
}
