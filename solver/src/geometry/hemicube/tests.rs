use super::*;
use crate::geometry::formfactor::point_to_polygon;

/// A rectangle in the plane z = `z`, corners (x0, y0)–(x1, y1), wound to face
/// −z (toward a receiver below it).
fn rect_facing_down(x0: f64, y0: f64, x1: f64, y1: f64, z: f64) -> Vec<DVec3> {
    vec![
        DVec3::new(x0, y0, z),
        DVec3::new(x0, y1, z),
        DVec3::new(x1, y1, z),
        DVec3::new(x1, y0, z),
    ]
}

#[test]
fn bad_resolutions_are_refused() {
    for r in [0, 1, 3, 17, MAX_RESOLUTION + 2] {
        assert_eq!(
            Hemicube::new(r).unwrap_err(),
            HemicubeError::Resolution(r),
            "{r}"
        );
    }
    assert!(Hemicube::new(2).is_ok());
}

#[test]
fn the_setting_accepts_exactly_the_resolutions_the_hemicube_does() {
    // settings.rs states the range by hand (it cannot name this module without
    // the `solve` feature's geometry); the two must not drift apart.
    let mut settings = crate::settings::SolverSettings::preset(crate::settings::Preset::Draft);
    for r in [
        0u32,
        1,
        2,
        3,
        64,
        127,
        128,
        2046,
        2047,
        MAX_RESOLUTION,
        MAX_RESOLUTION + 2,
        4096,
    ] {
        settings.hemicube_resolution = r;
        assert_eq!(
            settings.validate().is_ok(),
            check_resolution(r).is_ok(),
            "R = {r}"
        );
    }
}

#[test]
fn delta_form_factors_sum_to_one_and_match_002_midpoint_formulas() {
    // The exact cell factors tile the hemisphere: their sum is 1 up to f64
    // rounding of 3R² contour integrals (each ~1e-16 relative of its O(1)
    // terms), so 1e-10. The radiosity lecture notes' midpoint values ΔA/(πr⁴) and zΔA/(πr⁴) are the
    // one-point quadrature of the same integrals, with a relative error of
    // order h² times the kernel's relative curvature; measured: at most 0.67 h²
    // over all cells and resolutions below, so each cell's
    // |exact − midpoint| ≤ h² × exact, and the midpoint sum is 1 + O(h²).
    for r in [2u32, 8, 32, 128] {
        let cube = Hemicube::new(r).unwrap();
        let h = 2.0 / r as f64;
        let sum: f64 = (0..cube.cell_count()).map(|i| cube.delta(i)).sum();
        assert!((sum - 1.0).abs() < 1e-10, "R = {r}: exact sum {sum}");
        let mut worst: f64 = 0.0;
        let mut midpoint_sum = 0.0;
        for i in 0..cube.cell_count() {
            let (exact, mid) = (cube.delta(i), midpoint_delta(r, i));
            assert!(exact > 0.0, "R = {r}, cell {i}");
            worst = worst.max((exact - mid).abs() / exact);
            midpoint_sum += mid;
        }
        println!(
            "R = {r}: worst relative midpoint error {worst:.2e} (h² = {:.2e}), midpoint sum {midpoint_sum:.8}",
            h * h
        );
        assert!(worst <= h * h, "R = {r}: {worst} > h² = {}", h * h);
        assert!(
            (midpoint_sum - 1.0).abs() <= h * h,
            "R = {r}: midpoint sum {midpoint_sum}"
        );
    }
}

/// The root-mean-square error of the hemicube factor to `target` from the
/// origin (normal +z) over 16 rotations of the hemicube about the normal, as
/// the solver rotates it from patch to patch (module documentation).
fn rms_error_over_rotations(cube: &Hemicube, target: &[DVec3]) -> f64 {
    let exact = point_to_polygon(DVec3::ZERO, DVec3::Z, target);
    let mut sum = 0.0;
    for k in 0..16 {
        let angle = 0.05 + k as f64 * std::f64::consts::FRAC_PI_8;
        let hint = DVec3::new(angle.cos(), angle.sin(), 0.0);
        let f = cube.form_factors_from(DVec3::ZERO, DVec3::Z, hint, &[target])[0];
        sum += (f - exact).powi(2);
    }
    (sum / 16.0).sqrt()
}

/// A rectangle parallel to the receiver, off its axis, with edges at no
/// special cell boundary.
fn parallel_target() -> Vec<DVec3> {
    rect_facing_down(0.213, -0.337, 0.917, 0.641, 1.09)
}

