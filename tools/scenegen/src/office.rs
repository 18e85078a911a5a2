//! `office`: the [`floorplan`](crate::floorplan) grid of rooms, furnished.
//! Every room has a cabinet against one wall, a bookshelf against another,
//! two desks (a top on four legs) and two chairs (a seat on one column).
//! Each piece is a closed box of its own object, standing on the floor or on
//! another piece, or backed against a wall: the contacts that the solver's
//! contact conforming (`mesh::contact`) cuts receivers along, about a dozen
//! footprints per floor and four per desk top's underside. The count is
//! reached by the number of rooms and by the tessellation: every face,
//! walls and furniture alike, cut into quads of at most `edge` millimetres.

use crate::floorplan::{self, PITCH, THICKNESS};
use crate::mesh::Closure;
use crate::primitives::{add_box, BoxSpec, Placement};
use crate::scene::{Lights, Material, Scene};

/// About this many triangles a room at the coarsest tessellation (walls,
/// floor, ceiling, light and 16 boxes).
const ROOM_TRIANGLES: f64 = 460.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Rooms per side.
    pub rooms: u32,
    /// The longest edge of a face's quads, mm.
    pub edge: f64,
}

/// One piece of furniture: a box in room coordinates (x and z from the
/// room's wall-centre corner, millimetres) and its material.
struct Piece {
    name: &'static str,
    material: &'static str,
    min: [f64; 3],
    max: [f64; 3],
}

impl Params {
    /// The rooms from the target over about twice [`ROOM_TRIANGLES`], so that
    /// the tessellation has room to reach it; then the edge, on a geometric
    /// ladder from uncut down, whose count is nearest the target.
    pub fn for_triangles(triangles: usize) -> Params {
        let rooms = ((triangles as f64 / (2.0 * ROOM_TRIANGLES)).sqrt().round() as u32).max(2);
        let edge =
            floorplan::nearest_edge(triangles, |edge| Params { rooms, edge }.triangle_count());
        Params { rooms, edge }
    }

    fn plan(&self) -> floorplan::Params {
        floorplan::Params {
            rooms: self.rooms,
            edge: self.edge,
        }
    }

    /// The furniture's boxes, each with its faces' divisions.
    fn furniture(&self) -> Vec<(usize, &'static str, &'static str, BoxSpec)> {
        let plan = self.plan();
        let n = self.rooms as usize;
        let mut boxes = Vec::new();
        for room in 0..n * n {
            let origin = [(room / n) as f64 * PITCH, 0.0, (room % n) as f64 * PITCH];
            for piece in room_pieces() {
                let mut spec = BoxSpec {
                    min: std::array::from_fn(|a| origin[a] + piece.min[a]),
                    max: std::array::from_fn(|a| origin[a] + piece.max[a]),
                    divisions: [1; 3],
                };
                spec.divisions = plan.divisions(&spec);
                boxes.push((room, piece.name, piece.material, spec));
            }
        }
        boxes
    }

    pub fn triangle_count(&self) -> usize {
        self.plan().plan().triangle_count()
            + self
                .furniture()
                .iter()
                .map(|(.., spec)| spec.triangle_count())
                .sum::<usize>()
    }
}

/// The pieces of one room. The wall faces are at THICKNESS/2 from the
/// room's corner; the doors are at the middle of each wall (0.9 m wide),
/// which the cabinet, the shelf and the desks keep clear of.
fn room_pieces() -> Vec<Piece> {
    let w = 0.5 * THICKNESS;
    let mut pieces = vec![
        // Backed against the wall at low z, standing on the floor.
        Piece {
            name: "cabinet",
            material: "cabinet",
            min: [w + 300.0, 0.0, w],
            max: [w + 1100.0, 1900.0, w + 450.0],
        },
        // Backed against the wall at low x.
        Piece {
            name: "shelf",
            material: "cabinet",
            min: [w, 0.0, w + 2600.0],
            max: [w + 350.0, 2000.0, w + 3500.0],
        },
    ];
    for z in [900.0, 2300.0] {
        let (x0, x1, z1) = (1500.0, 2900.0, z + 700.0);
        pieces.push(Piece {
            name: "desk_top",
            material: "desk",
            min: [x0, 720.0, z],
            max: [x1, 750.0, z1],
        });
        for (x, zl) in [
            (x0, z),
            (x1 - 50.0, z),
            (x0, z1 - 50.0),
            (x1 - 50.0, z1 - 50.0),
        ] {
            pieces.push(Piece {
                name: "desk_leg",
                material: "metal",
                min: [x, 0.0, zl],
                max: [x + 50.0, 720.0, zl + 50.0],
            });
        }
        // The chair in front of the desk, its seat on one column.
        let (cx, cz) = (2200.0, z1 + 400.0);
        pieces.push(Piece {
            name: "chair_column",
            material: "metal",
            min: [cx - 30.0, 0.0, cz - 30.0],
            max: [cx + 30.0, 430.0, cz + 30.0],
        });
        pieces.push(Piece {
            name: "chair_seat",
            material: "seat",
            min: [cx - 225.0, 430.0, cz - 225.0],
            max: [cx + 225.0, 480.0, cz + 225.0],
        });
    }
    pieces
}

pub fn generate(params: Params) -> Scene {
    let mut mesh = params.plan().plan().mesh();
    for (i, (room, name, material, spec)) in params.furniture().iter().enumerate() {
        mesh.begin_object(format!("{name}_{room}_{i}"), material, Closure::Outward);
        add_box(&mut mesh, spec, &Placement::IDENTITY, Closure::Outward);
    }
    let mut materials = floorplan::materials();
    for (name, kd) in [
        ("cabinet", [0.55, 0.42, 0.3]),
        ("desk", [0.7, 0.65, 0.55]),
        ("metal", [0.3, 0.3, 0.32]),
        ("seat", [0.2, 0.25, 0.5]),
    ] {
        materials.push(Material::diffuse(name, kd));
    }
    let n = params.rooms;
    Scene {
        description: format!(
            "office: {n} x {n} furnished rooms, faces cut into quads of at most {:.0} mm",
            params.edge.min(1e9)
        ),
        mesh,
        materials,
        camera: floorplan::first_room_camera(),
        lights: Lights::default(),
    }
}
