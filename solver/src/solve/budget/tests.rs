//! The estimate against the solver's real allocations, and the budget's
//! decisions.

use super::*;
use crate::settings::Preset;
use solution::format::SolveMode;
use std::mem::size_of_val;

/// A bundled scene, meshed at `preset`'s settings (`patches` per polygon).
fn bundled(file: &str, preset: Preset, mode: SolveMode, patches: u32) -> (Scene, SolverSettings) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../config")
        .join(file);
    let loaded = crate::scene::load_scene(&path, &Default::default()).unwrap();
    let mut settings = SolverSettings::preset(preset);
    settings.apply(&loaded.settings);
    settings.mode = mode;
    settings.samples = 2;
    let mut scene = loaded.scene;
    scene.fill_default_patches(patches);
    (scene, settings)
}

/// The bytes the solver's per-vertex, per-element and per-patch arrays hold,
/// summed from the vectors themselves (`len` × element size, and the inner
/// vectors of the gather weights), independently of [`Counts`]: what the
/// estimate's mesh (without the vertex table), vertex-state, SH and patch
/// terms model. Directional coefficients are summed vertex by vertex through
/// [`Solver::vertex_sh`].
fn allocated(solver: &mut Solver) -> u64 {
    fn bytes<T>(v: &[T]) -> u64 {
        size_of_val(v) as u64
    }
    let m = &solver.mesh;
    let mut total = bytes(&m.vertices) + bytes(&m.elements) + bytes(&m.split_log);
    total += bytes(&solver.field.radiance)
        + bytes(&solver.field.received)
        + bytes(&solver.field.direct)
        + bytes(&solver.field.visible);
    total += bytes(&solver.field.hidden);
    total += (solver.enclosure.slots() * size_of::<f32>()) as u64;
    total += bytes(&m.patches)
        + bytes(&solver.patches.unshot)
        + bytes(&solver.patches.shoot_area)
        + bytes(&solver.patches.weights);
    for w in &solver.patches.weights {
        total += bytes(w) + HEAP_BLOCK_OVERHEAD;
    }
    if let Some(d) = solver.directional() {
        // Radiance, ΔL and recorded-shot coefficients, and the offset, per vertex.
        for v in 0..m.vertices.len() as u32 {
            let (_, c) = solver.vertex_sh(v).unwrap();
            total += 3 * size_of_val(c) as u64 + size_of::<usize>() as u64;
        }
        // Unshot and shot-sum coefficients and the offset, per patch.
        for p in &m.patches {
            let k = coefficients(d.surface_orders()[p.surface as usize]);
            total += 2 * k * 8 + size_of::<usize>() as u64;
        }
    }
    total
}

/// The estimate's terms that [`allocated`] sums.
fn modelled(solver: &Solver) -> u64 {
    let c = solver.memory_counts();
    let e = estimate(&c);
    e.mesh - table_bytes(c.vertices) + e.vertex_state + e.sh + e.patches
}

/// The diffuse indexes as allocated, against the estimate's index term.
/// The footprint's per-surface lists and the unshot tree are summed from
/// their capacities (the lists are small heap blocks, whose spare capacity is
/// resident): the estimate must give them exactly. The per-surface marks and
/// the touched list change length from shot to shot, and the estimate
/// charges their largest (one `bool` and one `u32` per surface): their
/// lengths are checked against those bounds, and the bounds make up the rest
/// of the term. The small
/// surfaces' index and points (`small.rs`), the twins' table (`twins.rs`)
/// and the sites' tables (`sites.rs`) are summed from their capacities.
fn check_index_term(solver: &Solver) {
    let c = solver.memory_counts();
    let e = estimate(&c);
    let lists = solver.sharing.footprint.surface_vertices.allocated_bytes();
    let tree = solver
        .unshot_tree_allocated()
        .expect("built on the first step");
    let (marked, touched) = solver.sharing.footprint.set_lengths();
    let surfaces = solver.mesh.surfaces.len();
    assert!(marked <= surfaces && touched <= surfaces);
    let bounds = (surfaces * (1 + 4)) as u64;
    let small = solver.sharing.small.allocated_bytes()
        + solver.sharing.twins.allocated_bytes()
        + solver.sharing.sites.allocated_bytes();
    assert_eq!(e.index, lists + tree + bounds + small, "{c:?}");
}

