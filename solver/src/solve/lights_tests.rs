//! The lights' shot against closed forms (issue 41, "Must show"): the
//! inverse-square law of a point lamp, a spot's cone, the sun's cosine law
//! and the area of a shadow, a uniform and a CIE overcast sky on open
//! planes; and a resumed solve with lights ends as an uninterrupted one.
//!
//! The scenes are open: a floor facing up and, below it, a small square
//! facing down, which nothing reaches (the solver wants two polygons). The
//! floor cannot light itself, so its radiance is the lights' direct ρE/π.

use super::tests::{material, scene_of};
use super::*;
use crate::light::lamp::Lamp;
use crate::light::sky::{BelowHorizon, Sky, SkyModel};
use crate::light::sun::{Sun, SunPosition};
use crate::light::Lights;
use crate::settings::Preset;

const RHO: f64 = 0.5;

/// A square floor of side `2 half` at height 0 (scene units), facing +y,
/// and a small square below it facing −y; `extra` polygons are added.
pub(super) fn open_floor(half: f64, extra: Vec<(Vec<DVec3>, usize)>, lights: Lights) -> Scene {
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z) * half;
    let mut polygons = vec![
        (
            vec![
                v(-1., 0., 1.),
                v(1., 0., 1.),
                v(1., 0., -1.),
                v(-1., 0., -1.),
            ],
            0,
        ),
        (
            vec![
                v(-0.1, -1., -0.1),
                v(0.1, -1., -0.1),
                v(0.1, -1., 0.1),
                v(-0.1, -1., 0.1),
            ],
            0,
        ),
    ];
    polygons.extend(extra);
    let mut scene = scene_of(polygons, vec![material("grey", RHO, 0.0)], 8);
    scene.lights = lights;
    scene
}

fn settings() -> SolverSettings {
    let mut s = SolverSettings::preset(Preset::Draft);
    s.ambient = false;
    s
}

/// The floor's (surface 0's) vertices and their radiance, each at the point its rays
/// leave from: its receiving point, 1e-3 of the way toward the centroid of
/// an element it belongs to (`shoot.rs`, `INWARD_STEP`), lifted by the
/// occluder's epsilon along the normal. In a spot's ramp that step alone
/// moves L by about 1%, so the laws are checked where they were applied.
fn floor_vertices(solver: &Solver) -> Vec<(DVec3, DVec3)> {
    let offset = solver.offset();
    let mesh = solver.mesh();
    (0..mesh.vertices.len() as u32)
        .filter(|&v| mesh.vertices[v as usize].surface == 0)
        .map(|v| {
            let epsilon = solver.occluder.scene_epsilon();
            let (q, n) = super::shoot::receiving_point(mesh, v, epsilon);
            (
                q + n * epsilon + offset,
                solver.vertex_radiance()[v as usize],
            )
        })
        .collect()
}

fn solved(scene: &Scene, settings: &SolverSettings) -> Solver {
    let mut solver = Solver::new(scene, settings).unwrap();
    while solver.step().is_some() {}
    solver
}

fn lamp_lights(lamp: Lamp) -> Lights {
    Lights {
        lamps: vec![lamp],
        ..Lights::default()
    }
}

/// The tolerance of the exact (one-ray) lamp tests, evaluated where the
/// rays leave ([`floor_vertices`]): rounding only, in f64; 1e-9 is far
/// above it and far below any error of the law.
const LIFT_TOLERANCE: f64 = 1e-9;

#[test]
fn point_lamp_follows_the_inverse_square_law_in_any_units() {
    // E = I cos θ / d² (metres), so L = ρ I cos θ / (π d²), at every floor
    // vertex; the same lamp in a scene modelled in millimetres gives the same.
    let intensity = DVec3::new(1.0, 2.0, 3.0);
    for units_per_metre in [1.0, 1000.0] {
        let at = DVec3::new(0.3, 2.0, -0.4) * units_per_metre;
        let lamp = Lamp::point("bulb", at, intensity, 0.0).unwrap();
        let mut scene = open_floor(5.0 * units_per_metre, Vec::new(), lamp_lights(lamp));
        scene.units_per_metre = units_per_metre;
        let solver = solved(&scene, &settings());
        let floor = floor_vertices(&solver);
        assert!(floor.len() > 50, "{} floor vertices", floor.len());
        for (p, l) in floor {
            let d = (at - p) / units_per_metre;
            let cos = d.y / d.length();
            let expected = RHO * intensity * cos / (PI * d.length_squared());
            let error = ((l - expected) / expected).abs().max_element();
            assert!(error < LIFT_TOLERANCE, "at {p}: {l} against {expected}");
        }
    }
}

