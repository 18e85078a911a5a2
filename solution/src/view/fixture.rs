//! Rooms made in code for the default-view chooser's tests, and for those of
//! the programs that use it (the solver's header camera, the runtime's XR start
//! pose): a closed box room with an inner block and a ceiling light.

use crate::camera::{Camera, UpAxis};
use crate::format::{
    Batch, Header, Representation, ScalarType, Solution, SolveMode, SolveStats, Vertex,
};
use glam::Vec3;

/// A quad `corner + s·e1 + t·e2` (s, t ∈ [0, 1]) as `n` × `n` cells, front face
/// toward e1 × e2, at radiance `l` (grey), appended to `batch`.
pub fn quad(batch: &mut Batch, corner: Vec3, e1: Vec3, e2: Vec3, n: u32, l: f32) {
    let normal = e1.cross(e2).normalize();
    let first = batch.vertices.len() as u32;
    for j in 0..=n {
        for i in 0..=n {
            let p = corner + e1 * (i as f32 / n as f32) + e2 * (j as f32 / n as f32);
            batch.vertices.push(Vertex {
                position: p.to_array(),
                normal: normal.to_array(),
                tangent: e1.normalize().to_array(),
            });
            // c₀₀ = L / Y₀₀, so the shown radiance is L.
            batch.coefficients.extend([l / crate::sh::Y00 as f32; 3]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = first + j * (n + 1) + i;
            let (b, c, d) = (a + 1, a + n + 2, a + n + 1);
            batch.indices.extend([a, b, c, a, c, d]);
        }
    }
}

/// An axis-aligned box from `lo` to `hi`, each face in `cells` × `cells` cells,
/// facing the outside (`inward` false) or the inside.
pub fn cuboid(batch: &mut Batch, lo: Vec3, hi: Vec3, inward: bool, cells: u32, l: f32) {
    let size = hi - lo;
    let (x, y, z) = (Vec3::X * size.x, Vec3::Y * size.y, Vec3::Z * size.z);
    // Each face's (corner, e1, e2) with e1 × e2 pointing outward.
    let faces = [
        (lo, z, y),     // −x
        (lo + x, y, z), // +x
        (lo, x, z),     // −y
        (lo + y, z, x), // +y
        (lo, y, x),     // −z
        (lo + z, x, y), // +z
    ];
    for (corner, e1, e2) in faces {
        if inward {
            quad(batch, corner, e2, e1, cells, l);
        } else {
            quad(batch, corner, e1, e2, cells, l);
        }
    }
}

/// An SH order-0 batch with nothing in it.
pub fn empty_batch() -> Batch {
    Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertices: Vec::new(),
        coefficients: Vec::new(),
        indices: Vec::new(),
        texturing: None,
    }
}

/// A one-batch solution with the batch's bounds, the given up axis, scale and
/// re-centring offset, and the default camera.
pub fn solution_of(batch: Batch, up: UpAxis, units_per_metre: f64, offset: [f64; 3]) -> Solution {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for v in &batch.vertices {
        lo = lo.min(Vec3::from(v.position));
        hi = hi.max(Vec3::from(v.position));
    }
    Solution {
        lighting: None,
        header: Header {
            units_per_metre,
            up_axis: up,
            recentre_offset: offset,
            camera: Camera::default(),
            bounds_min: lo.to_array(),
            bounds_max: hi.to_array(),
            partial: false,
            mode: SolveMode::Diffuse,
            stats: SolveStats::default(),
            settings_json: String::new(),
        },
        batches: vec![batch],
        textures: Vec::new(),
    }
}

/// The room's corners and the block's, metres, file coordinates.
pub const ROOM_LO: Vec3 = Vec3::new(-2.0, 0.0, -3.0);
pub const ROOM_HI: Vec3 = Vec3::new(2.0, 2.5, 3.0);
pub const BLOCK_LO: Vec3 = Vec3::new(-0.6, 0.0, -0.6);
pub const BLOCK_HI: Vec3 = Vec3::new(0.6, 1.0, 0.6);

/// A 4 × 2.5 × 6 m closed room (walls at radiance 0.5 facing in), a 1.2 m
/// block on its floor (0.3, facing out), a 1 m² ceiling light (radiance 20,
/// facing down) 5 mm below the ceiling at x = 1, z = 1.5.
pub fn box_room() -> Solution {
    box_room_with(4)
}

/// [`box_room`] with each of the 12 box faces in `cells` × `cells` cells: 24·cells² + 2
/// triangles.
pub fn box_room_with(cells: u32) -> Solution {
    let mut batch = empty_batch();
    cuboid(&mut batch, ROOM_LO, ROOM_HI, true, cells, 0.5);
    cuboid(&mut batch, BLOCK_LO, BLOCK_HI, false, cells, 0.3);
    let light = Vec3::new(0.5, 2.495, 1.0);
    quad(&mut batch, light, Vec3::X, Vec3::Z, 1, 20.0);
    solution_of(batch, UpAxis::PosY, 1.0, [10.0, 0.0, -5.0])
}