/// A wall standing on the receiver's plane (x = 0.43, facing −x), seen through
/// the top face and two sides: the seams between faces must neither drop nor
/// double cells.
fn perpendicular_target() -> Vec<DVec3> {
    vec![
        DVec3::new(0.43, -0.384, 0.0),
        DVec3::new(0.43, -0.384, 0.771),
        DVec3::new(0.43, 0.655, 0.771),
        DVec3::new(0.43, 0.655, 0.0),
    ]
}

#[test]
fn grid_aligned_edges_stay_within_the_half_cell_strip_bound() {
    // With the hemicube's u axis along the rectangle's edges, every cell of a
    // column crossed by an edge is misjudged by the same strip, at most h/2
    // wide: the error is O(h), bounded by (h/2) × the projected perimeter on
    // the top face × the largest density 1/π (in factor per unit face area).
    let target = parallel_target();
    let exact = point_to_polygon(DVec3::ZERO, DVec3::Z, &target);
    let perimeter = 2.0 * ((0.917 - 0.213) + (0.641 + 0.337)) / 1.09;
    for r in [8u32, 16, 32, 64, 128, 256] {
        let cube = Hemicube::new(r).unwrap();
        let f = cube.form_factors_from(DVec3::ZERO, DVec3::Z, DVec3::X, &[&target])[0];
        let bound = (1.0 / r as f64) * perimeter / std::f64::consts::PI;
        assert!(
            (f - exact).abs() <= bound,
            "R = {r}: {} > {bound}",
            (f - exact).abs()
        );
    }
}

#[test]
fn rotated_hemicube_factors_converge_to_the_exact_ones() {
    // Rotated off the edges' directions, the errors of the cells along an edge
    // cancel and the error falls faster than h. The RMS over 16 rotations
    // (the ensemble the solver's per-patch rotation samples) must fall at each
    // 4× step of R. Measured RMS at R = 256: 1.3e-5 (parallel, F ≈ 0.10) and
    // 1.5e-4 (perpendicular, F ≈ 0.19); the bounds 5e-5 and 5e-4 are about a
    // tenth of the hard half-cell-strip bound at R = 256 (~4e-3 and ~5e-3),
    // and 0.05% / 0.3% of the factors.
    for (name, target, bound) in [
        ("parallel", parallel_target(), 5e-5),
        ("perpendicular", perpendicular_target(), 5e-4),
    ] {
        let exact = point_to_polygon(DVec3::ZERO, DVec3::Z, &target);
        assert!(exact > 0.05);
        let errors: Vec<f64> = [16u32, 64, 256]
            .iter()
            .map(|&r| rms_error_over_rotations(&Hemicube::new(r).unwrap(), &target))
            .collect();
        println!("{name}: F = {exact:.6}, RMS errors at R = 16, 64, 256: {errors:?}");
        for pair in errors.windows(2) {
            assert!(pair[1] < pair[0], "{name}: error did not fall: {errors:?}");
        }
        assert!(errors[2] < bound, "{name}: R = 256: {}", errors[2]);
    }
}

/// The six inward-facing faces of the box [lo, hi].
fn box_faces(lo: DVec3, hi: DVec3) -> Vec<Vec<DVec3>> {
    let c = |x: f64, y: f64, z: f64| DVec3::new(x, y, z) * (hi - lo) + lo;
    let faces = [
        [c(0., 0., 0.), c(1., 0., 0.), c(1., 1., 0.), c(0., 1., 0.)],
        [c(0., 0., 1.), c(1., 0., 1.), c(1., 1., 1.), c(0., 1., 1.)],
        [c(0., 0., 0.), c(0., 1., 0.), c(0., 1., 1.), c(0., 0., 1.)],
        [c(1., 0., 0.), c(1., 1., 0.), c(1., 1., 1.), c(1., 0., 1.)],
        [c(0., 0., 0.), c(0., 0., 1.), c(1., 0., 1.), c(1., 0., 0.)],
        [c(0., 1., 0.), c(0., 1., 1.), c(1., 1., 1.), c(1., 1., 0.)],
    ];
    let centre = (lo + hi) * 0.5;
    faces
        .into_iter()
        .map(|f| {
            let mut f = f.to_vec();
            let mid = f.iter().copied().sum::<DVec3>() / 4.0;
            if newell_normal(&f).dot(centre - mid) < 0.0 {
                f.reverse();
            }
            f
        })
        .collect()
}

