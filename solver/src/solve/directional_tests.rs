//! Tests of directional (glossy) shooting: see [`super::directional`].

use super::tests::{material, scene_of};
use super::*;
use crate::settings::Preset;
use solution::format::Representation;
use solution::sh::{coefficient_count, gauss_legendre_on};

fn glossy_floor() -> (Scene, SolverSettings) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/glossy_floor.toml");
    let loaded = crate::scene::load_scene(&path, &Default::default()).unwrap();
    let mut settings = SolverSettings::preset(Preset::Draft);
    settings.apply(&loaded.settings);
    settings.samples = 2;
    let mut scene = loaded.scene;
    scene.fill_default_patches(2);
    (scene, settings)
}

fn run(scene: &Scene, settings: &SolverSettings) -> Solver {
    let mut solver = Solver::new(scene, settings).unwrap();
    while solver.step().is_some() {}
    solver
}

/// ∫ over the upper hemisphere of the radiance the SH `coefficients` (order
/// `order`, RGB interleaved) evaluate to, times cosθ: the exitance, per channel.
/// In μ = cosθ the integrand is a polynomial of degree ≤ order + 1 on [0, 1]
/// and in φ a trigonometric polynomial of degree ≤ order, so Gauss–Legendre
/// with order/2 + 2 nodes and 2·order + 2 uniform azimuths are exact (to
/// rounding): the quadrature adds no error of its own.
pub(super) fn exitance(order: u32, coefficients: &[f64]) -> DVec3 {
    let (mu, w) = gauss_legendre_on(order as usize / 2 + 2, 0.0, 1.0);
    let n_phi = 2 * order as usize + 2;
    let mut basis = vec![0.0; coefficient_count(order)];
    let mut sum = DVec3::ZERO;
    for (&m, &wm) in mu.iter().zip(&w) {
        let s = (1.0 - m * m).max(0.0).sqrt();
        for j in 0..n_phi {
            let phi = 2.0 * PI * j as f64 / n_phi as f64;
            solution::sh::eval_basis(
                order,
                DVec3::new(s * phi.cos(), s * phi.sin(), m),
                &mut basis,
            );
            let mut l = DVec3::ZERO;
            for (c, y) in coefficients.chunks_exact(3).zip(&basis) {
                l += DVec3::from_slice(c) * *y;
            }
            sum += l * m * wm * (2.0 * PI / n_phi as f64);
        }
    }
    sum
}

/// A square of side `side` centred at `centre`, facing `normal` (counter-
/// clockwise seen from the front).
fn square(centre: DVec3, normal: DVec3, side: f64) -> Vec<DVec3> {
    let n = normal.normalize();
    let e1 = n.any_orthonormal_vector();
    let e2 = n.cross(e1);
    let h = 0.5 * side;
    let v = vec![
        centre - e1 * h - e2 * h,
        centre + e1 * h - e2 * h,
        centre + e1 * h + e2 * h,
        centre - e1 * h + e2 * h,
    ];
    assert!((v[1] - v[0]).cross(v[2] - v[0]).dot(n) > 0.0);
    v
}

fn floor(half: f64) -> Vec<DVec3> {
    [
        [-half, 0.0, half],
        [half, 0.0, half],
        [half, 0.0, -half],
        [-half, 0.0, -half],
    ]
    .map(DVec3::from_array)
    .to_vec()
}

fn glossy(name: &str, kd: f64, ks: f64, alpha: f64) -> crate::scene::Material {
    let mut m = material(name, kd, 0.0);
    m.ks = DVec3::splat(ks);
    m.alpha = alpha;
    m
}

fn directional_settings() -> SolverSettings {
    let mut s = SolverSettings::preset(Preset::Draft);
    s.mode = SolveMode::Directional;
    s.adaptive = false;
    s.samples = 4;
    s
}

/// The vertex of `solver` at scene position `p`.
fn vertex_at(solver: &Solver, p: DVec3) -> u32 {
    let local = p - solver.offset();
    solver
        .mesh()
        .vertices
        .iter()
        .position(|v| (v.position - local).length() < 1e-9)
        .unwrap() as u32
}

/// With Ks = 0 everywhere, directional mode gives the diffuse solver's
/// result, on a fixed mesh and with adaptive meshing on: the refinement is
/// the same code (`refine::refine_field`, the diffuse split test on L = 0
/// surfaces, the same replay of emitter shots to new vertices), so the same
/// elements split in the same order and the vertices agree to rounding.
#[test]
fn with_ks_zero_directional_mode_equals_the_diffuse_solver() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/cornell_box.obj");
    let mut scene = crate::scene::load_scene(&path, &Default::default())
        .unwrap()
        .scene;
    scene.fill_default_patches(2);
    for m in &mut scene.materials {
        m.ks = DVec3::ZERO;
    }
    for adaptive in [false, true] {
        let mut diffuse = SolverSettings::preset(Preset::Draft);
        diffuse.samples = 4;
        diffuse.max_shots = 12;
        diffuse.adaptive = adaptive;
        // Directional mode shoots each patch's mean uniformly: the diffuse
        // solve must too for the two to solve the same system.
        diffuse.uniform_shooters = true;
        // And it keeps receivers whole, as directional mode does
        // (`mesh::contact` cuts them in the diffuse mode only).
        diffuse.whole_receivers = true;
        // And every ray: directional mode has no ray share
        // (`solve/ray_share.rs`), so the two sample the same points.
        diffuse.full_rays_above = 0.0;
        // And one patch a shot: directional mode groups its order-0
        // sources differently (emitters' first shots alone, no ray share;
        // `directional/group.rs`), so both shoot patch by patch.
        diffuse.shooters = crate::settings::Shooters::Patch;
        // The diffuse output weights the ambient term by each vertex's
        // enclosure (`solve/enclosure.rs`) and the directional output
        // carries Cohen's term unweighted, so the files are compared
        // without it.
        diffuse.ambient = false;
        let mut directional = diffuse.clone();
        directional.mode = SolveMode::Directional;
        let mut a = Solver::new(&scene, &diffuse).unwrap();
        let mut b = Solver::new(&scene, &directional).unwrap();
        while let Some(ra) = a.step() {
            let rb = b.step().unwrap();
            // The same source each shot (the hemisphere power of an L = 0
            // source is π A c₀₀ Y₀₀, the diffuse power) and the same mesh.
            assert_eq!(ra.source, rb.source);
            assert_eq!(ra.splits, rb.splits);
        }
        assert!(b.step().is_none());
        assert_eq!(a.mesh().split_log, b.mesh().split_log);
        // With adaptive meshing on, the mesh did refine (so the shared
        // refinement and the replay of emitter shots are exercised).
        assert_eq!(a.mesh().split_log.is_empty(), !adaptive);
        // 1e-6 relative: the two differ only in rounding (c₀₀ = L √(4π) and
        // back, per-sample sums of F instead of visible/samples · F), ~1e-15.
        let peak = a
            .vertex_radiance()
            .iter()
            .map(|l| l.max_element())
            .fold(0.0, f64::max);
        for (v, (la, lb)) in a
            .vertex_radiance()
            .iter()
            .zip(b.vertex_radiance())
            .enumerate()
        {
            let (order, sh) = b.vertex_sh(v as u32).unwrap();
            assert_eq!(order, 0);
            let from_sh = DVec3::from_slice(sh) * solution::sh::Y00;
            assert!(
                (*la - from_sh).abs().max_element() <= 1e-6 * peak,
                "{v}: {la} {from_sh}"
            );
            assert!((*la - *lb).abs().max_element() <= 1e-6 * peak);
        }
        let (sa, sb) = (a.to_solution(false), b.to_solution(false));
        assert_eq!(sb.batches.len(), 1);
        // Both outputs show a hidden vertex (`solve/hidden.rs`: the floor
        // under the blocks, the ceiling above the light) with its visible
        // neighbours' radiance (`hidden::fill_hidden`), so every
        // vertex is compared, hidden ones included.
        assert!(a.hidden_vertices().iter().any(|&h| h));
        let peak_coefficient = sa.batches[0]
            .coefficients
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs() as f64));
        for (x, y) in sa.batches[0]
            .coefficients
            .iter()
            .zip(&sb.batches[0].coefficients)
        {
            // Plus an absolute floor: directional mode keeps its state at 40
            // mantissa bits (`checkpoint/precision.rs`) and its recorded-shot
            // part at 53, so where the direct light is all a vertex has, the
            // two no longer cancel exactly and refinement interpolates their
            // difference, at most 2⁻⁴¹ of the radiance per shot: 12 shots ×
            // 2⁻⁴¹ × the peak coefficient.
            let floor = (12.0 * (2.0f64).powi(-41) * peak_coefficient) as f32;
            assert!((x - y).abs() <= 1e-6 * x.abs() + floor, "{x} {y}");
        }
        assert_eq!(sa.batches[0].indices, sb.batches[0].indices);
    }
}

