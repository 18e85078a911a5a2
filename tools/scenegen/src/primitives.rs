//! The solids the families are built from: boxes with subdivided faces, UV
//! spheres and capped cylinders. Each shares its vertices (so that every edge
//! joins exactly two of its triangles) and is wound counter-clockwise seen from
//! its front.

use crate::mesh::{add, length, sub, Closure, Corner, Mesh, Vec3};
use std::collections::HashMap;
use std::f64::consts::PI;

/// Where a box sits: world = pivot + R_y(yaw) · local.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    pub pivot: Vec3,
    /// Rotation about +y, radians (counter-clockwise seen from above).
    pub yaw: f64,
}

impl Placement {
    pub const IDENTITY: Placement = Placement {
        pivot: [0.0; 3],
        yaw: 0.0,
    };

    pub fn apply(&self, local: Vec3) -> Vec3 {
        let (s, c) = self.yaw.sin_cos();
        // R_y(yaw) is a proper rotation (determinant +1), so it keeps windings.
        let rotated = [
            c * local[0] + s * local[2],
            local[1],
            -s * local[0] + c * local[2],
        ];
        add(self.pivot, rotated)
    }
}

/// An axis-aligned box in local coordinates with each face cut into a grid.
#[derive(Clone, Copy, Debug)]
pub struct BoxSpec {
    pub min: Vec3,
    pub max: Vec3,
    /// Cells along x, y and z (each ≥ 1): the ±x faces get divisions[1] ×
    /// divisions[2] quads, and so on.
    pub divisions: [u32; 3],
}

impl BoxSpec {
    /// Two triangles per quad on each of the six faces.
    pub fn triangle_count(&self) -> usize {
        let [a, b, c] = self.divisions.map(|d| d as usize);
        4 * (a * b + b * c + c * a)
    }
}

/// Starts object "room" of material "wall" and adds to it a closed box from
/// the origin to `size`, its faces inward: the room the emissive-body and
/// spheres-room families stand in.
pub fn add_box_room(mesh: &mut Mesh, size: [f64; 3]) {
    mesh.begin_object("room", "wall", Closure::Inward);
    let room = BoxSpec {
        min: [0.0; 3],
        max: size,
        divisions: [1, 1, 1],
    };
    add_box(mesh, &room, &Placement::IDENTITY, Closure::Inward);
}

/// Adds `spec` as a closed box to the current object. `closure` Outward faces
/// its triangles out of the solid (a block, a wall slab), Inward into it (a room).
pub fn add_box(mesh: &mut Mesh, spec: &BoxSpec, placement: &Placement, closure: Closure) {
    let divisions = spec.divisions.map(|d| d.max(1));
    let lines: [Vec<f64>; 3] = std::array::from_fn(|axis| {
        (0..=divisions[axis])
            .map(|k| {
                let t = k as f64 / divisions[axis] as f64;
                spec.min[axis] + t * (spec.max[axis] - spec.min[axis])
            })
            .collect()
    });
    add_lattice_box(mesh, &lines, placement, closure, |_, _| {}, |_| true);
}

/// One face of a lattice box: the axis it is normal to and whether it lies at
/// that axis' last line (the far side) or its first.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BoxFace {
    pub axis: usize,
    pub far: bool,
}

/// One cell of a lattice box's face: its face, and its ranges along the
/// face's two other axes (axis + 1 and axis + 2, cyclically).
#[derive(Clone, Copy, Debug)]
pub struct FaceCell {
    pub face: BoxFace,
    pub u: [f64; 2],
    pub v: [f64; 2],
}

/// Triangles of a closed lattice box: two per cell of each face.
pub fn lattice_box_triangle_count(lines: &[Vec<f64>; 3]) -> usize {
    let [a, b, c] = lines.each_ref().map(|l| l.len() - 1);
    4 * (a * b + b * c + c * a)
}