#[test]
fn factors_to_the_faces_of_a_closed_box_sum_to_one() {
    // Inside a closed box every cell sees some face, and the exact delta
    // factors sum to 1 (1e-10, above), so the six factors sum to 1 within
    // 1e-10 at any resolution: nothing is lost between faces or between the
    // hemicube's own faces. Each face's factor is within the aliasing error of
    // its exact value: at R = 128 its outline crosses < 4·3R cells of at most
    // h²/π each; 2e-3 is about a quarter of that hard bound.
    let faces = box_faces(DVec3::new(-1.0, -0.5, 0.0), DVec3::new(2.0, 1.5, 1.2));
    for (centre, normal) in [
        (
            DVec3::new(0.1, 0.2, 0.3),
            DVec3::new(0.3, -0.5, 0.8).normalize(),
        ),
        (
            DVec3::new(1.9, 1.4, 0.6),
            DVec3::new(-1.0, 0.2, 0.1).normalize(),
        ),
        // On the floor (z = 0), as a receiving patch's centre is.
        (DVec3::new(0.4, 0.3, 0.0), DVec3::Z),
    ] {
        for r in [4u32, 32, 128] {
            let cube = Hemicube::new(r).unwrap();
            let frame = Frame::new(centre, normal, DVec3::Y).unwrap();
            let mut buffer = cube.buffer();
            buffer.render(&frame, &faces);
            assert!(
                buffer
                    .items()
                    .iter()
                    .all(|&i| i != NO_ITEM && i & BACK_FACE == 0),
                "R = {r}, {centre}: an empty or back-facing cell inside a closed box"
            );
            let mut f = vec![0.0; faces.len()];
            cube.accumulate(&buffer, &mut f);
            let sum: f64 = f.iter().sum();
            assert!((sum - 1.0).abs() < 1e-10, "R = {r}, {centre}: sum {sum}");
            if r == 128 {
                for (k, face) in faces.iter().enumerate() {
                    let exact = point_to_polygon(centre, normal, face);
                    assert!(
                        (f[k] - exact).abs() < 2e-3,
                        "{centre}, face {k}: {} vs exact {exact}",
                        f[k]
                    );
                }
            }
        }
    }
}

#[test]
fn nearer_polygons_hide_farther_ones_whatever_the_drawing_order() {
    // A small rectangle in front of a large one whose projection contains it.
    // With the z-buffer, the large one keeps exactly the cells it has alone
    // minus the small one's cells, in either drawing order: the factors obey
    // that identity to rounding (1e-12), whatever the aliasing.
    let near = rect_facing_down(-0.2, -0.1, 0.3, 0.25, 0.5);
    let far = rect_facing_down(-2.0, -2.0, 2.0, 2.0, 1.5);
    let cube = Hemicube::new(64).unwrap();
    let hint = DVec3::new(0.8, 0.6, 0.0);
    let alone = |t: &Vec<DVec3>| cube.form_factors_from(DVec3::ZERO, DVec3::Z, hint, &[t])[0];
    let (near_alone, far_alone) = (alone(&near), alone(&far));
    let a = cube.form_factors_from(DVec3::ZERO, DVec3::Z, hint, &[near.clone(), far.clone()]);
    let b = cube.form_factors_from(DVec3::ZERO, DVec3::Z, hint, &[far, near]);
    assert_eq!(a[0], b[1]);
    assert_eq!(a[1], b[0]);
    assert_eq!(a[0], near_alone);
    assert!((a[1] - (far_alone - near_alone)).abs() < 1e-12);
}

#[test]
fn polygons_seen_from_behind_hide_but_give_nothing() {
    // The same blocker wound the other way: it still hides its cells of the
    // far rectangle but, one-sided, sends nothing toward the receiver.
    let front = rect_facing_down(-0.2, -0.1, 0.3, 0.25, 0.5);
    let mut back = front.clone();
    back.reverse();
    let far = rect_facing_down(-2.0, -2.0, 2.0, 2.0, 1.5);
    let cube = Hemicube::new(64).unwrap();
    let hint = DVec3::new(0.8, 0.6, 0.0);
    let with_front = cube.form_factors_from(DVec3::ZERO, DVec3::Z, hint, &[front, far.clone()]);
    let with_back = cube.form_factors_from(DVec3::ZERO, DVec3::Z, hint, &[back, far]);
    assert!(with_front[0] > 0.0);
    assert_eq!(with_back[0], 0.0);
    assert_eq!(with_back[1], with_front[1]);
}