/// One small emitter shines on a glossy floor's centre vertex from incidence
/// μ_i; the exitance of the SH the solver stored there, integrated by exact
/// quadrature, must be (Kd + Ks) · ΔE. The normalization C_R is built from
/// the same truncated, windowed expansion (Funk–Hecke), so truncation and
/// windowing change the lobe's shape, not its energy: what is left is the
/// normalization table's interpolation (1e-6 relative) and rounding; the
/// tolerance 1e-5 allows for both. The lobe's own fit error is printed.
#[test]
fn one_beam_reflects_kd_plus_ks_of_its_irradiance() {
    let (kd, ks) = (0.3, 0.5);
    for alpha in [0.3, 0.1, 0.03] {
        for mu in [1.0, 0.5, 0.1, 0.01] {
            let sin = (1.0f64 - mu * mu).sqrt();
            let dir = DVec3::new(sin, mu, 0.0);
            let distance = 0.5;
            let emitter = square(dir * distance, -dir, 0.004);
            let scene = scene_of(
                vec![(floor(1.0), 0), (emitter, 1)],
                vec![
                    glossy("floor", kd, ks, alpha),
                    material("light", 0.0, 1000.0),
                ],
                2,
            );
            let mut scene = scene;
            scene.polygons[1].patches = 1;
            let mut solver = Solver::new(&scene, &directional_settings()).unwrap();
            let centre = vertex_at(&solver, DVec3::ZERO);
            let light = (0..solver.mesh().patches.len() as u32)
                .find(|&p| solver.mesh().patches[p as usize].surface == 1)
                .unwrap();
            let factor = solver.vertex_form_factors(light)[centre as usize];
            assert!(factor > 0.0);
            let report = solver.step().unwrap();
            assert_eq!(report.source, Some(light));
            let irradiance = 1000.0 * PI * factor;
            let (order, sh) = solver.vertex_sh(centre).unwrap();
            let out = exitance(order, sh);
            let expected = (kd + ks) * irradiance;
            let error = (out.x - expected).abs() / expected;
            let lobe = &solver.directional().unwrap().surface_orders();
            println!(
                "alpha {alpha} mu_i {mu}: L = {order} (orders {lobe:?}), fit error {:.2e}, \
                 exitance {:.6e} expected {:.6e}, relative error {error:.2e}",
                crate::brdf::fit_error(alpha, order),
                out.x,
                expected
            );
            assert!(error < 1e-5, "alpha {alpha} mu {mu}: {error:e}");
            assert_eq!(out.x, out.y);
        }
    }
}

/// A glossy floor under a small bright emitter, seen from an eye that moves:
/// the brightest floor vertex (its SH evaluated toward the eye) follows the
/// emitter's mirror point for that eye. The floor's vertices are 0.125 m apart;
/// the lobe (α = 0.1) and the per-incidence normalization shift the peak a
/// little, so the brightest vertex must lie within one spacing of the mirror
/// point, and move the way it does.
#[test]
fn highlight_tracks_the_mirror_point_as_the_eye_moves() {
    let light_centre = DVec3::new(0.0, 1.0, 0.0);
    let scene = scene_of(
        vec![(floor(1.0), 0), (square(light_centre, -DVec3::Y, 0.05), 1)],
        vec![
            glossy("floor", 0.05, 0.9, 0.1),
            material("light", 0.0, 100.0),
        ],
        16,
    );
    let mut settings = directional_settings();
    settings.max_shots = 1;
    let solver = run(&scene, &settings);
    let floor_vertices: Vec<u32> = (0..solver.mesh().vertices.len() as u32)
        .filter(|&v| solver.mesh().vertices[v as usize].surface == 0)
        .collect();
    let mut previous: Option<f64> = None;
    for eye_x in [-0.8, -0.3, 0.2, 0.7] {
        let eye = DVec3::new(eye_x, 1.0, 0.6);
        // Mirror the light in the floor (y → −y) and intersect eye→image with y = 0.
        let image = DVec3::new(light_centre.x, -light_centre.y, light_centre.z);
        let t = eye.y / (eye.y - image.y);
        let mirror_point = eye + (image - eye) * t;
        let mut best = (0u32, f64::NEG_INFINITY);
        for &v in &floor_vertices {
            let p = solver.mesh().vertices[v as usize].position + solver.offset();
            let s = &solver.mesh().surfaces[0];
            let dir = solution::sh::to_local((eye - p).normalize(), s.normal, s.tangent);
            let (order, sh) = solver.vertex_sh(v).unwrap();
            let f32s: Vec<f32> = sh.iter().map(|&c| c as f32).collect();
            let l = solution::sh::eval_rgb(order, &f32s, dir)[0];
            if l > best.1 {
                best = (v, l);
            }
        }
        let p = solver.mesh().vertices[best.0 as usize].position + solver.offset();
        let miss = (p - mirror_point).length();
        println!(
            "eye x {eye_x}: mirror point {mirror_point:?}, brightest vertex {p:?}, miss {miss:.3}"
        );
        assert!(miss <= 0.125, "eye x {eye_x}: {miss}");
        if let Some(x) = previous {
            assert!(p.x > x, "the highlight moves with the eye");
        }
        previous = Some(p.x);
    }
}

#[test]
fn glossy_floor_solves_to_batches_of_order_zero_and_above() {
    let (scene, mut settings) = glossy_floor();
    assert_eq!(settings.mode, SolveMode::Directional);
    settings.max_shots = 3;
    let solver = run(&scene, &settings);
    assert!(solver.warnings().is_empty(), "{:?}", solver.warnings());
    let solution = solver.to_solution(false);
    assert_eq!(solution.header.mode, SolveMode::Directional);
    let orders: Vec<u32> = solution
        .batches
        .iter()
        .map(|b| match b.representation {
            Representation::Sh { order } => order,
            _ => panic!("not SH"),
        })
        .collect();
    assert_eq!(orders[0], 0);
    assert!(orders.len() >= 2 && orders[1] > 0, "{orders:?}");
    let mut total = 0;
    for (b, &order) in solution.batches.iter().zip(&orders) {
        assert_eq!(
            b.coefficients.len(),
            b.vertices.len() * coefficient_count(order) * 3
        );
        assert!(!b.indices.is_empty());
        assert!(b.indices.iter().all(|&i| (i as usize) < b.vertices.len()));
        assert!(b.coefficients.iter().all(|c| c.is_finite()));
        total += b.vertices.len();
    }
    assert_eq!(total, solver.mesh().vertices.len());
}