#[test]
fn spot_lamp_is_full_inside_dark_outside_and_ramps_between() {
    // The cone of KHR_lights_punctual: saturate((cos θ − cos outer) /
    // (cos inner − cos outer))² times the point lamp's law.
    let at = DVec3::new(0.0, 2.0, 0.0);
    let lamp = Lamp::point("spot", at, DVec3::ONE, 0.0)
        .unwrap()
        .with_spot(DVec3::NEG_Y, 20.0, 30.0)
        .unwrap();
    let solver = solved(&open_floor(3.0, Vec::new(), lamp_lights(lamp)), &settings());
    let (ci, co) = (20f64.to_radians().cos(), 30f64.to_radians().cos());
    let (mut inside, mut outside, mut ramp) = (0, 0, 0);
    for (p, l) in floor_vertices(&solver) {
        let d = at - p;
        let cos = d.y / d.length();
        let t = ((cos - co) / (ci - co)).clamp(0.0, 1.0);
        let expected = RHO * cos * t * t / (PI * d.length_squared());
        if expected == 0.0 {
            assert_eq!(l, DVec3::ZERO, "outside the cone at {p}");
            outside += 1;
        } else {
            assert!(
                (l.x / expected - 1.0).abs() < LIFT_TOLERANCE,
                "at {p}: {l} against {expected}"
            );
            if t < 1.0 {
                ramp += 1;
            } else {
                inside += 1;
            }
        }
    }
    assert!(
        inside > 5 && outside > 5 && ramp > 5,
        "{inside} {outside} {ramp}"
    );
}

pub(super) fn sun_lights(elevation_deg: f64, irradiance: f64) -> Lights {
    let e = elevation_deg.to_radians();
    let toward = DVec3::new(e.cos() * 0.6, e.sin(), e.cos() * 0.8);
    let position = SunPosition::from_direction(toward).unwrap();
    Lights {
        sun: Some(Sun::new(position, DVec3::splat(irradiance), 0.53).unwrap()),
        ..Lights::default()
    }
}

#[test]
fn sun_lights_an_open_plane_by_the_cosine_law_and_a_shadow_has_its_area() {
    // E = E⊥ sin(elevation) on the floor, as the mean of cos θ over the
    // disc's directions: they differ from its centre by at most 0.27°
    // (4.6e-3 rad), which moves cos θ by at most 4.6e-3 · sin 40° / cos 40°
    // = 3.9e-3 relative, and the stratified mean of 16 samples of a linear
    // function of the direction lies far closer to the centre's value:
    // 2e-3 bounds it. A square of side s floating above the floor
    // casts a shadow whose missing light ∫ (L_lit − L) dA / L_lit is s²
    // exactly for a parallel light, penumbra included (the disc's blur
    // moves light, it does not remove it). Integrated over the refined
    // elements with linear interpolation, 3% allows for the elements along
    // the shadow's edge that still straddle it at draft.
    // The floor's 1 m patches put vertices inside the 2 m shadow, so that
    // refinement finds it (a shadow between vertices is invisible to them).
    let (elevation, irradiance, side) = (50.0f64, 100.0, 2.0);
    let lit = RHO * irradiance * elevation.to_radians().sin() / PI;
    let blocker = vec![
        DVec3::new(-1.0, 1.0, -1.0),
        DVec3::new(-1.0, 1.0, 1.0),
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(1.0, 1.0, -1.0),
    ];
    let scene = open_floor(4.0, vec![(blocker, 0)], sun_lights(elevation, irradiance));
    let solver = solved(&scene, &settings());
    let floor = floor_vertices(&solver);
    let open = floor
        .iter()
        .filter(|(_, l)| (l.x / lit - 1.0).abs() < 2e-3)
        .count();
    assert!(
        open > floor.len() / 2,
        "{open} of {} vertices lit fully",
        floor.len()
    );
    let mesh = solver.mesh();
    let radiance = solver.vertex_radiance();
    let mut missing = 0.0;
    for el in mesh.elements.iter().filter(|e| e.is_leaf()) {
        let corners = el.corners();
        let on_floor = corners.iter().all(|&c| {
            (mesh.vertices[c as usize].position + solver.offset())
                .y
                .abs()
                < 1e-9
        });
        if on_floor {
            let mean =
                corners.iter().map(|&c| radiance[c as usize].x).sum::<f64>() / corners.len() as f64;
            missing += el.area * (lit - mean) / lit;
        }
    }
    let expected = side * side;
    println!("shadow: missing light {missing:.4} m² against {expected} m²");
    assert!(
        (missing / expected - 1.0).abs() < 0.03,
        "shadow area {missing} against {expected}"
    );
}