/// Relative difference.
fn off(a: u64, b: u64) -> f64 {
    (a as f64 - b as f64).abs() / b as f64
}

#[test]
fn estimate_matches_the_allocated_state_of_a_diffuse_solve() {
    let (scene, mut settings) = bundled("cornell_box.obj", Preset::Draft, SolveMode::Diffuse, 4);
    settings.max_shots = 12;
    let mut solver = Solver::new(&scene, &settings).unwrap();
    // The terms are sums of the same sizes over the same counts: they agree to
    // rounding (the only modelled-not-measured figure is the heap block
    // overhead, in both).
    assert_eq!(modelled(&solver), allocated(&mut solver));
    while solver.step().is_some() {}
    assert!(solver.mesh.split_log.len() > 10, "the test must refine");
    assert_eq!(modelled(&solver), allocated(&mut solver));
    // The counts a fresh mesh is estimated with before its solver exists:
    // the gather weights are modelled as vertices + 3 per patch, an upper
    // bound on a fresh mesh within 30% (the Cornell box's patches share their
    // edges' vertices: 4 × 4 quads per wall, 25 vertices, 16 patches).
    let fresh = Solver::new(&scene, &settings).unwrap();
    let real = fresh.memory_counts();
    let model = counts_for_mesh(&fresh.mesh, &settings, |_| 0, &[], real.recorded_shots);
    // The footprint's lists before any shot has built them: the same counts
    // from the mesh as the running estimate takes from the lists.
    assert_eq!(
        (model.index_slots, model.index_lists),
        (real.index_slots, real.index_lists)
    );
    assert!(model.weight_entries >= real.weight_entries);
    assert!(off(model.weight_entries, real.weight_entries) < 0.3);
    // Before meshing, quads give exactly N² elements and (N+1)² vertices.
    // The floor's and the ceiling's parts cut along contact lines
    // (`mesh::contact`) include triangles and fans, whose elements are still
    // exact and whose vertices (n+1)² per piece over-counts (a triangle has
    // (n+1)(n+2)/2, a fan shares its diagonals): an upper bound, 13% over
    // here, within 20%.
    let before = counts_before_meshing(&scene, &settings, &cuts_of(&scene, &settings));
    assert_eq!(before.elements, real.elements);
    assert!(before.vertices >= real.vertices);
    assert!(off(before.vertices, real.vertices) < 0.2);
}

/// The footprint index and the unshot tree (diffuse mode) after every shot
/// of a refining solve.
#[test]
fn estimate_matches_the_allocated_indexes_of_a_diffuse_solve() {
    let (scene, mut settings) = bundled("cornell_box.obj", Preset::Draft, SolveMode::Diffuse, 4);
    settings.max_shots = 12;
    let mut solver = Solver::new(&scene, &settings).unwrap();
    let before = solver.memory_estimate();
    assert!(before.index > 0 && before.gather > 0);
    while solver.step().is_some() {
        check_index_term(&solver);
    }
    assert!(solver.mesh.split_log.len() > 10, "the test must refine");
}

/// A directional solve holds neither index: its estimate charges none.
#[test]
fn a_directional_estimate_has_no_diffuse_indexes() {
    let (scene, settings) = bundled(
        "glossy_floor.toml",
        Preset::Draft,
        SolveMode::Directional,
        2,
    );
    let solver = Solver::new(&scene, &settings).unwrap();
    let e = solver.memory_estimate();
    assert_eq!((e.index, e.gather), (0, 0));
}

/// `list_slots` against a real `Vec<u32>` grown one push at a time, as the
/// footprint's lists grow.
#[test]
fn list_slots_follow_vec_growth() {
    let mut list: Vec<u32> = Vec::new();
    assert_eq!(list_slots(0), list.capacity() as u64);
    for n in 1..5000u64 {
        list.push(n as u32);
        assert_eq!(list_slots(n), list.capacity() as u64, "{n} entries");
    }
}

#[test]
fn estimate_matches_the_allocated_state_of_a_directional_solve() {
    let (scene, mut settings) = bundled(
        "glossy_floor.toml",
        Preset::Draft,
        SolveMode::Directional,
        2,
    );
    settings.max_shots = 6;
    let mut solver = Solver::new(&scene, &settings).unwrap();
    let d = solver.directional().unwrap();
    assert!(d.surface_orders().iter().any(|&o| o > 4), "a glossy order");
    assert_eq!(modelled(&solver), allocated(&mut solver));
    while solver.step().is_some() {}
    assert_eq!(modelled(&solver), allocated(&mut solver));
    // The coefficients dominate: the SH term is most of what is held.
    let e = solver.memory_estimate();
    assert!(e.sh > e.mesh + e.vertex_state);
}

