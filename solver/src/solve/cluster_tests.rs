//! Bounded shooting (`cluster.rs`) against flat shooting on the Cornell box:
//! exact culls, energy bookkeeping, determinism.

use super::*;
use crate::settings::{Preset, Shooting};

fn cornell() -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/cornell_box.obj");
    let mut loaded = crate::scene::load_scene(&path, &Default::default())
        .unwrap()
        .scene;
    loaded.fill_default_patches(3);
    loaded
}

fn settings(shooting: Shooting, tolerance: f64, adaptive: bool) -> SolverSettings {
    let mut s = SolverSettings::preset(Preset::Draft);
    s.samples = 4;
    s.max_shots = 120;
    s.patches = 3;
    s.adaptive = adaptive;
    s.shooting = shooting;
    s.shooting_tolerance = tolerance;
    // Bounded shooting plans a patch shot's receivers; a grouped shot visits
    // every receiver (`group_shot.rs`), so these tests shoot patches.
    s.shooters = crate::settings::Shooters::Patch;
    s
}

fn bits(v: &[DVec3]) -> Vec<[u64; 3]> {
    v.iter().map(|l| l.to_array().map(f64::to_bits)).collect()
}

fn run(scene: &Scene, settings: &SolverSettings) -> Solver {
    let mut solver = Solver::new(scene, settings).unwrap();
    while solver.step().is_some() {}
    solver
}

/// With a zero tolerance bounded shooting skips only receivers that the flat
/// shooter gives exactly nothing (behind the source, facing away, the
/// source's surface, black), so the two solves are bit-identical, refinement
/// included: the culls are exact, not approximate.
#[test]
fn zero_tolerance_is_flat_to_the_bit() {
    let scene = cornell();
    let flat = run(&scene, &settings(Shooting::Flat, 0.0, true));
    let bounded = run(&scene, &settings(Shooting::Bounded, 0.0, true));
    assert!(bounded.timings().bounded_receivers == 0);
    assert!(
        bounded.timings().visited_receivers
            < flat.progress().shots * flat.mesh().vertices.len() as u64,
        "the culls should skip some receivers"
    );
    assert_eq!(flat.mesh().split_log, bounded.mesh().split_log);
    assert_eq!(
        bits(flat.vertex_radiance()),
        bits(bounded.vertex_radiance())
    );
    assert_eq!(flat.progress(), bounded.progress());
}

/// Energy bookkeeping: the emitted power plus the power reflected into the
/// receivers (π Σ_p Σ_v w_vp (L_v − Le_v), the displayed radiance each shot
/// added, integrated over the patches) equals the power shot plus the power
/// left unshot, within 1e-9 relative, with a tolerance loose enough that
/// most receivers are bounded. Without refinement every vertex's L − Le is
/// exactly the sum of what the shots gave it, so a deposit that reached the
/// display but not the patches' unshot (or the reverse) breaks the balance by
/// its whole power. The incident power (reflected / Kd per channel) splits the
/// shot power further into absorbed and escaped (the open front of the box);
/// both must be non-negative. 1e-9 is rounding: about 10⁴ terms summed in f64.
/// Hidden vertices (the floor under the blocks, the ceiling above the light,
/// `solve/hidden.rs`) are outside the bookkeeping: the gather leaves them
/// out and a patch's power is counted over its visible area, so what they
/// receive is absorbed by the object's inside.
#[test]
fn bounded_shooting_loses_no_energy() {
    let scene = cornell();
    for (shooting, tolerance) in [(Shooting::Bounded, 0.05), (Shooting::Flat, 0.0)] {
        let s = settings(shooting, tolerance, false);
        let mut solver = Solver::new(&scene, &s).unwrap();
        let emitted = solver.emitted_power;
        let mut shot_power = 0.0;
        while !solver.is_done() {
            let source = solver.choose_source();
            shot_power += PI
                * solver.patch_shoot_area[source as usize]
                * solver.patch_unshot[source as usize].element_sum();
            let report = solver.step().unwrap();
            assert_eq!(report.source, source);
        }
        let left = solver.total_unshot_power();
        let mut reflected = 0.0;
        let mut incident = 0.0;
        for (p, patch) in solver.mesh.patches.iter().enumerate() {
            let surface = patch.surface as usize;
            let (kd, le) = (solver.kd[surface], solver.emission[surface]);
            for &(v, w) in solver.patch_weights(p as u32) {
                if solver.hidden_vertices()[v as usize] {
                    continue;
                }
                let gained = solver.radiance[v as usize] - le;
                reflected += PI * w * gained.element_sum();
                incident += PI * w * (gained / kd.max(DVec3::splat(1e-300))).element_sum();
            }
        }
        let balance = (emitted + reflected) - (shot_power + left);
        assert!(
            balance.abs() <= 1e-9 * emitted,
            "{shooting:?}: emitted {emitted} + reflected {reflected} vs shot {shot_power} + \
             unshot {left}: off by {balance}"
        );
        let absorbed = incident - reflected;
        let escaped = shot_power - incident;
        assert!(
            absorbed >= 0.0 && escaped >= -1e-9 * emitted,
            "{absorbed} {escaped}"
        );
        if shooting == Shooting::Bounded {
            let t = solver.timings();
            assert!(
                t.bounded_receivers > t.visited_receivers / 10,
                "the tolerance should bound many receivers: {t:?}"
            );
        }
        eprintln!(
            "{shooting:?}: shots {}, absorbed {:.4}, escaped {:.4}, unshot {:.4} of emitted",
            solver.shots,
            absorbed / emitted,
            escaped / emitted,
            left / emitted
        );
    }
}

