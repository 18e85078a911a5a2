//! Small flat surfaces receive one sample per shot (issue 13: a scene's cost
//! follows what it needs to show, not how many polygons it was exported
//! with).
//!
//! A flat surface that is one patch whose longest edge is already within its
//! smallest element size is one element that refinement never splits
//! (`refine::Criteria::at_smallest`): the solution resolves nothing inside
//! it. Receiving a shot at each of its vertices then buys no detail the mesh
//! can keep, only four noisy point samples of a field that varies over the
//! face by less than the mesh's own resolution. Such a surface receives once,
//! at its area centroid with its facet normal and the shooter's usual rays,
//! and every vertex of it gets that ΔL: an estimate of the face's mean, exact
//! in its factor and traced like any receiver.
//!
//! On a floor of small boxes (the scale scenes' 1M Cornell boxes: faces of
//! 0.5–1 mm against a 25 mm smallest element at `draft`) this is one
//! receiver per face instead of four, and the shot's cost, which every
//! receiver pays, falls with it. No surface of the Cornell box qualifies (its
//! smallest face is 165 mm), so its solves do not change by a bit.
//!
//! What it changes: each such face is flat-shaded shot by shot, where its
//! four vertices used to carry their own samples' noise. The energy
//! bookkeeping is untouched: the vertices' ΔL is gathered into the patch
//! as any receiver's (test `small_surfaces_lose_no_energy`). Smooth
//! surfaces keep per-vertex receiving, since their vertices' shading normals
//! differ.
//!
//! Directional mode receives the same way (`directional/shot.rs`,
//! `receive_all`): a small face's one sample is its SH for all its vertices.
//! On boxes on a glossy floor, where the boxes' faces are most receivers,
//! that took the draft solve at 100k triangles from 248 to 81 CPU s
//! (docs/lab/glossy-grouped-shooters.md, "Small surfaces receive once").

use super::shoot::ReceivingPoint;
use crate::mesh::Mesh;

/// A surface's entry in [`SmallSurfaces::index`] when it is not small.
const NOT_SMALL: u32 = u32::MAX;

/// The small flat surfaces of a mesh and where each receives.
#[derive(Default)]
pub struct SmallSurfaces {
    /// Per surface: its index in `points`, or [`NOT_SMALL`].
    index: Vec<u32>,
    /// Per small surface, in increasing surface order: its receiving point.
    points: Vec<ReceivingPoint>,
}

/// Whether a surface whose patches are `patches` is one patch that
/// refinement never splits: the test refinement applies
/// (`refine::Criteria::at_smallest`) to its root element, its longest edge
/// within the surface's absolute smallest element size.
pub(super) fn one_small_patch(mesh: &Mesh, patches: &std::ops::Range<u32>) -> bool {
    if patches.len() != 1 {
        return false;
    }
    let patch = &mesh.patches[patches.start as usize];
    match mesh.surfaces[patch.surface as usize].min_element_size {
        Some(size) => super::refine::longest_edge(mesh, patch.root) <= size,
        None => false,
    }
}

impl SmallSurfaces {
    /// The surfaces of `mesh` that receive once per shot (see the module
    /// documentation); `patches[s]` is surface `s`'s patch count.
    pub fn new(mesh: &Mesh, patches: &[std::ops::Range<u32>]) -> SmallSurfaces {
        let mut small = SmallSurfaces {
            index: vec![NOT_SMALL; mesh.surfaces.len()],
            points: Vec::new(),
        };
        for (s, surface) in mesh.surfaces.iter().enumerate() {
            if surface.corner_normals.is_some() || !one_small_patch(mesh, &patches[s]) {
                continue;
            }
            small.index[s] = small.points.len() as u32;
            small.points.push(ReceivingPoint {
                q: super::cluster::polygon_centroid(&surface.vertices, surface.normal),
                n: surface.normal,
                surface: s as u32,
                // A stream above every vertex id in practice, so that no
                // vertex shares its random numbers.
                stream: u32::MAX - s as u32,
            });
        }
        small.points.shrink_to_fit();
        small
    }

    /// The bytes the index and the points hold as allocated (tests of the
    /// memory estimate).
    #[cfg(test)]
    pub fn allocated_bytes(&self) -> u64 {
        (self.index.capacity() * std::mem::size_of::<u32>()
            + self.points.capacity() * std::mem::size_of::<ReceivingPoint>()) as u64
    }

    /// Surface `s`'s index among the small surfaces, if it is one.
    pub fn of(&self, s: u32) -> Option<usize> {
        match self.index.get(s as usize) {
            Some(&k) if k != NOT_SMALL => Some(k as usize),
            _ => None,
        }
    }

    /// The small surfaces' receiving points, in increasing surface order.
    pub fn points(&self) -> &[ReceivingPoint] {
        &self.points
    }

    /// How many surfaces receive once per shot.
    pub(super) fn len(&self) -> usize {
        self.points.len()
    }

