//! The path tracer's sun, sky and lamps against closed forms (issue 41).
//!
//! Statistics as in `tests.rs`: estimates `x_k ± se_k` of known values pool
//! into z-scores, |mean z|·√N < 4 and 0.5 < mean z² < 2 (fixed seeds, so no
//! flake). Where an estimator has no variance at all (a point lamp seen along
//! a fixed ray over an open plane: one deterministic shadow ray, and the
//! continuation escapes into a scene with nothing else; a uniform sky over an
//! open horizontal plane, where both MIS strategies return exactly ρL times
//! weights that sum to one), the check is exact up to f64 rounding: a
//! relative tolerance of 1e-9, far above the rounding of a few dozen
//! operations (~1e-15) and far below any physical mistake (a missing π or
//! cosine is a factor of order 1).

use super::tests::{assert_unbiased, estimate, material, polygon, scene, square_at};
use super::*;
use crate::geometry::sampling::{stream_id, Rng};
use crate::light::lamp::Lamp;
use crate::light::sky::{BelowHorizon, Sky, SkyModel};
use crate::light::sun::{Sun, SunPosition, DEFAULT_ANGULAR_DIAMETER_DEG};
use crate::light::Lights;
use glam::DVec3;
use solution::camera::Camera;
use solution::format::SolveMode;
use std::f64::consts::PI;

const RHO: f64 = 0.6;

/// A large open floor z = 0 facing up (half-size 50: every test point is
/// near its middle), of diffuse albedo [`RHO`], lit by `lights`, plus
/// `extra` black (Kd = 0) polygons as occluders, ready to render.
fn lit_floor(lights: Lights, extra: Vec<Vec<DVec3>>) -> RenderScene {
    let mut polygons = vec![polygon(square_at(DVec3::ZERO, 50.0, false), 0)];
    polygons.extend(extra.into_iter().map(|p| polygon(p, 1)));
    let mut s = scene(
        polygons,
        vec![
            material("floor", RHO, 0.0, 1.0, DVec3::ZERO),
            material("black", 0.0, 0.0, 1.0, DVec3::ZERO),
        ],
    );
    s.lights = lights;
    RenderScene::new(&s, Physics::default())
}

/// The open floor of [`lit_floor`] lit by `lamps` alone, with `extra`
/// black occluders, ready to render.
fn lamps_over_floor(lamps: Vec<Lamp>, extra: Vec<Vec<DVec3>>) -> RenderScene {
    let lights = Lights {
        lamps,
        ..Lights::default()
    };
    lit_floor(lights, extra)
}

fn integrator(render: &RenderScene) -> Integrator<'_> {
    Integrator {
        scene: render,
        max_depth: None,
    }
}

/// Asserts `got` equals `want` to 1e-9 relative in every channel: the
/// tolerance of a variance-free estimate (module notes).
fn assert_exact(got: DVec3, want: DVec3, what: impl std::fmt::Display) {
    let error = ((got - want).abs() / want.abs().max(DVec3::splat(1e-300))).max_element();
    assert!(error < 1e-9, "{what}: {got} against {want}");
}

/// One sample of the radiance the camera at `eye` sees at the point `p`.
fn seen(tracer: &Integrator, eye: DVec3, p: DVec3) -> DVec3 {
    tracer.radiance(eye, (p - eye).normalize(), &mut Rng::new(1, 0))
}

/// Where the ray (o, d) meets the plane z = 0.
fn on_floor(o: DVec3, d: DVec3) -> DVec3 {
    o + d * (-o.z / d.z)
}

/// The irradiance a lamp of intensity `i0` at `lamp` gives the floor point
/// `p` (normal +z): I cos θ / d², written out independently of `Lamp`.
fn inverse_square(i0: DVec3, lamp: DVec3, p: DVec3) -> DVec3 {
    let to = lamp - p;
    let d2 = to.length_squared();
    i0 * (to.z / d2.sqrt()) / d2
}

