//! Emission textures (`textured.rs`): each patch of a `map_Ke` emitter
//! shoots its mean Le, the texture's exact integral over it, in the diffuse
//! solve and in directional (SH) mode (`directional/textured.rs`); the
//! global-cube method refuses them (`cube_gather`).

use super::tests::{material, scene_of};
use super::*;
use crate::geometry::formfactor::point_to_polygon;
use crate::scene::{Material, SceneTexture, UvMap};
use crate::settings::Preset;
use glam::DVec2;
use std::sync::Arc;

fn settings() -> SolverSettings {
    let mut s = SolverSettings::preset(Preset::Draft);
    s.adaptive = false;
    s.samples = 4;
    s
}

/// A 16 × 16 texture whose left half (u < ½) is sRGB `left` and right half
/// `right`.
fn halves(left: u8, right: u8) -> Arc<SceneTexture> {
    let mut rgba = Vec::new();
    for _ in 0..16 {
        for x in 0..16 {
            let c = if x < 8 { left } else { right };
            rgba.extend([c, c, c, 255]);
        }
    }
    Arc::new(SceneTexture::from_rgba("halves.png".into(), 16, 16, rgba).unwrap())
}

/// A unit-square emitter at height `d` facing down (−y), u along +x and v
/// along +z (both 0..1), `n` × `n` patches, with material `screen`; and a
/// 3 × 3 floor at y = 0 facing up, centred below it.
fn screen_over_floor(screen: Material, d: f64, n: u32) -> Scene {
    let c = DVec3::new(-0.5, d, -0.5);
    // Counter-clockwise seen from below: X × Z = −Y.
    let emitter = vec![c, c + DVec3::X, c + DVec3::X + DVec3::Z, c + DVec3::Z];
    let f = DVec3::new(-1.5, 0.0, -1.5);
    // Counter-clockwise seen from above: Z × X = +Y.
    let floor = vec![
        f,
        f + DVec3::Z * 3.0,
        f + DVec3::new(3.0, 0.0, 3.0),
        f + DVec3::X * 3.0,
    ];
    let mut scene = scene_of(
        vec![(emitter, 0), (floor, 1)],
        vec![screen, material("floor", 0.5, 0.0)],
        n,
    );
    scene.polygons[0].uv_map = Some(UvMap {
        origin: c,
        du: DVec3::X,
        dv: DVec3::Z,
        base: DVec2::ZERO,
    });
    scene
}

