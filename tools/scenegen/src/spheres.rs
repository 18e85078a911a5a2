//! `spheres-room`: a closed room (6 × 3 × 6 m, millimetres) lit by one area
//! light under the ceiling, with a g × g grid of tessellated UV spheres and
//! capped cylinders standing on the floor (a checkerboard of the two). The
//! triangle count is reached by both the object count and the tessellation:
//! g grows with the fourth root of the target, the tessellation level t with
//! the rest, so larger scenes have more objects and finer ones.

use crate::mesh::{Closure, Mesh};
use crate::primitives::{
    add_box_room, add_cylinder, add_horizontal_rect, add_sphere, cylinder_triangle_count,
    sphere_triangle_count,
};
use crate::scene::{Camera, Lights, Material, Scene};

const ROOM: [f64; 3] = [6000.0, 3000.0, 6000.0];
const LIGHT_SIDE: f64 = 1200.0;
/// The room (a closed box seen from inside) and the light quad.
pub const FIXED_TRIANGLES: usize = 12 + 2;

/// The parameters of one scene: objects per side and tessellation level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Params {
    pub grid: u32,
    pub level: u32,
}

impl Params {
    /// A sphere has 2t segments around and t rings; a cylinder 2t segments and
    /// max(1, t/2) side bands.
    fn sphere(&self) -> (u32, u32) {
        (2 * self.level, self.level)
    }
    fn cylinder(&self) -> (u32, u32) {
        (2 * self.level, (self.level / 2).max(1))
    }
    fn sphere_count(&self) -> usize {
        let n = (self.grid * self.grid) as usize;
        n.div_ceil(2)
    }
    fn cylinder_count(&self) -> usize {
        (self.grid * self.grid) as usize - self.sphere_count()
    }

    pub fn triangle_count(&self) -> usize {
        let (su, sv) = self.sphere();
        let (cu, cv) = self.cylinder();
        FIXED_TRIANGLES
            + self.sphere_count() * sphere_triangle_count(su, sv)
            + self.cylinder_count() * cylinder_triangle_count(cu, cv)
    }

    /// The grid from the target's fourth root (2 per side at 1k, 3 at 10k, 5 at
    /// 100k, 8 at 1M), then the level whose count is nearest the target.
    pub fn for_triangles(triangles: usize) -> Params {
        let grid = ((triangles as f64 / 200.0).powf(0.25).round() as u32).max(2);
        (3..=4096)
            .map(|level| Params { grid, level })
            .min_by_key(|p| p.triangle_count().abs_diff(triangles))
            // 3..=4096 is a constant, non-empty range: min_by_key returns Some.
            .expect("a non-empty range")
    }
}

pub fn generate(params: Params) -> Scene {
    let mut mesh = Mesh::default();
    add_box_room(&mut mesh, ROOM);
    // 1 mm below the ceiling, facing down (as the Cornell light is lowered).
    mesh.begin_object("light", "light", Closure::Open);
    let (lo, hi) = (0.5 * (ROOM[0] - LIGHT_SIDE), 0.5 * (ROOM[0] + LIGHT_SIDE));
    add_horizontal_rect(&mut mesh, [lo, hi], [lo, hi], ROOM[1] - 1.0, false);

    let cell = ROOM[0] / params.grid as f64;
    let (su, sv) = params.sphere();
    let (cu, cv) = params.cylinder();
    for row in 0..params.grid {
        for column in 0..params.grid {
            let x = (column as f64 + 0.5) * cell;
            let z = (row as f64 + 0.5) * cell;
            if (row + column) % 2 == 0 {
                let radius = (0.3 * cell).min(600.0);
                mesh.begin_object(format!("sphere_{row}_{column}"), "sphere", Closure::Outward);
                // Resting on the floor: the south pole touches y = 0.
                add_sphere(&mut mesh, [x, radius, z], radius, su, sv);
            } else {
                let radius = (0.25 * cell).min(500.0);
                let height = (0.8 * cell).min(2000.0);
                mesh.begin_object(
                    format!("cylinder_{row}_{column}"),
                    "cylinder",
                    Closure::Outward,
                );
                add_cylinder(&mut mesh, [x, 0.0, z], radius, height, cu, cv);
            }
        }
    }
    Scene {
        description: format!(
            "spheres-room: a 6 x 3 x 6 m room with {} spheres ({su} x {sv}) and {} cylinders ({cu} x {cv}), grid {}, level {}",
            params.sphere_count(),
            params.cylinder_count(),
            params.grid,
            params.level
        ),
        mesh,
        materials: vec![
            Material::diffuse("wall", [0.7, 0.68, 0.65]),
            Material::diffuse("sphere", [0.7, 0.3, 0.2]),
            Material::diffuse("cylinder", [0.2, 0.4, 0.7]),
            Material::emitter("light", [0.78, 0.78, 0.78], [10.0, 10.0, 10.0]),
        ],
        // Inside, near the z = 0 wall at eye height, looking across the room.
        camera: Camera {
            eye: [3000.0, 1600.0, 300.0],
            target: [3000.0, 800.0, 4000.0],
            fov_y_deg: 60.0,
        },
        lights: Lights::default(),
    }
}
