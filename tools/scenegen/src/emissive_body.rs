//! `emissive-body`: a stand-in for Khronos's ToyCar (issue 42), whose whole
//! body is an emitter: a rounded box the size of a car (4.2 × 1.3 × 1.8 m,
//! millimetres), finely tessellated with smooth normals, whose one material
//! emits (a flat `Ke`; the OBJ/MTL importer reads `map_Ke` too, but a flat
//! colour is enough to make every facet an emitting patch), standing in a
//! closed 10 × 4 × 8 m room with no other light. The triangle count is
//! reached by the body's tessellation alone; the room is 12 triangles.
//!
//! The body is a superellipsoid |x/a|⁴ + |y/b|⁴ + |z/c|⁴ = 1: each point of a
//! UV sphere's direction d is mapped to (a sgn d_x |d_x|^½, …), so its faces
//! are nearly flat and its edges rounded, like a car's panels; its normal is
//! the implicit surface's gradient, ∝ (sgn d_x |d_x|^{3/2} / a, …).

use crate::mesh::{Closure, Mesh, Vec3};
use crate::primitives::{add_box_room, add_mapped_sphere};
use crate::scene::{Camera, Lights, Material, Scene};

const ROOM: [f64; 3] = [10_000.0, 4000.0, 8000.0];
/// The body's half extents (length, height, width).
const HALF: [f64; 3] = [2100.0, 650.0, 900.0];
/// Its lowest point, above the floor (a car's ground clearance).
const CLEARANCE: f64 = 150.0;
/// The room, a closed box seen from inside.
pub const FIXED_TRIANGLES: usize = 12;

/// The parameters of one scene: the body has 2 `rings` segments around and
/// `rings` rings from pole to pole.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Params {
    pub rings: u32,
}

impl Params {
    pub fn triangle_count(&self) -> usize {
        let (segments, rings) = (2 * self.rings as usize, self.rings as usize);
        FIXED_TRIANGLES + 2 * segments * (rings - 1)
    }

    /// The ring count whose triangle count is nearest the target (4 r² − 4 r
    /// for the body: 71 rings at 20k, 158 at 100k).
    pub fn for_triangles(triangles: usize) -> Params {
        (4..=20_000)
            .map(|rings| Params { rings })
            .min_by_key(|p| p.triangle_count().abs_diff(triangles))
            // 4..=20_000 is a constant, non-empty range: min_by_key returns Some.
            .expect("a non-empty range")
    }
}

/// The body's centre.
pub fn body_centre() -> Vec3 {
    [0.5 * ROOM[0], CLEARANCE + HALF[1], 0.5 * ROOM[2]]
}

/// The superellipsoid's point and (unnormalised) normal for the unit
/// direction `d`.
fn body_point(d: Vec3) -> (Vec3, Vec3) {
    let centre = body_centre();
    let position = std::array::from_fn(|a| centre[a] + HALF[a] * d[a].signum() * d[a].abs().sqrt());
    let normal = std::array::from_fn(|a| d[a].signum() * d[a].abs().powf(1.5) / HALF[a]);
    (position, normal)
}

pub fn generate(params: Params) -> Scene {
    let mut mesh = Mesh::default();
    add_box_room(&mut mesh, ROOM);
    mesh.begin_object("body", "body", Closure::Outward);
    add_mapped_sphere(
        &mut mesh,
        body_centre(),
        2 * params.rings,
        params.rings,
        body_point,
    );
    // In a corner of the room at eye height, looking at the body.
    let eye = [1500.0, 1700.0, 1200.0];
    Scene {
        description: format!(
            "emissive-body: a 10 x 4 x 8 m room lit only by an emitting rounded body of 4.2 x 1.3 \
             x 1.8 m, {} x {} (rings {})",
            2 * params.rings,
            params.rings,
            params.rings
        ),
        mesh,
        materials: vec![
            Material::diffuse("wall", [0.7, 0.68, 0.65]),
            // A glowing car paint: red-orange emission over a reflecting
            // body, as an emissive texture over ToyCar's body would be.
            Material::emitter("body", [0.5, 0.2, 0.15], [4.0, 2.0, 1.0]),
        ],
        camera: Camera {
            eye,
            target: body_centre(),
            fov_y_deg: 60.0,
        },
        lights: Lights::default(),
    }
}