/// The mean over the floor's vertices of L / (ρ E_expected / π), and the
/// vertex count.
fn mean_ratio(solver: &Solver, irradiance: f64) -> (f64, usize) {
    let floor = floor_vertices(solver);
    let expected = RHO * irradiance / PI;
    let sum: f64 = floor.iter().map(|(_, l)| l.x / expected).sum();
    (sum / floor.len() as f64, floor.len())
}

fn sky_lights(model: SkyModel, up: DVec3) -> Lights {
    Lights {
        sky: Some(Sky::new(model, up, BelowHorizon::Black, None).unwrap()),
        ..Lights::default()
    }
}

#[test]
fn uniform_sky_gives_pi_l_on_an_open_plane_and_less_when_tilted() {
    // Level: E = πL, and every cosine-distributed sample carries L, so the
    // estimate is exact (1e-12 for rounding). Tilted by β (the sky's up
    // turned instead of the plane): E = πL (1 + cos β) / 2. Each sample is
    // then L or 0 with p = (1 + cos β)/2, so a vertex's relative standard
    // error is at most √((1 − p)/(p N)) with N = 8 · samples rays
    // (stratification only lowers it); the mean over n vertices, whose
    // streams are independent, is within 4 of those over √n.
    let radiance = 2.0;
    let level = sky_lights(SkyModel::uniform(DVec3::splat(radiance)).unwrap(), DVec3::Y);
    let solver = solved(&open_floor(2.0, Vec::new(), level), &settings());
    for (p, l) in floor_vertices(&solver) {
        let expected = RHO * radiance;
        assert!((l.x / expected - 1.0).abs() < 1e-12, "at {p}: {l}");
    }
    let beta = 60f64.to_radians();
    let up = DVec3::new(beta.sin(), beta.cos(), 0.0);
    let tilted = sky_lights(SkyModel::uniform(DVec3::splat(radiance)).unwrap(), up);
    let solver = solved(&open_floor(2.0, Vec::new(), tilted), &settings());
    let p = (1.0 + beta.cos()) / 2.0;
    let (ratio, n) = mean_ratio(&solver, PI * radiance * p);
    let rays = (8 * settings().samples) as f64;
    let sigma = ((1.0 - p) / (p * rays)).sqrt() / (n as f64).sqrt();
    println!("uniform sky tilted 60°: mean ratio {ratio:.5}, σ {sigma:.5}, {n} vertices");
    assert!(
        (ratio - 1.0).abs() < 4.0 * sigma,
        "ratio {ratio}, σ {sigma}, {n} vertices"
    );
}

#[test]
fn cie_overcast_sky_gives_seven_ninths_pi_lz_on_an_open_plane() {
    // E = 7πL_z/9 (Moon and Spencer's sky). A cosine-distributed sample
    // carries L_z (1 + 2 cos θ)/3, whose relative standard deviation under
    // that density is (2/3)√(1/18) / (7/9) = 0.20; per vertex over N rays
    // 0.20/√N, and the mean over n independent vertices within 4 of that
    // over √n.
    let lz = 3.0;
    let sky = sky_lights(SkyModel::cie_overcast(DVec3::splat(lz)).unwrap(), DVec3::Y);
    let solver = solved(&open_floor(2.0, Vec::new(), sky), &settings());
    let (ratio, n) = mean_ratio(&solver, 7.0 * PI * lz / 9.0);
    let rays = (8 * settings().samples) as f64;
    let sigma = 0.20 / (rays * n as f64).sqrt();
    println!("CIE overcast: mean ratio {ratio:.5}, σ {sigma:.5}, {n} vertices");
    assert!(
        (ratio - 1.0).abs() < 4.0 * sigma,
        "ratio {ratio}, σ {sigma}, {n} vertices"
    );
}

#[test]
fn a_scene_without_emitter_or_light_is_refused_naming_the_light_options() {
    let err = Solver::new(&open_floor(1.0, Vec::new(), Lights::default()), &settings())
        .err()
        .unwrap();
    let text = err.to_string();
    assert!(text.contains("[sun]") && text.contains("--sky"), "{text}");
}

