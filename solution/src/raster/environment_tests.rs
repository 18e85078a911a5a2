//! Stage 7: the environment behind the geometry (format x.1).

use super::*;
use crate::camera::{Fov, UpAxis};
use crate::format::{equirect_direction, Lighting, ScalarType, SunDisc, Vertex};

fn solution(batches: Vec<Batch>, env: Environment) -> Solution {
    Solution {
        header: super::tests::header(),
        batches,
        textures: Vec::new(),
        lighting: Some(Lighting {
            exposure_key: 1.0,
            lights_json: None,
            environment: Some(env),
        }),
    }
}

/// A sky whose texel (i, j) holds (i, j, 1): every column and row tells.
fn ramp(width: u32, height: u32, sun: Option<SunDisc>) -> Environment {
    Environment {
        width,
        height,
        texels: (0..height)
            .flat_map(|j| (0..width).map(move |i| [i as f32, j as f32, 1.0]))
            .collect(),
        sun,
    }
}

fn view(forward: DVec3, up: DVec3) -> EyeView {
    EyeView {
        position: DVec3::ZERO,
        right: forward.cross(up).normalize(),
        up,
        forward,
        fov: Fov::symmetric(60f64.to_radians(), 48, 32),
        width: 48,
        height: 32,
    }
}

#[test]
fn uncovered_pixels_show_the_sky_toward_their_centre() {
    let env = ramp(16, 8, None);
    let v = view(DVec3::NEG_Z, DVec3::Y);
    let image = render(
        &solution(Vec::new(), env.clone()),
        &v,
        &RenderOptions::default(),
    )
    .unwrap();
    for j in 0..v.height {
        for i in 0..v.width {
            let d = pixel_direction(&v, i, j).to_array();
            assert_eq!(image.pixel(i, j), env.radiance(UpAxis::PosY, d));
            assert!(!image.covered(i, j), "the sky leaves the depth at 1");
        }
    }
    // The centre pixel looks along −z, up × x's direction turned half:
    // u = 0.25 is −z for a y-up file, on the horizon (v = 0.5). Bilinear
    // between texel centres there: column u·16 − 0.5 = 3.5, row 3.5.
    let centre = image.pixel(24, 16);
    let d = equirect_direction(UpAxis::PosY, 0.25, 0.5);
    assert!((DVec3::from(d) - DVec3::NEG_Z).length() < 1e-12);
    assert!((centre[0] - 3.5).abs() < 0.1, "{centre:?}");
    assert!((centre[1] - 3.5).abs() < 0.1, "{centre:?}");
}

#[test]
fn geometry_hides_the_sky_and_the_sun_disc_shows() {
    // A triangle in front of the eye covering the lower left; the sun
    // straight ahead, in the uncovered part, with a 10° disc.
    let sun = SunDisc {
        direction: [0.0, 0.0, -1.0],
        angular_diameter_deg: 10.0,
        radiance: [1000.0; 3],
    };
    let env = ramp(16, 8, Some(sun));
    let p = |x: f32, y: f32| Vertex {
        position: [x, y, -5.0],
        normal: [0.0, 0.0, 1.0],
        tangent: [1.0, 0.0, 0.0],
    };
    let batch = Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertices: vec![p(-20.0, -20.0), p(18.0, -20.0), p(-20.0, 18.0)],
        coefficients: vec![7.0; 9],
        indices: vec![0, 1, 2],
        texturing: None,
    };
    let v = view(DVec3::NEG_Z, DVec3::Y);
    let image = render(
        &solution(vec![batch], env.clone()),
        &v,
        &RenderOptions::default(),
    )
    .unwrap();
    let triangle = (7.0 * sh::Y00) as f32;
    assert_eq!(image.pixel(0, 31), [triangle; 3]);
    assert!(image.covered(0, 31));
    assert!(image.pixel(24, 16)[0] > 1000.0, "the sun's disc");
    let corner = pixel_direction(&v, 47, 0).to_array();
    assert_eq!(image.pixel(47, 0), env.radiance(UpAxis::PosY, corner));
    assert!(image.pixel(47, 0)[0] < 1000.0, "outside the disc");
}
