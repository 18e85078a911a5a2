//! End-to-end physics of the solver core on the Cornell box, through the OBJ
//! importer: adaptive meshing follows the shadows and leaves smooth light
//! coarse (Remington 1992, §3.3).

use glam::DVec3;
use solver::geometry::visibility::Occluder;
use solver::scene::{load_scene, ImportOptions, Scene};
use solver::settings::{Preset, Shooters, SolverSettings};
use solver::solve::Solver;
use std::path::Path;

fn cornell() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/cornell_box.obj");
    load_scene(&path, &ImportOptions::default())
        .expect("config/cornell_box.obj imports")
        .scene
}

/// Fraction of an 8 × 8 grid of points on the light that floor point `p` sees
/// (scene coordinates): 1 fully lit, 0 in umbra.
fn lit_fraction(occluder: &Occluder, light: &[DVec3], p: DVec3) -> f64 {
    let mut seen = 0;
    for i in 0..8 {
        for j in 0..8 {
            let (u, v) = ((i as f64 + 0.5) / 8.0, (j as f64 + 0.5) / 8.0);
            let q = light[0]
                .lerp(light[1], u)
                .lerp(light[3].lerp(light[2], u), v);
            // Just above the floor, just below the light.
            if occluder.visible(p + DVec3::Y * 0.05, q - DVec3::Y * 0.05) {
                seen += 1;
            }
        }
    }
    seen as f64 / 64.0
}

#[test]
fn meshing_refines_along_shadow_boundaries_and_leaves_smooth_light_coarse() {
    let mut scene = cornell();
    let mut settings = SolverSettings::preset(Preset::Medium);
    settings.samples = 16;
    settings.max_shots = 30;
    // The meshing this test's thresholds were derived from (the medium preset
    // before docs/tradeoffs.md re-chose it): 4×4 patches per wall, refinement
    // in at most 6 levels (a size floor of 0.5 mm, below a wall's sixth
    // level, 2.2 mm, so the depth decides, as the area floor 5e-5 of a
    // polygon these thresholds were first derived with let it).
    let patches = 4;
    settings.edge_threshold = 0.3;
    settings.shadow_threshold = 0.1;
    settings.min_element_size = 0.5 / 960.0;
    settings.max_depth = 6;
    // Whole receivers: the floor as one surface of 4×4 patches, as these
    // thresholds assume (cutting it along the blocks' bases, `mesh::contact`,
    // would make it eleven pieces).
    settings.whole_receivers = true;
    // And 30 patch shots: the emitters' and the first reflectors' light. 30
    // grouped shots carry nearly the whole solve (43 converge), and at
    // convergence either shooter refines the open back wall one level
    // deeper than asserted below (the interreflected light varies there).
    settings.shooters = Shooters::Patch;
    scene.fill_default_patches(patches);
    let mut solver = Solver::new(&scene, &settings).unwrap();
    while solver.step().is_some() {}
    let mesh = solver.mesh();
    // Solver positions plus this are the importer's (re-centred) coordinates.
    let to_scene = solver.offset();
    let original = to_scene + scene.recentre_offset;
    let surface_of = |normal: DVec3| {
        mesh.surfaces
            .iter()
            .position(|s| s.normal.dot(normal) > 0.999 && s.area > 2.5e5)
            .unwrap()
    };
    let (floor, back) = (surface_of(DVec3::Y), surface_of(-DVec3::Z));
    let light = scene
        .polygons
        .iter()
        .find(|p| scene.materials[p.material].is_emitter())
        .unwrap();
    let occluder = Occluder::from_polygons(&scene.polygons);
    let patch_area = |s: usize| mesh.surfaces[s].area / (patches * patches) as f64;

    // Leaves of a surface with their centroid in original coordinates (mm).
    let leaves = |s: usize| {
        mesh.leaves()
            .map(|e| &mesh.elements[e as usize])
            .filter(move |el| mesh.patches[el.patch as usize].surface as usize == s)
            .map(move |el| {
                let c = el
                    .corners()
                    .iter()
                    .map(|&v| mesh.vertices[v as usize].position)
                    .sum::<DVec3>()
                    / el.corner_count as f64;
                (el, c)
            })
    };

    // The open part of the back wall (above the tall block's shadow, away from
    // the ceiling's 0.1 mm band behind the light's plane and from the side walls)
    // is lit smoothly: it must stay within two splits of its patches (elements
    // of at least 1/16 of a 139 mm patch).
    let mut open = 0;
    for (el, c) in leaves(back) {
        let p = c + original;
        if (150.0..400.0).contains(&p.x) && (330.0..430.0).contains(&p.y) {
            open += 1;
            assert!(
                el.depth <= 2 && el.area >= patch_area(back) / 16.0 * 0.999,
                "back wall element at {p} has depth {} (area {})",
                el.depth,
                el.area
            );
        }
    }
    assert!(open >= 16, "the open region holds {open} leaves");

    // The floor: fine elements (≥ 4 splits below their patch, under 9 mm wide)
    // must lie where the light is partly hidden. Classify each deep leaf by the
    // lit fraction at its corners: a shadow boundary runs through or next to
    // it when the fractions differ or lie strictly between 0 and 1.
    let (mut deep, mut on_boundary, mut coarse_lit) = (0, 0, 0);
    for (el, c) in leaves(floor) {
        let fractions: Vec<f64> = el
            .corners()
            .iter()
            .map(|&v| {
                lit_fraction(
                    &occluder,
                    &light.vertices,
                    mesh.vertices[v as usize].position + to_scene,
                )
            })
            .chain(std::iter::once(lit_fraction(
                &occluder,
                &light.vertices,
                c + to_scene,
            )))
            .collect();
        let all_lit = fractions.iter().all(|&f| f == 1.0);
        let boundary = fractions.iter().any(|&f| f > 0.0 && f < 1.0)
            || fractions.iter().any(|&f| f != fractions[0]);
        if el.depth >= 4 {
            deep += 1;
            if boundary {
                on_boundary += 1;
            }
        } else if all_lit {
            coarse_lit += 1;
        }
    }
    let share = on_boundary as f64 / deep as f64;
    println!(
        "floor: {deep} leaves at depth >= 4, {on_boundary} ({:.0}%) on a penumbra; {coarse_lit} coarse fully lit leaves; \
         {} leaves, {} vertices in all after {} shots",
        100.0 * share,
        solver.progress().elements,
        solver.progress().vertices,
        solver.progress().shots
    );
    // The shadows of both blocks need hundreds of fine elements; nearly all of
    // them must sit on a penumbra (the rest refine the floor's junction with the
    // walls, where the near field of wall patches varies fast).
    assert!(deep >= 200, "only {deep} fine floor elements");
    assert!(
        share >= 0.75,
        "{on_boundary} of {deep} fine floor elements on a shadow boundary"
    );
    assert!(
        coarse_lit >= 16,
        "fully lit floor is meshed finely everywhere"
    );
}