#[test]
fn non_convex_targets_and_degenerate_input_are_handled() {
    // An L-shaped (non-convex) polygon is drawn as its triangles.
    let l_shape = vec![
        DVec3::new(-0.5, -0.5, 0.8),
        DVec3::new(-0.5, 0.7, 0.8),
        DVec3::new(0.1, 0.7, 0.8),
        DVec3::new(0.1, 0.0, 0.8),
        DVec3::new(0.6, 0.0, 0.8),
        DVec3::new(0.6, -0.5, 0.8),
    ];
    assert!(newell_normal(&l_shape).z < 0.0 && !is_convex(&l_shape));
    let exact = point_to_polygon(DVec3::ZERO, DVec3::Z, &l_shape);
    let cube = Hemicube::new(256).unwrap();
    let degenerate = vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
    let with_nan = vec![DVec3::NAN, DVec3::X, DVec3::Y];
    let f = cube.form_factors_from(
        DVec3::ZERO,
        DVec3::Z,
        DVec3::X,
        &[l_shape, degenerate, with_nan, vec![DVec3::X]],
    );
    assert!((f[0] - exact).abs() < 1e-4, "{} vs {exact}", f[0]);
    assert_eq!(&f[1..], &[0.0, 0.0, 0.0]);
    // A zero normal gives nothing rather than NaN.
    let f = cube.form_factors_from(
        DVec3::ZERO,
        DVec3::ZERO,
        DVec3::X,
        &[rect_facing_down(0.0, 0.0, 1.0, 1.0, 1.0)],
    );
    assert_eq!(f, vec![0.0]);
}

/// The five outward faces (no bottom) of the block [lo, hi] standing on a floor.
fn block_faces(lo: DVec3, hi: DVec3) -> Vec<Vec<DVec3>> {
    let centre = (lo + hi) * 0.5;
    box_faces(lo, hi)
        .into_iter()
        .filter(|f| !f.iter().all(|v| v.z == lo.z))
        .map(|mut f| {
            // box_faces winds toward the inside; a block's faces face out.
            f.reverse();
            debug_assert!(newell_normal(&f).dot(f[0] - centre) > 0.0);
            f
        })
        .collect()
}

#[test]
fn the_buffer_answers_segment_visibility_exactly_for_the_candidates_it_shows() {
    // A room [−2, 2]³ with a block on its floor, seen from the room's centre
    // looking down. Points behind the block (their segment to the centre
    // crosses its top) are hidden; points beside it, on its top next to an
    // edge (its side fills the neighbouring cells but is not crossed), and in
    // the room's corners (the other wall fills the neighbouring cells) are
    // seen.
    let room = box_faces(DVec3::splat(-2.0), DVec3::splat(2.0));
    let block = block_faces(DVec3::new(0.5, -0.5, -2.0), DVec3::new(1.0, 0.5, -1.5));
    let mut targets = room.clone();
    targets.extend(block.iter().cloned());
    let item = |f: &dyn Fn(&Vec<DVec3>) -> bool| targets.iter().position(f).unwrap() as u32;
    let floor = item(&|f| f.iter().all(|v| v.z == -2.0));
    let wall = item(&|f| f.iter().all(|v| v.x == 2.0));
    let top = item(&|f| f.iter().all(|v| v.z == -1.5));
    let frame = Frame::new(DVec3::ZERO, -DVec3::Z, DVec3::new(0.3, 1.0, 0.0)).unwrap();
    for r in [16u32, 64, 256] {
        let mut buffer = ItemBuffer::with_resolution(r);
        buffer.render(&frame, &targets);
        let seen = |p: DVec3, own: u32| buffer.segment_visible(p, own, 1, 0.0);
        // Behind the block: the segment crosses its top at x = 0.8.
        assert_eq!(
            seen(DVec3::new(0.8 * 2.0 / 1.5, 0.0, -2.0), floor),
            Some(false),
            "R = {r}"
        );
        // Beside it, toward the centre, right at its foot.
        assert_eq!(
            seen(DVec3::new(0.49, 0.0, -2.0), floor),
            Some(true),
            "R = {r}"
        );
        assert_eq!(
            seen(DVec3::new(0.3, 0.2, -2.0), floor),
            Some(true),
            "R = {r}"
        );
        // On its top, 1e-6 from the far edge.
        assert_eq!(
            seen(DVec3::new(1.0 - 1e-6, 0.1, -1.5), top),
            Some(true),
            "R = {r}"
        );
        // In the room's corner, on the wall x = 2 next to the floor and y = 2.
        assert_eq!(
            seen(DVec3::new(2.0, 2.0 - 1e-6, -2.0 + 1e-6), wall),
            Some(true),
            "R = {r}"
        );
        // Behind the base plane: no answer.
        assert_eq!(seen(DVec3::new(0.0, 0.0, 1.0), floor), None, "R = {r}");
    }
}
