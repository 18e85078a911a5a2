use super::*;
use crate::settings::Preset;
use crate::solve::tests::{material, scene_of};

/// The six inward-facing faces of the unit cube, all of material 0.
fn cube() -> Vec<(Vec<DVec3>, usize)> {
    let c = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let faces = [
        [c(0., 0., 0.), c(1., 0., 0.), c(1., 1., 0.), c(0., 1., 0.)],
        [c(0., 0., 1.), c(1., 0., 1.), c(1., 1., 1.), c(0., 1., 1.)],
        [c(0., 0., 0.), c(0., 1., 0.), c(0., 1., 1.), c(0., 0., 1.)],
        [c(1., 0., 0.), c(1., 1., 0.), c(1., 1., 1.), c(1., 0., 1.)],
        [c(0., 0., 0.), c(0., 0., 1.), c(1., 0., 1.), c(1., 0., 0.)],
        [c(0., 1., 0.), c(0., 1., 1.), c(1., 1., 1.), c(1., 1., 0.)],
    ];
    let centre = DVec3::splat(0.5);
    faces
        .into_iter()
        .map(|f| {
            let mut f = f.to_vec();
            let mid = f.iter().copied().sum::<DVec3>() / 4.0;
            if crate::geometry::polygon::newell_normal(&f).dot(centre - mid) < 0.0 {
                f.reverse();
            }
            (f, 0)
        })
        .collect()
}

/// The scenes below give every polygon its patch count.
fn settings(resolution: u32) -> SolverSettings {
    let mut s = SolverSettings::preset(Preset::Draft);
    s.hemicube_resolution = resolution;
    s
}

#[test]
fn furnace_gives_le_over_one_minus_rho() {
    // A closed cube with uniform Kd = ρ and Le = 1: L = Le/(1 − ρ) everywhere
    // (design notes, "Extremes"). Inside a closed box every hemicube cell sees
    // a patch, so each row sums to 1 within 1e-10 in f64 (the exact delta
    // factors do), whatever the aliasing. Two errors remain: the iteration's,
    // at most γ/(1 − γ) × the last change (≈ 1e-7 at ρ = 0.99 with tolerance
    // 1e-9), and f32 storage of the factors, which moves a row sum s by up to
    // 6e-8 relative and L = Le/(1 − ρs) by ρ·6e-8/(1 − ρ) = 6e-6 at ρ = 0.99.
    // 1e-5 relative covers both.
    for rho in [0.5, 0.9, 0.99] {
        let scene = scene_of(cube(), vec![material("furnace", rho, 1.0)], 3);
        let limits = GaussSeidelLimits {
            tolerance: 1e-9,
            max_sweeps: 20_000,
            ..Default::default()
        };
        let result = solve_gauss_seidel(&scene, &settings(16), &limits).unwrap();
        let exact = 1.0 / (1.0 - rho);
        assert!(result.converged, "ρ = {rho}: {} sweeps", result.sweeps);
        for s in &result.row_sums {
            assert!((s - 1.0).abs() < 1e-10, "ρ = {rho}: row sum {s}");
        }
        let worst = |values: &[DVec3]| {
            values
                .iter()
                .map(|l| ((*l - DVec3::splat(exact)) / exact).abs().max_element())
                .fold(0.0, f64::max)
        };
        let (patch_err, vertex_err) = (
            worst(&result.patch_radiance),
            worst(&result.vertex_radiance),
        );
        println!(
            "furnace ρ = {rho}: {} sweeps, bound {:.1e}, worst patch error {patch_err:.1e}, vertex {vertex_err:.1e}",
            result.sweeps, result.error_bound
        );
        assert!(
            patch_err < 1e-5 && vertex_err < 1e-5,
            "ρ = {rho}: {patch_err} {vertex_err}"
        );
        assert_eq!(result.patch_radiance.len(), 6 * 9);
    }
}