    /// The bytes the index holds per surface, and per small surface its
    /// receiving point (the memory estimate, `budget.rs`).
    pub fn bytes(surfaces: u64, small: u64) -> u64 {
        surfaces * std::mem::size_of::<u32>() as u64
            + small * std::mem::size_of::<ReceivingPoint>() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::super::physics_tests::{cube, floor_patch_nearest, lit_room_with};
    use super::super::tests::{material, scene_of};
    use super::super::Solver;
    use crate::scene::{Scene, PATCHES_UNSET};
    use crate::settings::{Preset, Shooters, SolverSettings};
    use crate::solve::checkpoint::Checkpoint;
    use glam::DVec3;
    use solution::format::SolveMode;
    use std::f64::consts::PI;

    /// Howell's catalogue B-3: a differential area at height `h` under one
    /// corner of a parallel rectangle `a` × `b`, facing it.
    fn under_corner(a: f64, b: f64, h: f64) -> f64 {
        let (x, y) = (a / h, b / h);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
    }

    fn settings() -> SolverSettings {
        let mut s = SolverSettings::preset(Preset::Draft);
        s.ambient = false;
        s.adaptive = false;
        s
    }

    /// A 1 mm square receiver (Kd 0.5) facing up at (x0, 0, z0), under a
    /// 200 mm square emitter (Le 1, black) 100 mm above, centred on the axis.
    fn square_under_light(x0: f64, z0: f64) -> Scene {
        let square = |y: f64, half: f64, cx: f64, cz: f64, up: bool| {
            let mut q = vec![
                DVec3::new(cx - half, y, cz - half),
                DVec3::new(cx - half, y, cz + half),
                DVec3::new(cx + half, y, cz + half),
                DVec3::new(cx + half, y, cz - half),
            ];
            if !up {
                q.reverse();
            }
            q
        };
        scene_of(
            vec![
                (square(0.0, 0.5, x0, z0, true), 0),
                (square(100.0, 100.0, 0.0, 0.0, false), 1),
            ],
            vec![material("receiver", 0.5, 0.0), material("light", 0.0, 1.0)],
            PATCHES_UNSET,
        )
    }

    #[test]
    fn a_small_surface_receives_the_exact_factor_at_its_centroid() {
        // The only light the receiver gets is the emitter's direct light, with
        // nothing in between, so every vertex's L = ρ Le F(c ← emitter) at the
        // receiver's centroid c: the emitter split into patches as the sizes
        // ask, each factor exact (contour integral, ~1e-13) and every ray
        // visible. F by Howell B-3, four rectangles meeting under c. 1e-9
        // relative: the sum over the emitter's patches of exact factors.
        let (x0, z0, h, a) = (30.0, 20.0, 100.0, 100.0);
        let exact = 0.5
            * (under_corner(a - x0, a - z0, h)
                + under_corner(a + x0, a - z0, h)
                + under_corner(a - x0, a + z0, h)
                + under_corner(a + x0, a + z0, h));
        let scene = square_under_light(x0, z0);
        let modes = [SolveMode::Diffuse, SolveMode::Directional];
        for (shooters, mode) in [Shooters::Patch, Shooters::Grouped]
            .into_iter()
            .flat_map(|s| modes.map(|m| (s, m)))
        {
            let mut s = settings();
            s.shooters = shooters;
            s.mode = mode;
            let mut solver = Solver::new(&scene, &s).unwrap();
            assert_eq!(solver.small_surface_count(), 1, "the 1 mm receiver only");
            while solver.step().is_some() {}
            let receiver: Vec<DVec3> = (0..solver.mesh().vertices.len())
                .filter(|&v| solver.mesh().vertices[v].surface == 0)
                .map(|v| solver.vertex_radiance()[v])
                .collect();
            assert_eq!(receiver.len(), 4);
            for l in &receiver {
                assert_eq!(*l, receiver[0], "{shooters:?} {mode:?}: one sample for all");
                let error = (l.x - exact).abs() / exact;
                assert!(
                    error < 1e-9,
                    "{shooters:?} {mode:?}: {} against {exact}",
                    l.x
                );
            }
        }
    }

    /// A closed 1 m room (Kd 0.5) lit by a ceiling panel, with 16 boxes of
    /// 20 mm (Kd 0.7) on its floor: their faces are within the draft
    /// preset's smallest element (0.026 of the 1.7 m diagonal, 45 mm).
    fn room_with_small_boxes() -> Scene {
        let mut faces = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                let offset = DVec3::new(200.0 + 200.0 * i as f64, 0.0, 200.0 + 200.0 * j as f64);
                for (mut face, _) in cube(20.0, offset) {
                    face.reverse();
                    faces.push(face);
                }
            }
        }
        lit_room_with(faces, "boxes")
    }

    #[test]
    fn small_faces_join_a_group_by_their_radiance() {
        // A floor patch of the room seeds a group with unshot radiance 1; the
        // boxes' faces have 0.5, but each holds 400 mm² against the patch's
        // 62,500, so under a tenth of its power. By power alone none joins
        // (the walls' groups of a few dozen patches at 1M boxes); as small
        // faces a tenth as bright as the seed, those within the group radius
        // do. The control: faces at 0.09, under a tenth of the seed's
        // radiance, do not.
        let scene = room_with_small_boxes();
        for (face_unshot, joins) in [(0.5, true), (0.09, false)] {
            let mut s = settings();
            s.shooters = Shooters::Grouped;
            let mut solver = Solver::new(&scene, &s).unwrap();
            let faces: Vec<u32> = (0..solver.mesh.patches.len() as u32)
                .filter(|&p| {
                    solver.materials.kd[solver.mesh.patches[p as usize].surface as usize].x == 0.7
                })
                .collect();
            solver.patches.unshot.fill(DVec3::ZERO);
            for &p in &faces {
                solver.patches.unshot[p as usize] = DVec3::splat(face_unshot);
            }
            let floor = floor_patch_nearest(&solver, DVec3::new(500.0, 0.0, 500.0));
            // Unshot power π U A: the seed's with U = 1, a face's with 0.5.
            let seed_power = solver.patches.shoot_area[floor as usize];
            let face_power = 0.5 * solver.patches.shoot_area[faces[0] as usize];
            assert!(face_power < 0.1 * seed_power, "{face_power} {seed_power}");
            let members = solver.take_group(floor, DVec3::ONE);
            let joined = members.map_or(0, |m| m.iter().filter(|(p, _)| faces.contains(p)).count());
            if joins {
                assert!(joined >= 4 * 5, "{joined} faces joined");
            } else {
                assert_eq!(joined, 0);
            }
        }
    }

    #[test]
    fn small_surfaces_lose_no_energy() {
        // Emitted + reflected = shot + unshot (the bookkeeping of
        // `progressive_shooting_loses_no_energy`), to 1e-9 of the emitted power:
        // one sample's ΔL on all of a face's vertices is gathered into its
        // patch like any vertex's.
        let scene = room_with_small_boxes();
        for shooters in [Shooters::Patch, Shooters::Grouped] {
            let mut s = settings();
            s.shooters = shooters;
            s.threshold = 0.01;
            let mut solver = Solver::new(&scene, &s).unwrap();
            // Every box face, and the floor's piece under each box (its
            // contact cut, `mesh::contact`).
            assert_eq!(solver.small_surface_count(), 16 * 6 + 16);
            while solver.step().is_some() {}
            let emitted = solver.stats.emitted_power;
            let left = solver.total_unshot_power();
            let mut reflected = 0.0;
            for (p, patch) in solver.mesh.patches.iter().enumerate() {
                let surface = patch.surface as usize;
                let le = solver.materials.emission[surface];
                for &(v, w) in solver.patch_weights(p as u32) {
                    if !solver.hidden_vertices()[v as usize] {
                        let gained = solver.field.radiance[v as usize] - le;
                        reflected += PI * w * gained.element_sum();
                    }
                }
            }
            let shot = solver.timings().shot_power;
            let balance = (emitted + reflected) - (shot + left);
            assert!(
                balance.abs() <= 1e-9 * emitted,
                "{shooters:?}: emitted {emitted} + reflected {reflected} vs shot {shot} + \
                 unshot {left}: off by {balance}"
            );
        }
    }

    #[test]
    fn a_directional_solve_with_small_surfaces_resumes_bit_for_bit() {
        // A small face's vertices take its one sample in directional mode
        // too (a resume recomputes their recorded part at the face's point,
        // as the solve received it): the room with small boxes, its walls
        // glossy, checkpointed after 4 shots and resumed, gives the same
        // bits after 8 as a solve never stopped.
        let mut scene = room_with_small_boxes();
        for m in &mut scene.materials {
            if m.name == "walls" {
                m.ks = DVec3::splat(0.3);
                m.alpha = 0.2;
            }
        }
        let mut s = settings();
        s.mode = SolveMode::Directional;
        s.shooters = Shooters::Grouped;
        // Refinement reads each vertex's recorded part (`direct`).
        s.adaptive = true;
        let solve = |shots: usize| {
            let mut solver = Solver::new(&scene, &s).unwrap();
            for _ in 0..shots {
                solver.step();
            }
            solver
        };
        let (straight, first) = (solve(8), solve(4));
        assert!(straight.small_surface_count() > 0);
        assert!(!straight.mesh.split_log.is_empty(), "the room refined");
        let mut resumed = Solver::resume(&scene, &s, Checkpoint::round_trip(&first)).unwrap();
        for _ in 0..4 {
            resumed.step();
        }
        super::super::tests::assert_same_directional_bits(&straight, &resumed);
    }
}