/// Adds the box spanned by `lines` (per axis, increasing; the first and last
/// are its extent) with each face cut on the lines of its two axes, so that
/// a face has an edge wherever something touches it along a line. Faces
/// meeting at an edge share its vertices. `begin_face` is called before each
/// face's cells (to start an object per face, or nothing); a cell for which
/// `keep` is false is left out (a window), which opens the box there.
pub fn add_lattice_box(
    mesh: &mut Mesh,
    lines: &[Vec<f64>; 3],
    placement: &Placement,
    closure: Closure,
    mut begin_face: impl FnMut(&mut Mesh, BoxFace),
    keep: impl Fn(&FaceCell) -> bool,
) {
    let last = lines.each_ref().map(|l| l.len() - 1);
    // Lattice points on the surface, keyed by their integer coordinates, so
    // that the faces meeting at an edge share its vertices.
    let mut lattice: HashMap<[usize; 3], u32> = HashMap::new();
    let mut vertex = |mesh: &mut Mesh, ijk: [usize; 3]| -> u32 {
        *lattice.entry(ijk).or_insert_with(|| {
            let local: [f64; 3] = std::array::from_fn(|axis| lines[axis][ijk[axis]]);
            mesh.add_position(placement.apply(local))
        })
    };
    for axis in 0..3 {
        // (u, v, axis) is a cyclic, right-handed triple, so a quad walked
        // u0v0 → u1v0 → u1v1 → u0v1 has normal +axis.
        let u = (axis + 1) % 3;
        let v = (axis + 2) % 3;
        for side in [0, last[axis]] {
            let face = BoxFace {
                axis,
                far: side != 0,
            };
            begin_face(mesh, face);
            let reversed = face.far == (closure == Closure::Inward);
            for i in 0..last[u] {
                for j in 0..last[v] {
                    let cell = FaceCell {
                        face,
                        u: [lines[u][i], lines[u][i + 1]],
                        v: [lines[v][j], lines[v][j + 1]],
                    };
                    if !keep(&cell) {
                        continue;
                    }
                    let at = |di: usize, dj: usize| {
                        let mut ijk = [0usize; 3];
                        ijk[axis] = side;
                        ijk[u] = i + di;
                        ijk[v] = j + dj;
                        ijk
                    };
                    let mut quad = [at(0, 0), at(1, 0), at(1, 1), at(0, 1)]
                        .map(|ijk| Corner::flat(vertex(mesh, ijk)));
                    if reversed {
                        quad.reverse();
                    }
                    mesh.quad(quad);
                }
            }
        }
    }
}

/// Triangles of a UV sphere with `segments` around and `rings` from pole to pole.
pub fn sphere_triangle_count(segments: u32, rings: u32) -> usize {
    2 * segments as usize * (rings as usize - 1)
}

/// Adds a UV sphere (segments ≥ 3, rings ≥ 2) to the current object: poles
/// and rings with shared vertices, smooth normals (the unit radius vector),
/// wound counter-clockwise seen from outside.
pub fn add_sphere(mesh: &mut Mesh, centre: Vec3, radius: f64, segments: u32, rings: u32) {
    add_mapped_sphere(mesh, centre, segments, rings, |d| {
        (add(centre, d.map(|x| x * radius)), d)
    });
}

/// Adds a UV sphere's topology (segments ≥ 3, rings ≥ 2: poles and rings
/// with shared vertices) with each unit direction d mapped by `point` to a
/// position and a smooth normal (any length), wound counter-clockwise seen
/// from outside: the surface must be star-shaped about `centre`, so that a
/// facet's front is the side away from it.
pub fn add_mapped_sphere(
    mesh: &mut Mesh,
    centre: Vec3,
    segments: u32,
    rings: u32,
    point: impl Fn(Vec3) -> (Vec3, Vec3),
) {
    let corner = |mesh: &mut Mesh, direction: Vec3| {
        let (position, normal) = point(direction);
        Corner {
            position: mesh.add_position(position),
            normal: Some(mesh.add_normal(normal)),
        }
    };
    let north = corner(mesh, [0.0, 1.0, 0.0]);
    let mut ring_corners: Vec<Vec<Corner>> = Vec::new();
    for k in 1..rings {
        let theta = PI * k as f64 / rings as f64;
        let ring = (0..segments)
            .map(|i| {
                let phi = 2.0 * PI * i as f64 / segments as f64;
                let d = [
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                ];
                corner(mesh, d)
            })
            .collect();
        ring_corners.push(ring);
    }
    let south = corner(mesh, [0.0, -1.0, 0.0]);
    let n = segments as usize;
    let outward = |mesh: &Mesh, t: &[Corner; 3]| {
        let c: Vec3 = std::array::from_fn(|a| {
            t.iter()
                .map(|k| mesh.positions[k.position as usize][a])
                .sum::<f64>()
                / 3.0
        });
        sub(c, centre)
    };
    let facing = |mesh: &mut Mesh, t: [Corner; 3]| {
        let front = outward(mesh, &t);
        mesh.triangle_facing(t, front);
    };
    for i in 0..n {
        let j = (i + 1) % n;
        facing(mesh, [north, ring_corners[0][i], ring_corners[0][j]]);
        let last = &ring_corners[ring_corners.len() - 1];
        let (a, b) = (last[i], last[j]);
        facing(mesh, [south, a, b]);
    }
    for r in 0..ring_corners.len() - 1 {
        for i in 0..n {
            let j = (i + 1) % n;
            let (a, b) = (ring_corners[r][i], ring_corners[r][j]);
            let (c, d) = (ring_corners[r + 1][i], ring_corners[r + 1][j]);
            facing(mesh, [a, c, d]);
            facing(mesh, [a, d, b]);
        }
    }
}