#[test]
fn diffuse_solve_of_a_glossy_scene_warns_once_per_glossy_material_naming_the_fold_and_the_flag() {
    let (scene, mut settings) = glossy_floor();
    settings.mode = SolveMode::Diffuse;
    let glossy = scene.materials.iter().filter(|m| m.is_glossy()).count();
    assert_eq!(glossy, 1, "the config's one glossy material");
    let solver = Solver::new(&scene, &settings).unwrap();
    assert_eq!(solver.warnings().len(), 1, "{:?}", solver.warnings());
    let w = &solver.warnings()[0];
    assert!(
        w.contains("`glossy_floor`")
            && w.contains("folded into its diffuse reflectance")
            && w.contains("--mode directional"),
        "{w}"
    );
    assert!(!w.contains("`white`"), "{w}");
    // Two dielectrics (glTF's Ks = 0.04) beside it: one line counts them.
    let mut scene = scene;
    for m in scene.materials.iter_mut().filter(|m| !m.is_glossy()) {
        m.ks = DVec3::splat(super::directional::DIELECTRIC_KS);
    }
    let faint = scene
        .materials
        .iter()
        .filter(|m| m.ks.max_element() == 0.04)
        .count();
    let solver = Solver::new(&scene, &settings).unwrap();
    let warnings = solver.warnings();
    assert_eq!(warnings.len(), 2, "{warnings:?}");
    assert!(
        warnings[1].contains(&format!("{faint} material(s)")),
        "{warnings:?}"
    );
}

#[test]
fn capped_order_warns_with_the_error_left() {
    let scene = scene_of(
        vec![(floor(1.0), 0), (square(DVec3::Y, -DVec3::Y, 0.2), 1)],
        vec![glossy("sharp", 0.1, 0.5, 0.05), material("light", 0.0, 1.0)],
        1,
    );
    let mut settings = directional_settings();
    settings.max_sh_order = 8;
    let solver = Solver::new(&scene, &settings).unwrap();
    assert_eq!(solver.directional().unwrap().surface_orders(), &[8, 0]);
    let w = &solver.warnings()[0];
    assert!(w.contains("`sharp`") && w.contains("L = 8"), "{w}");
}

fn sh_bits(solver: &Solver) -> Vec<u64> {
    (0..solver.mesh().vertices.len() as u32)
        .flat_map(|v| solver.vertex_sh(v).unwrap().1.to_vec())
        .map(f64::to_bits)
        .collect()
}

#[test]
fn resumed_directional_solve_equals_an_uninterrupted_one() {
    let (scene, mut settings) = glossy_floor();
    // A finer glossy floor than draft's, so that shots after the light's
    // split the glossy floor too (the sixth does), gathering shot sums.
    settings.max_shots = 8;
    settings.glossy_edge = 0.125;
    settings.adaptive = true;
    let whole = run(&scene, &settings);
    assert!(
        whole.progress().elements > whole.mesh().patches.len(),
        "should refine"
    );

    let mut first = Solver::new(&scene, &settings).unwrap();
    for _ in 0..3 {
        first.step().unwrap();
    }
    // The state keeps 40 mantissa bits (`checkpoint/precision.rs`): the
    // dropped ones are zero in every radiance and unshot coefficient, so the
    // checkpoint stores no noise there.
    let sections = first.directional().unwrap().checkpoint_sections();
    let low = (1u64 << crate::solve::checkpoint::precision::DROPPED_BITS) - 1;
    assert!(sections.radiance.iter().all(|x| x.to_bits() & low == 0));
    assert!(sections.patch_unshot.iter().all(|x| x.to_bits() & low == 0));
    // The patches' shot sums, which later splits gather (`near_gather.rs`),
    // are part of the state.
    assert!(
        sections.shot_sum.iter().any(|&x| x != 0.0),
        "the test should checkpoint after an unrecorded shot"
    );
    let state = Checkpoint::round_trip(&first);
    assert!(state.directional.is_some());
    let mut resumed = Solver::resume(&scene, &settings, state.clone()).unwrap();
    // The recorded shots' part, which the checkpoint does not store, is
    // recomputed bit for bit (for vertices shot directly and by replay).
    assert!(
        first
            .record
            .shots
            .iter()
            .any(|r| (r.receivers as usize) < first.mesh().vertices.len()),
        "the test should create vertices after a recorded shot"
    );
    assert_eq!(
        resumed.directional_direct_bits(),
        first.directional_direct_bits()
    );
    drop(first);
    let splits_at_checkpoint = resumed.mesh().split_log.len();
    let vertices_at_checkpoint = resumed.mesh().vertices.len();
    while resumed.step().is_some() {}
    assert!(
        resumed.mesh().split_log.len() > splits_at_checkpoint,
        "the resumed part should split (and so read the recomputed part)"
    );
    let glossy = |v: &crate::mesh::MeshVertex| {
        resumed.directional().unwrap().surface_orders()[v.surface as usize] > 0
    };
    assert!(
        resumed.mesh().vertices[vertices_at_checkpoint..]
            .iter()
            .any(glossy),
        "the resumed part should split the glossy floor (and so gather shot sums)"
    );
    assert_eq!(resumed.mesh().split_log, whole.mesh().split_log);
    assert_eq!(sh_bits(&resumed), sh_bits(&whole));
    assert_eq!(resumed.progress(), whole.progress());
    let (mut a, mut b) = (resumed.to_solution(false), whole.to_solution(false));
    a.header.stats.seconds = 0.0;
    b.header.stats.seconds = 0.0;
    assert_eq!(a, b);

    // A directional checkpoint is refused by a diffuse solve, and vice versa.
    let mut diffuse = settings.clone();
    diffuse.mode = SolveMode::Diffuse;
    let err = Solver::resume(&scene, &diffuse, state.clone())
        .err()
        .unwrap();
    assert!(err.to_string().contains("directional"), "{err}");
}

/// Bytes written to a sink that keeps only their count.
struct Counting(u64);

