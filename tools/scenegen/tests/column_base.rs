//! A column standing on a floor in the sun must not leak at its base: the
//! floor beside it is drawn as the sun and the column's shadow say, right up
//! to the contact (docs/lab/lights-atrium.md, "Column bases").
//!
//! The scene is the atrium's ground floor reduced to one column: a 35 × 16 m
//! floor quad and a column of the atrium's size and tessellation, lit by the
//! atrium's sun alone (no sky). The solve stops after the sun's shot with no
//! ambient term, so every floor point's truth is exact: ρE⊥ sin 55°/π where
//! the column does not hide the sun, 0 where it does (on the column's
//! shadow axis within 1 m the penumbra, 1 m · tan 0.53° ≈ 9 mm to either side
//! of the umbra's 600 mm width, does not reach the axis).

use scenegen::mesh::{Closure, Mesh};
use scenegen::primitives::{add_cylinder, add_horizontal_rect};
use scenegen::scene::{write_scene, Camera, Lights, Material, Scene, Sun};
use solution::format::{read_solution, Representation};
use std::process::Command;

mod common;

const RADIUS: f64 = 300.0;
const CENTRE: [f64; 2] = [17_500.0, 12_500.0];
/// The atrium's sun (55° high): toward it, and its irradiance per channel.
const SUN: [f64; 3] = [0.496732, 0.819152, -0.286788];
const E_SUN: f64 = 146.4;
const FLOOR_KD: [f64; 3] = [0.5, 0.47, 0.42];

fn luminance(rgb: [f64; 3]) -> f64 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

fn scene() -> Scene {
    let mut mesh = Mesh::default();
    mesh.begin_object("floor", "floor", Closure::Open);
    add_horizontal_rect(&mut mesh, [0.0, 35_000.0], [0.0, 16_000.0], 0.0, true);
    mesh.begin_object("column", "column", Closure::Outward);
    // The atrium's ground-storey column at 62k triangles: 56 segments, 13 bands.
    add_cylinder(
        &mut mesh,
        [CENTRE[0], 0.0, CENTRE[1]],
        RADIUS,
        5_100.0,
        56,
        13,
    );
    Scene {
        description: "one column on a floor in the sun (column-base leak test)".into(),
        mesh,
        materials: vec![
            Material::diffuse("floor", FLOOR_KD),
            Material::diffuse("column", [0.65, 0.62, 0.56]),
        ],
        camera: Camera {
            eye: [17_500.0, 3_000.0, 9_000.0],
            target: [CENTRE[0], 0.0, CENTRE[1]],
            fov_y_deg: 60.0,
        },
        lights: Lights {
            sun: Some(Sun {
                direction: SUN,
                irradiance: [E_SUN; 3],
                angular_diameter_deg: 0.53,
            }),
            sky: None,
        },
    }
}

/// The floor's visible triangles (outside the column's footprint), each as its
/// corners (x, z) and their luminances.
type FloorTriangle = ([[f64; 2]; 3], [f64; 3]);

fn visible_floor(path: &std::path::Path) -> Vec<FloorTriangle> {
    let solution = read_solution(path).unwrap();
    let offset = solution.header.recentre_offset;
    let mut triangles = Vec::new();
    for batch in &solution.batches {
        // Diffuse: one SH coefficient per channel, radiance = c · Y00 toward any eye.
        assert_eq!(batch.representation, Representation::Sh { order: 0 });
        let position = |i: u32| batch.vertices[i as usize].position;
        let value = |i: u32| {
            let c = &batch.coefficients[3 * i as usize..3 * i as usize + 3];
            luminance([0, 1, 2].map(|k| c[k] as f64 * solution::sh::Y00))
        };
        for t in batch.indices.chunks_exact(3) {
            let p = [position(t[0]), position(t[1]), position(t[2])];
            let on_floor = p.iter().all(|q| (q[1] as f64 + offset[1]).abs() < 0.5);
            let up = t
                .iter()
                .all(|&i| batch.vertices[i as usize].normal[1] > 0.9);
            let xz = p.map(|q| [q[0] as f64 + offset[0], q[2] as f64 + offset[2]]);
            let centroid = [0, 1].map(|k| (xz[0][k] + xz[1][k] + xz[2][k]) / 3.0);
            let r = (centroid[0] - CENTRE[0]).hypot(centroid[1] - CENTRE[1]);
            if on_floor && up && r > RADIUS {
                triangles.push((xz, [value(t[0]), value(t[1]), value(t[2])]));
            }
        }
    }
    triangles
}