/// The spot falloff of `light/lamp.rs` written out: saturate((cos θ − cos
/// outer) / (cos inner − cos outer))².
fn falloff(cos: f64, inner_deg: f64, outer_deg: f64) -> f64 {
    let (ci, co) = (inner_deg.to_radians().cos(), outer_deg.to_radians().cos());
    ((cos - co) / (ci - co)).clamp(0.0, 1.0).powi(2)
}

/// An isotropic point lamp of intensity I at height h over the open floor:
/// along rays from a camera looking down, the radiance is exactly
/// ρ I cos θ / (π d²) at points of known θ (0° to 75° from the lamp's
/// vertical), to 1e-9 (a variance-free estimator, module notes).
#[test]
fn point_lamp_over_a_plane_is_rho_i_cos_over_pi_d_squared() {
    let (i0, h) = (DVec3::new(2.0, 1.0, 0.5), 2.0);
    let at = DVec3::new(0.3, -0.2, h);
    let lamp = Lamp::point("bulb", at, i0, 0.0).unwrap();
    let render = lamps_over_floor(vec![lamp], vec![]);
    let tracer = integrator(&render);
    let eye = DVec3::new(0.0, 0.0, 4.0);
    for (k, theta_deg) in [0.0f64, 15.0, 30.0, 45.0, 60.0, 75.0].iter().enumerate() {
        let theta = theta_deg.to_radians();
        let phi = k as f64;
        let p =
            DVec3::new(at.x, at.y, 0.0) + h * theta.tan() * DVec3::new(phi.cos(), phi.sin(), 0.0);
        let d = h / theta.cos();
        let exact = RHO * i0 * theta.cos() / (PI * d * d);
        assert_exact(seen(&tracer, eye, p), exact, format!("θ = {theta_deg}°"));
    }
}

/// A spot lamp straight down (inner 20°, outer 30°): inside the inner cone
/// the floor shows the point lamp's ρ I cos θ / (π d²); outside the outer
/// cone exactly nothing; halfway between the cones' cosines a quarter of it
/// (the squared ramp at 1/2). Exact to 1e-9 (variance-free).
#[test]
fn spot_lamp_has_its_cone_and_squared_ramp() {
    let (i0, h) = (DVec3::new(3.0, 2.0, 1.0), 2.0);
    let at = DVec3::new(0.0, 0.0, h);
    let lamp = Lamp::point("spot", at, i0, 0.0)
        .unwrap()
        .with_spot(DVec3::NEG_Z, 20.0, 30.0)
        .unwrap();
    let render = lamps_over_floor(vec![lamp], vec![]);
    let tracer = integrator(&render);
    let eye = DVec3::new(0.1, 0.0, 4.0);
    let halfway = (0.5 * (20f64.to_radians().cos() + 30f64.to_radians().cos())).acos();
    for (theta, factor) in [
        (0.0, 1.0),
        (10f64.to_radians(), 1.0),
        (19.9f64.to_radians(), 1.0),
        (halfway, 0.25),
        (30.1f64.to_radians(), 0.0),
        (45f64.to_radians(), 0.0),
    ] {
        let p = DVec3::new(h * theta.tan(), 0.0, 0.0);
        let d = h / theta.cos();
        let exact = RHO * i0 * theta.cos() / (PI * d * d) * factor;
        let got = seen(&tracer, eye, p);
        if factor == 0.0 {
            assert_eq!(
                got,
                DVec3::ZERO,
                "θ = {}° is outside the cone",
                theta.to_degrees()
            );
        } else {
            assert_exact(got, exact, format!("θ = {}°", theta.to_degrees()));
        }
    }
}