impl std::io::Write for Counting {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0 += buf.len() as u64;
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn directional_checkpoint_is_at_most_twice_the_solution_plus_the_patches() {
    // The bound's reason: each vertex SH coefficient is stored once in each
    // file, as an f64 in the checkpoint (exact resume needs its bits) and as an
    // f32 in the solution, so those are at most 2× (the checkpoint packs them
    // losslessly, byte planes and deflate, which only shrinks them; a chunk
    // that does not compress is stored with 5 bytes per 64 kB of framing, and
    // its length, 4 bytes a MiB). What else the checkpoint stores per vertex
    // (~1 B of split log; the diffuse proxies and the recorded-shot part are
    // recomputed on resume) is less than twice what the solution adds per
    // vertex (36 B of position, normal, tangent; 12 B per triangle). The
    // parts without a counterpart in the solution are each patch's unshot SH
    // and the SH it has shot (`near_gather.rs`), at most 8 B each per patch
    // coefficient: so checkpoint ≤ 2 × solution + 16 × patch coefficients +
    // the header sections and framing (< 1 kB here).
    // Packed, this scene is well below 2× (docs/benchmarks.md, "Checkpoints
    // at scale", has the glossy Cornell box too).
    let (scene, mut settings) = glossy_floor();
    settings.max_shots = 6;
    settings.adaptive = true;
    let solver = run(&scene, &settings);
    assert!(
        solver.progress().vertices > 4 * solver.mesh().patches.len(),
        "the test should refine"
    );
    let mut checkpoint = Counting(0);
    solver.write_checkpoint(&mut checkpoint).unwrap();
    let patch_coefficients = Checkpoint::round_trip(&solver)
        .directional
        .unwrap()
        .patch_unshot
        .len() as u64;
    let solution = solution::format::encode(&solver.to_solution(false))
        .unwrap()
        .len() as u64;
    let ratio = checkpoint.0 as f64 / solution as f64;
    eprintln!(
        "glossy floor: checkpoint {} B, solution {solution} B, ratio {ratio:.3}, patch \
         coefficients {patch_coefficients}",
        checkpoint.0
    );
    assert!(
        checkpoint.0 <= 2 * solution + 16 * patch_coefficients + 1024,
        "checkpoint {} B > 2 × solution {solution} B + 16 × {patch_coefficients} + 1 kB",
        checkpoint.0
    );
    // This scene's patch coefficients are few enough: below 2× overall.
    assert!(
        ratio <= 2.0,
        "checkpoint {} B > 2 × solution {solution} B",
        checkpoint.0
    );
}

/// Source choice by hemispherical unshot power (design notes) against Remington's (1992)
/// [0,0] term alone: prints the shots each needs to reach the threshold, and
/// checks both converge to the same floor radiance (within the threshold's
/// share of the emitted power, as either stops with that much unshot).
#[test]
fn source_choice_hemisphere_against_zeroth_term() {
    let (scene, mut settings) = glossy_floor();
    settings.threshold = 0.05;
    settings.max_shots = 400;
    let mut shots = Vec::new();
    let mut solvers = Vec::new();
    for choice in [SourceChoice::Hemisphere, SourceChoice::ZerothTerm] {
        let mut solver = Solver::new(&scene, &settings).unwrap();
        solver.set_source_choice(choice);
        while solver.step().is_some() {}
        let p = solver.progress();
        println!(
            "{choice:?}: {} shots to unshot fraction {:.4} (threshold {})",
            p.shots, p.unshot_fraction, settings.threshold
        );
        assert!(p.unshot_fraction < settings.threshold);
        shots.push(p.shots);
        solvers.push(solver);
    }
    // Mean radiance of the scene (L = c₀₀ Y₀₀), area-weighted by the gather
    // weights (each vertex's share of each patch's area), so that the two
    // solves' different adaptive meshes compare.
    let mean = |s: &Solver| {
        let (mut sum, mut area) = (0.0, 0.0);
        for p in 0..s.mesh().patches.len() as u32 {
            for &(v, w) in s.patch_weights(p) {
                sum += s.vertex_radiance()[v as usize].x * w;
                area += w;
            }
        }
        sum / area
    };
    let (a, b) = (mean(&solvers[0]), mean(&solvers[1]));
    assert!(
        (a - b).abs() <= 2.0 * settings.threshold * a.max(b),
        "{a} {b}"
    );
}

/// The six inward-facing unit squares of the cube [0, 1]³, material 0.
fn inward_cube() -> Vec<(Vec<DVec3>, usize)> {
    let centre = DVec3::splat(0.5);
    [DVec3::X, DVec3::Y, DVec3::Z]
        .into_iter()
        .flat_map(|axis| [(axis, 0.0), (axis, 1.0)])
        .map(|(axis, side)| {
            // Inward normal: +axis on the face at 0, −axis on the face at 1.
            let normal = if side == 0.0 { axis } else { -axis };
            (square(centre + axis * (side - 0.5), normal, 1.0), 0)
        })
        .collect()
}

/// Radiance of every vertex toward `directions` (local, z = normal), relative
/// to `exact`: (min, max, RMS deviation from 1), and the vertices' exitance
/// (∫ L cosθ dω, exact quadrature of the stored SH) relative to π · exact.
fn furnace_spread(solver: &Solver, exact: f64) -> (f64, f64, f64, f64, f64) {
    let (mu, _) = gauss_legendre_on(8, 0.0, 1.0);
    let (mut lo, mut hi, mut sq, mut n) = (f64::INFINITY, 0.0f64, 0.0, 0.0);
    let (mut m_lo, mut m_hi) = (f64::INFINITY, 0.0f64);
    for v in 0..solver.mesh().vertices.len() as u32 {
        let (order, c) = solver.vertex_sh(v).unwrap();
        let mut basis = vec![0.0; coefficient_count(order)];
        for &m in &mu {
            let s = (1.0 - m * m).sqrt();
            for j in 0..8 {
                let phi = 2.0 * PI * j as f64 / 8.0;
                solution::sh::eval_basis(
                    order,
                    DVec3::new(s * phi.cos(), s * phi.sin(), m),
                    &mut basis,
                );
                let l: f64 = c.chunks_exact(3).zip(&basis).map(|(c, y)| c[0] * y).sum();
                let r = l / exact;
                lo = lo.min(r);
                hi = hi.max(r);
                sq += (r - 1.0) * (r - 1.0);
                n += 1.0;
            }
        }
        let m = exitance(order, c).x / (PI * exact);
        m_lo = m_lo.min(m);
        m_hi = m_hi.max(m);
    }
    (lo, hi, (sq / n).sqrt(), m_lo, m_hi)
}

/// A glossy furnace: a closed cube whose faces all have Kd = 0, Ks = 0.5,
/// α = 0.3 and emit Le = 1. A reciprocal BRDF whose albedo were Ks for every
/// direction would give Le / (1 − Ks) = L∞ = 2 everywhere; the figures printed
/// are the thesis normalization's deviation from it (recorded in
/// docs/lab/brdf-normalization.md). Measured (3 × 3 patches per face, 16 rays, threshold
/// 1%), with the samples of a glossy receiver spread by solid angle
/// (`geometry/solid_angle.rs`): L/L∞ spans 0.60..1.15 over vertices ×
/// directions (RMS deviation 0.17, mean exitance 0.980 of π L∞). The removed
/// reciprocal variant measured 0.54..0.92 (RMS 0.32, mean exitance 0.75: its
/// albedo falls toward grazing), a less uniform furnace.
///
/// Asserted, each with its reason:
/// * the diffuse control (Kd = 0.5, Ks = 0) is uniform to the unshot light:
///   error ≈ ρ × unshot fraction ≤ 0.5%, so 0.97..1.02;
/// * the thesis's C_R reflects exactly Ks of every beam, so the room's power
///   balances and the mean exitance is π L∞ less the unshot light (1%) and
///   the glossy transport's discretization loss (measured 1%: lobes aimed at
///   grazing directions land near edges, where few vertices sample them; it
///   was 6.8% with equal shares of area samples, which sent a corner
///   vertex's light from the far faces), so 0.95..1.01.
#[test]
fn glossy_furnace_uniformity_by_normalization() {
    let mut settings = directional_settings();
    settings.samples = 16;
    settings.threshold = 0.01;
    settings.max_shots = 100_000;
    settings.ambient = false;
    let exact = 2.0;
    for (label, ks, kd) in [("diffuse control", 0.0, 0.5), ("thesis", 0.5, 0.0)] {
        let scene = scene_of(inward_cube(), vec![glossy("furnace", kd, ks, 0.3)], 3);
        let mut scene = scene;
        scene.materials[0].emission = DVec3::ONE;
        let solver = run(&scene, &settings);
        let (lo, hi, rms, m_lo, m_hi) = furnace_spread(&solver, exact);
        let mean_exitance = {
            let mut sum = 0.0;
            for v in 0..solver.mesh().vertices.len() as u32 {
                let (order, c) = solver.vertex_sh(v).unwrap();
                sum += exitance(order, c).x / (PI * exact);
            }
            sum / solver.mesh().vertices.len() as f64
        };
        println!(
            "glossy furnace {label}: L/L∞ over vertices × directions {lo:.3}..{hi:.3} (RMS dev \
             {rms:.3}), exitance/(π L∞) {m_lo:.3}..{m_hi:.3}, mean {mean_exitance:.4} ({} shots)",
            solver.progress().shots
        );
        match label {
            "diffuse control" => assert!(lo > 0.97 && hi < 1.02, "{lo} {hi}"),
            _ => assert!((0.95..1.01).contains(&mean_exitance), "{mean_exitance}"),
        }
    }
}

/// Glossy refinement stops at the α floor: on the glossy floor (α = 0.1),
/// with the area and depth limits below it, the floor refines (the
/// highlight) but no floor leaf has a longest edge shorter than
/// `min_glossy_edge` (α · D / 2, D half the diagonal of the scene's bounds).
#[test]
fn glossy_elements_stop_at_the_alpha_floor() {
    let (scene, mut settings) = glossy_floor();
    settings.max_shots = 4;
    settings.adaptive = true;
    // Depth 5 would allow floor edges of 1.5 m / 2⁵ = 0.047 m, a third of the
    // floor's h_min (0.14 m), so the α floor is what stops the floor.
    settings.max_depth = 5;
    // A size floor far below the α floor (a millimetre or so), so the α
    // floor decides.
    settings.min_element_size = 1e-3;
    settings.edge_threshold = 0.05;
    let solver = run(&scene, &settings);
    let mesh = solver.mesh();
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for v in &mesh.vertices {
        lo = lo.min(v.position);
        hi = hi.max(v.position);
    }
    let h_min = super::directional::min_glossy_edge(0.1, 0.5 * (hi - lo).length(), 0.5);
    let orders = solver.directional().unwrap().surface_orders();
    let mut glossy_splits = 0;
    // The floor is measured on each leaf's longest edge (a sliver refines
    // until its long side is short): the shortest of those.
    let mut shortest_glossy = f64::INFINITY;
    for el in &mesh.elements {
        let surface = mesh.patches[el.patch as usize].surface as usize;
        if orders[surface] == 0 {
            continue;
        }
        if !el.is_leaf() {
            glossy_splits += 1;
            continue;
        }
        let c = el.corners();
        let longest = (0..c.len())
            .map(|k| {
                let (a, b) = (c[k] as usize, c[(k + 1) % c.len()] as usize);
                (mesh.vertices[a].position - mesh.vertices[b].position).length()
            })
            .fold(0.0, f64::max);
        shortest_glossy = shortest_glossy.min(longest);
    }
    println!(
        "α floor {h_min:.3}: {glossy_splits} glossy splits, shortest longest glossy edge \
         {shortest_glossy:.3}"
    );
    assert!(glossy_splits > 0);
    // 1e-9: the edge lengths are differences of f64 positions.
    assert!(
        shortest_glossy >= h_min * (1.0 - 1e-9),
        "{shortest_glossy} < {h_min}"
    );
}

/// A glossy floor (x, z in [0, 2], y = 0) with a black box over [0.7, 1.3]²
/// of height 0.3 standing on it (no bottom face: the floor runs under it) and
/// a black 0.8 × 0.8 light (Le 400) facing down at y = 20 over x in
/// [−0.5, 0.3], z in [0.6, 1.4]: `hidden_tests.rs`'s contact scene with a
/// glossy floor. Every polygon is cut into 5 × 5 patches, so the floor
/// elements [0.4, 0.8] × … straddle the box's face at x = 0.7.
fn glossy_box_on_floor(kd: f64, ks: f64, alpha: f64, le: f64) -> Scene {
    glossy_box_on_floor_under(kd, ks, alpha, le, contact_light())
}

/// [`glossy_box_on_floor`] lit by `light` (a black emitter of Le `le`).
fn glossy_box_on_floor_under(kd: f64, ks: f64, alpha: f64, le: f64, light: Vec<DVec3>) -> Scene {
    let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let (a, b, h) = (0.7, 1.3, 0.3);
    let floor = vec![p(0., 0., 0.), p(0., 0., 2.), p(2., 0., 2.), p(2., 0., 0.)];
    let top = vec![p(a, h, a), p(a, h, b), p(b, h, b), p(b, h, a)];
    let front = vec![p(a, 0., a), p(a, h, a), p(b, h, a), p(b, 0., a)];
    let back = vec![p(a, 0., b), p(b, 0., b), p(b, h, b), p(a, h, b)];
    let left = vec![p(a, 0., a), p(a, 0., b), p(a, h, b), p(a, h, a)];
    let right = vec![p(b, 0., a), p(b, h, a), p(b, h, b), p(b, 0., b)];
    scene_of(
        vec![
            (floor, 0),
            (top, 1),
            (front, 1),
            (back, 1),
            (left, 1),
            (right, 1),
            (light, 2),
        ],
        vec![
            glossy("floor", kd, ks, alpha),
            material("black", 0.0, 0.0),
            material("light", 0.0, le),
        ],
        5,
    )
}

fn contact_light() -> Vec<DVec3> {
    let p = |x: f64, z: f64| DVec3::new(x, 20.0, z);
    // Counter-clockwise seen from below: the normal points down.
    vec![p(-0.5, 0.6), p(0.3, 0.6), p(0.3, 1.4), p(-0.5, 1.4)]
}

/// The solution's first batch above SH order 0 (the glossy floor's) and its
/// order.
fn glossy_batch(solution: &solution::format::Solution) -> (&solution::format::Batch, u32) {
    let batch = solution
        .batches
        .iter()
        .find(|b| !matches!(b.representation, Representation::Sh { order: 0 }))
        .expect("a glossy batch");
    let Representation::Sh { order } = batch.representation else {
        unreachable!()
    };
    (batch, order)
}

/// The floor's displayed SH at scene point (x, 0, z): the coefficients of
/// the glossy batch's triangle holding it, interpolated barycentrically, as
/// the runtime interpolates before evaluating toward the eye. Returns the
/// order and the coefficients.
fn displayed_floor_sh(
    solution: &solution::format::Solution,
    offset: DVec3,
    x: f64,
    z: f64,
) -> (u32, Vec<f64>) {
    let (batch, order) = glossy_batch(solution);
    let n = 3 * coefficient_count(order);
    let position =
        |i: u32| glam::Vec3::from_array(batch.vertices[i as usize].position).as_dvec3() + offset;
    for t in batch.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(position);
        if [a, b, c].iter().any(|v| v.y.abs() > 1e-6) {
            continue;
        }
        let det = (b.x - a.x) * (c.z - a.z) - (c.x - a.x) * (b.z - a.z);
        let u = ((x - a.x) * (c.z - a.z) - (c.x - a.x) * (z - a.z)) / det;
        let v = ((b.x - a.x) * (z - a.z) - (x - a.x) * (b.z - a.z)) / det;
        if u >= -1e-9 && v >= -1e-9 && u + v <= 1.0 + 1e-9 {
            let weights = [1.0 - u - v, u, v];
            let mut out = vec![0.0; n];
            for (&i, w) in t.iter().zip(weights) {
                let block = &batch.coefficients[n * i as usize..n * (i as usize + 1)];
                for (o, &c) in out.iter_mut().zip(block) {
                    *o += w * c as f64;
                }
            }
            return (order, out);
        }
    }
    panic!("no glossy floor triangle holds ({x}, {z})");
}