/// Bounded shooting is deterministic whatever the thread count: the plan is
/// built serially and each bounded estimate draws from its own stream.
#[test]
fn bounded_shooting_is_deterministic_across_threads() {
    let scene = cornell();
    let s = settings(Shooting::Bounded, 0.02, true);
    let with = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| run(&scene, &s))
    };
    let (one, three) = (with(1), with(3));
    assert!(one.timings().bounded_receivers > 0);
    assert_eq!(one.mesh().split_log, three.mesh().split_log);
    assert_eq!(bits(one.vertex_radiance()), bits(three.vertex_radiance()));
    assert_eq!(one.progress(), three.progress());
}

/// The furnace with bounded shooting on: a closed unit cube, Kd = ρ = 0.5 and
/// Le = 1 on every face, converges to L = Le / (1 − ρ) at every vertex within
/// 1%, as flat shooting does (physics_tests: at threshold 0.002 the unshot
/// light leaves ≈ 0.1%). A bounded deposit is gathered and reshot like any other
/// light, so no energy is lost; what can err is its placement within a face
/// (uniform at the face's centroid factor instead of per vertex). At the default
/// tolerance 1e-4 nothing is bounded in so small a box; at 1e-3 the opposite
/// faces' weak shots are, and the worst vertex is 0.18% off. Looser tolerances
/// are not held to 1%: at 1e-2 the uniform deposits put the worst vertex 3.0%
/// off (measured), which is the accuracy cost docs/benchmarks.md reports.
/// Ambient off, so the figure is the solver's.
#[test]
fn bounded_furnace_converges_to_le_over_one_minus_rho() {
    use super::tests::{material, scene_of};
    let c = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let faces = [
        [c(0., 0., 0.), c(1., 0., 0.), c(1., 1., 0.), c(0., 1., 0.)],
        [c(0., 0., 1.), c(0., 1., 1.), c(1., 1., 1.), c(1., 0., 1.)],
        [c(0., 0., 0.), c(0., 1., 0.), c(0., 1., 1.), c(0., 0., 1.)],
        [c(1., 0., 0.), c(1., 0., 1.), c(1., 1., 1.), c(1., 1., 0.)],
        [c(0., 0., 0.), c(0., 0., 1.), c(1., 0., 1.), c(1., 0., 0.)],
        [c(0., 1., 0.), c(1., 1., 0.), c(1., 1., 1.), c(0., 1., 1.)],
    ];
    let centre = c(0.5, 0.5, 0.5);
    let polygons = faces
        .into_iter()
        .map(|f| {
            let mut f = f.to_vec();
            let normal = crate::geometry::polygon::newell_normal(&f);
            if normal.dot(centre - f[0]) < 0.0 {
                f.reverse();
            }
            (f, 0)
        })
        .collect();
    let scene = scene_of(polygons, vec![material("furnace", 0.5, 1.0)], 2);
    for tolerance in [1e-4, 1e-3] {
        let mut s = SolverSettings::preset(Preset::Draft);
        s.samples = 4;
        s.threshold = 0.002;
        s.max_shots = 20_000;
        s.ambient = false;
        s.shooting = Shooting::Bounded;
        s.shooting_tolerance = tolerance;
        s.shooters = crate::settings::Shooters::Patch;
        let solver = run(&scene, &s);
        let p = solver.progress();
        assert!(p.unshot_fraction < 0.002, "did not converge: {p:?}");
        let worst = solver
            .vertex_radiance()
            .iter()
            .map(|l| ((*l - DVec3::splat(2.0)).abs() / 2.0).max_element())
            .fold(0.0, f64::max);
        eprintln!(
            "bounded furnace, tolerance {tolerance}: {} shots, worst error {worst:.2e}, {:?}",
            p.shots,
            solver.timings()
        );
        assert!(
            worst < 0.01,
            "tolerance {tolerance}: worst relative error {worst}"
        );
        if tolerance >= 1e-3 {
            // Not vacuous: at 1e-3 the opposite faces' weak shots are bounded
            // (909 receivers when this was written).
            assert!(solver.timings().bounded_receivers > 0);
        }
    }
}

/// The sparse passes (`footprint.rs`: shooting only the visited surfaces'
/// vertices, refinement scanning only the touched surfaces' patches, the
/// gather and the reset of ΔL over the touched surfaces only) against the same
/// passes over the whole scene, as the step ran them before: a consistency
/// check (the same solver twice), asserting bit-identical radiance, unshot
/// radiance, splits and counts, with refinement on and a tolerance that
/// bounds many receivers, for bounded and flat shooting. It holds exactly
/// because an untouched surface has no changed leaf and adds exactly 0 to its
/// patches (see `footprint.rs`).
#[test]
fn sparse_passes_match_whole_scene() {
    let scene = cornell();
    for (shooting, tolerance) in [(Shooting::Bounded, 0.02), (Shooting::Flat, 0.0)] {
        let s = settings(shooting, tolerance, true);
        let solve = |whole_scene: bool| {
            let mut solver = Solver::new(&scene, &s).unwrap();
            solver.footprint.whole_scene = whole_scene;
            solver.footprint.always_sparse = !whole_scene;
            while solver.step().is_some() {}
            solver
        };
        let (sparse, whole) = (solve(false), solve(true));
        if shooting == Shooting::Bounded {
            assert!(sparse.timings().bounded_receivers > 0);
        }
        assert!(
            sparse.mesh().split_log.len() > 10,
            "refinement should split"
        );
        assert_eq!(sparse.mesh().split_log, whole.mesh().split_log);
        assert_eq!(
            bits(sparse.vertex_radiance()),
            bits(whole.vertex_radiance())
        );
        assert_eq!(bits(&sparse.direct), bits(&whole.direct));
        assert_eq!(bits(sparse.patch_unshot()), bits(whole.patch_unshot()));
        assert_eq!(sparse.progress(), whole.progress());
    }
}
