//! `floor-plan`: an n × n grid of rooms (4 m pitch, 2.7 m high, millimetres)
//! with walls of thickness: closed wall slabs between corner pillars, and a
//! door (0.9 × 2.1 m) in every wall between two neighbouring rooms, so each
//! room opens to each neighbour. Every room has a floor, a ceiling and one
//! ceiling light, and each door a floor strip (its threshold). The count is
//! reached by the number of rooms (n grows with the square root of the
//! target) and by the wall tessellation: slab faces cut into quads of at most
//! `edge` millimetres.

use crate::mesh::{Closure, Mesh};
use crate::primitives::{add_box, add_horizontal_rect, BoxSpec, Placement};
use crate::scene::{Camera, Lights, Material, Scene};

/// Wall centre line to wall centre line.
pub const PITCH: f64 = 4000.0;
pub const THICKNESS: f64 = 150.0;
pub const HEIGHT: f64 = 2700.0;
const DOOR_WIDTH: f64 = 900.0;
const DOOR_HEIGHT: f64 = 2100.0;
const LIGHT_SIDE: f64 = 600.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Rooms per side.
    pub rooms: u32,
    /// The longest edge of a wall quad, mm (walls are not cut when it exceeds them).
    pub edge: f64,
}

/// A flat rectangle at height y: x range, z range, facing up or down.
#[derive(Clone, Copy, Debug)]
struct Rect {
    name_kind: &'static str,
    x: [f64; 2],
    z: [f64; 2],
    y: f64,
    up: bool,
}

/// The quad edge, on a geometric ladder from uncut (infinite) down to
/// 10 mm, whose `count(edge)` is nearest `triangles`; the ladder stops once
/// the count passes twice the target.
pub(crate) fn nearest_edge(triangles: usize, count: impl Fn(f64) -> usize) -> f64 {
    let mut best = (f64::INFINITY, count(f64::INFINITY).abs_diff(triangles));
    let mut edge = HEIGHT;
    while edge > 10.0 {
        let n = count(edge);
        if n.abs_diff(triangles) < best.1 {
            best = (edge, n.abs_diff(triangles));
        }
        if n > 2 * triangles {
            break;
        }
        edge *= 0.97;
    }
    best.0
}

/// The solids and rectangles of a plan, before meshing.
pub(crate) struct Plan {
    pub(crate) walls: Vec<BoxSpec>,
    rects: Vec<Rect>,
}

impl Params {
    /// The rooms from the target's square root (2 per side at 1k, 6 at 10k, 20
    /// at 100k, 63 at 1M: about 250 triangles a room), then the wall edge, on
    /// a geometric ladder from uncut down, whose count is nearest the target.
    pub fn for_triangles(triangles: usize) -> Params {
        let rooms = ((triangles as f64 / 250.0).sqrt().round() as u32).max(2);
        let edge = nearest_edge(triangles, |edge| Params { rooms, edge }.triangle_count());
        Params { rooms, edge }
    }

    pub(crate) fn divisions(&self, spec: &BoxSpec) -> [u32; 3] {
        std::array::from_fn(|a| {
            let length = spec.max[a] - spec.min[a];
            ((length / self.edge).ceil() as u32).max(1)
        })
    }

    pub fn triangle_count(&self) -> usize {
        self.plan().triangle_count()
    }