/// The floor as drawn at (x, z): the luminance interpolated over the visible
/// triangle that holds the point, as the renderers do.
fn drawn(triangles: &[FloorTriangle], x: f64, z: f64) -> f64 {
    for (p, v) in triangles {
        let (e1, e2) = (
            [p[1][0] - p[0][0], p[1][1] - p[0][1]],
            [p[2][0] - p[0][0], p[2][1] - p[0][1]],
        );
        let det = e1[0] * e2[1] - e2[0] * e1[1];
        let (dx, dz) = (x - p[0][0], z - p[0][1]);
        let u = (dx * e2[1] - e2[0] * dz) / det;
        let w = (e1[0] * dz - dx * e1[1]) / det;
        if u >= -1e-9 && w >= -1e-9 && u + w <= 1.0 + 1e-9 {
            return v[0] * (1.0 - u - w) + v[1] * u + v[2] * w;
        }
    }
    panic!("no visible floor triangle holds ({x}, {z})");
}

#[test]
fn the_floor_beside_a_sunlit_column_is_drawn_as_the_sun_and_its_shadow_say() {
    let dir = tempfile::tempdir().unwrap();
    let paths = write_scene(&scene(), dir.path(), "column").unwrap();
    let out = dir.path().join("column.sol");
    let run = Command::new(common::solver())
        .arg("solve")
        .arg(&paths.toml)
        .arg("--out")
        .arg(&out)
        .args(["--preset", "draft", "--max-shots", "1", "--no-ambient"])
        .args(["--strict", "--threads", "2"])
        .output()
        .unwrap();
    // Stopped at its one-shot cap on purpose: exit status 4, a partial file.
    assert_eq!(
        run.status.code(),
        Some(4),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let floor = visible_floor(&out);

    let sin_elevation = SUN[1] / (SUN[0].hypot(SUN[1]).hypot(SUN[2]));
    let lit = luminance(FLOOR_KD) * E_SUN * sin_elevation / std::f64::consts::PI;
    let bearing = SUN[2].atan2(SUN[0]);
    let at = |r: f64, angle: f64| {
        drawn(
            &floor,
            CENTRE[0] + r * angle.cos(),
            CENTRE[1] + r * angle.sin(),
        )
    };
    // No floor vertex holds more than the direct sun gives: 1% covers the f32
    // coefficients (the sun's disc, fully visible, is exact).
    let brightest = floor.iter().flat_map(|(_, v)| *v).fold(0.0, f64::max);
    assert!(
        brightest <= 1.01 * lit,
        "a floor vertex at {brightest}, the sun gives {lit}"
    );
    // The sun side, 5 mm from the column, within 30° of the sun's bearing: the
    // column is behind these points as seen from the sun, so all of it shines.
    for k in -3..=3 {
        let angle = bearing + (10.0 * k as f64).to_radians();
        let value = at(RADIUS + 5.0, angle);
        assert!(
            value >= 0.95 * lit,
            "sun side at {k}0°: {value}, truth {lit}"
        );
    }
    // The umbra behind the column, 0.1 to 1 m from its surface: the truth is 0;
    // 5% of the lit floor allows a ramp's foot, not a sunlit triangle.
    for step in 1..=10 {
        let value = at(RADIUS + 100.0 * step as f64, bearing + std::f64::consts::PI);
        assert!(
            value <= 0.05 * lit,
            "umbra at {step}00 mm: {value}, lit {lit}"
        );
    }
}
