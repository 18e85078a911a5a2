//! Tests of grouped shooters in directional mode (`group.rs`).

use super::*;
use crate::settings::{Preset, Shooters};
use crate::solve::directional_tests::exitance;
use crate::solve::tests::{material, scene_of};
use solution::format::SolveMode;
use solution::sh::gauss_legendre_on;

/// A glossy floor (Kd 0, Ks 0.5, α 0.3; 2 × 2 at y = 0) under a diffuse
/// square (1 × 1 at y = 1, facing down) whose 16 patches hold unshot light;
/// a faint emitter under the floor, facing away, only so that the solve
/// has emitted power.
fn floor_under_a_lit_square() -> Scene {
    let quad = |y: f64, h: f64, up: bool| {
        let mut v = vec![
            DVec3::new(-h, y, h),
            DVec3::new(h, y, h),
            DVec3::new(h, y, -h),
            DVec3::new(-h, y, -h),
        ];
        if !up {
            v.reverse();
        }
        v
    };
    let mut floor = material("floor", 0.0, 0.0);
    floor.ks = DVec3::splat(0.5);
    floor.alpha = 0.3;
    let mut scene = scene_of(
        vec![
            (quad(0.0, 1.0, true), 0),
            (quad(1.0, 0.5, false), 1),
            (quad(-1.0, 0.01, false), 2),
        ],
        vec![
            floor,
            material("square", 0.5, 0.0),
            material("faint", 0.0, 1e-9),
        ],
        4,
    );
    scene.polygons[0].patches = 8;
    scene
}

/// The square's patches, each given unit unshot radiance: its SH (c₀₀ =
/// √(4π)) and its diffuse proxy.
fn light_the_square(s: &mut Solver) -> Vec<u32> {
    let lit: Vec<u32> = (0..s.mesh.patches.len() as u32)
        .filter(|&p| s.mesh.patches[p as usize].surface == 1)
        .collect();
    let d = s.directional.as_deref_mut().unwrap();
    for &p in &lit {
        let range = d.patch_range(&s.mesh, p as usize);
        let c00 = round_to_kept((4.0 * PI).sqrt());
        d.patch_unshot[range.clone()].copy_from_slice(&[c00; 3]);
        s.patches.unshot[p as usize] = d.hemisphere_equivalent(0, &d.patch_unshot[range]);
    }
    lit
}

/// Every floor vertex's SH after the square's patches have shot, with
/// `shooters`: one grouped shot, or one shot per patch.
fn floor_after_the_square_shoots(shooters: Shooters) -> (Vec<Vec<f64>>, u32, Solver) {
    let mut settings = SolverSettings::preset(Preset::Draft);
    settings.mode = SolveMode::Directional;
    settings.adaptive = false;
    settings.ambient = false;
    settings.uniform_shooters = true;
    settings.samples = 64;
    settings.group_samples = 1024;
    settings.shooters = shooters;
    let mut s = Solver::new(&floor_under_a_lit_square(), &settings).unwrap();
    let lit = light_the_square(&mut s);
    let shots = match shooters {
        Shooters::Grouped => 1,
        Shooters::Patch => lit.len(),
    };
    for _ in 0..shots {
        let report = s.step().unwrap();
        assert!(lit.contains(&report.source.unwrap()), "{report:?}");
    }
    let floor: Vec<Vec<f64>> = (0..s.mesh.vertices.len() as u32)
        .filter(|&v| s.mesh.vertices[v as usize].surface == 0)
        .map(|v| s.vertex_sh(v).unwrap().1.to_vec())
        .collect();
    let order = s.directional().unwrap().surface_orders()[0];
    (floor, order, s)
}

/// The radiance of SH `c` (order `order`, red channel) toward a grid of
/// upper-hemisphere directions (local, z = normal).
fn toward_grid(order: u32, c: &[f64]) -> Vec<f64> {
    let (mu, _) = gauss_legendre_on(6, 0.0, 1.0);
    let mut basis = vec![0.0; coefficient_count(order)];
    let mut out = Vec::new();
    for &m in &mu {
        let s = (1.0 - m * m).sqrt();
        for j in 0..12 {
            let phi = 2.0 * PI * j as f64 / 12.0;
            solution::sh::eval_basis(
                order,
                DVec3::new(s * phi.cos(), s * phi.sin(), m),
                &mut basis,
            );
            out.push(c.chunks_exact(3).zip(&basis).map(|(c, y)| c[0] * y).sum());
        }
    }
    out
}

/// One grouped shot of 16 diffuse patches onto a glossy floor gives the
/// floor what the 16 patch shots give it:
///
/// * **energy:** the floor's total exitance (the integral of its stored SH,
///   the reflected power: Ks × the incident, since each ray's lobe carries
///   Ks of its ΔE) within 0.2%. Nothing occludes and every member is near
///   (exact factors, no cluster kernel here), so every one of a receiver's
///   1,024 rays arrives carrying W/R of the members' exact summed factor W:
///   the group's irradiance is exact, as are the patch shots' (their
///   solid-angle samples share each member's exact factor). Measured
///   −0.055%; the rest of the allowance is the next point's;
/// * **per vertex:** each vertex's exitance within 2%, and its radiance
///   toward 72 directions of the upper hemisphere within 5% RMS of the
///   patch shots'. The group's rays are uniform in area over a member, 64
///   a member on average; the patch shots' uniform in solid angle: the
///   directions within each member's solid angle are sampled differently,
///   a Monte Carlo error of order 1/√64 = 12% a member that the 16
///   members' sum and the lobe's width (α 0.3) average down, and the
///   exitance of a truncated lobe depends a little on its incidence (its
///   ringing below the horizon). Measured 0.93% worst vertex, 0.92% RMS.
#[test]
fn a_grouped_shot_onto_a_glossy_floor_gives_the_patch_shots_light() {
    let (grouped, order, gs) = floor_after_the_square_shoots(Shooters::Grouped);
    assert!(order > 0);
    let t = gs.timings();
    assert_eq!((t.group_shots, t.grouped_patches), (1, 16), "{t:?}");
    let (alone, _, _) = floor_after_the_square_shoots(Shooters::Patch);
    let (mut worst, mut sq, mut norm) = (0.0f64, 0.0, 0.0);
    let mut total = (0.0, 0.0);
    for (g, a) in grouped.iter().zip(&alone) {
        let (eg, ea) = (exitance(order, g).x, exitance(order, a).x);
        assert!(ea > 0.0);
        worst = worst.max((eg / ea - 1.0).abs());
        total = (total.0 + eg, total.1 + ea);
        for (x, y) in toward_grid(order, g).iter().zip(toward_grid(order, a)) {
            sq += (x - y) * (x - y);
            norm += y * y;
        }
    }
    let rms = (sq / norm).sqrt();
    println!(
        "grouped against patch shots: worst vertex exitance {:.3}%, total {:+.3}%, radiance \
         RMS {:.2}% over {} vertices",
        100.0 * worst,
        100.0 * (total.0 / total.1 - 1.0),
        100.0 * rms,
        grouped.len()
    );
    assert!((total.0 / total.1 - 1.0).abs() < 0.002, "{total:?}");
    assert!(worst < 0.02, "{worst}");
    assert!(rms < 0.05, "{rms}");
}