/// Linear value of an sRGB code by IEC 61966-2-1, in f64, independent of
/// `texture::srgb_to_linear`.
fn iec_srgb(code: u8) -> f64 {
    let c = f64::from(code) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[test]
fn a_half_grey_half_white_emitter_emits_pi_times_the_integral_of_its_radiance() {
    // Ke 3 × (grey 128 | white), 3 × 3 patches: the left column's patches
    // lie in the grey half, the right column's in the white, the middle
    // column's straddle the edge half and half. The emitted power must be
    // π ∫ Le dA = π · 3 · 1 m² · (g + 1)/2 per channel, g = 0.2159 the
    // decoded grey: exact integration leaves only rounding (1e-12), so 1e-9
    // relative is asserted. Without the sRGB decode g would be 0.502, 18%
    // more power.
    let g = f64::from(crate::texture::srgb_to_linear(128));
    // The pyramid is f32: the decoded grey agrees with IEC 61966-2-1 to f32
    // precision, and is not the code's 128/255.
    assert!((g - iec_srgb(128)).abs() < 1e-7, "{g}");
    assert!((g - 128.0 / 255.0).abs() > 0.2);
    let mut screen = material("screen", 0.0, 3.0);
    screen.emission_texture = Some(halves(128, 255));
    let scene = screen_over_floor(screen, 1.0, 3);
    let solver = Solver::new(&scene, &settings()).unwrap();
    let want = 3.0 * PI * 3.0 * (g + 1.0) / 2.0;
    let got = solver.progress().emitted_power;
    assert!((got - want).abs() <= 1e-9 * want, "{got} vs {want}");
    // Each patch's unshot radiance is Ke times its texels' mean.
    let mut columns = [0; 3];
    for (p, patch) in solver.mesh.patches.iter().enumerate() {
        if patch.surface != 0 {
            continue;
        }
        let centre = patch.polygon().iter().sum::<DVec3>() / patch.polygon().len() as f64;
        let column = ((centre.x + 0.5) * 3.0).floor() as usize;
        let mean = [g, (g + 1.0) / 2.0, 1.0][column];
        let u = solver.patch_unshot()[p];
        assert!(
            (u - DVec3::splat(3.0 * mean)).abs().max_element() < 1e-12,
            "{u}"
        );
        columns[column] += 1;
    }
    assert_eq!(columns, [3, 3, 3]);
    // The surface's vertices start at its mean Le (the display adds the
    // texture back: `output_textured.rs`).
    assert!(
        (solver.materials.emission[0] - DVec3::splat(1.5 * (g + 1.0)))
            .abs()
            .max_element()
            < 1e-12
    );
}

#[test]
fn an_emitters_display_carries_le_of_uv_and_its_reflected_light_apart() {
    let mut screen = material("screen", 0.5, 3.0);
    screen.emission_texture = Some(halves(128, 255));
    let scene = screen_over_floor(screen, 1.0, 2);
    let mut solver = Solver::new(&scene, &settings()).unwrap();
    for _ in 0..12 {
        solver.step();
    }
    assert_emitter_display(&solver.to_solution(false));
}

/// Checks the display of [`screen_over_floor`]'s emitter (Ke 3, 2 × 2
/// patches, Kd 0.5, Ks 0) in `solution`. The emitter's textured batch:
/// texture = the emission texture, factor Ke, "E/π" 1 at every vertex, so a
/// renderer shows Ke ⊙ texture(uv); its coefficients (order 0) hold only
/// reflected light. Here the emitter faces the floor, whose light comes back
/// to it: positive, and far below Le.
fn assert_emitter_display(solution: &solution::format::Solution) {
    let textured: Vec<&solution::format::Batch> = solution
        .batches
        .iter()
        .filter(|b| b.texturing.is_some())
        .collect();
    assert_eq!(textured.len(), 1);
    assert_eq!(solution.textures.len(), 1);
    let t = textured[0].texturing.as_ref().unwrap();
    assert_eq!(t.factor, [3.0; 3]);
    assert!(t.vertices.iter().all(|v| v.irradiance_over_pi == [1.0; 3]));
    // UVs span the square: corners (0, 0) and (1, 1) are among them.
    let has = |uv: [f32; 2]| {
        t.vertices
            .iter()
            .any(|v| (v.uv[0] - uv[0]).abs() < 1e-6 && (v.uv[1] - uv[1]).abs() < 1e-6)
    };
    assert!(has([0.0, 0.0]) && has([1.0, 1.0]));
    let scale = (4.0 * PI).sqrt() as f32;
    let reflected: Vec<f32> = textured[0].coefficients.iter().map(|c| c / scale).collect();
    assert!(reflected.iter().all(|&l| l >= 0.0));
    let mean = reflected.iter().sum::<f32>() / reflected.len() as f32;
    assert!(mean > 0.0 && mean < 0.5, "{mean}");
    // The untextured batch (the floor) is unchanged in kind.
    assert!(solution.batches.iter().any(|b| b.texturing.is_none()));
}

/// Settings for the directional (SH) mode, else as [`settings`].
fn directional() -> SolverSettings {
    let mut s = settings();
    s.mode = SolveMode::Directional;
    s
}

#[test]
fn directional_mode_shoots_each_patchs_texel_mean_and_emits_pi_times_the_integral() {
    // As the diffuse test above, in SH: Ke 3 × (grey 128 | white), 3 × 3
    // patches. Each patch's unshot SH must start at c₀₀ = √(4π) · Ke ·
    // (its texels' mean), the SH of isotropic radiance (Y₀₀ = 1/√(4π)),
    // higher bands 0; summed, π Σ_p A_p c₀₀ Y₀₀ = π ∫ Le dA within 1e-9
    // relative (exact integration; the state's 40-bit rounding is 1e-12).
    // A missing sRGB decode would be 24% off, flat Ke 64%. Both a diffuse
    // (L = 0) and a glossy (L > 0) emitter.
    let g = f64::from(crate::texture::srgb_to_linear(128));
    let want = 3.0 * PI * 3.0 * (g + 1.0) / 2.0;
    let scale = (4.0 * PI).sqrt();
    for ks in [0.0, 0.3] {
        let mut screen = material("screen", 0.0, 3.0);
        screen.ks = DVec3::splat(ks);
        screen.alpha = 0.2;
        screen.emission_texture = Some(halves(128, 255));
        let scene = screen_over_floor(screen, 1.0, 3);
        let solver = Solver::new(&scene, &directional()).unwrap();
        assert!(
            !solver.warnings().iter().any(|w| w.contains("emission")),
            "{:?}",
            solver.warnings()
        );
        let got = solver.progress().emitted_power;
        assert!(
            (got - want).abs() <= 1e-9 * want,
            "Ks {ks}: {got} vs {want}"
        );
        let mut from_sh = 0.0;
        for (p, patch) in solver.mesh.patches.iter().enumerate() {
            if patch.surface != 0 {
                continue;
            }
            let sh = solver.directional_patch_unshot(p);
            assert_eq!(sh.len() > 3, ks > 0.0, "the glossy screen has L > 0");
            let centre = patch.polygon().iter().sum::<DVec3>() / patch.polygon().len() as f64;
            let column = ((centre.x + 0.5) * 3.0).floor() as usize;
            let mean = [g, (g + 1.0) / 2.0, 1.0][column];
            for (k, &c) in sh.iter().enumerate() {
                let expected = if k < 3 { scale * 3.0 * mean } else { 0.0 };
                assert!((c - expected).abs() <= 1e-11 * scale * 3.0, "{k}: {c}");
            }
            from_sh += PI * patch.area * (sh[0] + sh[1] + sh[2]) / scale;
        }
        assert!((from_sh - want).abs() <= 1e-9 * want, "{from_sh} vs {want}");
    }
}

#[test]
fn an_emitters_display_in_directional_mode_carries_le_of_uv_and_its_reflected_light() {
    // The diffuse mode's batch convention, in SH mode (order 0 here: Ks 0).
    let mut screen = material("screen", 0.5, 3.0);
    screen.emission_texture = Some(halves(128, 255));
    let scene = screen_over_floor(screen, 1.0, 2);
    let mut solver = Solver::new(&scene, &directional()).unwrap();
    for _ in 0..12 {
        solver.step();
    }
    assert_emitter_display(&solver.to_solution(false));
}

/// Irradiance at `x` (normal +y) from `screen` regions of uniform radiance:
/// E = Σ L_i · π · F(x → region i), F by the exact point-to-polygon formula.
fn irradiance(x: DVec3, regions: &[(Vec<DVec3>, f64)]) -> f64 {
    regions
        .iter()
        .map(|(polygon, le)| le * PI * point_to_polygon(x, DVec3::Y, polygon))
        .sum()
}

/// How the error of shooting each patch's mean Le uniformly depends on the
/// patch size (docs/textures.md, "Accuracy and patch size"). The emitter is
/// the unit square with Le = 1 (white) on its left half and 0 (black) on its
/// right; the receivers are the floor's points at distance d below it. The
/// true direct irradiance integrates the two halves exactly; the solver's
/// integrates each patch's mean (from `patch_unshot`, the solver's own
/// values) over the patch, also exactly, so the difference is the
/// uniform-patch error alone, without the ray-cast form factor's.
///
/// The bound checked: with K(x, y) = cos θ cos θ' / r² (E = ∫ Le K dA),
/// ΔE(x) = Σ_P ∫_P (Le − m_P)(K − c_P) dA for any constant c_P (since
/// ∫_P (Le − m_P) = 0), so |ΔE| ≤ Σ_P ½ A_P (Le_max − Le_min) · ½ diam(P) ·
/// sup|∇K|, and for parallel planes sup|∇K| = (4 · 125 / (216 √5)) / d³ ≈
/// 1.035 / d³ (K = d² / (d² + ρ²)², steepest at ρ = d / √5). Only patches the
/// texture varies across count; with an even number of patches per side the
/// patches' edges fall on the texture's edge and the error is rounding.
#[test]
fn the_uniform_patch_error_shrinks_as_patch_size_squared_and_stays_within_its_bound() {
    let regions = |d: f64| {
        let half = |x0: f64| {
            let c = DVec3::new(x0, d, -0.5);
            vec![
                c,
                c + DVec3::X * 0.5,
                c + DVec3::new(0.5, 0.0, 1.0),
                c + DVec3::Z,
            ]
        };
        vec![(half(-0.5), 1.0), (half(0.0), 0.0)]
    };
    let gradient = 4.0 * 125.0 / (216.0 * 5f64.sqrt());
    let mut table = Vec::new();
    for d in [0.25, 1.0] {
        for n in [1u32, 2, 3, 5, 9, 17] {
            let mut screen = material("screen", 0.0, 1.0);
            screen.emission_texture = Some(halves(255, 0));
            let solver = Solver::new(&screen_over_floor(screen, d, n), &settings()).unwrap();
            let offset = solver.offset();
            let mut patches = Vec::new();
            let mut bound_sum = 0.0;
            for (p, patch) in solver.mesh.patches.iter().enumerate() {
                if patch.surface != 0 {
                    continue;
                }
                let polygon: Vec<DVec3> = patch.polygon().iter().map(|&q| q + offset).collect();
                let le = solver.patch_unshot()[p].x;
                let straddles =
                    polygon.iter().any(|q| q.x < -1e-12) && polygon.iter().any(|q| q.x > 1e-12);
                if straddles {
                    let diam = (polygon[2] - polygon[0]).length();
                    bound_sum += 0.5 * patch.area * 1.0 * 0.5 * diam * gradient / d.powi(3);
                }
                patches.push((polygon, le));
            }
            assert_eq!(patches.len() as u32, n * n);
            let (mut worst, mut worst_rel) = (0.0f64, 0.0f64);
            for i in 0..=8 {
                for k in 0..=8 {
                    let x = DVec3::new(-1.0 + 0.25 * i as f64, 0.0, -1.0 + 0.25 * k as f64);
                    let truth = irradiance(x, &regions(d));
                    let ours = irradiance(x, &patches);
                    worst = worst.max((ours - truth).abs());
                    worst_rel = worst_rel.max((ours - truth).abs() / truth.max(1e-3 * PI));
                }
            }
            table.push((d, n, worst, worst_rel, bound_sum));
            // Rounding in a handful of exact form factors: 1e-12 absolute;
            // 1e-9 is asserted for aligned patches.
            if n % 2 == 0 {
                assert!(worst < 1e-9, "d {d}, {n}²: {worst}");
            } else {
                assert!(
                    worst <= bound_sum,
                    "d {d}, {n}²: {worst} > bound {bound_sum}"
                );
            }
        }
    }
    for (d, n, worst, rel, bound) in &table {
        eprintln!(
            "d {d}: {n:>2}² patches: max |ΔE| {worst:.3e} (max relative {rel:.3e}), bound {bound:.3e}"
        );
    }
    // Second order once patches are smaller than the distance: a patch
    // halved by a straight edge errs by ∇K · ∫_P (Le − m)(y − c) dA =
    // ΔLe h³ / 8 · ∂K/∂x, and h⁻¹ such patches line the edge, so
    // ΔE ≈ (h² / 8) ΔLe ∫_edge ∂K/∂x. 17 patches a side err at most 1.5 ×
    // (9/17)² of what 9 do.
    for d in [0.25, 1.0] {
        let at = |n: u32| table.iter().find(|t| t.0 == d && t.1 == n).unwrap().2;
        let ratio = at(17) / at(9);
        assert!(
            ratio <= 1.5 * (9.0f64 / 17.0).powi(2),
            "d {d}: ratio {ratio}"
        );
    }
}

#[test]
fn a_directional_solve_with_an_emission_texture_resumes_bit_for_bit() {
    // A consistency check (the same solve twice): the emitter's per-patch
    // unshot SH start from its texels' means, which a resume rebuilds from
    // the scene before restoring the checkpoint's state. Checkpointed after
    // 3 shots and resumed, a glossy textured emitter over a floor with
    // adaptive meshing must hold the same bits after 6 as one never stopped.
    let mut screen = material("screen", 0.2, 3.0);
    screen.ks = DVec3::splat(0.3);
    screen.alpha = 0.2;
    screen.emission_texture = Some(halves(128, 255));
    let scene = screen_over_floor(screen, 1.0, 3);
    let mut s = directional();
    s.adaptive = true;
    let run = |solver: &mut Solver, shots: usize| {
        for _ in 0..shots {
            solver.step();
        }
    };
    let mut straight = Solver::new(&scene, &s).unwrap();
    run(&mut straight, 6);
    let mut first = Solver::new(&scene, &s).unwrap();
    run(&mut first, 3);
    let mut resumed = Solver::resume(
        &scene,
        &s,
        super::checkpoint::Checkpoint::round_trip(&first),
    )
    .unwrap();
    run(&mut resumed, 3);
    assert_eq!(straight.mesh.vertices.len(), resumed.mesh.vertices.len());
    let bits = |x: &[f64]| x.iter().map(|c| c.to_bits()).collect::<Vec<_>>();
    for v in 0..straight.mesh.vertices.len() {
        assert_eq!(
            bits(&straight.directional_vertex(v).1),
            bits(&resumed.directional_vertex(v).1)
        );
    }
    for p in 0..straight.mesh.patches.len() {
        assert_eq!(
            bits(&straight.directional_patch_unshot(p)),
            bits(&resumed.directional_patch_unshot(p))
        );
    }
}