#[test]
fn lights_in_a_closed_room_converge_and_resume_bit_identically() {
    // A lamp inside a closed cube: the lights shoot first, their reflected
    // light then converges as an emitter's (unshot fraction below the
    // threshold of the power they put in), and a solve resumed after three
    // shots ends with the same bits as one never interrupted.
    let mut scene = scene_of(
        super::physics_tests::cube(1.0, DVec3::ZERO),
        vec![material("wall", 0.5, 0.0)],
        2,
    );
    let lamp = Lamp::point("bulb", DVec3::new(0.4, 0.6, 0.5), DVec3::ONE, 0.05).unwrap();
    scene.lights = lamp_lights(lamp);
    let mut s = settings();
    s.threshold = 0.01;
    let whole = solved(&scene, &s);
    let p = whole.progress();
    assert!(p.unshot_fraction < 0.01 && p.shots > 5, "{p:?}");
    let mut first = Solver::new(&scene, &s).unwrap();
    let report = first.step().unwrap();
    assert_eq!(report.source, None, "the lights shoot first");
    first.step().unwrap();
    first.step().unwrap();
    let state = super::Checkpoint::round_trip(&first);
    let mut resumed = Solver::resume(&scene, &s, state).unwrap();
    while resumed.step().is_some() {}
    let bits = |l: &[DVec3]| {
        l.iter()
            .map(|v| v.to_array().map(f64::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(
        bits(resumed.vertex_radiance()),
        bits(whole.vertex_radiance())
    );
    assert_eq!(resumed.progress(), whole.progress());
}

/// A closed 2 m cube room whose ceiling has a 0.6 m square hole in its
/// middle, every face facing in: four ceiling panels around the hole.
pub(super) fn skylit_room(portal: bool, seed: u64) -> (Scene, SolverSettings) {
    let mut polygons: Vec<(Vec<DVec3>, usize)> = super::physics_tests::cube(2.0, DVec3::ZERO)
        .into_iter()
        .filter(|(f, _)| !f.iter().all(|p| (p.y - 2.0).abs() < 1e-12))
        .collect();
    let (a, b) = (0.7, 1.3);
    let v = |x: f64, z: f64| DVec3::new(x, 2.0, z);
    // Facing down (into the room): counter-clockwise seen from below.
    for quad in [
        [v(0., 0.), v(2., 0.), v(2., a), v(0., a)],
        [v(0., b), v(2., b), v(2., 2.), v(0., 2.)],
        [v(0., a), v(a, a), v(a, b), v(0., b)],
        [v(b, a), v(2., a), v(2., b), v(b, b)],
    ] {
        let mut q = quad.to_vec();
        if crate::geometry::polygon::newell_normal(&q).y > 0.0 {
            q.reverse();
        }
        polygons.push((q, 0));
    }
    let mut scene = scene_of(polygons, vec![material("wall", RHO, 0.0)], 6);
    scene.lights = sky_lights(SkyModel::uniform(DVec3::ONE).unwrap(), DVec3::Y);
    if portal {
        let hole = [v(a, a), v(b, a), v(b, b), v(a, b)];
        scene.lights.portals = vec![crate::light::portal::Portal::new(&hole).unwrap()];
    }
    let mut s = settings();
    s.adaptive = false;
    s.seed = seed;
    (scene, s)
}

/// The floor's direct light from the lights' shot alone in a
/// [`skylit_room`], per vertex, and its exact value ρ L F, F the form
/// factor from the point the rays leave to the hole (Lambert's polygon
/// formula, `geometry::formfactor`).
fn floor_direct((scene, settings): (Scene, SolverSettings)) -> (Vec<f64>, Vec<f64>) {
    let mut solver = Solver::new(&scene, &settings).unwrap();
    solver.step().unwrap();
    let mesh = solver.mesh();
    let offset = solver.offset();
    let epsilon = solver.occluder.scene_epsilon();
    let hole = [(0.7, 0.7), (1.3, 0.7), (1.3, 1.3), (0.7, 1.3)]
        .map(|(x, z)| DVec3::new(x, 2.0, z) - offset);
    (0..mesh.vertices.len() as u32)
        .filter(|&v| mesh.vertices[v as usize].position.y + offset.y < 1e-9)
        .map(|v| {
            let (q, n) = super::shoot::receiving_point(mesh, v, epsilon);
            let exact =
                RHO * crate::geometry::formfactor::point_to_polygon(q + n * epsilon, n, &hole);
            (solver.field.direct[v as usize].x, exact)
        })
        .unzip()
}

#[test]
fn a_portal_gives_the_same_light_with_less_noise() {
    // The floor under a skylight, lit by a uniform sky of radiance 1 through
    // it: each vertex's exact direct light is ρ F to the hole. With and
    // without a portal on the hole the estimates are unbiased, so each
    // one's mean over the n floor vertices lies within 4 standard errors of
    // the exact mean; each vertex's noise is measured from two seeds, σ² =
    // ⟨(a − b)²⟩ / 2. The portal sends half of the rays through the hole,
    // where cosine sampling sends the hole's small projected solid angle's
    // share: its noise must be lower by at least half.
    let portal = FloorNoise::of(|seed| skylit_room(true, seed));
    let cosine = FloorNoise::of(|seed| skylit_room(false, seed));
    portal.compare("portal", &cosine);
}

/// The floor's direct light in a skylit room from two seeds: its mean over
/// the n floor vertices, the exact mean, and the per-vertex noise σ,
/// measured as σ² = ⟨(a − b)²⟩ / 2 over the vertices.
pub(super) struct FloorNoise {
    n: f64,
    mean: f64,
    exact: f64,
    sigma: f64,
}

impl FloorNoise {
    /// Solves the rooms `room(1)` and `room(2)` (seeds 1 and 2).
    pub(super) fn of(room: impl Fn(u64) -> (Scene, SolverSettings)) -> FloorNoise {
        let ((a, exact), (b, _)) = (floor_direct(room(1)), floor_direct(room(2)));
        let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
        let squares: f64 = a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum();
        FloorNoise {
            n: a.len() as f64,
            mean: mean(&a),
            exact: mean(&exact),
            sigma: (squares / (2.0 * a.len() as f64)).sqrt(),
        }
    }

    /// Both estimates are unbiased, so each mean lies within 4 standard
    /// errors of the exact mean; `self` (sampled through portals, `label`)
    /// has at most half of `cosine`'s noise.
    pub(super) fn compare(&self, label: &str, cosine: &FloorNoise) {
        let (sp, sc, me) = (self.sigma, cosine.sigma, self.exact);
        println!(
            "skylight: {} floor vertices, mean {:.5} ({label}) / {:.5} (cosine) / {me:.5} \
             (exact), per-vertex σ {sp:.5} / {sc:.5} ({:.1}% / {:.1}% of the mean)",
            self.n,
            self.mean,
            cosine.mean,
            100.0 * sp / me,
            100.0 * sc / me
        );
        for (noise, name) in [(self, label), (cosine, "cosine")] {
            assert!(
                (noise.mean - noise.exact).abs() < 4.0 * noise.sigma / noise.n.sqrt(),
                "{name} mean {}, exact {}",
                noise.mean,
                noise.exact
            );
        }
        assert!(sp < 0.5 * sc, "σ with the {label} {sp}, without {sc}");
    }
}

#[test]
fn before_the_lights_shoot_all_of_their_light_is_unshot() {
    // A scene lit only by lights has emitted nothing before their shot: its
    // unshot fraction is 1 (not 0 / 0), so progress and ETA start sane.
    let lamp = Lamp::point("bulb", DVec3::new(0.0, 1.0, 0.0), DVec3::ONE, 0.0).unwrap();
    let mut solver =
        Solver::new(&open_floor(1.0, Vec::new(), lamp_lights(lamp)), &settings()).unwrap();
    assert_eq!(solver.progress().unshot_fraction, 1.0);
    solver.step().unwrap();
    assert_eq!(solver.progress().unshot_fraction, 1.0);
}

fn map_sky(width: usize, height: usize, texel: impl Fn(usize, usize) -> f32) -> Lights {
    let texels = (0..height)
        .flat_map(|row| (0..width).map(move |col| (row, col)))
        .map(|(row, col)| [texel(row, col); 3])
        .collect();
    let map = crate::light::envmap::EnvMap::new(width, height, texels, 1.0, 0.0).unwrap();
    let model = SkyModel::Map {
        map: std::sync::Arc::new(map),
        north: DVec3::NEG_Z,
    };
    Lights {
        sky: Some(Sky::new(model, DVec3::Y, BelowHorizon::Black, None).unwrap()),
        ..Lights::default()
    }
}

#[test]
fn a_constant_map_lights_as_the_uniform_sky() {
    // Every texel 2: each cosine sample sees 2 from the map as from the
    // uniform sky, along the same directions, so the two solves agree to
    // rounding (1e-12).
    let uniform = sky_lights(SkyModel::uniform(DVec3::splat(2.0)).unwrap(), DVec3::Y);
    let a = solved(&open_floor(2.0, Vec::new(), uniform), &settings());
    let b = solved(
        &open_floor(2.0, Vec::new(), map_sky(16, 8, |_, _| 2.0)),
        &settings(),
    );
    for (la, lb) in a.vertex_radiance().iter().zip(b.vertex_radiance()) {
        assert!(
            (*la - *lb).abs().max_element() <= 1e-12 * la.max_element(),
            "{la} {lb}"
        );
    }
}

#[test]
fn a_map_with_one_bright_quadrant_lights_the_wall_facing_it() {
    // Four walls facing north, east, south and west around a post; the map
    // is bright (10) only between azimuths 45° and 135° (centred on east)
    // above the horizon. East = north × up = +x for north −z and up +y. The
    // east wall's vertices must match ρ E / π with E the map's irradiance on
    // that plane, by the midpoint rule over the hemisphere (`Sky::irradiance`,
    // independent of the solver's sampling), within 4 standard errors of
    // the mean over its vertices; the west wall, facing away, gets nothing;
    // north and south get the quadrant's edge only, less than east.
    let lights = map_sky(8, 4, |row, col| {
        if row < 2 && (1..=2).contains(&col) {
            10.0
        } else {
            0.0
        }
    });
    let sky = lights.sky.clone().unwrap();
    let c = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    let walls = vec![
        (
            vec![
                c(-1., 0., -1.),
                c(-1., 2., -1.),
                c(1., 2., -1.),
                c(1., 0., -1.),
            ],
            0,
        ),
        (
            vec![c(1., 0., -1.), c(1., 2., -1.), c(1., 2., 1.), c(1., 0., 1.)],
            0,
        ),
        (
            vec![c(1., 0., 1.), c(1., 2., 1.), c(-1., 2., 1.), c(-1., 0., 1.)],
            0,
        ),
        (
            vec![
                c(-1., 0., 1.),
                c(-1., 2., 1.),
                c(-1., 2., -1.),
                c(-1., 0., -1.),
            ],
            0,
        ),
    ];
    let mut scene = scene_of(walls, vec![material("grey", RHO, 0.0)], 4);
    scene.lights = lights;
    let solver = solved(&scene, &settings());
    let mean_on = |normal: DVec3| {
        let mesh = solver.mesh();
        let values: Vec<f64> = mesh
            .vertices
            .iter()
            .zip(solver.vertex_radiance())
            .filter(|(v, _)| v.normal.dot(normal) > 0.99)
            .map(|(_, l)| l.x)
            .collect();
        values.iter().sum::<f64>() / values.len() as f64
    };
    let east = mean_on(DVec3::X);
    let expected = RHO * sky.irradiance(DVec3::X, 256).x / PI;
    // Per vertex a cosine sample is 10 or 0 with p the bright share of the
    // projected hemisphere; σ/mean ≤ √((1 − p)/(p N)); ≥ 20 vertices.
    let p = expected * PI / RHO / (10.0 * PI);
    let rays = (8 * settings().samples) as f64;
    let sigma = ((1.0 - p) / (p * rays)).sqrt() / 20f64.sqrt();
    println!("bright quadrant: east wall {east:.4} against {expected:.4} (σ {sigma:.4} relative)");
    assert!(
        (east / expected - 1.0).abs() < 4.0 * sigma,
        "east {east}, expected {expected}"
    );
    assert_eq!(mean_on(DVec3::NEG_X), 0.0, "the west wall faces away");
    for side in [DVec3::Z, DVec3::NEG_Z] {
        let l = mean_on(side);
        assert!(l < 0.5 * east, "{side}: {l} against east {east}");
    }
}

#[test]
fn a_lamp_inside_a_closed_bulb_mesh_is_warned_about() {
    // A lamp inside a closed 4 cm cube (a bulb modelled around it) lights
    // nothing outside it: the set-up warns, naming the lamp; the same lamp
    // above the open floor raises no warning.
    let bulb = super::physics_tests::cube(0.04, DVec3::new(-0.02, 0.98, -0.02));
    let lamp = Lamp::point("desk", DVec3::new(0.0, 1.0, 0.0), DVec3::ONE, 0.0).unwrap();
    let inside = open_floor(2.0, bulb, lamp_lights(lamp.clone()));
    let solver = Solver::new(&inside, &settings()).unwrap();
    let warned: Vec<&String> = solver
        .warnings()
        .iter()
        .filter(|w| w.contains("enclosed"))
        .collect();
    assert!(
        warned.len() == 1 && warned[0].contains("desk"),
        "{:?}",
        solver.warnings()
    );
    let open = Solver::new(&open_floor(2.0, Vec::new(), lamp_lights(lamp)), &settings()).unwrap();
    assert!(!open.warnings().iter().any(|w| w.contains("enclosed")));
}

/// The floor's vertex radiance (red channel) under `lights` with `seed`.
fn floor_red(lights: Lights, seed: u64) -> Vec<f64> {
    let mut s = settings();
    s.seed = seed;
    s.adaptive = false;
    let solver = solved(&open_floor(2.0, Vec::new(), lights), &s);
    floor_vertices(&solver).iter().map(|(_, l)| l.x).collect()
}

#[test]
fn a_clear_sky_sampled_by_its_radiance_gives_its_irradiance() {
    // Preetham's clear sky over an open floor: E = the sky's horizontal
    // irradiance (its own quadrature, relative error under 1e-4), so
    // L = ρE/π at every vertex. The estimate mixes cosine and table samples
    // by the balance heuristic, unbiased; its per-vertex noise σ is
    // measured from two seeds (σ² = ⟨(a − b)²⟩ / 2), and the mean over the n
    // vertices must lie within 4 σ / √n of the exact value.
    let sun = DVec3::new(0.4, 0.35, -0.2);
    let sky = Sky::new(
        SkyModel::clear(3.0, sun).unwrap(),
        DVec3::Y,
        BelowHorizon::Black,
        None,
    )
    .unwrap();
    let exact = RHO * sky.horizontal_irradiance().x / PI;
    let lights = || Lights {
        sky: Some(sky.clone()),
        ..Lights::default()
    };
    let (a, b) = (floor_red(lights(), 1), floor_red(lights(), 2));
    let n = a.len() as f64;
    let mean = a.iter().sum::<f64>() / n;
    let sigma = (a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / (2.0 * n)).sqrt();
    println!(
        "clear sky: mean {mean:.5} against {exact:.5}, per-vertex σ {:.2}% ({n} vertices)",
        100.0 * sigma / exact
    );
    assert!(
        (mean - exact).abs() < 4.0 * sigma / n.sqrt() + 1e-4 * exact,
        "{mean} {exact}"
    );
}

#[test]
fn a_map_with_a_painted_sun_is_sampled_by_its_radiance() {
    // A 64 × 32 map of radiance 1 with one texel of 5,000 (a sun painted
    // into it, 5.6° wide): E on the open floor is the map's own exact
    // integral (`EnvMap::horizontal_irradiance`, rows integrated exactly).
    // Its estimate is unbiased, so the mean over the n vertices lies within
    // 4 σ / √n of it, σ the per-vertex noise from two seeds. Sampled by
    // the cosine alone that noise was 218% (measured when the table was
    // added, docs/lights.md); with the table it must stay under 10%.
    let lights = || {
        map_sky(
            64,
            32,
            |row, col| if row == 8 && col == 20 { 5000.0 } else { 1.0 },
        )
    };
    let (a, b) = (floor_red(lights(), 1), floor_red(lights(), 2));
    let n = a.len() as f64;
    let mean = a.iter().sum::<f64>() / n;
    let sigma = (a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / (2.0 * n)).sqrt();
    let exact = RHO * lights().sky.unwrap().horizontal_irradiance().x / PI;
    println!(
        "painted sun: mean {mean:.4} against {exact:.4}, per-vertex σ {:.2}%",
        100.0 * sigma / exact
    );
    assert!(
        (mean - exact).abs() < 4.0 * sigma / n.sqrt(),
        "{mean} {exact}"
    );
    assert!(sigma < 0.1 * exact, "σ {sigma}");
}

#[test]
fn an_ies_profile_comes_back_at_the_receiver_in_every_file_form() {
    // The same quadrant-symmetric table in each LM-63 form (1986 to 2019),
    // on a lamp 2 m over the open floor aimed down: at every floor vertex
    // L = ρ (I(θ, φ) / 683) cos θ_r / (π d²), with I the table's bilinear
    // value written out by hand (`ies/tests.rs`) at the vertex's angles in
    // the lamp's type C frame (θ from the nadir, φ from its `across` axis,
    // folded into the quadrant), times the file's scale. Exact (one ray a
    // vertex): 1e-9.
    use crate::light::ies::tests::{bilinear_by_hand, forms};
    use crate::light::ies::IesProfile;
    let at = DVec3::new(0.0, 2.0, 0.0);
    for (form, spec) in forms() {
        let profile = std::sync::Arc::new(IesProfile::parse(&spec.render(), "lamp.ies").unwrap());
        let mut lamp = Lamp::point("ies", at, DVec3::ONE, 0.0)
            .unwrap()
            .with_profile(profile.clone(), DVec3::NEG_Y)
            .unwrap();
        let frame = lamp.profile.clone().unwrap();
        lamp.intensity = DVec3::splat(frame.peak_candela / 683.0);
        let solver = solved(&open_floor(3.0, Vec::new(), lamp_lights(lamp)), &settings());
        let side = frame.down.cross(frame.across);
        for (p, l) in floor_vertices(&solver) {
            let w = (p - at).normalize();
            let theta = w.dot(frame.down).clamp(-1.0, 1.0).acos().to_degrees();
            let phi = w
                .dot(side)
                .atan2(w.dot(frame.across))
                .to_degrees()
                .rem_euclid(360.0);
            let half = if phi > 180.0 { 360.0 - phi } else { phi };
            let folded = if half > 90.0 { 180.0 - half } else { half };
            let candela = bilinear_by_hand(&spec, theta, folded) * profile.scale();
            let d2 = (at - p).length_squared();
            let expected = RHO * (candela / 683.0) * (at.y - p.y) / d2.sqrt() / (PI * d2);
            assert!(
                (l.x - expected).abs() <= 1e-9 * expected.max(1e-12),
                "{form:?} at {p}: {} against {expected}",
                l.x
            );
        }
    }
}

#[test]
fn the_one_call_gathers_refuse_a_scene_with_lights_naming_the_method_that_lights_it() {
    // Gauss–Seidel and the global cube gather emissive polygons only: a
    // sun-lit scene would come out black, so it is refused before any work.
    let scene = open_floor(1.0, Vec::new(), sun_lights(40.0, 100.0));
    let limits = super::gauss_seidel::GaussSeidelLimits::default();
    let text = super::gauss_seidel::solve_gauss_seidel(&scene, &settings(), &limits)
        .err()
        .unwrap()
        .to_string();
    assert!(
        text.contains("gauss-seidel") && text.contains("--method progressive"),
        "{text}"
    );
    let mut cube = settings();
    cube.mode = SolveMode::Directional;
    let limits = super::cube_gather::CubeLimits::default();
    let text = super::cube_gather::solve_cube(&scene, &cube, &limits)
        .err()
        .unwrap()
        .to_string();
    assert!(
        text.contains("cube") && text.contains("--method progressive"),
        "{text}"
    );
}

/// The side walls of an upright prism of `segments` sides, radius `radius`
/// and height `height`, standing on the floor at (x, z) = (0, 0), each wall
/// facing out (no caps: the floor under it is the covered piece).
fn column(radius: f64, height: f64, segments: usize) -> Vec<(Vec<DVec3>, usize)> {
    let at = |k: usize, y: f64| {
        let a = 2.0 * PI * k as f64 / segments as f64;
        DVec3::new(radius * a.cos(), y, radius * a.sin())
    };
    (0..segments)
        .map(|k| {
            (
                vec![at(k, 0.0), at(k, height), at(k + 1, height), at(k + 1, 0.0)],
                0,
            )
        })
        .collect()
}

#[test]
fn the_floor_at_a_sunlit_column_base_takes_the_sun_on_its_sunny_side_only() {
    // A column 0.3 m in radius and 4 m high on an open floor, the sun at 55°,
    // stopped after the lights' shot: each floor vertex on the contact ring
    // holds the direct light alone, exactly ρ E⊥ sin 55°/π where the column
    // does not stand between it and the sun, 0 where it does. A ring vertex at
    // bearing φ from the sun's is in the open when cos φ > 0 (the sun ray
    // leaves the column), in the column's shadow when cos φ < 0; within 10°
    // of the terminator the ray grazes the walls and is left out. The
    // visible pieces that the contact and the sun's shadow lines cut share
    // sites only within themselves (`sites.rs`): a ring vertex that took a
    // sample from a piece across the column drew its shadow on the sunny side
    // (docs/lab/lights-atrium.md, "Column bases"). Tolerance: the disc's
    // 16 samples about 55° move E by at most 2e-3 (as in
    // `sun_lights_an_open_plane_by_the_cosine_law_and_a_shadow_has_its_area`).
    let (elevation, irradiance, radius) = (55.0f64, 100.0, 0.3);
    let lit = RHO * irradiance * elevation.to_radians().sin() / PI;
    let lights = sun_lights(elevation, irradiance);
    let toward = lights.sun.as_ref().map(|s| s.direction()).unwrap();
    let azimuth = toward.z.atan2(toward.x);
    let scene = open_floor(4.0, column(radius, 4.0, 24), lights);
    let mut solver = Solver::new(&scene, &settings()).unwrap();
    solver.step();
    let (mut sunny, mut shaded) = (0, 0);
    let offset = solver.offset();
    for (v, vertex) in solver.mesh().vertices.iter().enumerate() {
        let p = vertex.position + offset;
        let on_ring = p.y.abs() < 1e-9 && (p.x.hypot(p.z) - radius).abs() < 1e-6;
        // The visible pieces are the floor's smooth ones; the covered piece
        // under the column stays flat (`mesh::contact`).
        let surface = &solver.mesh().surfaces[vertex.surface as usize];
        if !on_ring || surface.polygon != 0 || surface.corner_normals.is_none() {
            continue;
        }
        let cos_phi = (p.z.atan2(p.x) - azimuth).cos();
        let l = solver.vertex_radiance()[v].x;
        if cos_phi > 10f64.to_radians().sin() {
            sunny += 1;
            assert!(
                (l / lit - 1.0).abs() < 2e-3,
                "sunny ring vertex at {p}: {l}, truth {lit}"
            );
        } else if cos_phi < -(10f64.to_radians().sin()) {
            shaded += 1;
            assert!(l < 1e-3 * lit, "shaded ring vertex at {p}: {l}, truth 0");
        }
    }
    assert!(
        sunny >= 8 && shaded >= 8,
        "{sunny} sunny and {shaded} shaded ring vertices"
    );
}