/// The directional output treats hidden vertices as hidden: a glossy floor
/// next to a block's base shows its own light, not a blend toward the dark
/// floor under the block. The truth at a floor point is exact: only the
/// light reaches it (the box and the light are black, a plane cannot light
/// itself), unoccluded for x < 0.7, with irradiance E = π Le F (F the exact
/// point-to-polygon factor), and the SH holds Kd E/π plus Ks × a lobe whose
/// exitance is Ks E (the normalization C_R; `one_beam_reflects_kd_plus_ks`
/// checks it to 1e-5), so the displayed exitance is (Kd + Ks) E, by exact
/// quadrature of the interpolated SH ([`exitance`]).
#[test]
fn glossy_floor_next_to_a_contact_line_shows_its_own_exitance() {
    use crate::geometry::formfactor::SourcePolygon;
    let (kd, ks, alpha, le) = (0.3, 0.5, 0.3, 400.0);
    let scene = glossy_box_on_floor(kd, ks, alpha, le);
    let mut settings = directional_settings();
    settings.samples = 16;
    settings.ambient = false;
    settings.threshold = 1e-4;
    // Whole receivers, so that floor elements straddle the box's base and
    // their hidden corners are filled (conformed to the base, none would be
    // hidden: `conformed_glossy_floor_on_the_contact_line_receives_exactly`).
    settings.whole_receivers = true;
    let solver = run(&scene, &settings);
    let solution = solver.to_solution(false);
    let offset = solver.offset();
    let light = SourcePolygon::new(&contact_light());
    let exact =
        |x: f64, z: f64| (kd + ks) * PI * le * light.form_factor(DVec3::new(x, 0.0, z), DVec3::Y);
    // Points 1 to 10 cm on the visible side of the box's face at x = 0.7, in
    // the floor elements [0.4, 0.8] × [0.8, 1.2] whose corners at x = 0.8 are
    // hidden. Tolerance 3%, as in `hidden_tests.rs`'s diffuse test: a hidden
    // corner shows its visible neighbours' mean, so what is left is the exact
    // field's spread over the vertices within one element of the box (under
    // 2%, checked there for the same light and floor) and the SH stored in
    // f32 (measured: at most 0.13%). Without the fill the hidden corners are
    // black and these points show 28–50% of their exitance (measured: errors
    // of 50–72%).
    let mut worst: f64 = 0.0;
    for x in [0.6, 0.65, 0.69] {
        for z in [0.85, 1.0, 1.15] {
            let (order, sh) = displayed_floor_sh(&solution, offset, x, z);
            let shown = exitance(order, &sh).x;
            let truth = exact(x, z);
            let error = (shown - truth).abs() / truth;
            println!(
                "floor ({x}, {z}) L={order}: shown {shown:.4}, exact {truth:.4}, error {error:.4}"
            );
            worst = worst.max(error);
        }
    }
    assert!(
        worst < 0.03,
        "worst relative error {worst:.4} beside the contact line"
    );
}