/// The scene term against the imported polygons' allocations: the vector of
/// polygons by length (a large vector: its spare capacity is never touched,
/// see the module documentation), and per polygon the heap blocks of its
/// corners, its shading normals and its source reference's path and item
/// name by capacity, each the chunk glibc's malloc takes for it
/// (`heap_chunk`). The model counts lengths (and the item names' doubling
/// growth): the two agree exactly when each block's spare capacity stays
/// within its chunk's rounding.
#[test]
fn scene_bytes_match_the_imported_polygons() {
    for file in ["cornell_box.obj", "glossy_floor.toml", "box_room.toml"] {
        let (scene, _) = bundled(file, Preset::Draft, SolveMode::Diffuse, 4);
        let block = heap_chunk;
        let dvec3 = size_of::<DVec3>();
        let allocated: u64 = (scene.polygons.len() * size_of::<Polygon>()) as u64
            + scene
                .polygons
                .iter()
                .map(|p| {
                    block(p.vertices.capacity() * dvec3)
                        + p.vertex_normals
                            .as_ref()
                            .map_or(0, |n| block(n.capacity() * dvec3))
                        + block(p.source.file.capacity())
                        + block(p.source.item.capacity())
                })
                .sum::<u64>();
        // Exact for the OBJ importer's names; other names' capacities need
        // not be a power of two, so the model may be one 16-byte chunk off a
        // polygon: within 16 bytes per polygon.
        let model = scene_bytes(&scene);
        if file.ends_with(".obj") {
            assert_eq!(model, allocated, "{file}");
        }
        assert!(
            model.abs_diff(allocated) <= 16 * scene.polygons.len() as u64,
            "{file}: {model} against {allocated}"
        );
    }
}

/// The vertex table: its bucket count is the smallest power of two at most
/// 7/8 full, which is hashbrown's rule; checked against a real map grown one
/// entry at a time (its capacity is 7/8 of its buckets).
#[test]
fn vertex_table_buckets_follow_hashbrown() {
    let mut map: std::collections::HashMap<u32, u32> = Default::default();
    for n in 1..5000u64 {
        map.insert(n as u32, 0);
        let buckets = table_buckets(n);
        let capacity = if buckets < 8 {
            buckets - 1
        } else {
            buckets / 8 * 7
        };
        assert_eq!(map.capacity() as u64, capacity, "{n} entries");
    }
}

#[test]
fn budget_caps_the_sh_order_with_the_parseval_error() {
    // 12 patches per side: the full estimate is 17.8 MB, of which the fixed
    // process bytes and the checkpoint's buffers are 9.2 MB; the SH state is
    // what a cap can save.
    let (scene, mut settings) = bundled(
        "glossy_floor.toml",
        Preset::Draft,
        SolveMode::Directional,
        12,
    );
    let wanted = Solver::new(&scene, &settings).unwrap();
    let full = wanted.directional().unwrap().surface_orders().to_vec();
    let top = *full.iter().max().unwrap();
    let full_peak = wanted.memory_estimate().peak();
    // A budget whose order share lies halfway between the unrefined mesh's
    // estimate at SH order 0 (what any cap can reach) and at the full
    // orders: the full orders cannot fit, order 0 fits with room to spare.
    let recorded = emitter_patches(&scene, &wanted.mesh);
    let order_zero = estimate(&counts_for_mesh(
        &wanted.mesh,
        &settings,
        |_| 0,
        &[],
        recorded,
    ))
    .peak();
    assert!(order_zero < full_peak);
    let share = (order_zero + full_peak) / 2;
    let limit = (share as f64 / (PLANNING_FRACTION * ORDER_SHARE)) as u64;
    settings.memory_budget = Some(limit);
    let capped = Solver::new(&scene, &settings).unwrap();
    let kept = capped.directional().unwrap().surface_orders().to_vec();
    let kept_top = *kept.iter().max().unwrap();
    assert!(kept_top < top, "{kept_top} < {top}");
    assert!(capped.memory_estimate().peak() <= (plan(limit) as f64 * ORDER_SHARE) as u64);
    let warning = capped
        .warnings()
        .iter()
        .find(|w| w.contains("keeps L ="))
        .expect("a cap warning");
    assert!(
        warning.contains(&format!("keeps L = {kept_top}")),
        "{warning}"
    );
    assert!(warning.contains("blurred"), "{warning}");
    // The energy in the dropped bands, from the lobe's Legendre coefficients
    // directly: 1 − Σ_{l ≤ L} a_l² 2/(2l+1) / Σ_all a_l² 2/(2l+1).
    let alpha = scene
        .materials
        .iter()
        .find(|m| m.is_glossy())
        .unwrap()
        .alpha;
    let fit = crate::brdf::LegendreFit::new(alpha, kept_top);
    let energy = |l: usize, a: &f64| a * a * 2.0 / (2.0 * l as f64 + 1.0);
    let kept_energy: f64 = fit.coefficients[..=kept_top as usize]
        .iter()
        .enumerate()
        .map(|(l, a)| energy(l, a))
        .sum();
    let dropped = 1.0 - kept_energy / fit.norm_squared;
    let percent = format!("hold {:.1}% of the lobe's energy", 100.0 * dropped);
    assert!(warning.contains(&percent), "{warning} / {percent}");
}