/// A point lamp and a spot, rendered through the camera: every pixel's mean
/// (128 samples, uniform over the pixel) against the pixel's exact mean of
/// Σ ρ I_k(ω) cos θ / (π d²) over its square (a 16 × 16 midpoint rule: its
/// error, ~1e-5 relative on these smooth fields, is far below the ~1%
/// standard errors). The variance comes from the position in the pixel and
/// from picking one lamp by power (about 0.7 : 0.3 here), so this also
/// checks the selection's weights.
#[test]
fn lamps_through_the_camera_match_the_pixel_integrals() {
    let point = (DVec3::new(0.3, -0.2, 2.0), DVec3::new(1.0, 0.8, 0.6));
    let spot = (DVec3::new(-0.4, 0.3, 1.5), DVec3::new(8.0, 10.0, 12.0));
    let lamps = vec![
        Lamp::point("point", point.0, point.1, 0.0).unwrap(),
        Lamp::point("spot", spot.0, spot.1, 0.0)
            .unwrap()
            .with_spot(DVec3::new(0.2, 0.0, -1.0), 20.0, 30.0)
            .unwrap(),
    ];
    let axis = DVec3::new(0.2, 0.0, -1.0).normalize();
    let render = lamps_over_floor(lamps, vec![]);
    let tracer = integrator(&render);
    let camera = Camera {
        eye: [0.0, 0.0, 4.0],
        target: [0.0, 0.0, 0.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 60.0,
        width: 12,
        height: 10,
    };
    let view = camera.mono_view(DVec3::ZERO);
    let mut image = Accumulator::new(12, 10);
    image.render_pass(&tracer, &view, 3, 128, &|_| {});
    let exact_at = |p: DVec3| {
        let from_spot = (p - spot.0).normalize();
        let cone = falloff(from_spot.dot(axis), 20.0, 30.0);
        RHO / PI * (inverse_square(point.1, point.0, p) + inverse_square(spot.1, spot.0, p) * cone)
    };
    let mut z = Vec::new();
    for (index, pixel) in image.pixels.iter().enumerate() {
        let (i, j) = ((index % 12) as u32, (index / 12) as u32);
        let mut exact = DVec3::ZERO;
        for a in 0..16 {
            for b in 0..16 {
                let (du, dv) = ((a as f64 + 0.5) / 16.0, (b as f64 + 0.5) / 16.0);
                let (o, d) = super::camera::pixel_ray(&view, i, j, du, dv);
                exact += exact_at(on_floor(o, d)) / 256.0;
            }
        }
        for c in 0..3 {
            z.push((pixel.mean(c) - exact[c]) / pixel.standard_error(c));
        }
    }
    assert_unbiased("lamps through the camera", &z);
}

/// A uniform sky.
fn uniform_sky(radiance: DVec3, below: BelowHorizon) -> Sky {
    Sky::new(SkyModel::uniform(radiance).unwrap(), DVec3::Z, below, None).unwrap()
}

/// A uniform sky of radiance L (black below the horizon) over the open
/// floor: the camera sees ρL there, exactly (variance-free, module notes).
#[test]
fn uniform_sky_over_a_plane_shows_rho_l() {
    let l = DVec3::new(1.0, 2.0, 3.0);
    let render = lit_floor(
        Lights {
            sky: Some(uniform_sky(l, BelowHorizon::Black)),
            ..Lights::default()
        },
        vec![],
    );
    let tracer = integrator(&render);
    let eye = DVec3::new(0.0, 0.0, 3.0);
    for k in 0..8u64 {
        let p = DVec3::new(k as f64 * 0.7 - 2.0, 1.0 - k as f64 * 0.3, 0.0);
        let mut rng = Rng::new(4, k);
        for _ in 0..16 {
            let got = tracer.radiance(eye, (p - eye).normalize(), &mut rng);
            assert_exact(got, RHO * l, format!("{p}"));
        }
    }
}

/// A square of half-size 50 through the origin, tilted by β about the x
/// axis: normal (0, −sin β, cos β), counter-clockwise about it.
fn tilted_plane(beta: f64) -> (Vec<DVec3>, DVec3) {
    let n = DVec3::new(0.0, -beta.sin(), beta.cos());
    let (e1, e2) = (DVec3::X, n.cross(DVec3::X));
    let v = |a: f64, b: f64| 50.0 * (a * e1 + b * e2);
    (vec![v(-1., -1.), v(1., -1.), v(1., 1.), v(-1., 1.)], n)
}

/// A plane tilted by β under a uniform sky of radiance L: it sees
/// (1 + cos β)/2 of the sky's hemisphere above the horizon, so it shows
/// ρL (1 + cos β)/2 when the sky is black below; ρL (1 + cos β)/2 +
/// ρ g L (1 − cos β)/2 over a ground of albedo g (whose radiance is
/// g E_h / π = gL); and ρL when the sky continues below ("same", which is
/// variance-free and checked exactly). 256 samples at 6 points per case.
#[test]
fn tilted_plane_under_a_uniform_sky_sees_its_share() {
    let l = DVec3::new(1.0, 0.5, 2.0);
    let g = DVec3::new(0.2, 0.4, 0.6);
    let mut z = Vec::new();
    for (case, beta_deg) in [30.0f64, 60.0, 90.0, 135.0].iter().enumerate() {
        let beta = beta_deg.to_radians();
        let (plane, n) = tilted_plane(beta);
        let up = (1.0 + beta.cos()) / 2.0;
        let rules = [
            (BelowHorizon::Black, RHO * l * up),
            (
                BelowHorizon::Ground { albedo: g },
                RHO * l * (up + g * (1.0 - up)),
            ),
            (BelowHorizon::Same, RHO * l),
        ];
        for (rule, (below, exact)) in rules.into_iter().enumerate() {
            let mut s = scene(
                vec![polygon(plane.clone(), 0)],
                vec![material("plane", RHO, 0.0, 1.0, DVec3::ZERO)],
            );
            s.lights.sky = Some(uniform_sky(l, below));
            let render = RenderScene::new(&s, Physics::default());
            let tracer = integrator(&render);
            let wo = (n + 0.3 * DVec3::X).normalize();
            for k in 0..6u64 {
                let x = DVec3::X * (k as f64 - 2.5) + n.cross(DVec3::X) * (0.4 * k as f64 - 1.0);
                let mut rng = Rng::new(5, stream_id(case as u64 * 3 + rule as u64, k));
                let samples: Vec<DVec3> = (0..256)
                    .map(|_| tracer.outgoing(0, x, wo, &mut rng))
                    .collect();
                if below == BelowHorizon::Same {
                    for got in samples {
                        assert_exact(got, exact, format!("β = {beta_deg}°"));
                    }
                    continue;
                }
                for c in 0..3 {
                    let (mean, se) = estimate(samples.len(), |i| samples[i][c]);
                    z.push((mean - exact[c]) / se);
                }
            }
        }
    }
    assert_unbiased("tilted plane under a uniform sky", &z);
}

/// A sun of irradiance E⊥ at elevation e, its disc of angular radius α
/// wholly above the horizon, over the open floor: E = E⊥ sin e (1 + cos α)/2
/// (the mean of the disc directions' cosine with the normal; the factor is
/// 1 − 5e-6 for the real sun and 0.9981 for a 10° disc), so the floor shows
/// ρ E / π. Four elevations, two disc sizes, 8 points each, 256 samples.
#[test]
fn sun_over_a_plane_gives_rho_e_sin_elevation_over_pi() {
    let e_perp = DVec3::new(100.0, 80.0, 60.0);
    let mut z = Vec::new();
    for (case, diameter) in [DEFAULT_ANGULAR_DIAMETER_DEG, 10.0].into_iter().enumerate() {
        for (step, elevation) in [15.0f64, 40.0, 65.0, 90.0].into_iter().enumerate() {
            let e = elevation.to_radians();
            let toward = DVec3::new(e.cos() * 0.6, e.cos() * 0.8, e.sin());
            let position = SunPosition::from_direction(toward).unwrap();
            let sun = Sun::new(position, e_perp, diameter).unwrap();
            let render = lit_floor(
                Lights {
                    sun: Some(sun),
                    ..Lights::default()
                },
                vec![],
            );
            let tracer = integrator(&render);
            let alpha = (0.5 * diameter).to_radians();
            let exact = RHO * e_perp * e.sin() * (1.0 + alpha.cos()) / 2.0 / PI;
            for k in 0..8u64 {
                let x = DVec3::new(k as f64 * 0.5 - 2.0, 1.5 - k as f64 * 0.4, 0.0);
                let wo = DVec3::new(0.2, -0.1, 1.0).normalize();
                let mut rng = Rng::new(6, stream_id(case as u64 * 4 + step as u64, k));
                let samples: Vec<DVec3> = (0..256)
                    .map(|_| tracer.outgoing(0, x, wo, &mut rng))
                    .collect();
                let (mean, se) = estimate(samples.len(), |i| samples[i].x);
                z.push((mean - exact.x) / se);
            }
        }
    }
    assert_unbiased("sun over a plane", &z);
}

/// The real sun (0.53°) at elevation 60° toward +x over a black square of
/// half-size 0.5 at height 1: the square's shadow is the square moved by
/// cot 60° away from the sun (x from −1.077 to −0.077), with a penumbra
/// about 0.01 wide. Points 0.15 or more inside it get exactly nothing
/// (every disc direction is blocked); points as far outside get the open
/// value to within 4 standard errors.
#[test]
fn a_square_casts_the_sun_shadow_its_projection_predicts() {
    let e = 60f64.to_radians();
    let sun = Sun::new(
        SunPosition::from_direction(DVec3::new(e.cos(), 0.0, e.sin())).unwrap(),
        DVec3::splat(100.0),
        DEFAULT_ANGULAR_DIAMETER_DEG,
    )
    .unwrap();
    let blocker = square_at(DVec3::new(0.0, 0.0, 1.0), 0.5, false);
    let render = lit_floor(
        Lights {
            sun: Some(sun),
            ..Lights::default()
        },
        vec![blocker],
    );
    let tracer = integrator(&render);
    let shift = 1.0 / e.tan();
    let open = RHO * 100.0 * e.sin() / PI;
    let points = [
        (DVec3::new(-0.5 - shift + 0.15, 0.0, 0.0), 0.0),
        (DVec3::new(-shift, 0.3, 0.0), 0.0),
        (DVec3::new(0.5 - shift - 0.15, -0.35, 0.0), 0.0),
        (DVec3::new(0.5 - shift + 0.15, 0.0, 0.0), open),
        (DVec3::new(-0.5 - shift - 0.15, 0.0, 0.0), open),
        (DVec3::new(-shift, 0.65, 0.0), open),
        // Under the square but out of its shadow.
        (DVec3::new(0.4, 0.0, 0.0), open),
    ];
    for (k, (x, exact)) in points.into_iter().enumerate() {
        let mut rng = Rng::new(7, k as u64);
        let (mean, se) = estimate(256, |_| tracer.outgoing(0, x, DVec3::Z, &mut rng).y);
        if exact == 0.0 {
            assert_eq!(mean, 0.0, "{x} is in the umbra");
        } else {
            assert!(
                (mean - exact).abs() < 4.0 * se.max(1e-12 * exact),
                "{x}: {mean} ± {se} against {exact}"
            );
        }
    }
}

/// Camera rays that meet nothing show the sky's radiance and, inside the
/// sun's disc, the disc's E⊥ / Ω on top: a CIE overcast sky
/// L_z (1 + 2 cos θ)/3 at several zenith angles, black below the horizon,
/// the sun's disc at its centre and none 0.3° from it (the disc's radius is
/// 0.265°). Exact to 1e-9: no sampling is involved.
#[test]
fn rays_that_escape_show_the_sky_and_the_sun_disc() {
    let lz = DVec3::new(3.0, 2.0, 1.0);
    let sky = Sky::new(
        SkyModel::cie_overcast(lz).unwrap(),
        DVec3::Z,
        BelowHorizon::Black,
        None,
    )
    .unwrap();
    let toward = DVec3::new(1.0, 1.0, 1.5).normalize();
    let e_perp = DVec3::new(50.0, 60.0, 70.0);
    let sun = Sun::new(
        SunPosition::from_direction(toward).unwrap(),
        e_perp,
        DEFAULT_ANGULAR_DIAMETER_DEG,
    )
    .unwrap();
    // Some geometry far below, which no ray here meets.
    let mut s = scene(
        vec![polygon(
            square_at(DVec3::new(0.0, 0.0, -10.0), 1.0, false),
            0,
        )],
        vec![material("floor", RHO, 0.0, 1.0, DVec3::ZERO)],
    );
    s.lights.sky = Some(sky);
    s.lights.sun = Some(sun);
    let render = RenderScene::new(&s, Physics::default());
    let tracer = integrator(&render);
    let cie = |cos: f64| lz * (1.0 + 2.0 * cos) / 3.0;
    for theta_deg in [0.0f64, 30.0, 60.0, 89.0] {
        let t = theta_deg.to_radians();
        let dir = DVec3::new(-t.sin(), 0.0, t.cos());
        let got = seen(&tracer, DVec3::ZERO, dir);
        assert_exact(got, cie(t.cos()), format!("θ = {theta_deg}°"));
    }
    let below = DVec3::new(-1.0, 0.0, -0.05);
    assert_eq!(seen(&tracer, DVec3::ZERO, below), DVec3::ZERO);
    let omega = 4.0
        * PI
        * (0.25 * DEFAULT_ANGULAR_DIAMETER_DEG)
            .to_radians()
            .sin()
            .powi(2);
    let want = cie(toward.z) + e_perp / omega;
    assert_exact(seen(&tracer, DVec3::ZERO, toward), want, "sun disc");
    let aside = (toward + 0.3f64.to_radians() * toward.any_orthonormal_vector()).normalize();
    let got = seen(&tracer, DVec3::ZERO, aside);
    assert_exact(got, cie(aside.z), "beside the disc");
}

/// Lamp distances are in metres: the same scene modelled in millimetres
/// (units_per_metre = 1000) gives the same radiance as in metres, to 1e-9,
/// and both the closed form ρ I cos θ / (π d²). Lamps are in the polygons'
/// frame (`Scene::lights`), so the import's recentre offset, a record of
/// what was subtracted from both, moves neither.
#[test]
fn lamp_distances_are_in_metres_and_lamps_share_the_polygons_frame() {
    let i0 = DVec3::new(1.0, 2.0, 3.0);
    let at = DVec3::new(0.3, 0.1, 0.8);
    let offset = DVec3::new(1234.0, -567.0, 89.0);
    let render_in = |scale: f64| {
        let lamp = Lamp::point("bulb", at * scale, i0, 0.0).unwrap();
        let mut s = scene(
            vec![polygon(square_at(DVec3::ZERO, 50.0 * scale, false), 0)],
            vec![material("floor", RHO, 0.0, 1.0, DVec3::ZERO)],
        );
        s.units_per_metre = scale;
        s.recentre_offset = offset;
        s.lights.lamps.push(lamp);
        RenderScene::new(&s, Physics::default())
    };
    let (metres, millimetres) = (render_in(1.0), render_in(1000.0));
    for k in 0..6u64 {
        let p = DVec3::new(0.4 * k as f64 - 1.0, 0.5 - 0.2 * k as f64, 0.0);
        let eye = DVec3::new(0.0, 0.0, 3.0);
        let exact = RHO / PI * inverse_square(i0, at, p);
        let a = seen(&integrator(&metres), eye, p);
        assert_exact(a, exact, "metres");
        let b = seen(&integrator(&millimetres), eye * 1000.0, p * 1000.0);
        assert_exact(b, exact, "millimetres");
    }
}

/// A bulb of radius r lights as the point does where it is unoccluded (the
/// solver's E = I cos θ / max(d², r²) with d to its centre), exactly; a
/// receiver closer than r gets I cos θ / r², no spike; and under the straight
/// edge of a black half-plane halfway between the floor and the bulb, the
/// plane through the edge and the receiver splits the disc the bulb shows
/// it in half: half the open value, estimated from 256 shadow rays at each
/// of 48 points (a Bernoulli standard error of 1/(2√256), 3% of the mean).
#[test]
fn a_bulb_with_a_radius_has_soft_shadows_and_no_spike() {
    let (i0, r) = (DVec3::new(4.0, 3.0, 2.0), 0.2);
    let with_bulb = |at: DVec3, extra: Vec<Vec<DVec3>>| {
        lamps_over_floor(vec![Lamp::point("bulb", at, i0, r).unwrap()], extra)
    };
    let at = DVec3::new(0.0, 0.0, 2.0);
    let open = with_bulb(at, vec![]);
    let near = with_bulb(DVec3::new(0.0, 0.0, 0.1), vec![]);
    let half_plane = vec![
        DVec3::new(-20.0, -20.0, 1.0),
        DVec3::new(0.0, -20.0, 1.0),
        DVec3::new(0.0, 20.0, 1.0),
        DVec3::new(-20.0, 20.0, 1.0),
    ];
    let shadowed = with_bulb(at, vec![half_plane]);
    let mut z = Vec::new();
    for k in 0..48u64 {
        let p = DVec3::new(0.0, 0.05 * k as f64 - 1.2, 0.0);
        let exact = RHO / PI * inverse_square(i0, at, p);
        let mut rng = Rng::new(10, k);
        let got = integrator(&open).outgoing(0, p, DVec3::Z, &mut rng);
        assert_exact(got, exact, "open");
        let (mean, se) = estimate(256, |_| {
            integrator(&shadowed).outgoing(0, p, DVec3::Z, &mut rng).z
        });
        z.push((mean - 0.5 * exact.z) / se);
    }
    assert_unbiased("half-shadowed bulb", &z);
    let mut rng = Rng::new(10, 99);
    let got = integrator(&near).outgoing(0, DVec3::ZERO, DVec3::Z, &mut rng);
    let exact = RHO / PI * i0 / (r * r);
    assert_exact(got, exact, "touching");
}

/// The sun on a glossy floor (directional mode, Ks only), seen near its
/// mirror direction, where BSDF sampling finds the disc often and MIS
/// matters: L = ∫_disc Ks C_R(μ_i) g(ω_o · r_i) L_disc μ_i dω with
/// C_R = 1 / S(μ_i) from `brdf::exact_hemisphere_integral` and L_disc =
/// E⊥ / Ω, by a 12 × 24 Gauss–Legendre rule over the disc's cone in
/// (θ, φ) about the sun (a smooth integrand over 5°: converged far below the
/// standard errors). 1,000 samples at 24 points.
#[test]
fn sun_on_a_glossy_floor_matches_its_closed_form() {
    let (ks, alpha, diameter) = (0.8, 0.2, 10.0f64);
    let e = 35f64.to_radians();
    let toward = DVec3::new(e.cos(), 0.0, e.sin());
    let e_perp = 100.0;
    let sun = Sun::new(
        SunPosition::from_direction(toward).unwrap(),
        DVec3::splat(e_perp),
        diameter,
    )
    .unwrap();
    let mut s = scene(
        vec![polygon(square_at(DVec3::ZERO, 50.0, false), 0)],
        vec![material("gloss", 0.0, ks, alpha, DVec3::ZERO)],
    );
    s.lights.sun = Some(sun);
    let physics = Physics {
        mode: SolveMode::Directional,
    };
    let render = RenderScene::new(&s, physics);
    let tracer = integrator(&render);
    // Just off the mirror direction of the sun's centre.
    let wo = DVec3::new(-e.cos(), 0.05, e.sin()).normalize();
    let half = (0.5 * diameter).to_radians();
    let omega = 2.0 * PI * (1.0 - half.cos());
    let l_disc = e_perp / omega;
    let (t, b) = toward.any_orthonormal_pair();
    let (nodes_t, weights_t) = solution::sh::gauss_legendre(12);
    let (nodes_p, weights_p) = solution::sh::gauss_legendre(24);
    let mut exact = 0.0;
    for (xt, wt) in nodes_t.iter().zip(&weights_t) {
        let theta = 0.5 * half * (xt + 1.0);
        for (xp, wp) in nodes_p.iter().zip(&weights_p) {
            let phi = PI * (xp + 1.0);
            let wi = toward * theta.cos() + theta.sin() * (phi.cos() * t + phi.sin() * b);
            let mu_i = wi.z;
            let mirror = 2.0 * mu_i * DVec3::Z - wi;
            let g = crate::brdf::lobe(alpha, wo.dot(mirror));
            let c_r = ks / crate::brdf::exact_hemisphere_integral(alpha, mu_i);
            // dω = sin θ dθ dφ; the maps [−1, 1] → [0, α] and → [0, 2π).
            exact += wt * wp * (0.5 * half) * PI * theta.sin() * c_r * g * l_disc * mu_i;
        }
    }
    let mut z = Vec::new();
    for k in 0..24u64 {
        let x = DVec3::new(0.1 * k as f64 - 1.2, 0.5 - 0.05 * k as f64, 0.0);
        let mut rng = Rng::new(11, k);
        let (mean, se) = estimate(1000, |_| tracer.outgoing(0, x, wo, &mut rng).x);
        z.push((mean - exact) / se);
    }
    assert_unbiased("sun on a glossy floor", &z);
}

/// An axially symmetric LM-63-2002 profile (candela multiplier 1.5) hung
/// nadir down at height h, its peak given as the lamp's intensity by the
/// 683 rule: at floor points seen at each tabulated vertical angle θ_k the
/// radiance is ρ (1.5 · cd_k / 683) cos θ_k / (π d²). Exact to 1e-9
/// (variance-free; θ from the geometry lands on the table's angles to
/// ~1e-14°, where the bilinear table returns cd_k).
#[test]
fn ies_profile_candela_come_back_on_the_floor() {
    let vertical = [0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0];
    let candela = [
        900.0, 1000.0, 950.0, 700.0, 400.0, 250.0, 120.0, 50.0, 10.0, 0.0,
    ];
    let list = |v: &[f64]| {
        v.iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(" ")
    };
    let text = format!(
        "IESNA:LM-63-2002\n[TEST] path tracer\nTILT=NONE\n1 -1 1.5 10 1 1 2 0.1 0.1 0\n1 1 40\n{}\n0\n{}\n",
        list(&vertical),
        list(&candela)
    );
    let ies = std::sync::Arc::new(crate::light::ies::IesProfile::parse(&text, "lamp.ies").unwrap());
    let peak = 1.5 * 1000.0;
    let white = DVec3::ONE;
    let h = 2.0;
    let lamp = Lamp::point(
        "luminaire",
        DVec3::new(0.0, 0.0, h),
        crate::light::units::candela_to_intensity(peak, white),
        0.0,
    )
    .unwrap()
    .with_profile(ies, DVec3::NEG_Z)
    .unwrap();
    let render = lamps_over_floor(vec![lamp], vec![]);
    let tracer = integrator(&render);
    let eye = DVec3::new(0.2, 0.1, 5.0);
    for (k, (theta_deg, cd)) in vertical.iter().zip(candela).enumerate().take(9) {
        let theta = theta_deg.to_radians();
        let phi = 0.7 * k as f64;
        let p = h * theta.tan() * DVec3::new(phi.cos(), phi.sin(), 0.0);
        let d = h / theta.cos();
        let exact = RHO * (1.5 * cd / 683.0) * theta.cos() / (PI * d * d);
        let got = seen(&tracer, eye, p);
        assert_exact(got, DVec3::splat(exact), format!("θ = {theta_deg}°"));
    }
}