/// Shadow lines (`mesh::contact::cut_shadow_lines`, directional mode) at
/// the box's corner (0.7, 0.7) under a light over x in [−0.5, 0.3], z in
/// [0.8, 1.6], 20 above the floor. Seen from the corner (angles in the floor
/// plane from +x toward +z) the light spans 114°–175° and the box 0°–90°, so
/// near the corner, where the box is a vertical wedge, a floor point sees all
/// of the light between 90° and 294° and none of it between 355° and 360°
/// (the umbra, a thin wedge in front of the box's face z = 0.7), with the
/// penumbra between. The corner is an apex: every part meeting there keeps
/// its own output vertex, received a step inside the part. The truth there
/// is exact: the light and the box are black and a plane cannot light
/// itself, so a floor point gets only the light's direct light, and a lit
/// part's vertex shows the exitance (Kd + Ks) π Le F(corner) (F the exact
/// point-to-polygon factor; see
/// [`glossy_floor_next_to_a_contact_line_shows_its_own_exitance`]), the
/// umbra's none. Merged into one vertex, as the seam pass did before, the
/// corner shows one mean of the parts, which is neither.
#[test]
fn each_part_at_a_shadow_apex_keeps_its_own_radiance() {
    use crate::geometry::formfactor::SourcePolygon;
    let (kd, ks, alpha, le) = (0.3, 0.5, 0.3, 400.0);
    let p = |x: f64, z: f64| DVec3::new(x, 20.0, z);
    // Counter-clockwise seen from below: the normal points down.
    let light = vec![p(-0.5, 0.8), p(0.3, 0.8), p(0.3, 1.6), p(-0.5, 1.6)];
    let scene = glossy_box_on_floor_under(kd, ks, alpha, le, light.clone());
    let mut settings = directional_settings();
    settings.samples = 16;
    settings.ambient = false;
    settings.threshold = 1e-4;
    let solver = run(&scene, &settings);
    let solution = solver.to_solution(false);
    let corner = DVec3::new(0.7, 0.0, 0.7);
    let lit = (kd + ks) * PI * le * SourcePolygon::new(&light).form_factor(corner, DVec3::Y);
    let (batch, order) = glossy_batch(&solution);
    let n = 3 * coefficient_count(order);
    let position = |i: u32| {
        glam::Vec3::from_array(batch.vertices[i as usize].position).as_dvec3() + solver.offset()
    };
    // The visible floor's vertices at the corner (1e-6: positions are
    // stored in f32): those of triangles outside the box's base (the covered
    // piece has its own, hidden ones).
    let mut at_corner = std::collections::BTreeSet::new();
    for t in batch.indices.chunks_exact(3) {
        let centre = (position(t[0]) + position(t[1]) + position(t[2])) / 3.0;
        let under = (0.7..1.3).contains(&centre.x) && (0.7..1.3).contains(&centre.z);
        if centre.y.abs() < 1e-6 && !under {
            at_corner.extend(
                t.iter()
                    .copied()
                    .filter(|&i| (position(i) - corner).length() < 1e-6),
            );
        }
    }
    let shown: Vec<f64> = at_corner
        .into_iter()
        .map(|i| i as usize)
        .map(|i| {
            let block: Vec<f64> = batch.coefficients[n * i..n * (i + 1)]
                .iter()
                .map(|&c| c as f64)
                .collect();
            exitance(order, &block).x
        })
        .collect();
    println!("exitance at the apex: {shown:.4?}, fully lit {lit:.4}");
    // The umbra part, the penumbra's parts and the lit ones: three at least.
    assert!(shown.len() >= 3, "{} vertices at the apex", shown.len());
    let (lo, hi) = shown.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &e| {
        (lo.min(e), hi.max(e))
    });
    // The umbra's vertex: exactly dark (every ray is blocked, nothing else
    // reaches it); 1e-3 of the lit value allows only rounding.
    assert!(
        lo < 1e-3 * lit,
        "darkest vertex at the apex {lo:.5}, lit {lit:.5}"
    );
    // A lit part's vertex: 1%, as `conformed_glossy_floor_on_the_contact_line_receives_exactly`
    // (a receiving step under 1e-3 of its element, every ray reaches the
    // light, f32 SH).
    assert!(
        (hi - lit).abs() < 0.01 * lit,
        "brightest vertex at the apex {hi:.5}, exact {lit:.5}"
    );
}

/// A 0.4 × 0.4 light facing down 0.2 above the floor beside the box, over x
/// in [0.2, 0.6], z in [0.8, 1.2] (`hidden_tests.rs`'s near light): the
/// floor's irradiance at z = 1 falls by a factor of 3.4 from x = 0.4 to the
/// box's face at x = 0.7, so a value extended over an element's width is far
/// off there.
fn near_light() -> Vec<DVec3> {
    let p = |x: f64, z: f64| DVec3::new(x, 0.2, z);
    vec![p(0.2, 0.8), p(0.6, 0.8), p(0.6, 1.2), p(0.2, 1.2)]
}