#[test]
fn refinement_stays_within_the_planned_budget() {
    let (scene, mut settings) = bundled("cornell_box.obj", Preset::Draft, SolveMode::Diffuse, 4);
    settings.max_shots = 40;
    let free = Solver::new(&scene, &settings).unwrap();
    let start = free.memory_estimate().peak();
    // Room for a few dozen splits past the unrefined mesh.
    let limit = ((start + 30 * split_cost(0, false)) as f64 / PLANNING_FRACTION) as u64;
    settings.memory_budget = Some(limit);
    let mut solver = Solver::new(&scene, &settings).unwrap();
    let mut warnings = Vec::new();
    while solver.step().is_some() {
        // The invariant the budget keeps: after every refinement the estimate
        // is within the plan.
        let c = solver.memory_counts();
        assert!(
            solver.memory_estimate().peak() <= plan(limit),
            "{} > {}: {c:?} {:?}",
            solver.memory_estimate().peak(),
            plan(limit),
            solver.memory_estimate()
        );
        warnings.extend(solver.take_warnings());
    }
    assert_eq!(warnings.len(), 1, "warned once: {warnings:?}");
    assert!(
        warnings[0].contains("refinement stopped"),
        "{}",
        warnings[0]
    );
    assert!(solver.peak_memory_estimate() <= plan(limit));
    // Without the budget the same solve refines further.
    settings.memory_budget = None;
    let mut unbounded = Solver::new(&scene, &settings).unwrap();
    while unbounded.step().is_some() {}
    assert!(unbounded.mesh.split_log.len() > solver.mesh.split_log.len());
}

#[test]
fn a_scene_that_cannot_fit_is_refused_with_the_estimate_and_the_budget() {
    let (scene, mut settings) = bundled("cornell_box.obj", Preset::Draft, SolveMode::Diffuse, 4);
    settings.memory_budget = Some(4 << 20);
    let err = Solver::new(&scene, &settings).err().expect("refused");
    let text = err.to_string();
    assert!(matches!(err, super::super::SolveError::OverBudget(_)));
    assert!(text.contains("exceeds the memory budget 4.0 MiB"), "{text}");
    assert!(text.contains("estimated peak"), "{text}");
    assert!(text.contains("before meshing"), "{text}");
    assert!(text.contains("--memory-budget"), "{text}");
}

