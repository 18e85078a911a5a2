//! The environment behind the geometry (solution format x.1, issue 41): the
//! GPU's background pass against the CPU reference (`solution::raster`,
//! stage 7) in an open room, looking at the walls' tops and up at the sky
//! and the sun's disc; and an x.0 file keeps its black background.

mod common;

use glam::DVec3;
use runtime::render::{MultiviewMode, RendererDesc, StereoRenderer};
use runtime::session::OffscreenSwapchain;
use solution::camera::Camera;
use solution::format::{Environment, Lighting, Solution, SunDisc};

/// A smooth sky that varies in azimuth and elevation (so orientation and
/// interpolation errors show), 64 × 32 texels, and a 6° sun.
fn environment(sun_toward: DVec3) -> Environment {
    let (w, h) = (64u32, 32u32);
    let texels = (0..h)
        .flat_map(|j| {
            (0..w).map(move |i| {
                let u = (f64::from(i) + 0.5) / f64::from(w);
                let v = (f64::from(j) + 0.5) / f64::from(h);
                let a = (std::f64::consts::TAU * u).sin();
                [(1.0 + 0.5 * a) as f32, (0.4 + v) as f32, 0.8]
            })
        })
        .collect();
    let d = sun_toward.normalize().as_vec3();
    Environment {
        width: w,
        height: h,
        texels,
        sun: Some(SunDisc {
            direction: [d.x, d.y, d.z],
            angular_diameter_deg: 6.0,
            radiance: [40.0, 38.0, 30.0],
        }),
    }
}

fn lit_room(sun_toward: DVec3) -> Solution {
    let mut solution = common::diffuse_room(4);
    solution.lighting = Some(Lighting {
        exposure_key: 0.5,
        lights_json: Some("{\"lights\":[]}".into()),
        environment: Some(environment(sun_toward)),
    });
    solution
}