/// Triangles of a capped cylinder: 2 per side cell, and a fan of `segments`
/// triangles around a centre vertex on each cap.
pub fn cylinder_triangle_count(segments: u32, side_rings: u32) -> usize {
    2 * segments as usize * (side_rings as usize + 1)
}

/// Adds a closed cylinder standing on `base` (its axis along +y): the side
/// in `side_rings` bands with radial smooth normals, flat caps fanned around a
/// centre vertex. The rim vertices are shared by side and cap (separate
/// normals), so the solid is closed.
pub fn add_cylinder(
    mesh: &mut Mesh,
    base: Vec3,
    radius: f64,
    height: f64,
    segments: u32,
    side_rings: u32,
) {
    let n = segments as usize;
    let radial: Vec<Vec3> = (0..n)
        .map(|i| {
            let phi = 2.0 * PI * i as f64 / n as f64;
            [phi.cos(), 0.0, phi.sin()]
        })
        .collect();
    let radial_normals: Vec<u32> = radial.iter().map(|&d| mesh.add_normal(d)).collect();
    let up = mesh.add_normal([0.0, 1.0, 0.0]);
    let down = mesh.add_normal([0.0, -1.0, 0.0]);
    let rings: Vec<Vec<u32>> = (0..=side_rings)
        .map(|k| {
            let y = height * k as f64 / side_rings as f64;
            radial
                .iter()
                .map(|d| mesh.add_position(add(base, [d[0] * radius, y, d[2] * radius])))
                .collect()
        })
        .collect();
    let side = |p: u32, i: usize| Corner {
        position: p,
        normal: Some(radial_normals[i]),
    };
    for k in 0..side_rings as usize {
        for i in 0..n {
            let j = (i + 1) % n;
            let front = radial[i];
            let (a, b) = (side(rings[k][i], i), side(rings[k][j], j));
            let (c, d) = (side(rings[k + 1][i], i), side(rings[k + 1][j], j));
            mesh.triangle_facing([a, d, c], front);
            mesh.triangle_facing([a, b, d], front);
        }
    }
    let caps = [
        (0usize, down, [0.0, -1.0, 0.0], 0.0),
        (side_rings as usize, up, [0.0, 1.0, 0.0], height),
    ];
    for (ring, normal, front, y) in caps {
        let centre = Corner {
            position: mesh.add_position(add(base, [0.0, y, 0.0])),
            normal: Some(normal),
        };
        for i in 0..n {
            let j = (i + 1) % n;
            let rim = |p: u32| Corner {
                position: p,
                normal: Some(normal),
            };
            mesh.triangle_facing([centre, rim(rings[ring][i]), rim(rings[ring][j])], front);
        }
    }
}

/// Adds a flat axis-aligned rectangle at height `y`, facing up (+y) or down.
pub fn add_horizontal_rect(mesh: &mut Mesh, x: [f64; 2], z: [f64; 2], y: f64, facing_up: bool) {
    let p = |mesh: &mut Mesh, px: f64, pz: f64| Corner::flat(mesh.add_position([px, y, pz]));
    // Seen from above, (x0,z1) → (x1,z1) → (x1,z0) → (x0,z0) is counter-clockwise:
    // (x1−x0, 0, 0) × (x1−x0, 0, z0−z1) = (0, (x1−x0)(z1−z0), 0), +y for x1 > x0, z1 > z0.
    let mut quad = [
        p(mesh, x[0], z[1]),
        p(mesh, x[1], z[1]),
        p(mesh, x[1], z[0]),
        p(mesh, x[0], z[0]),
    ];
    if !facing_up {
        quad.reverse();
    }
    mesh.quad(quad);
}

/// Half the diagonal of a width × depth footprint: the radius of the circle
/// about its centre that holds the footprint whatever its yaw.
pub fn footprint_radius(width: f64, depth: f64) -> f64 {
    0.5 * length([width, 0.0, depth])
}
