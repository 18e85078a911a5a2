//! `window-room`: a closed 5.5 m cube room (millimetres, white walls with a
//! red left and a green right wall, the Cornell box's reflectances) whose
//! back wall has a rectangular window, a hole. It is lit only by a sun that
//! shines through the window onto the floor and by a uniform sky; two boxes
//! on the floor cast shadows, one of them inside the sun patch.
//!
//! The room is one shell: all six faces are cut on one lattice of grid lines
//! (x, y, z), which includes the window's edges, and share its vertices, so
//! every edge joins exactly two triangles except the window's rim. The count
//! is reached by the lattice's cells per side (the window's edges added, and
//! the uniform lines too close to them dropped) and the boxes' face grid.

use crate::mesh::{Closure, Mesh};
use crate::primitives::{
    add_box, add_lattice_box, lattice_box_triangle_count, BoxFace, BoxSpec, Placement,
};
use crate::scene::{Camera, Lights, Material, Scene};

/// The room's inner side: it spans [0, SIDE] on every axis.
pub const SIDE: f64 = 5_500.0;
/// The window in the back wall (z = SIDE): its x and y ranges.
pub const WINDOW_X: [f64; 2] = [1_500.0, 4_000.0];
pub const WINDOW_Y: [f64; 2] = [1_500.0, 3_700.0];
/// The sun's elevation and its bearing from the room, degrees from +z toward +x.
pub const SUN_ELEVATION_DEG: f64 = 40.0;
const SUN_BEARING_DEG: f64 = 15.0;

/// The boxes: footprint centre (x, z), width, height, depth, yaw in degrees.
const BOXES: [([f64; 2], [f64; 3], f64); 2] = [
    // In the sun patch.
    ([2_000.0, 2_600.0], [1_000.0, 1_000.0, 1_000.0], 25.0),
    // Tall, in the back corner by the red wall: it cuts the sun beam's edge.
    ([4_300.0, 4_000.0], [1_200.0, 2_400.0, 1_200.0], -15.0),
];

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Uniform cells per side of the room before the window's lines are added (≥ 1).
    pub cells: u32,
    /// Cells per edge of each box's faces (≥ 1).
    pub box_divisions: u32,
}

/// The room's faces as objects: name and material by (axis, far side).
fn face_object(face: BoxFace) -> (&'static str, &'static str) {
    match (face.axis, face.far) {
        (0, false) => ("right_wall_green", "green"),
        // As in the Cornell box: red at +x, on the left seen from the camera
        // (which looks along +z), green at x = 0 on the right.
        (0, true) => ("left_wall_red", "red"),
        (1, false) => ("floor", "white"),
        (1, true) => ("ceiling", "white"),
        (2, false) => ("front_wall", "white"),
        _ => ("back_wall", "white"),
    }
}

/// The back wall, which holds the window; its cells' u is x and v is y.
const BACK: BoxFace = BoxFace { axis: 2, far: true };

impl Params {
    pub fn at_level(cells: u32) -> Params {
        Params {
            cells,
            box_divisions: cells.div_ceil(2),
        }
    }

    /// The level whose count is nearest `triangles`.
    pub fn for_triangles(triangles: usize) -> Params {
        let mut best = Params::at_level(1);
        let mut cells = 1;
        loop {
            let p = Params::at_level(cells);
            let count = p.triangle_count();
            if count.abs_diff(triangles) < best.triangle_count().abs_diff(triangles) {
                best = p;
            }
            if count > 2 * triangles || cells >= 10_000 {
                return best;
            }
            cells += 1;
        }
    }

    /// The grid lines of each axis: x and y carry the window's edges.
    pub fn lattice(&self) -> [Vec<f64>; 3] {
        [
            grid_lines(self.cells, &WINDOW_X),
            grid_lines(self.cells, &WINDOW_Y),
            grid_lines(self.cells, &[]),
        ]
    }