    /// Walls along x at z = j·PITCH and along z at x = i·PITCH, pillars at
    /// the grid nodes. Slabs run between pillars, so no two solids overlap.
    pub(crate) fn plan(&self) -> Plan {
        let n = self.rooms as usize;
        let t = 0.5 * THICKNESS;
        let mut walls = Vec::new();
        let mut rects = Vec::new();
        let mut slab = |min: [f64; 3], max: [f64; 3]| {
            let mut spec = BoxSpec {
                min,
                max,
                divisions: [1; 3],
            };
            spec.divisions = self.divisions(&spec);
            walls.push(spec);
        };
        for i in 0..=n {
            for j in 0..=n {
                let (x, z) = (i as f64 * PITCH, j as f64 * PITCH);
                slab([x - t, 0.0, z - t], [x + t, HEIGHT, z + t]);
            }
        }
        // A wall segment along `axis` (0: x, 2: z) from a to b at cross
        // coordinate c; with a door when it separates two rooms.
        let mut segment = |axis: usize, a: f64, b: f64, c: f64, door: bool| {
            let at = |lo: f64, hi: f64, y0: f64, y1: f64| {
                if axis == 0 {
                    ([lo, y0, c - t], [hi, y1, c + t])
                } else {
                    ([c - t, y0, lo], [c + t, y1, hi])
                }
            };
            if !door {
                let (min, max) = at(a, b, 0.0, HEIGHT);
                slab(min, max);
                return;
            }
            let mid = 0.5 * (a + b);
            let (d0, d1) = (mid - 0.5 * DOOR_WIDTH, mid + 0.5 * DOOR_WIDTH);
            for (lo, hi, y0) in [(a, d0, 0.0), (d1, b, 0.0), (d0, d1, DOOR_HEIGHT)] {
                let (min, max) = at(lo, hi, y0, HEIGHT);
                slab(min, max);
            }
            let (x, z) = if axis == 0 {
                ([d0, d1], [c - t, c + t])
            } else {
                ([c - t, c + t], [d0, d1])
            };
            rects.push(Rect {
                name_kind: "threshold",
                x,
                z,
                y: 0.0,
                up: true,
            });
        };
        for k in 0..=n {
            let c = k as f64 * PITCH;
            let interior = k > 0 && k < n;
            for m in 0..n {
                let (a, b) = (m as f64 * PITCH + t, (m + 1) as f64 * PITCH - t);
                segment(0, a, b, c, interior);
                segment(2, a, b, c, interior);
            }
        }
        for i in 0..n {
            for j in 0..n {
                let x = [i as f64 * PITCH + t, (i + 1) as f64 * PITCH - t];
                let z = [j as f64 * PITCH + t, (j + 1) as f64 * PITCH - t];
                rects.push(Rect {
                    name_kind: "floor",
                    x,
                    z,
                    y: 0.0,
                    up: true,
                });
                rects.push(Rect {
                    name_kind: "ceiling",
                    x,
                    z,
                    y: HEIGHT,
                    up: false,
                });
                let (cx, cz) = ((i as f64 + 0.5) * PITCH, (j as f64 + 0.5) * PITCH);
                let h = 0.5 * LIGHT_SIDE;
                // 1 mm below the ceiling, facing down (as the Cornell light is lowered).
                rects.push(Rect {
                    name_kind: "light",
                    x: [cx - h, cx + h],
                    z: [cz - h, cz + h],
                    y: HEIGHT - 1.0,
                    up: false,
                });
            }
        }
        Plan { walls, rects }
    }
}

impl Plan {
    pub(crate) fn triangle_count(&self) -> usize {
        self.walls.iter().map(|w| w.triangle_count()).sum::<usize>() + 2 * self.rects.len()
    }

    /// The walls (one object each) and the rectangles, in that order.
    pub(crate) fn mesh(&self) -> Mesh {
        let mut mesh = Mesh::default();
        for (i, wall) in self.walls.iter().enumerate() {
            mesh.begin_object(format!("wall_{i}"), "wall", Closure::Outward);
            add_box(&mut mesh, wall, &Placement::IDENTITY, Closure::Outward);
        }
        for (i, r) in self.rects.iter().enumerate() {
            mesh.begin_object(format!("{}_{i}", r.name_kind), r.name_kind, Closure::Open);
            add_horizontal_rect(&mut mesh, r.x, r.z, r.y, r.up);
        }
        mesh
    }
}

pub fn generate(params: Params) -> Scene {
    let mesh = params.plan().mesh();
    let n = params.rooms;
    Scene {
        description: format!(
            "floor-plan: {n} x {n} rooms, walls cut into quads of at most {:.0} mm",
            params.edge.min(1e9)
        ),
        mesh,
        materials: materials(),
        camera: first_room_camera(),
        lights: Lights::default(),
    }
}

/// The walls', floors', ceilings' and lights' materials.
pub(crate) fn materials() -> Vec<Material> {
    vec![
        Material::diffuse("wall", [0.7, 0.68, 0.65]),
        Material::diffuse("floor", [0.45, 0.35, 0.25]),
        Material::diffuse("threshold", [0.45, 0.35, 0.25]),
        Material::diffuse("ceiling", [0.8, 0.8, 0.8]),
        Material::emitter("light", [0.78, 0.78, 0.78], [10.0, 10.0, 10.0]),
    ]
}

/// In the first room, looking diagonally toward its doors.
pub(crate) fn first_room_camera() -> Camera {
    Camera {
        eye: [600.0, 1600.0, 600.0],
        target: [PITCH, 1100.0, PITCH],
        fov_y_deg: 60.0,
    }
}
