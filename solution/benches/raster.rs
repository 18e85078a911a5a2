//! Speed of the CPU reference renderer (`solution::raster::render`): the vertex
//! stage (SH toward the eye) and the whole frame, for a room of gridded walls.
//!
//! `cargo bench -p solution --bench raster` (figures in docs/benchmarks.md, section
//! "CPU rasterizer"). The scene is a 10 × 4 × 8 room seen from inside, each of its
//! six walls a grid of `GRID × GRID` quads with shared vertices; the floor is
//! either diffuse (order 0) or glossy (order 8, 81 coefficients per channel).

use glam::DVec3;
use solution::camera::{Camera, UpAxis};
use solution::format::{
    Batch, Header, Representation, ScalarType, Solution, SolveMode, SolveStats, Vertex,
};
use solution::raster::{render, shade_vertices, RenderOptions};
use std::hint::black_box;
use std::time::Instant;

const GRID: u32 = 100;

/// One wall: origin corner, two edge vectors (u × v is the inward normal).
fn wall(origin: DVec3, u: DVec3, v: DVec3, order: u32) -> Batch {
    let normal = u.cross(v).normalize();
    let tangent = u.normalize();
    let mut vertices = Vec::new();
    for j in 0..=GRID {
        for i in 0..=GRID {
            let p = origin + u * (i as f64 / GRID as f64) + v * (j as f64 / GRID as f64);
            vertices.push(Vertex {
                position: p.as_vec3().into(),
                normal: normal.as_vec3().into(),
                tangent: tangent.as_vec3().into(),
            });
        }
    }
    let row = GRID + 1;
    let mut indices = Vec::new();
    for j in 0..GRID {
        for i in 0..GRID {
            let a = j * row + i;
            // Counter-clockwise seen from the normal side (u, then v).
            indices.extend_from_slice(&[a, a + 1, a + row + 1, a, a + row + 1, a + row]);
        }
    }
    let per_vertex = ((order + 1) * (order + 1) * 3) as usize;
    let coefficients = (0..vertices.len() * per_vertex)
        .map(|k| {
            if k % per_vertex < 3 {
                2.0
            } else {
                ((k * 2_654_435_761) % 1000) as f32 * 1e-4
            }
        })
        .collect();
    Batch {
        representation: Representation::Sh { order },
        scalar: ScalarType::F32,
        vertices,
        coefficients,
        indices,
        texturing: None,
    }
}

fn room(floor_order: u32) -> Solution {
    let (x, y, z) = (DVec3::X * 10.0, DVec3::Y * 4.0, DVec3::Z * 8.0);
    let o = DVec3::new(-5.0, -2.0, -4.0);
    let far = o + x + y + z;
    let batches = vec![
        wall(o, z, x, floor_order), // floor, normal +y
        wall(far, -x, -z, 0),       // ceiling, normal −y
        wall(o, x, y, 0),           // back wall z = −4, normal +z
        wall(far, -y, -x, 0),       // front wall z = +4, normal −z
        wall(o, y, z, 0),           // left wall, normal +x
        wall(far, -z, -y, 0),       // right wall, normal −x
    ];
    Solution {
        lighting: None,
        header: Header {
            units_per_metre: 1.0,
            up_axis: UpAxis::PosY,
            recentre_offset: [0.0; 3],
            camera: Camera {
                eye: [0.0, 0.0, 3.0],
                target: [0.5, -0.4, -4.0],
                up: [0.0, 1.0, 0.0],
                fov_y_deg: 75.0,
                width: 1024,
                height: 768,
            },
            bounds_min: o.as_vec3().into(),
            bounds_max: far.as_vec3().into(),
            partial: false,
            mode: SolveMode::Directional,
            stats: SolveStats::default(),
            settings_json: String::new(),
        },
        batches,
        textures: Vec::new(),
    }
}

/// Median of `runs` timings of `f`, seconds.
fn median_seconds(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[runs / 2]
}

fn main() {
    let threads = std::thread::available_parallelism().map_or(1, |t| t.get());
    println!("raster bench: {threads} hardware threads, room of 6 walls × {GRID}² quads");
    for floor_order in [0u32, 8] {
        let scene = room(floor_order);
        let triangles: usize = scene.batches.iter().map(|b| b.indices.len() / 3).sum();
        let vertices: usize = scene.batches.iter().map(|b| b.vertices.len()).sum();
        let view = scene.header.camera.mono_view(DVec3::ZERO);
        let floor = &scene.batches[0];
        let shade = median_seconds(5, || {
            black_box(
                shade_vertices(floor, floor_order, view.position, true).expect("valid batch"),
            );
        });
        let options = RenderOptions::default();
        let mut covered = 0;
        let frame = median_seconds(5, || {
            let image = render(&scene, &view, &options).expect("bench scene renders");
            covered = image.depth.iter().filter(|&&d| d < 1.0).count();
            black_box(image);
        });
        println!(
            "floor L = {floor_order}: {triangles} triangles, {vertices} vertices, {}x{} px ({covered} covered): \
             frame {:.1} ms ({:.2} Mtri/s); floor vertex stage {:.2} ms ({:.2} Mvert/s, {} coefficients/channel)",
            view.width,
            view.height,
            frame * 1e3,
            triangles as f64 / frame * 1e-6,
            shade * 1e3,
            floor.vertices.len() as f64 / shade * 1e-6,
            (floor_order + 1) * (floor_order + 1),
        );
    }
}