    pub fn triangle_count(&self) -> usize {
        let room = lattice_box_triangle_count(&self.lattice()) - 2 * self.window_cells();
        let box_spec = BoxSpec {
            min: [0.0; 3],
            max: [1.0; 3],
            divisions: [self.box_divisions; 3],
        };
        room + BOXES.len() * box_spec.triangle_count()
    }

    /// The back wall's cells inside the window.
    fn window_cells(&self) -> usize {
        let [x, y, _] = self.lattice();
        let inside = |lines: &[f64], range: [f64; 2]| {
            lines
                .windows(2)
                .filter(|w| w[0] >= range[0] && w[1] <= range[1])
                .count()
        };
        inside(&x, WINDOW_X) * inside(&y, WINDOW_Y)
    }
}

/// `cells` uniform lines over [0, SIDE] with `fixed` added; a uniform line
/// within a quarter cell of a fixed one is dropped so that no cell is a
/// sliver (the ends 0 and SIDE stay).
fn grid_lines(cells: u32, fixed: &[f64]) -> Vec<f64> {
    let cell = SIDE / cells as f64;
    let mut lines: Vec<f64> = (0..=cells)
        .map(|k| if k == cells { SIDE } else { k as f64 * cell })
        .filter(|&u| u == 0.0 || u == SIDE || fixed.iter().all(|f| (u - f).abs() > 0.25 * cell))
        .collect();
    lines.extend_from_slice(fixed);
    lines.sort_by(f64::total_cmp);
    lines
}

fn in_window(x: [f64; 2], y: [f64; 2]) -> bool {
    x[0] >= WINDOW_X[0] && x[1] <= WINDOW_X[1] && y[0] >= WINDOW_Y[0] && y[1] <= WINDOW_Y[1]
}

/// Adds the room as one lattice box facing in, an object per face, without
/// the window's cells.
fn add_room(mesh: &mut Mesh, lattice: &[Vec<f64>; 3]) {
    add_lattice_box(
        mesh,
        lattice,
        &Placement::IDENTITY,
        Closure::Inward,
        |mesh, face| {
            let (name, material) = face_object(face);
            mesh.begin_object(name, material, Closure::Open);
        },
        |cell| !(cell.face == BACK && in_window(cell.u, cell.v)),
    );
}

pub fn generate(params: Params) -> Scene {
    let mut mesh = Mesh::default();
    add_room(&mut mesh, &params.lattice());
    for (i, (centre, size, yaw)) in BOXES.iter().enumerate() {
        mesh.begin_object(format!("box_{i}"), "white", Closure::Outward);
        let spec = BoxSpec {
            min: [-0.5 * size[0], 0.0, -0.5 * size[2]],
            max: [0.5 * size[0], size[1], 0.5 * size[2]],
            divisions: [params.box_divisions; 3],
        };
        let placement = Placement {
            pivot: [centre[0], 0.0, centre[1]],
            yaw: yaw.to_radians(),
        };
        add_box(&mut mesh, &spec, &placement, Closure::Outward);
    }
    let bearing = SUN_BEARING_DEG.to_radians();
    Scene {
        description: format!(
            "window-room: a closed 5.5 m room with a 2.5 x 2.2 m window, lit by sun and sky; {} cells a side, boxes {} x {}",
            params.cells, params.box_divisions, params.box_divisions
        ),
        mesh,
        materials: vec![
            Material::diffuse("white", [0.725, 0.71, 0.68]),
            Material::diffuse("red", [0.63, 0.065, 0.05]),
            Material::diffuse("green", [0.14, 0.45, 0.091]),
        ],
        // By the front wall at eye height, looking at the window and the sun
        // patch below it.
        camera: Camera {
            eye: [0.5 * SIDE, 1_700.0, 300.0],
            target: [0.5 * SIDE, 1_400.0, SIDE],
            fov_y_deg: 60.0,
        },
        // Behind the back wall (+z), a little toward +x: the sun comes in
        // through the window and lands on the floor.
        lights: Lights::daylight(SUN_ELEVATION_DEG, [bearing.sin(), bearing.cos()]),
    }
}
