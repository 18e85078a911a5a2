//! The diffuse step's bookkeeping on the Cornell box: energy conservation
//! and the footprint's sparse passes (`footprint.rs`).

use super::*;
use crate::settings::Preset;

fn cornell() -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../config/cornell_box.obj");
    let mut loaded = crate::scene::load_scene(&path, &Default::default())
        .unwrap()
        .scene;
    loaded.fill_default_patches(3);
    loaded
}

fn settings(adaptive: bool) -> SolverSettings {
    let mut s = SolverSettings::preset(Preset::Draft);
    s.samples = 4;
    s.max_shots = 120;
    s.adaptive = adaptive;
    s.shooters = crate::settings::Shooters::Patch;
    s
}

fn bits(v: &[DVec3]) -> Vec<[u64; 3]> {
    v.iter().map(|l| l.to_array().map(f64::to_bits)).collect()
}

/// Energy bookkeeping: the emitted power plus the power reflected into the
/// receivers (π Σ_p Σ_v w_vp (L_v − Le_v), the displayed radiance each shot
/// added, integrated over the patches) equals the power shot plus the power
/// left unshot, within 1e-9 relative. Without refinement every vertex's L − Le is
/// exactly the sum of what the shots gave it, so a ΔL that reached the
/// display but not the patches' unshot (or the reverse) breaks the balance by
/// its whole power. The incident power (reflected / Kd per channel) splits the
/// shot power further into absorbed and escaped (the open front of the box);
/// both must be non-negative. 1e-9 is rounding: about 10⁴ terms summed in f64.
/// Hidden vertices (the floor under the blocks, the ceiling above the light,
/// `solve/hidden.rs`) are outside the bookkeeping: the gather leaves them
/// out and a patch's power is counted over its visible area, so what they
/// receive is absorbed by the object's inside.
#[test]
fn progressive_shooting_loses_no_energy() {
    let scene = cornell();
    let s = settings(false);
    let mut solver = Solver::new(&scene, &s).unwrap();
    let emitted = solver.stats.emitted_power;
    let mut shot_power = 0.0;
    while !solver.is_done() {
        let source = solver.choose_source();
        shot_power += PI
            * solver.patches.shoot_area[source as usize]
            * solver.patches.unshot[source as usize].element_sum();
        let report = solver.step().unwrap();
        assert_eq!(report.source, Some(source));
    }
    let left = solver.total_unshot_power();
    let mut reflected = 0.0;
    let mut incident = 0.0;
    for (p, patch) in solver.mesh.patches.iter().enumerate() {
        let surface = patch.surface as usize;
        let (kd, le) = (
            solver.materials.kd[surface],
            solver.materials.emission[surface],
        );
        for &(v, w) in solver.patch_weights(p as u32) {
            if solver.hidden_vertices()[v as usize] {
                continue;
            }
            let gained = solver.field.radiance[v as usize] - le;
            reflected += PI * w * gained.element_sum();
            incident += PI * w * (gained / kd.max(DVec3::splat(1e-300))).element_sum();
        }
    }
    let balance = (emitted + reflected) - (shot_power + left);
    assert!(
        balance.abs() <= 1e-9 * emitted,
        "emitted {emitted} + reflected {reflected} vs shot {shot_power} + \
         unshot {left}: off by {balance}"
    );
    let absorbed = incident - reflected;
    let escaped = shot_power - incident;
    assert!(
        absorbed >= 0.0 && escaped >= -1e-9 * emitted,
        "{absorbed} {escaped}"
    );
    eprintln!(
        "shots {}, absorbed {:.4}, escaped {:.4}, unshot {:.4} of emitted",
        solver.stats.shots,
        absorbed / emitted,
        escaped / emitted,
        left / emitted
    );
}

/// The sparse passes (`footprint.rs`: shooting only the visited surfaces'
/// vertices, refinement scanning only the touched surfaces' patches, the
/// gather and the reset of ΔL over the touched surfaces only) against the same
/// passes over the whole scene, as the step ran them before: a consistency
/// check (the same solver twice), asserting bit-identical radiance, unshot
/// radiance, splits and counts, with refinement on. It holds exactly
/// because an untouched surface has no changed leaf and adds exactly 0 to its
/// patches (see `footprint.rs`).
#[test]
fn sparse_passes_match_whole_scene() {
    let scene = cornell();
    let s = settings(true);
    let solve = |whole_scene: bool| {
        let mut solver = Solver::new(&scene, &s).unwrap();
        solver.sharing.footprint.whole_scene = whole_scene;
        solver.sharing.footprint.always_sparse = !whole_scene;
        while solver.step().is_some() {}
        solver
    };
    let (sparse, whole) = (solve(false), solve(true));
    assert!(
        sparse.mesh().split_log.len() > 10,
        "refinement should split"
    );
    assert_eq!(sparse.mesh().split_log, whole.mesh().split_log);
    assert_eq!(
        bits(sparse.vertex_radiance()),
        bits(whole.vertex_radiance())
    );
    assert_eq!(bits(&sparse.field.direct), bits(&whole.field.direct));
    assert_eq!(bits(sparse.patch_unshot()), bits(whole.patch_unshot()));
    assert_eq!(sparse.progress(), whole.progress());
}