/// Directional mode cuts receivers along contact lines (`mesh::contact`) as
/// the diffuse mode does: the glossy floor's vertices on the box's base, on
/// the visible side, receive where they are, and the displayed SH there has
/// the exact exitance (Kd + Ks) π Le F (F the exact point-to-polygon factor;
/// the box and the light are black, so only the light reaches the floor, and
/// the lobe's normalization reflects exactly Ks of each beam, see
/// [`glossy_floor_next_to_a_contact_line_shows_its_own_exitance`]).
#[test]
fn conformed_glossy_floor_on_the_contact_line_receives_exactly() {
    use crate::geometry::formfactor::SourcePolygon;
    let (kd, ks, alpha, le) = (0.3, 0.5, 0.3, 6.0);
    let scene = glossy_box_on_floor_under(kd, ks, alpha, le, near_light());
    let light = SourcePolygon::new(&near_light());
    let exact =
        |x: f64, z: f64| (kd + ks) * PI * le * light.form_factor(DVec3::new(x, 0.0, z), DVec3::Y);
    let worst = |whole: bool| {
        let mut settings = directional_settings();
        settings.samples = 16;
        settings.ambient = false;
        settings.threshold = 1e-4;
        settings.whole_receivers = whole;
        let solver = run(&scene, &settings);
        let solution = solver.to_solution(false);
        let mut worst: f64 = 0.0;
        for z in [0.8, 1.2] {
            let x = 0.7 - 1e-7;
            let (order, sh) = displayed_floor_sh(&solution, solver.offset(), x, z);
            let shown = exitance(order, &sh).x;
            let truth = exact(x, z);
            let error = (shown - truth).abs() / truth;
            println!("whole {whole}: floor ({x}, {z}) L={order}: shown {shown:.5}, exact {truth:.5}, error {error:.4}");
            worst = worst.max(error);
        }
        worst
    };
    // 1%, as the diffuse test (`hidden_tests.rs`): the vertex receives at a
    // point stepped 1e-3 of the way toward its element's centre (under 0.3
    // mm, where F changes by under 0.1%), all 16 visibility rays reach the
    // light, and the SH is stored in f32.
    let conformed = worst(false);
    assert!(conformed < 0.01, "conformed: worst error {conformed:.4}");
    // Whole, the element [0.4, 0.8] straddles the line and its corners at x
    // = 0.8 show their visible neighbours' mean, 0.4 away: far off.
    let whole = worst(true);
    assert!(whole > 0.3, "whole floor: worst error {whole:.4}");
}

/// The glossy floor's cut pieces share their seams in the SH output
/// (`seams.rs`, `Merge::WithinPolygons`): after adaptive subdivision every edge of the
/// displayed floor is shared by two triangles (one output vertex per
/// position, no T-junction across the cuts), except on the floor's outline,
/// round the box's base, where the covered piece meets the visible ones, and
/// at the shadow apexes, where neighbouring edges meet in position only.
#[test]
fn conformed_glossy_floor_seams_are_crack_free() {
    let scene = glossy_box_on_floor_under(0.3, 0.5, 0.3, 6.0, near_light());
    let mut settings = directional_settings();
    settings.adaptive = true;
    settings.ambient = false;
    let mut solver = Solver::new(&scene, &settings).unwrap();
    for _ in 0..40 {
        if solver.step().is_none() {
            break;
        }
    }
    let solution = solver.to_solution(false);
    let offset = solver.offset();
    let batch = solution
        .batches
        .iter()
        .find(|b| !matches!(b.representation, Representation::Sh { order: 0 }))
        .expect("the glossy floor's batch");
    let position =
        |i: u32| glam::Vec3::from_array(batch.vertices[i as usize].position).as_dvec3() + offset;
    let mut edges = std::collections::HashMap::new();
    for t in batch.indices.chunks_exact(3) {
        for k in 0..3 {
            *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0u32) += 1;
        }
    }
    let triangles = batch.indices.len() / 3;
    // 25 patches, two triangles each, before any cut or split.
    assert!(triangles > 100, "{triangles} floor triangles");
    // On the outline x or z ∈ {0, 2}, or on the base's boundary; 1e-6: the
    // positions are stored in f32.
    let on = |v: f64, a: f64| (v - a).abs() < 1e-6;
    let boundary = |p: DVec3| {
        on(p.x, 0.0) || on(p.x, 2.0) || on(p.z, 0.0) || on(p.z, 2.0) || {
            let inside = |v: f64| (0.7 - 1e-6..=1.3 + 1e-6).contains(&v);
            inside(p.x) && inside(p.z) && [p.x, p.z].iter().any(|&v| on(v, 0.7) || on(v, 1.3))
        }
    };
    // Each part meeting at a shadow apex (a corner of the base,
    // `mesh::contact::cut_shadow_lines`) has its own vertex there, so an
    // edge from an apex meets its neighbour's in position, not in index: a
    // step in value, no crack.
    let corner =
        |p: DVec3| [0.7, 1.3].iter().any(|&x| on(p.x, x)) && [0.7, 1.3].iter().any(|&z| on(p.z, z));
    let key = |p: DVec3| (p * 1e5).round().to_array().map(|c| c as i64);
    let by_position: std::collections::HashSet<_> = edges
        .keys()
        .map(|&(a, b)| (key(position(a)), key(position(b))))
        .collect();
    let (mut open, mut at_apex) = (0, 0);
    for (&(a, b), &count) in &edges {
        assert_eq!(count, 1, "edge {a}-{b} used twice in one direction");
        if edges.contains_key(&(b, a)) {
            continue;
        }
        let (pa, pb) = (position(a), position(b));
        if boundary(pa) && boundary(pb) && boundary((pa + pb) * 0.5) {
            continue;
        }
        if (corner(pa) || corner(pb)) && by_position.contains(&(key(pb), key(pa))) {
            at_apex += 1;
            continue;
        }
        println!("open edge {pa} - {pb}");
        open += 1;
    }
    assert_eq!(open, 0, "{open} floor edges without a neighbour");
    // The light beside the box leaves shadow lines at its far corners.
    assert!(at_apex > 0, "no edge from a shadow apex");
}

