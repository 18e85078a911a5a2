//! `cornell-boxes`: the Cornell box (the room, its materials and its ceiling
//! light as in /work/shared/scenes/cornell_box.obj, from the Cornell Program of
//! Computer Graphics' published measurements, millimetres) with its two blocks
//! replaced by K small closed boxes (12 triangles each) standing on the floor.
//!
//! Layout: the floor inside a margin is cut into a grid of square cells, at
//! least K of them; K cells are drawn from the seed, and each holds one box of
//! random width, depth, height and yaw whose footprint circle lies inside its
//! cell. Cells are disjoint, so boxes never overlap.

use crate::mesh::{Closure, Corner, Mesh, Vec3};
use crate::primitives::{add_box, footprint_radius, BoxSpec, Placement};
use crate::rng::SplitMix64;
use crate::scene::{Camera, Lights, Material, Scene};

/// The room's triangles: floor, ceiling, back, left and right walls (one quad,
/// two triangles each) and the light (two).
pub const ROOM_TRIANGLES: usize = 12;
pub const BOX_TRIANGLES: usize = 12;

/// The floor region boxes may use: inside the walls with a 10 mm margin (the
/// published floor narrows from 552.8 mm at z = 0 to 549.6 mm at the back).
const FLOOR_X: [f64; 2] = [10.0, 539.0];
const FLOOR_Z: [f64; 2] = [10.0, 549.0];
/// Boxes stay well below the light (548.7 mm) and the ceiling.
const MAX_BOX_HEIGHT: f64 = 400.0;

/// One small box: footprint centre on the floor (y = 0), size and yaw.
#[derive(Clone, Copy, Debug)]
pub struct SmallBox {
    pub centre: [f64; 2],
    pub width: f64,
    pub depth: f64,
    pub height: f64,
    pub yaw: f64,
}

impl SmallBox {
    pub fn footprint_radius(&self) -> f64 {
        footprint_radius(self.width, self.depth)
    }
}

/// The number of boxes whose scene lands nearest `triangles`.
pub fn boxes_for(triangles: usize) -> usize {
    ((triangles.saturating_sub(ROOM_TRIANGLES) as f64 / BOX_TRIANGLES as f64).round() as usize)
        .max(1)
}

/// K boxes laid out deterministically from `seed`.
pub fn layout(count: usize, seed: u64) -> Vec<SmallBox> {
    let width = FLOOR_X[1] - FLOOR_X[0];
    let depth = FLOOR_Z[1] - FLOOR_Z[0];
    let mut cell = (width * depth / count as f64).sqrt();
    let grid = |cell: f64| {
        (
            (width / cell).floor() as usize,
            (depth / cell).floor() as usize,
        )
    };
    while grid(cell).0 * grid(cell).1 < count {
        cell *= 0.99;
    }
    let (columns, rows) = grid(cell);
    let mut rng = SplitMix64::new(seed);
    // The first `count` entries of a Fisher–Yates shuffle of the cells.
    let mut cells: Vec<usize> = (0..columns * rows).collect();
    for i in 0..count {
        let j = i + rng.below((cells.len() - i) as u64) as usize;
        cells.swap(i, j);
    }
    cells[..count]
        .iter()
        .map(|&c| {
            let (column, row) = (c % columns, c / columns);
            let w = cell * rng.range(0.3, 0.6);
            let d = cell * rng.range(0.3, 0.6);
            // The footprint circle (radius ≤ 0.43 cell) stays inside the cell
            // with a margin of 2% of the cell on every side.
            let slack = 0.48 * cell - footprint_radius(w, d);
            let centre = [
                FLOOR_X[0] + (column as f64 + 0.5) * cell + rng.range(-slack, slack),
                FLOOR_Z[0] + (row as f64 + 0.5) * cell + rng.range(-slack, slack),
            ];
            SmallBox {
                centre,
                width: w,
                depth: d,
                height: (cell * rng.range(0.3, 1.2)).min(MAX_BOX_HEIGHT),
                yaw: rng.range(0.0, std::f64::consts::FRAC_PI_2),
            }
        })
        .collect()
}

/// The scene with `count` boxes.
pub fn generate(count: usize, seed: u64) -> Scene {
    let mut mesh = Mesh::default();
    add_room(&mut mesh);
    for (i, b) in layout(count, seed).iter().enumerate() {
        mesh.begin_object(format!("box_{i}"), "white", Closure::Outward);
        let spec = BoxSpec {
            min: [-0.5 * b.width, 0.0, -0.5 * b.depth],
            max: [0.5 * b.width, b.height, 0.5 * b.depth],
            divisions: [1, 1, 1],
        };
        let placement = Placement {
            pivot: [b.centre[0], 0.0, b.centre[1]],
            yaw: b.yaw,
        };
        add_box(&mut mesh, &spec, &placement, Closure::Outward);
    }
    Scene {
        description: format!(
            "cornell-boxes: the Cornell box with {count} small boxes (seed {seed})"
        ),
        mesh,
        materials: vec![
            Material::diffuse("white", [0.725, 0.71, 0.68]),
            Material::diffuse("red", [0.63, 0.065, 0.05]),
            Material::diffuse("green", [0.14, 0.45, 0.091]),
            Material::emitter("light", [0.78, 0.78, 0.78], [17.0, 12.0, 4.0]),
        ],
        // The standard Cornell box camera.
        camera: Camera {
            eye: [278.0, 273.0, -800.0],
            target: [278.0, 273.0, 0.0],
            fov_y_deg: 39.3077,
        },
        lights: Lights::default(),
    }
}

/// The published quads (counter-clockwise seen from inside the room), each
/// split into (v1, v2, v3) + (v1, v3, v4) as the published file advises for
/// the slightly non-planar red wall.
fn add_room(mesh: &mut Mesh) {
    let quads: [(&str, &str, [Vec3; 4]); 6] = [
        (
            "floor",
            "white",
            [
                [552.8, 0.0, 0.0],
                [0.0, 0.0, 0.0],
                [0.0, 0.0, 559.2],
                [549.6, 0.0, 559.2],
            ],
        ),
        (
            "ceiling",
            "white",
            [
                [556.0, 548.8, 0.0],
                [556.0, 548.8, 559.2],
                [0.0, 548.8, 559.2],
                [0.0, 548.8, 0.0],
            ],
        ),
        (
            "back_wall",
            "white",
            [
                [549.6, 0.0, 559.2],
                [0.0, 0.0, 559.2],
                [0.0, 548.8, 559.2],
                [556.0, 548.8, 559.2],
            ],
        ),
        (
            "right_wall_green",
            "green",
            [
                [0.0, 0.0, 559.2],
                [0.0, 0.0, 0.0],
                [0.0, 548.8, 0.0],
                [0.0, 548.8, 559.2],
            ],
        ),
        (
            "left_wall_red",
            "red",
            [
                [552.8, 0.0, 0.0],
                [549.6, 0.0, 559.2],
                [556.0, 548.8, 559.2],
                [556.0, 548.8, 0.0],
            ],
        ),
        // Lowered 0.1 mm below the ceiling, as published, against z-fighting.
        (
            "light",
            "light",
            [
                [343.0, 548.7, 227.0],
                [343.0, 548.7, 332.0],
                [213.0, 548.7, 332.0],
                [213.0, 548.7, 227.0],
            ],
        ),
    ];
    for (name, material, corners) in quads {
        mesh.begin_object(name, material, Closure::Open);
        let c = corners.map(|p| Corner::flat(mesh.add_position(p)));
        mesh.quad(c);
    }
}
