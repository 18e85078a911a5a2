//! The chooser on rooms made in code: a closed box room with an inner block
//! and a ceiling light, a model seen from outside, and a room in z-up units of
//! millimetres.

use super::*;
use solution::view::fixture::*;

/// The solver's old framing camera: the bounding sphere seen under 45° from +z.
fn framing_eye_z(lo: Vec3, hi: Vec3) -> f64 {
    let centre = (lo + hi).as_dvec3() * 0.5;
    let radius = (hi - lo).as_dvec3().length() * 0.5;
    centre.z + radius / 22.5f64.to_radians().sin()
}

fn inside(p: DVec3, lo: Vec3, hi: Vec3) -> bool {
    p.cmpgt(lo.as_dvec3()).all() && p.cmplt(hi.as_dvec3()).all()
}

/// Front-face fraction from `eye` over `n` Fibonacci directions about +x (not
/// the chooser's own set, so the check is independent of it).
fn front_fraction(scene: &ViewScene, eye: DVec3, n: usize) -> f64 {
    let front = fibonacci_sphere(n, DVec3::X)
        .into_iter()
        .filter(|&d| scene.cast(eye, d).is_some_and(|h| h.front))
        .count();
    front as f64 / n as f64
}

#[test]
fn a_closed_room_gets_an_eye_inside_it_that_sees_its_lit_walls() {
    let solution = box_room();
    let scene = ViewScene::from_solution(&solution);
    // The old default stood outside: 8 m radius bounding sphere → z ≈ 9.1 m.
    let old = framing_eye_z(ROOM_LO, ROOM_HI);
    assert!(old > ROOM_HI.z as f64 + 1.0, "{old}");
    assert!(front_fraction(&scene, DVec3::new(0.0, 1.25, old), 1024) < 0.5);

    let view = choose_view(&scene, UpAxis::PosY, 1.0).expect("a candidate inside the room");
    assert!(inside(view.eye, ROOM_LO, ROOM_HI), "{view:?}");
    assert!(!inside(view.eye, BLOCK_LO, BLOCK_HI), "{view:?}");
    // A closed room seen from inside: every ray meets a front face, both in the
    // chooser's own survey and in 1024 other directions.
    assert_eq!(view.front_fraction, 1.0, "{view:?}");
    assert_eq!((view.back_fraction, view.escaped_fraction), (0.0, 0.0));
    assert!(front_fraction(&scene, view.eye, 1024) >= 0.9);
    // The mean luminance seen is at least the walls' 0.3–0.5, since the light
    // only adds to it (Rec. 709 weights sum to 1).
    assert!(view.score > 0.3, "{view:?}");
    // 4 × 4 × 3 grid + centre; a point inside the block sees only its backs,
    // so not every candidate is kept.
    assert_eq!(view.candidates, 49);
    assert!(view.kept >= 10 && view.kept < 49, "{view:?}");
    // Level view: the target is at the eye's height.
    assert!((view.target.y - view.eye.y).abs() < 1e-12);

    // The header camera: original coordinates, 60°, the framing camera's size.
    let framing = Camera {
        width: 320,
        height: 200,
        ..Camera::default()
    };
    let camera = default_camera(&solution, framing);
    assert_eq!(
        camera.eye,
        (view.eye + DVec3::new(10.0, 0.0, -5.0)).to_array()
    );
    assert_eq!(
        (camera.width, camera.height, camera.fov_y_deg),
        (320, 200, 60.0)
    );
    assert_eq!(camera.up, [0.0, 1.0, 0.0]);
    camera.validate().unwrap();
}

#[test]
fn the_choice_is_deterministic() {
    let a = choose_view(&ViewScene::from_solution(&box_room()), UpAxis::PosY, 1.0);
    let b = choose_view(&ViewScene::from_solution(&box_room()), UpAxis::PosY, 1.0);
    assert!(a.is_some());
    // Bit for bit: the jitter is a fixed hash, the survey a fixed lattice.
    assert_eq!(a, b);
}

#[test]
fn the_eye_stands_at_eye_height_above_the_floor_below_it() {
    let solution = box_room();
    let scene = ViewScene::from_solution(&solution);
    let view = choose_view(&scene, UpAxis::PosY, 1.0).unwrap();
    let floor = view.floor.expect("a floor below the eye");
    // The floor found by the chooser is the one a downward ray from the eye
    // meets, front side up.
    let down = scene.cast(view.eye, DVec3::NEG_Y).unwrap();
    assert!(down.front);
    let height = view.eye.y - floor.y;
    assert!(
        (down.t as f64 - height).abs() < 1e-5,
        "{} vs {height}",
        down.t
    );
    // The room is 2.5 m high: 0.7 × 2.5 m > 1.6 m, so a person stands upright
    // on its floor, and an upright eye outranks one on the block (1.5 m below
    // the ceiling: 0.7 × 1.5 m < 1.6 m) whatever either sees. f32 positions of
    // a 6 m room: within 1e-5 m.
    assert!(floor.y.abs() < 1e-6, "{floor}");
    assert!((height - EYE_HEIGHT_M).abs() < 1e-5, "{height}");
    assert!((down.t as f64 - EYE_HEIGHT_M).abs() < 1e-5, "{}", down.t);
}

#[test]
fn a_room_in_millimetres_with_z_up_scales_the_eye_height() {
    // The same room in mm with z up: x → x, y (up) → z, z → −y, ×1000.
    let mut batch = empty_batch();
    let mm = |v: Vec3| Vec3::new(v.x, -v.z, v.y) * 1000.0;
    let (lo, hi) = (mm(ROOM_LO).min(mm(ROOM_HI)), mm(ROOM_LO).max(mm(ROOM_HI)));
    cuboid(&mut batch, lo, hi, true, 4, 0.5);
    let solution = solution_of(batch, UpAxis::PosZ, 1000.0, [0.0; 3]);
    let scene = ViewScene::from_solution(&solution);
    let view = choose_view(&scene, UpAxis::PosZ, 1000.0).unwrap();
    let floor = view.floor.unwrap();
    assert!(floor.z.abs() < 1e-3, "{floor}");
    // 1.6 m = 1600 mm, f32 positions of a 6 m room in mm: within 1e-3 mm.
    assert!((view.eye.z - 1600.0).abs() < 1e-3, "{view:?}");
    assert_eq!(view.front_fraction, 1.0);
}

#[test]
fn a_model_seen_from_outside_keeps_the_framing_camera() {
    // One closed block and nothing around it: every candidate outside it sees
    // most rays escape, every one inside sees backs.
    let mut batch = empty_batch();
    cuboid(&mut batch, BLOCK_LO, BLOCK_HI, false, 4, 0.3);
    let solution = solution_of(batch, UpAxis::PosY, 1.0, [0.0; 3]);
    assert_eq!(
        choose_view(&ViewScene::from_solution(&solution), UpAxis::PosY, 1.0),
        None
    );
    let framing = Camera {
        eye: [0.0, 0.5, 5.0],
        ..Camera::default()
    };
    assert_eq!(default_camera(&solution, framing), framing);
}

#[test]
fn fibonacci_directions_are_unit_and_balanced() {
    let d = fibonacci_sphere(RAYS, DVec3::Y);
    assert_eq!(d.len(), RAYS);
    assert!(d.iter().all(|v| (v.length() - 1.0).abs() < 1e-12));
    // The lattice is symmetric in height: the mean vector is zero up to the
    // spiral's imbalance, below 1/n per component.
    let mean = d.iter().copied().sum::<DVec3>() / RAYS as f64;
    assert!(mean.abs().max_element() < 1.0 / RAYS as f64, "{mean}");
}