#[test]
fn matrix_size_check_states_n_bytes_and_the_bound() {
    let limits = GaussSeidelLimits::default();
    // 2 GiB of f32 holds 23170² factors but not 23171².
    assert_eq!(
        check_matrix_size(23_170, &limits).unwrap(),
        23_170 * 23_170 * 4
    );
    let err = check_matrix_size(23_171, &limits).unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("23171 patches")
            && text.contains(&(23_171u128 * 23_171 * 4).to_string())
            && text.contains(&DEFAULT_MAX_MATRIX_BYTES.to_string())
            && text.contains("2.0 GiB"),
        "{text}"
    );
    // No overflow for absurd counts.
    assert!(matches!(
        check_matrix_size(u64::MAX, &limits),
        Err(GaussSeidelError::MatrixTooLarge { .. })
    ));
}

#[test]
fn a_scene_too_large_is_refused_before_meshing() {
    // 256 × 256 patches on each of the cube's six faces: 393 216 patches,
    // 618 GB of factors. The refusal comes from the count before meshing, so
    // it is immediate (meshing 393 216 patches would take seconds); the
    // integration test `gauss_seidel_refusal` checks that it allocates nothing
    // of that size.
    let scene = scene_of(cube(), vec![material("furnace", 0.5, 1.0)], 256);
    let s = settings(16);
    assert_eq!(patch_count_lower_bound(&scene, &s), 6 * 256 * 256);
    match solve_gauss_seidel(&scene, &s, &GaussSeidelLimits::default()) {
        Err(GaussSeidelError::MatrixTooLarge {
            patches,
            bytes,
            limit,
        }) => {
            assert_eq!(patches, 393_216);
            assert_eq!(bytes, 393_216u128 * 393_216 * 4);
            assert_eq!(limit, DEFAULT_MAX_MATRIX_BYTES);
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    // A small bound refuses a small scene with its exact count.
    let scene = scene_of(cube(), vec![material("furnace", 0.5, 1.0)], 2);
    let limits = GaussSeidelLimits {
        max_matrix_bytes: 1000,
        ..Default::default()
    };
    assert!(matches!(
        solve_gauss_seidel(&scene, &settings(16), &limits),
        Err(GaussSeidelError::MatrixTooLarge { patches: 24, .. })
    ));
}

#[test]
fn bad_input_is_refused_with_clear_errors() {
    let one = scene_of(vec![cube().remove(0)], vec![material("lamp", 0.5, 1.0)], 2);
    assert!(matches!(
        solve_gauss_seidel(&one, &settings(16), &GaussSeidelLimits::default()),
        Err(GaussSeidelError::Solve(SolveError::SinglePolygon))
    ));
    let dark = scene_of(cube(), vec![material("grey", 0.5, 0.0)], 2);
    assert!(matches!(
        solve_gauss_seidel(&dark, &settings(16), &GaussSeidelLimits::default()),
        Err(GaussSeidelError::Solve(SolveError::NoEmitter { .. }))
    ));
    let scene = scene_of(cube(), vec![material("furnace", 0.5, 1.0)], 2);
    let err = solve_gauss_seidel(&scene, &settings(15), &GaussSeidelLimits::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("hemicube_resolution") && err.contains("15"),
        "{err}"
    );
    let limits = GaussSeidelLimits {
        tolerance: 0.0,
        ..Default::default()
    };
    assert!(matches!(
        solve_gauss_seidel(&scene, &settings(16), &limits),
        Err(GaussSeidelError::BadTolerance(_))
    ));
}

/// Area-weighted mean radiance of each surface of the Cornell box solved both
/// ways on the same N × N patch mesh, the emitter excluded, and as the last
/// entry the mean over all those surfaces: (Gauss–Seidel, progressive).
fn cornell_surface_means(patches: u32) -> (Vec<DVec3>, Vec<DVec3>) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/cornell_box.obj");
    let mut scene = crate::scene::load_scene(&path, &Default::default())
        .unwrap()
        .scene;
    scene.fill_default_patches(patches);
    let mut s = settings(64);
    // Gauss–Seidel meshes receivers whole; the progressive solve must too
    // for the two to share their patches.
    s.whole_receivers = true;
    s.adaptive = false;
    s.samples = 8;
    s.threshold = 2e-3;
    s.max_shots = 100_000;
    s.ambient = false;
    let limits = GaussSeidelLimits {
        tolerance: 1e-6,
        ..Default::default()
    };
    let gs = solve_gauss_seidel(&scene, &s, &limits).unwrap();
    assert!(gs.converged);
    let mut progressive = Solver::new(&scene, &s).unwrap();
    while progressive.step().is_some() {}
    let mesh = progressive.mesh();
    assert_eq!(mesh.patches.len(), gs.patch_radiance.len());
    // Per input polygon: the floor and the ceiling are cut into several
    // surfaces along the blocks' and the light's contact lines
    // (`mesh::contact`).
    let count = scene.polygons.len() + 1;
    let (mut g, mut p, mut area) = (
        vec![DVec3::ZERO; count],
        vec![DVec3::ZERO; count],
        vec![0.0; count],
    );
    for (i, patch) in mesh.patches.iter().enumerate() {
        let k = mesh.surfaces[patch.surface as usize].polygon;
        if scene.materials[mesh.surfaces[patch.surface as usize].material]
            .emission
            .max_element()
            > 0.0
        {
            continue;
        }
        // Patches holding a hidden vertex (the floor under the blocks, the
        // ceiling above the light) are left out: the progressive solve treats
        // those vertices as hidden (`solve/hidden.rs`), Gauss–Seidel's patch
        // gather does not, so the two discretisations differ there by design.
        if progressive
            .patch_weights(i as u32)
            .iter()
            .any(|&(v, _)| progressive.hidden_vertices()[v as usize])
        {
            continue;
        }
        // The progressive patch mean: its displayed (Gouraud) field integrated
        // over the patch, Σ_v w_vp L_v.
        let integral: DVec3 = progressive
            .patch_weights(i as u32)
            .iter()
            .map(|&(v, w)| progressive.vertex_radiance()[v as usize] * w)
            .sum();
        for slot in [k, count - 1] {
            g[slot] += gs.patch_radiance[i] * patch.area;
            p[slot] += integral;
            area[slot] += patch.area;
        }
    }
    let mean = |sums: Vec<DVec3>| -> Vec<DVec3> {
        sums.iter()
            .zip(&area)
            .map(|(s, &a)| if a > 0.0 { *s / a } else { DVec3::ZERO })
            .collect()
    };
    (mean(g), mean(p))
}

#[test]
fn gauss_seidel_and_progressive_refinement_agree_on_the_cornell_box() {
    // Both solve the same radiosity equation on the same patches, but
    // discretise it differently: Gauss–Seidel takes each patch's radiance at
    // its centre (centre-point hemicube factors, constant per patch), the
    // progressive solver keeps radiance at vertices and interpolates linearly
    // between them (exact point-to-patch factors, ray-cast visibility). Their
    // difference is therefore the sum of two discretisation errors, and the
    // tolerance is derived from estimates of those: both errors fall at least
    // linearly with the patch size h, so the change of each method from h to
    // h/2 (3 × 3 to 6 × 6 patches per polygon) is at least its remaining error
    // at h/2 (Richardson: error(h/2) ≈ change / (2^p − 1) ≤ change for order
    // p ≥ 1). So at 6 × 6, per surface and channel,
    //   |GS − PR| ≤ |GS₆ − GS₃| + |PR₆ − PR₃| + convergence slack,
    // the slack covering the progressive solve's stop at 0.2% unshot power
    // (≤ ρ/(1 − ρ) × 0.2% ≈ 0.5% of the radiance for the box's ρ ≤ 0.7) and the
    // Gauss–Seidel tolerance (1e-6, negligible). Checked on the five room
    // surfaces (floor, ceiling, back, left and right walls) and the mean over
    // every surface. Measured: the differences use 1% to 77% of the bound,
    // and are 0.1% to 8.3% of the radiance (the walls' top rows, lit at grazing
    // incidence by a light 0.1 mm below the ceiling, are where the two
    // discretisations part most).
    let (g3, p3) = cornell_surface_means(3);
    let (g6, p6) = cornell_surface_means(6);
    let all = g6.len() - 1;
    for k in [0usize, 1, 2, 3, 4, all] {
        for c in 0..3 {
            let difference = (g6[k][c] - p6[k][c]).abs();
            let bound = (g6[k][c] - g3[k][c]).abs() + (p6[k][c] - p3[k][c]).abs() + 5e-3 * p6[k][c];
            println!(
                "surface {k} channel {c}: GS {:.4}, PR {:.4}, |difference| {difference:.4} ({:.1}%), bound {bound:.4}",
                g6[k][c],
                p6[k][c],
                100.0 * difference / p6[k][c]
            );
            assert!(p6[k][c] > 0.0, "surface {k} is dark");
            assert!(
                difference <= bound,
                "surface {k} channel {c}: {difference} > {bound}"
            );
        }
    }
}

// The progressive solver with hemicube form factors (the hemicube on the
// shooting patch, `FormFactorMethod::Hemicube`): tests beside the gathering
// ones, since both are the radiosity lecture notes' hemicube methods.

use crate::settings::FormFactorMethod;

fn emitter_patch(solver: &Solver, scene: &Scene) -> u32 {
    let mesh = solver.mesh();
    (0..mesh.patches.len() as u32)
        .find(|&p| {
            let surface = &mesh.surfaces[mesh.patches[p as usize].surface as usize];
            scene.materials[surface.material].emission.max_element() > 0.0
        })
        .unwrap()
}

#[test]
fn hemicube_shooting_sees_every_vertex_of_a_convex_room() {
    // In a closed cube nothing is occluded, so the hemicube's visibility must
    // be 1 for every receiving vertex, corners and edges included (where a
    // neighbouring wall fills the receiver's cell and only the depth test
    // lets it through): the factors equal the exact unoccluded ones bit for
    // bit.
    let scene = scene_of(cube(), vec![material("furnace", 0.5, 1.0)], 3);
    let mut hemicube = settings(64);
    hemicube.form_factors = FormFactorMethod::Hemicube;
    let mut unoccluded = settings(64);
    unoccluded.shadows = false;
    let (a, b) = (
        Solver::new(&scene, &hemicube).unwrap(),
        Solver::new(&scene, &unoccluded).unwrap(),
    );
    for source in [0u32, 4, 13, 22, 40, 53] {
        let (fa, fb) = (a.vertex_form_factors(source), b.vertex_form_factors(source));
        let lit = fb.iter().filter(|&&f| f > 0.0).count();
        assert!(lit > 20, "source {source}: only {lit} receivers");
        assert_eq!(fa, fb, "source {source}");
    }
}

#[test]
fn hemicube_shooting_casts_the_shadow_seen_from_the_source_centre() {
    // A 1 × 1 emitter at height 3 facing down, a 1 × 1 blocker at height 2
    // (both sides drawn: it faces up, toward the source) and a 6 × 6 floor.
    // The hemicube sees the blocker from the source's centre c; a floor point
    // p is behind it exactly when the ray c → p crosses the blocker's square,
    // i.e. when its crossing of the blocker's plane, c + (p − c)·(1/3) here, is
    // inside the square. The blocker is parallel to the top face, so in that
    // plane a cell is h·D wide (D = 1 the plane's distance, h = 2/R): the 3 × 3
    // filter sees across the edge only within 1.5·√2·h·D of it. Outside a band
    // of 2.5·h·D around the edge, the visible fraction must be exactly 0
    // (inside) or 1 (outside).
    let (r, d) = (64u32, 1.0);
    let floor = vec![
        DVec3::new(-3.0, -3.0, 0.0),
        DVec3::new(3.0, -3.0, 0.0),
        DVec3::new(3.0, 3.0, 0.0),
        DVec3::new(-3.0, 3.0, 0.0),
    ];
    let square = |z: f64, half: f64| {
        vec![
            DVec3::new(-half, -half, z),
            DVec3::new(-half, half, z),
            DVec3::new(half, half, z),
            DVec3::new(half, -half, z),
        ]
    };
    let mut blocker_up = square(2.0, 0.5);
    blocker_up.reverse();
    let scene = {
        let mut s = scene_of(
            vec![
                (floor, 0),
                (square(3.0, 0.5), 1),
                (square(2.0, 0.5), 0),
                (blocker_up, 0),
            ],
            vec![material("grey", 0.5, 0.0), material("lamp", 0.5, 1.0)],
            1,
        );
        s.polygons[0].patches = 16;
        s
    };
    let mut hemicube = settings(r);
    hemicube.form_factors = FormFactorMethod::Hemicube;
    let mut unoccluded = settings(r);
    unoccluded.shadows = false;
    let (a, b) = (
        Solver::new(&scene, &hemicube).unwrap(),
        Solver::new(&scene, &unoccluded).unwrap(),
    );
    let source = emitter_patch(&a, &scene);
    let (fa, fb) = (a.vertex_form_factors(source), b.vertex_form_factors(source));
    let mesh = a.mesh();
    let centre = DVec3::new(0.0, 0.0, 3.0) - a.offset();
    let margin = 2.5 * (2.0 / r as f64) * d;
    let (mut inside, mut outside) = (0, 0);
    for (v, vertex) in mesh.vertices.iter().enumerate() {
        if mesh.surfaces[vertex.surface as usize].polygon != 0 || fb[v] <= 0.0 {
            continue;
        }
        let p = vertex.position;
        let crossing =
            centre + (p - centre) * ((centre.z - (2.0 - a.offset().z)) / (centre.z - p.z));
        let reach = (crossing - (DVec3::new(0.0, 0.0, 2.0) - a.offset()))
            .abs()
            .max_element();
        let fraction = fa[v] / fb[v];
        if reach < 0.5 - margin {
            assert_eq!(fraction, 0.0, "vertex {v} at {p} should be in the shadow");
            inside += 1;
        } else if reach > 0.5 + margin {
            assert!(
                (fraction - 1.0).abs() < 1e-12,
                "vertex {v} at {p}: {fraction}"
            );
            outside += 1;
        }
    }
    println!("{inside} vertices in the shadow, {outside} lit, checked");
    assert!(inside >= 9 && outside >= 100, "{inside} {outside}");
}

// Textured surfaces (`solve/textured.rs`; the module notes, "Textured surfaces").

/// A `size` × `size` checkerboard of `square`-texel squares, sRGB codes 255
/// and 50.
fn checkerboard(size: u32, square: u32) -> std::sync::Arc<crate::scene::SceneTexture> {
    let mut rgba = Vec::new();
    for y in 0..size {
        for x in 0..size {
            let c = if (x / square + y / square).is_multiple_of(2) {
                255
            } else {
                50
            };
            rgba.extend([c, c, c, 255]);
        }
    }
    std::sync::Arc::new(
        crate::scene::SceneTexture::from_rgba("checker.png".into(), size, size, rgba).unwrap(),
    )
}

/// Maps each polygon of `scene` (a quad) once onto the texture, u along its
/// first edge and v along its last, shifted by `shift` in both.
fn map_once(scene: &mut Scene, shift: f64) {
    for p in &mut scene.polygons {
        let o = p.vertices[0];
        let (a, b) = (p.vertices[1] - o, p.vertices[3] - o);
        p.uv_map = Some(crate::scene::UvMap {
            origin: o,
            du: a / a.length_squared(),
            dv: b / b.length_squared(),
            base: glam::DVec2::splat(shift),
        });
    }
}

#[test]
fn textured_furnace_gives_le_over_one_minus_the_textures_mean() {
    // The closed cube, every face emitting Le = 1 with Kd 1 × a checkerboard
    // (8 × 8 texels, squares of 2, codes 255 and 50: linear 1 and 0.0319,
    // mean m = 0.516). Each face is mapped once, shifted by half a square,
    // so that each of its 2 × 2 patches covers exactly 2 × 2 squares, ∫ρ/A =
    // m, while its centre lies inside one square (ρ 1 or 0.0319): a patch
    // reflecting ρ at its centre would fail. Then L = Le + m E/π with E/π =
    // L everywhere: L = Le/(1 − m) and E/π the same, per patch and vertex,
    // and the file's textured batch holds E/π with Le as its SH term. The
    // tolerance of the untextured furnace (1e-5 relative: the iteration and
    // f32 factors) holds here too.
    let mut furnace = material("furnace", 1.0, 1.0);
    let texture = checkerboard(8, 2);
    let m = texture.texture.mean().x;
    furnace.diffuse_texture = Some(texture);
    let mut scene = scene_of(cube(), vec![furnace], 2);
    map_once(&mut scene, 1.0 / 8.0);
    let limits = GaussSeidelLimits {
        tolerance: 1e-9,
        max_sweeps: 20_000,
        ..Default::default()
    };
    let result = solve_gauss_seidel(&scene, &settings(16), &limits).unwrap();
    assert!(result.converged);
    let exact = 1.0 / (1.0 - m);
    let worst = |values: &[DVec3]| {
        values
            .iter()
            .map(|l| ((*l - DVec3::splat(exact)) / exact).abs().max_element())
            .fold(0.0, f64::max)
    };
    for (what, values) in [
        ("patch radiance", &result.patch_radiance),
        ("patch E/π", &result.patch_irradiance_over_pi),
        ("vertex E/π", &result.vertex_irradiance_over_pi),
    ] {
        let err = worst(values);
        println!("textured furnace m = {m:.4}: worst {what} error {err:.1e}");
        assert!(err < 1e-5, "{what}: {err}");
    }
    let batch = &result.solution.batches[0];
    let texturing = batch.texturing.as_ref().expect("a textured batch");
    let scale = (4.0 * std::f64::consts::PI).sqrt();
    for (k, tv) in texturing.vertices.iter().enumerate() {
        let e = f64::from(tv.irradiance_over_pi[0]);
        assert!((e - exact).abs() < 1e-5 * exact, "vertex {k}: E/π {e}");
        let c00 = f64::from(batch.coefficients[3 * k]);
        assert!((c00 - scale).abs() < 1e-6, "vertex {k}: Le · √(4π) {c00}");
    }
}

#[test]
fn textured_gauss_seidel_agrees_with_the_progressive_solve() {
    // A consistency check between two solvers of one model (`textured.rs`'s
    // E/π representation and ∫ρE reflection, gathered by Gauss–Seidel and
    // shot progressively): the Cornell box with its back wall Kd 1 × the
    // checkerboard (64², squares of 8, codes 255 and 50), mapped once. Both
    // discretise differently (see the untextured test above), so the bound
    // is that test's: per surface and channel, |GS − PR| ≤ |GS₆ − GS₃| +
    // |PR₆ − PR₃| + 0.5%, here on the displayed light ∫ρ E/π dA / A (the
    // progressive side through the RGB weights), for the back wall and the
    // mean over all surfaces.
    let (g3, p3, back) = textured_cornell_means(3);
    let (g6, p6, _) = textured_cornell_means(6);
    let all = g6.len() - 1;
    for k in [back, all] {
        for c in 0..3 {
            let difference = (g6[k][c] - p6[k][c]).abs();
            let bound = (g6[k][c] - g3[k][c]).abs() + (p6[k][c] - p3[k][c]).abs() + 5e-3 * p6[k][c];
            println!(
                "textured surface {k} channel {c}: GS {:.4}, PR {:.4}, |difference| {difference:.4}, bound {bound:.4}",
                g6[k][c], p6[k][c]
            );
            assert!(p6[k][c] > 0.0);
            assert!(
                difference <= bound,
                "surface {k} channel {c}: {difference} > {bound}"
            );
        }
    }
}

/// As [`cornell_surface_means`] with the back wall textured (see the test);
/// also returns the back wall's surface index.
fn textured_cornell_means(patches: u32) -> (Vec<DVec3>, Vec<DVec3>, usize) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/cornell_box.obj");
    let mut scene = crate::scene::load_scene(&path, &Default::default())
        .unwrap()
        .scene;
    scene.fill_default_patches(patches);
    // The back wall: the farthest quad facing −z (the scene is re-centred).
    let back_polygon = (0..scene.polygons.len())
        .filter(|&i| {
            let p = &scene.polygons[i];
            p.normal().z < -0.99 && p.vertices.len() == 4
        })
        .max_by(|&a, &b| {
            scene.polygons[a].vertices[0]
                .z
                .total_cmp(&scene.polygons[b].vertices[0].z)
        })
        .unwrap();
    let mut back = scene.materials[scene.polygons[back_polygon].material].clone();
    back.name = "checker".into();
    back.kd = DVec3::ONE;
    back.diffuse_texture = Some(checkerboard(64, 8));
    scene.materials.push(back);
    scene.polygons[back_polygon].material = scene.materials.len() - 1;
    let mut one = Scene {
        polygons: vec![scene.polygons[back_polygon].clone()],
        ..scene.clone()
    };
    map_once(&mut one, 0.0);
    scene.polygons[back_polygon].uv_map = one.polygons[0].uv_map;
    let mut s = settings(64);
    s.adaptive = false;
    s.samples = 8;
    s.threshold = 2e-3;
    s.max_shots = 100_000;
    s.ambient = false;
    // Gauss–Seidel keeps receivers whole (`mesh::contact` off), so the
    // progressive solve it is compared with patch by patch must too.
    s.whole_receivers = true;
    let limits = GaussSeidelLimits {
        tolerance: 1e-6,
        ..Default::default()
    };
    let gs = solve_gauss_seidel(&scene, &s, &limits).unwrap();
    assert!(gs.converged);
    let mut progressive = Solver::new(&scene, &s).unwrap();
    assert!(progressive.materials.texturing.any());
    while progressive.step().is_some() {}
    let mesh = progressive.mesh();
    let count = mesh.surfaces.len() + 1;
    let back_surface = mesh
        .surfaces
        .iter()
        .position(|s| s.polygon == back_polygon)
        .unwrap();
    let (mut g, mut p, mut area) = (
        vec![DVec3::ZERO; count],
        vec![DVec3::ZERO; count],
        vec![0.0; count],
    );
    for (i, patch) in mesh.patches.iter().enumerate() {
        let k = patch.surface as usize;
        let material = &scene.materials[mesh.surfaces[k].material];
        // Emitters and patches with hidden vertices are left out, as above.
        if material.emission.max_element() > 0.0
            || progressive
                .patch_weights(i as u32)
                .iter()
                .any(|&(v, _)| progressive.hidden_vertices()[v as usize])
        {
            continue;
        }
        // The progressive patch's displayed light: through the RGB weights
        // (∫ ρ E/π) on the textured wall, the area weights elsewhere.
        let radiance = progressive.vertex_radiance();
        let integral: DVec3 = if progressive.patches.rgb_weights[i].is_empty() {
            progressive
                .patch_weights(i as u32)
                .iter()
                .map(|&(v, w)| radiance[v as usize] * w)
                .sum()
        } else {
            progressive.patches.rgb_weights[i]
                .iter()
                .map(|&(v, w)| radiance[v as usize] * w)
                .sum()
        };
        for slot in [k, count - 1] {
            g[slot] += gs.patch_radiance[i] * patch.area;
            p[slot] += integral;
            area[slot] += patch.area;
        }
    }
    let mean = |sums: Vec<DVec3>| -> Vec<DVec3> {
        sums.iter()
            .zip(&area)
            .map(|(s, &a)| if a > 0.0 { *s / a } else { DVec3::ZERO })
            .collect()
    };
    (mean(g), mean(p), back_surface)
}