/// The fixed term starts from the larger of the process and scene as
/// modelled and the resident set measured before meshing, which import's
/// freed but kept pages can make larger (the 1M floor plan: 254 MiB against
/// 68 MiB). Every other term is the same, and so is every estimate before
/// and after meshing, by that difference; a measured set below the model
/// changes nothing.
#[test]
fn the_fixed_term_starts_from_the_resident_set_measured_before_meshing() {
    let (scene, settings) = bundled("cornell_box.obj", Preset::Draft, SolveMode::Diffuse, 4);
    let modelled = Solver::new(&scene, &settings).unwrap().memory_estimate();
    let before = FIXED_BYTES + scene_bytes(&scene);
    for (resident, extra) in [(before + (100 << 20), 100 << 20), (before / 2, 0)] {
        let mut measured_settings = settings.clone();
        measured_settings.resident_before_meshing = Some(resident);
        let solver = Solver::new(&scene, &measured_settings).unwrap();
        let measured = solver.memory_estimate();
        assert_eq!(measured.fixed, modelled.fixed + extra);
        assert_eq!(measured.peak(), modelled.peak() + extra);
        let c = counts_before_meshing(
            &scene,
            &measured_settings,
            &cuts_of(&scene, &measured_settings),
        );
        let c0 = counts_before_meshing(&scene, &settings, &cuts_of(&scene, &settings));
        assert_eq!(estimate(&c).peak(), estimate(&c0).peak() + extra);
    }
}

/// The per-surface term against the tables a solver really holds per
/// surface, summed from the structures themselves (by length, the heap
/// blocks of the surfaces' corners included). The Cornell box's 30 surfaces
/// are quads, as the term assumes, but three of them weld two polygons into
/// six pieces and some hold shading normals; its BVH is too small for the
/// node share to settle, so the tolerance is 15% (measured: 3.8% under; on
/// the 10k Cornell boxes, 5,003 surfaces, the tables hold 939 bytes a
/// surface against the term's 944).
#[test]
fn surface_term_matches_the_allocated_per_surface_structures() {
    let (scene, settings) = bundled("cornell_box.obj", Preset::Draft, SolveMode::Diffuse, 4);
    let solver = Solver::new(&scene, &settings).unwrap();
    let m = &solver.mesh;
    let corners: u64 = m
        .surfaces
        .iter()
        .map(|s| {
            heap_chunk(size_of_val(s.vertices.as_slice()))
                + s.corner_normals
                    .as_ref()
                    .map_or(0, |n| heap_chunk(size_of_val(n.as_slice())))
                + heap_chunk(size_of_val(s.apexes.as_slice()))
        })
        .sum();
    let mesh = (size_of_val(m.surfaces.as_slice())
        + size_of_val(m.pieces.as_slice())
        + size_of_val(m.piece_patches.as_slice())) as u64
        + corners;
    let tables = (size_of_val(solver.materials.kd.as_slice())
        + size_of_val(solver.materials.albedo.as_slice())
        + size_of_val(solver.materials.emission.as_slice())
        + size_of_val(solver.patches.of_surface.as_slice())
        + size_of_val(solver.materials.texturing.per_surface.as_slice())) as u64;
    let allocated = mesh
        + tables
        + solver.occluder.allocated_bytes()
        + solver.groups.receivers.allocated_bytes();
    let modelled = m.surfaces.len() as u64 * surface_bytes();
    assert!(
        off(modelled, allocated) < 0.15,
        "modelled {modelled} B, allocated {allocated} B over {} surfaces",
        m.surfaces.len()
    );
}

/// A grouped shot's bytes are counted where shots are grouped: with
/// `--shooters grouped`, in a diffuse solve and in a directional one (which
/// groups its order-0 sources, `directional/group.rs`), not with the patch
/// shooter.
#[test]
fn the_group_term_follows_what_the_solve_shoots() {
    for (mode, shooters, grouped) in [
        (SolveMode::Diffuse, crate::settings::Shooters::Grouped, true),
        (SolveMode::Diffuse, crate::settings::Shooters::Patch, false),
        (
            SolveMode::Directional,
            crate::settings::Shooters::Grouped,
            true,
        ),
        (
            SolveMode::Directional,
            crate::settings::Shooters::Patch,
            false,
        ),
    ] {
        let (scene, mut settings) = bundled("cornell_box.obj", Preset::Draft, mode, 2);
        settings.shooters = shooters;
        assert_eq!(
            counts_before_meshing(&scene, &settings, &cuts_of(&scene, &settings)).grouped,
            grouped,
            "{mode:?}, {shooters:?}"
        );
        let with = estimate(&counts_before_meshing(
            &scene,
            &settings,
            &cuts_of(&scene, &settings),
        ))
        .shot;
        settings.shooters = crate::settings::Shooters::Patch;
        let without = estimate(&counts_before_meshing(
            &scene,
            &settings,
            &cuts_of(&scene, &settings),
        ))
        .shot;
        assert_eq!(with > without, grouped, "{mode:?}, {shooters:?}");
    }
}
