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

fn settings(patches: u32, resolution: u32) -> SolverSettings {
    let mut s = SolverSettings::preset(Preset::Draft);
    s.patches = patches;
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
        let result = solve_gauss_seidel(&scene, &settings(3, 16), &limits).unwrap();
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
    let s = settings(256, 16);
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
        solve_gauss_seidel(&scene, &settings(2, 16), &limits),
        Err(GaussSeidelError::MatrixTooLarge { patches: 24, .. })
    ));
}

#[test]
fn bad_input_is_refused_with_clear_errors() {
    let one = scene_of(vec![cube().remove(0)], vec![material("lamp", 0.5, 1.0)], 2);
    assert!(matches!(
        solve_gauss_seidel(&one, &settings(2, 16), &GaussSeidelLimits::default()),
        Err(GaussSeidelError::Solve(SolveError::SinglePolygon))
    ));
    let dark = scene_of(cube(), vec![material("grey", 0.5, 0.0)], 2);
    assert!(matches!(
        solve_gauss_seidel(&dark, &settings(2, 16), &GaussSeidelLimits::default()),
        Err(GaussSeidelError::Solve(SolveError::NoEmitter))
    ));
    let scene = scene_of(cube(), vec![material("furnace", 0.5, 1.0)], 2);
    let err = solve_gauss_seidel(&scene, &settings(2, 15), &GaussSeidelLimits::default())
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
        solve_gauss_seidel(&scene, &settings(2, 16), &limits),
        Err(GaussSeidelError::BadTolerance(_))
    ));
}