/// A glossy floor (Kd 0, Ks 1, α = 0.1) under a 0.25 m square emitter 1 m
/// above it, after the emitter's one shot: each floor vertex in the
/// highlight seen from an eye at (0, 0.8, 0.9), its SH evaluated toward the
/// eye, against a 100 × 100 midpoint quadrature of the exact lobe
/// (`reference::lobe`, not the solver's expansion) over the emitter:
/// L = ∫ f_s(ω_i, ω_o) Le cos θ_r cos θ_s / r² dA. With 256 samples by solid
/// angle the mean |relative error| over the vertices above a tenth of the
/// peak is 0.59% (mean −0.05%), the SH truncation at 1e-4 and the samples'
/// noise; 1.5% is asserted. Area samples with equal shares measured 3.8% at
/// 256 samples and 4.5% at 32 (3.1% by solid angle): their error does not
/// fall with the sample count.
#[test]
fn glossy_highlight_at_each_vertex_matches_a_quadrature_of_the_exact_lobe() {
    use crate::reference::lobe::ExactLobe;
    let light = square(DVec3::new(0.0, 1.0, 0.0), -DVec3::Y, 0.25);
    let mut scene = scene_of(
        vec![(floor(1.0), 0), (light.clone(), 1)],
        vec![glossy("floor", 0.0, 1.0, 0.1), material("light", 0.0, 1.0)],
        32,
    );
    scene.polygons[1].patches = 1;
    let mut settings = directional_settings();
    settings.max_shots = 1;
    settings.samples = 256;
    settings.sh_error_target = 1e-4;
    let solver = run(&scene, &settings);
    let exact = ExactLobe::new(0.1);
    let eye = DVec3::new(0.0, 0.8, 0.9);
    // The mirror point of the light's centre for this eye: (0, 0, 0.5).
    let mirror_point = DVec3::new(0.0, 0.0, 0.5);
    let s = &solver.mesh().surfaces[0];
    let (a, b, d) = (light[0], light[1], light[3]);
    let area = (b - a).cross(d - a).length();
    let quadrature = |p: DVec3, wo: DVec3| {
        let n = 100;
        let mut sum = 0.0;
        for i in 0..n {
            for j in 0..n {
                let x = a
                    + (b - a) * ((i as f64 + 0.5) / n as f64)
                    + (d - a) * ((j as f64 + 0.5) / n as f64);
                let to = x - p;
                let r2 = to.length_squared();
                let wi = to / r2.sqrt();
                // Both cosines are wi.y: the floor faces up, the light down.
                sum += exact.eval(wi, wo, DVec3::Y) * wi.y * wi.y / r2;
            }
        }
        sum * area / (n * n) as f64
    };
    let mut rows = Vec::new();
    for v in 0..solver.mesh().vertices.len() as u32 {
        let p = solver.mesh().vertices[v as usize].position + solver.offset();
        if solver.mesh().vertices[v as usize].surface != 0 || (p - mirror_point).length() > 0.3 {
            continue;
        }
        let wo = (eye - p).normalize();
        let (order, sh) = solver.vertex_sh(v).unwrap();
        let mut basis = vec![0.0; coefficient_count(order)];
        solution::sh::eval_basis(
            order,
            solution::sh::to_local(wo, s.normal, s.tangent),
            &mut basis,
        );
        let shown: f64 = sh.chunks_exact(3).zip(&basis).map(|(c, y)| c[0] * y).sum();
        rows.push((shown, quadrature(p, wo)));
    }
    let peak = rows.iter().map(|r| r.1).fold(0.0, f64::max);
    let lit: Vec<f64> = rows
        .iter()
        .filter(|r| r.1 > 0.1 * peak)
        .map(|r| r.0 / r.1 - 1.0)
        .collect();
    let mean_abs = lit.iter().map(|e| e.abs()).sum::<f64>() / lit.len() as f64;
    println!(
        "{} vertices in the highlight: mean |relative error| {mean_abs:.4}, mean {:+.4}",
        lit.len(),
        lit.iter().sum::<f64>() / lit.len() as f64
    );
    assert!(lit.len() >= 16, "{}", lit.len());
    assert!(mean_abs <= 0.015, "{mean_abs}");
}

/// A source quad lit unevenly shoots by quadrants in directional mode, as
/// the diffuse solver does (`regions.rs`), checked against exact factors: a
/// floor lit by a low light over its far edge shoots onto a low wall along
/// its near edge, past a black cover lying 1 mm above one of the floor's
/// quadrants. Each wall vertex must get Kd · Σ_q U_q F(v←q) over the three
/// uncovered quadrants, with their exact point-to-polygon factors (Baum,
/// Rushmeier and Winget 1989). The shot estimates it from its samples by
/// solid angle, each weighted by the quadrant it lies in and made exact
/// where nothing occludes ([`super::regions::QuadrantScale::sample_scales`]), so
/// the cover is what the samples must get right. Nothing else occludes the
/// floor from the wall (the light sits below every wall-to-floor line).
///
/// Tolerance 2%: 1024 samples stratified in solid angle, some of whose
/// strata the cover's edges cut (the visible fraction's noise: 1.9% and 3.9%
/// at the top corners with 256 samples), plus the slivers that the cover's
/// 1 mm height hides or shows past its edges (under 0.1% here); measured
/// 0.42% at most. Summed over the wall, the patch's mean shot everywhere
/// (no quadrants) gives 3.2× the exact light and counting the covered
/// quadrant's light 1.12× (its bottom vertices see that quadrant at grazing
/// angles), so the check tells them apart.
#[test]
fn unevenly_lit_source_shoots_by_quadrants_against_exact_factors() {
    let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let floor = vec![p(0., 0., 0.), p(0., 0., 1.), p(1., 0., 1.), p(1., 0., 0.)];
    let wall = vec![p(0., 0., 0.), p(0., 0.3, 0.), p(0., 0.3, 1.), p(0., 0., 1.)];
    // The cover overhangs the floor's edges, so the floor corner under it is
    // hidden (`hidden.rs`) rather than dark, and its quadrant shoots the
    // visible corners' mean.
    let h = 0.001;
    let cover = vec![
        p(0.5, h, 0.5),
        p(0.5, h, 1.2),
        p(1.2, h, 1.2),
        p(1.2, h, 0.5),
    ];
    let light = vec![
        p(0.8, 0.08, 0.4),
        p(0.95, 0.08, 0.4),
        p(0.95, 0.08, 0.6),
        p(0.8, 0.08, 0.6),
    ];
    let scene = scene_of(
        vec![(floor, 0), (wall, 1), (cover, 3), (light, 2)],
        vec![
            material("floor", 0.5, 0.0),
            material("wall", 0.6, 0.0),
            material("light", 0.0, 1.0),
            material("black", 0.0, 0.0),
        ],
        1,
    );
    let mut settings = directional_settings();
    settings.samples = 1024;
    settings.ambient = false;
    // The floor's corners, its only vertices, get little of the light: no
    // stop threshold may end the solve before the floor's shot.
    settings.threshold = 1e-9;
    let mut solver = Solver::new(&scene, &settings).unwrap();
    solver.step().unwrap();
    let floor_patch = solver
        .mesh()
        .patches
        .iter()
        .position(|patch| patch.surface == 0)
        .unwrap() as u32;
    let unshot = solver.patches.unshot[floor_patch as usize];
    let regions = solver
        .source_regions(floor_patch, unshot)
        .expect("the floor is lit unevenly");
    let offset = solver.offset();
    let covered = |k: usize| {
        let centroid = regions.centroids[k] + offset;
        centroid.x > 0.5 && centroid.z > 0.5
    };
    let before = solver.vertex_radiance().to_vec();
    assert_eq!(solver.step().unwrap().source, Some(floor_patch));
    let epsilon = solver.occluder.scene_epsilon();
    let mut checked = 0;
    // Summed over the wall: exact, uniform, and with the cover's light.
    let mut totals = [0.0; 3];
    for (v, vertex) in solver.mesh().vertices.iter().enumerate() {
        if vertex.surface != 1 {
            continue;
        }
        let (q, n) = super::shoot::receiving_point(solver.mesh(), v as u32, epsilon);
        let factors: Vec<f64> = regions
            .polygons
            .iter()
            .map(|quadrant| quadrant.form_factor(q, n))
            .collect();
        let seen = |k: usize| regions.unshot[k] * factors[k] * 0.6;
        let exact: DVec3 = (0..4).filter(|&k| !covered(k)).map(seen).sum();
        let uncovered: DVec3 = (0..4).map(seen).sum();
        let uniform = unshot
            * (0..4)
                .filter(|&k| !covered(k))
                .map(|k| factors[k])
                .sum::<f64>()
            * 0.6;
        let got = solver.vertex_radiance()[v] - before[v];
        let error = (got.x - exact.x).abs() / exact.x;
        println!(
            "wall vertex {v}: {:.4e} against exact {:.4e} ({:.2}%); uniform {:.4e}, cover ignored {:.4e}",
            got.x,
            exact.x,
            100.0 * error,
            uniform.x,
            uncovered.x
        );
        assert!(error < 0.03, "vertex {v}: {got} against {exact}");
        totals[0] += exact.x;
        totals[1] += uniform.x;
        totals[2] += uncovered.x;
        checked += 1;
    }
    assert!(checked >= 4);
    let [exact, uniform, uncovered] = totals;
    assert!(uniform > 2.0 * exact, "{uniform} against {exact}");
    assert!(uncovered > 1.1 * exact, "{uncovered} against {exact}");
}