/// From inside the room, looking up over the walls' tops at the sky.
fn looking_up(width: u32, height: u32) -> Camera {
    Camera {
        eye: [0.3, 1.2, 2.5],
        target: [-0.4, 4.0, -2.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 70.0,
        width,
        height,
    }
}

fn render(solution: &Solution, camera: &Camera) -> Vec<runtime::render::EyeImage> {
    let gpu = common::gpu();
    let views = camera.stereo_views(0.3, DVec3::ZERO);
    let swapchain = OffscreenSwapchain::new(&gpu, camera.width, camera.height, 1).unwrap();
    let desc = RendererDesc {
        width: camera.width,
        height: camera.height,
        max_samples: 1,
        multiview: MultiviewMode::Auto,
        ..RendererDesc::default()
    };
    let (_dir, file) = common::mapped(solution);
    let mut renderer = StereoRenderer::from_mapped(&gpu, &file, desc, &swapchain.desc()).unwrap();
    renderer.render(&views, 0).unwrap();
    let eyes = renderer.read_back(&gpu, 0, views.len()).unwrap();
    common::assert_validation_clean(&gpu);
    eyes
}

// Tolerances (relative to the reference's mean radiance), as for the
// diffuse room (`reference.rs`): the half-float target (2⁻¹¹ of the scene's
// radiance bound), and the silhouette pixels of the walls' tops, whose
// centres may fall on the other side on the GPU. The sky adds its f32
// direction, atan and acos (a few 1e-7 rad, far below a texel's 0.1 rad, so
// ~1e-6 of a texel difference), and the rim of the sun's disc (6° ≈ 8 px
// across at 96 × 80: about 25 rim pixels, 0.3%, each off by up to the disc's
// 40 against a mean near 1). Allowed: mean 5e-3, p99 5e-2, 1.5% of pixels.
// Measured on lavapipe: mean 5.2e-4, p99 1.4e-3, none differing (room);
// mean 4.9e-4, p99 9.0e-4, 0.38% differing, max 2.6e-2 (looking up, the
// disc's 29 pixels identical).
const TOLERANCES: common::Tolerances = common::Tolerances {
    mean: 5e-3,
    p99: 5e-2,
    fraction: 0.015,
};

#[test]
fn open_room_shows_the_sky_and_sun_as_the_cpu_reference() {
    // The sun in the view, up and ahead.
    let solution = lit_room(DVec3::new(-0.15, 0.6, -1.0));
    for (name, camera) in [
        ("sky-room", common::room_camera(96, 80)),
        ("sky-up", looking_up(96, 80)),
    ] {
        let eyes = render(&solution, &camera);
        let views = camera.stereo_views(0.3, DVec3::ZERO);
        for (eye, (view, label)) in eyes.iter().zip(views.iter().zip(["left", "right"])) {
            let name = format!("{name}-{label}");
            common::assert_matches_cpu_reference(&name, &solution, view, eye, TOLERANCES);
            // The sky is drawn: no pixel is black any more.
            let black = eye
                .radiance
                .chunks_exact(3)
                .filter(|p| p.iter().all(|&c| c == 0.0));
            assert_eq!(black.count(), 0, "{name}: black pixels");
            let cpu = solution::raster::render(&solution, view, &Default::default()).unwrap();
            let sky = (0..cpu.pixels.len())
                .filter(|&k| cpu.depth[k] == 1.0)
                .count();
            let sun = eye.radiance.chunks_exact(3).filter(|p| p[0] > 20.0).count();
            eprintln!("{name}: {sky} sky pixels, {sun} in the sun's disc");
            assert!(sky > 100, "{name}: the test sees the sky");
            if name.starts_with("sky-up") {
                assert!(sun > 10, "{name}: the test sees the sun");
            }
        }
    }
}

#[test]
fn a_file_without_environment_keeps_its_black_background() {
    let eyes = render(&common::diffuse_room(4), &looking_up(48, 40));
    let black = eyes[0]
        .radiance
        .chunks_exact(3)
        .filter(|p| p.iter().all(|&c| c == 0.0))
        .count();
    assert!(black > 100, "{black} black pixels above the walls");
}

#[test]
fn screenshot_of_a_lit_file_is_exposed_from_its_key_through_aces() {
    // `runtime screenshot` of a lit file: the file's key 0.5 gives
    // log2(0.18 / 0.5) = −1.47 stops, `--exposure 1` adds one, and the
    // default curve is ACES; the PNG matches the CPU reference (sky
    // included) tone-mapped so. Tolerance: ±2 of 255 per channel (the
    // half-float target and Vulkan's sRGB conversion, each about one step)
    // for all but 2% of pixels (silhouette pixels of the walls' tops).
    // Measured on lavapipe: no value off by more than 2.
    common::use_lavapipe_unless_chosen();
    let dir = tempfile::tempdir().unwrap();
    let solution = lit_room(DVec3::new(-0.15, 0.6, -1.0));
    let path = dir.path().join("lit.sol");
    solution::format::write_solution(&path, &solution).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_runtime"))
        .arg("screenshot")
        .arg(&path)
        .args(["--eye", "0.3", "1.2", "2.5", "--target", "-0.4", "4", "-2"])
        .args([
            "--fov-y",
            "70",
            "--size",
            "48x40",
            "--mono",
            "--exposure",
            "1",
        ])
        .args(["--samples", "1", "--out"])
        .arg(dir.path().join("shot"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let png = image::open(dir.path().join("shot.png")).unwrap().to_rgb8();
    let view = looking_up(48, 40).mono_view(DVec3::from(solution.header.recentre_offset));
    let cpu = solution::raster::render(&solution, &view, &Default::default()).unwrap();
    let stops = (0.18f32 / 0.5).log2() + 1.0;
    let expected =
        solution::raster::tonemap_srgb8(&cpu, stops, solution::raster::ToneCurve::AcesFit);
    let off = png
        .as_raw()
        .iter()
        .zip(&expected)
        .filter(|(a, b)| a.abs_diff(**b) > 2)
        .count();
    eprintln!(
        "lit screenshot: {off} of {} channel values off by more than 2",
        expected.len()
    );
    assert!(
        off * 50 <= expected.len(),
        "{off} of {} values differ",
        expected.len()
    );
    // And the exposure was applied: the clamp curve at 0 EV would give
    // other bytes.
    let clamp0 = solution::raster::tonemap_srgb8(&cpu, 0.0, solution::raster::ToneCurve::Clamp);
    assert_ne!(png.as_raw(), &clamp0);
}

#[test]
fn a_reloaded_file_brings_its_sky_or_its_black() {
    // The mirror's `--watch` reload (`StereoRenderer::set_mapped`): a plain
    // file, then a lit one, then the plain one again.
    let gpu = common::gpu();
    let camera = looking_up(48, 40);
    let views = [camera.mono_view(DVec3::ZERO)];
    let swapchain = OffscreenSwapchain::new(&gpu, 48, 40, 1).unwrap();
    let desc = RendererDesc {
        width: 48,
        height: 40,
        max_samples: 1,
        ..RendererDesc::default()
    };
    let (_plain_dir, plain) = common::mapped(&common::diffuse_room(4));
    let (_lit_dir, lit) = common::mapped(&lit_room(DVec3::new(0.0, 1.0, 0.0)));
    let mut renderer = StereoRenderer::from_mapped(&gpu, &plain, desc, &swapchain.desc()).unwrap();
    let mut black = Vec::new();
    for file in [&plain, &lit, &plain] {
        renderer.set_mapped(&gpu, file).unwrap();
        renderer.render(&views, 0).unwrap();
        let eye = &renderer.read_back(&gpu, 0, 1).unwrap()[0];
        let zero = eye
            .radiance
            .chunks_exact(3)
            .filter(|p| p.iter().all(|&c| c == 0.0));
        black.push(zero.count());
    }
    assert!(
        black[0] > 100 && black[1] == 0 && black[2] == black[0],
        "{black:?}"
    );
    common::assert_validation_clean(&gpu);
}
