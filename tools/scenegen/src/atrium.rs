//! `atrium`: a courtyard the size of Sponza (35 × 16 m in plan, 16 m high,
//! millimetres) with an open roof, lit by a sun and a uniform sky.
//!
//! Along each long side runs an arcade of two storeys: a row of columns
//! (capped cylinders) carrying arch blocks ([`crate::arch`]), a gallery floor
//! slab over the ground storey and a solid roof block over the upper one up
//! to 16 m (its court face is the attic); behind each arcade a back wall
//! closes its aisle, and plain walls close the two short ends. A half-column
//! (pilaster) against each end wall carries the end arches. Each column
//! stands exactly on the floor or on the gallery slab and ends exactly on the
//! spring line, where the arch blocks' bottom strips cover its top disc, so
//! no light leaks at its base or its top; the walls and slabs are cut where
//! the slabs and arcades touch them, so that none of their elements reaches
//! across a contact. Drapes hang in every other bay of the upper galleries
//! and a fountain stands in the middle of the court. Nothing covers the
//! court.
//!
//! The count is reached by the number of bays (10 when it lands within 5%,
//! as Sponza's long sides have, else the nearest of 4–14) and a level t: the
//! columns get 4t + 4 segments around and t bands, the arches 2·min(t+1, 12)
//! segments.

use crate::arch::{add_arch, ArchSpec};
use crate::mesh::{Closure, Mesh, Vec3};
use crate::primitives::{
    add_box, add_cylinder, add_horizontal_rect, add_lattice_box, cylinder_triangle_count,
    lattice_box_triangle_count, BoxSpec, Placement,
};
use crate::scene::{Camera, Lights, Material, Scene};

/// The court's extent along x (the long axis) and z, and the walls' height.
pub const LENGTH: f64 = 35_000.0;
pub const WIDTH: f64 = 16_000.0;
pub const HEIGHT: f64 = 16_000.0;
const WALL: f64 = 600.0;
/// From a back wall to its column line.
const AISLE: f64 = 3_500.0;
pub const COLUMN_RADIUS: f64 = 300.0;
/// Half the arch blocks' depth: more than the column radius, so
/// that the arches' bottom strips cover the columns' top discs.
pub const ARCH_HALF_DEPTH: f64 = 350.0;
/// From an arch's crown to the slab over it.
const CROWN: f64 = 450.0;
const SLAB: f64 = 500.0;
/// The fountain: a basin and a pillar on it, in the middle of the court.
const BASIN: (f64, f64) = (1_600.0, 500.0);
const PILLAR: (f64, f64) = (200.0, 1_200.0);
/// Drapes hang this far into the upper galleries, this long, this thick.
const DRAPE: (f64, f64, f64) = (250.0, 3_500.0, 50.0);

/// The two column lines (z) and the open court between the arcades.
pub const COLUMN_LINES: [f64; 2] = [AISLE, WIDTH - AISLE];
pub const COURT_Z: [f64; 2] = [AISLE + ARCH_HALF_DEPTH, WIDTH - AISLE - ARCH_HALF_DEPTH];
/// The highest point of anything standing in the court (the fountain).
pub const COURT_OBJECTS_TOP: f64 = BASIN.1 + PILLAR.1;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Bays per arcade: bays − 1 columns between the two pilasters.
    pub bays: u32,
    /// Column segments around (≥ 3).
    pub segments: u32,
    /// Column side bands (≥ 1).
    pub rings: u32,
    /// Arch intrados segments (even, ≥ 2).
    pub arch_segments: u32,
}

/// One storey of the arcades, millimetres above the floor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Storey {
    /// The columns' feet: the floor, or the top of the gallery slab.
    pub base: f64,
    /// The columns' tops and the arches' springs.
    pub spring: f64,
    /// The underside of the slab the arches carry.
    pub top: f64,
}

/// A named solid of the plan.
enum Solid {
    Block(BoxSpec),
    /// A box cut on these lines per axis ([`add_lattice_box`]).
    Lattice([Vec<f64>; 3]),
    Column {
        base: Vec3,
        height: f64,
    },
    Fountain {
        base: Vec3,
        radius: f64,
        height: f64,
    },
    Arch(ArchSpec),
}

struct Part {
    name: String,
    material: &'static str,
    solid: Solid,
}

const BAY_PREFERENCE: [u32; 11] = [10, 11, 9, 12, 8, 13, 7, 14, 6, 5, 4];

impl Params {
    /// The ladder's level t.
    pub fn at_level(bays: u32, t: u32) -> Params {
        Params {
            bays,
            segments: 4 * t + 4,
            rings: t,
            arch_segments: 2 * (t + 1).min(12),
        }
    }

    /// The first bay count in [`BAY_PREFERENCE`] whose best level lands within
    /// 5% of `triangles`, else the nearest over all.
    pub fn for_triangles(triangles: usize) -> Params {
        let mut best = (usize::MAX, Params::at_level(BAY_PREFERENCE[0], 1));
        for bays in BAY_PREFERENCE {
            let mut t = 1;
            loop {
                let p = Params::at_level(bays, t);
                let count = p.triangle_count();
                let error = count.abs_diff(triangles);
                if error < best.0 {
                    best = (error, p);
                }
                if count > 2 * triangles || t >= 1_000 {
                    break;
                }
                t += 1;
            }
            let (error, p) = best;
            if p.bays == bays && (error as f64) <= 0.05 * triangles as f64 {
                return p;
            }
        }
        best.1
    }

    /// Column centre to column centre.
    pub fn pitch(&self) -> f64 {
        LENGTH / self.bays as f64
    }

    /// The x of column line j (0 and `bays` are the end walls' faces): the
    /// last is exactly the east wall's, not bays · pitch rounded.
    pub fn bay_x(&self, j: u32) -> f64 {
        if j == self.bays {
            LENGTH
        } else {
            j as f64 * self.pitch()
        }
    }

    /// The ground storey up to the gallery slab, the upper one up to the roof
    /// slab. Each arch's rise is its half-opening (a round arch) unless that
    /// exceeds 40% of the storey (a flatter, elliptical arch); the spring
    /// line is rounded to a whole millimetre.
    pub fn storeys(&self) -> [Storey; 2] {
        let half_opening = 0.5 * self.pitch() - COLUMN_RADIUS;
        let storey = |base: f64, top: f64| {
            let rise = half_opening.min(0.4 * (top - base));
            Storey {
                base,
                spring: (top - CROWN - rise).round(),
                top,
            }
        };
        [storey(0.0, 7_000.0), storey(7_000.0 + SLAB, 13_000.0)]
    }

    pub fn triangle_count(&self) -> usize {
        let solids: usize = self
            .plan()
            .iter()
            .map(|part| match &part.solid {
                Solid::Block(spec) => spec.triangle_count(),
                Solid::Lattice(lines) => lattice_box_triangle_count(lines),
                Solid::Column { .. } => cylinder_triangle_count(self.segments, self.rings),
                Solid::Fountain { .. } => cylinder_triangle_count(self.segments, 1),
                Solid::Arch(spec) => spec.triangle_count(),
            })
            .sum();
        // The floor is one quad.
        solids + 2
    }

    /// Every solid: walls and slabs, then each storey's arcades, then the
    /// drapes and the fountain.
    fn plan(&self) -> Vec<Part> {
        let mut parts = Vec::new();
        self.shell(&mut parts);
        let [ground, upper] = self.storeys();
        for (level, storey) in [ground, upper].iter().enumerate() {
            for (side, line) in ["south", "north"].into_iter().zip(COLUMN_LINES) {
                self.arcade(&mut parts, storey, level, side, line);
            }
        }
        self.drapes(&mut parts, &upper);
        let centre = [0.5 * LENGTH, 0.0, 0.5 * WIDTH];
        parts.push(Part {
            name: "fountain_basin".into(),
            material: "fountain",
            solid: Solid::Fountain {
                base: centre,
                radius: BASIN.0,
                height: BASIN.1,
            },
        });
        parts.push(Part {
            name: "fountain_pillar".into(),
            material: "fountain",
            solid: Solid::Fountain {
                base: [centre[0], BASIN.1, centre[2]],
                radius: PILLAR.0,
                height: PILLAR.1,
            },
        });
        parts
    }

    /// The end walls, and along each side its back wall, gallery slab and
    /// roof block (the upper gallery's ceiling, whose court face is the
    /// attic up to 16 m). Each is a lattice box cut on the lines where other
    /// solids touch it (the slabs' and roof's heights on the walls, the
    /// arcades' depth on the end walls and under the slabs), so that no
    /// element of a visible face reaches across a contact into another room:
    /// an aisle's wall cannot borrow the gallery's light above the slab, nor
    /// an end wall's aisle part the court's.
    fn shell(&self, parts: &mut Vec<Part>) {
        let [ground, upper] = self.storeys();
        let heights = vec![0.0, ground.top, upper.base, upper.top, HEIGHT];
        let [south, north] =
            COLUMN_LINES.map(|line| [line - ARCH_HALF_DEPTH, line + ARCH_HALF_DEPTH]);
        let across = vec![
            -WALL,
            0.0,
            south[0],
            south[1],
            north[0],
            north[1],
            WIDTH,
            WIDTH + WALL,
        ];
        let mut lattice = |name: String, material, lines: [Vec<f64>; 3]| {
            parts.push(Part {
                name,
                material,
                solid: Solid::Lattice(lines),
            });
        };
        lattice(
            "end_wall_west".into(),
            "wall",
            [vec![-WALL, 0.0], heights.clone(), across.clone()],
        );
        lattice(
            "end_wall_east".into(),
            "wall",
            [vec![LENGTH, LENGTH + WALL], heights.clone(), across],
        );
        let along = vec![0.0, LENGTH];
        let bay_lines: Vec<f64> = (0..=self.bays).map(|j| self.bay_x(j)).collect();
        for (side, arcade) in [("south", south), ("north", north)] {
            // From the back wall to the arcade's front, cut at the arcade;
            // the roof's underside also where the drapes hang from it.
            let drape = drape_z(0.5 * (arcade[0] + arcade[1]));
            let (back, aisle, roof) = if side == "south" {
                let aisle = vec![0.0, arcade[0], arcade[1]];
                let roof = vec![0.0, drape[0], drape[1], arcade[0], arcade[1]];
                (vec![-WALL, 0.0], aisle, roof)
            } else {
                let aisle = vec![arcade[0], arcade[1], WIDTH];
                let roof = vec![arcade[0], arcade[1], drape[0], drape[1], WIDTH];
                (vec![WIDTH, WIDTH + WALL], aisle, roof)
            };
            let solids = [
                ("back_wall", "wall", heights.clone(), back),
                ("gallery_slab", "slab", vec![ground.top, upper.base], aisle),
                ("roof", "wall", vec![upper.top, HEIGHT], roof),
            ];
            for (kind, material, y, z) in solids {
                // The roof also at every bay: its 50 mm drape strips would
                // otherwise be slivers 35 m long.
                let x = if kind == "roof" {
                    bay_lines.clone()
                } else {
                    along.clone()
                };
                lattice(format!("{kind}_{side}"), material, [x, y, z]);
            }
        }
    }

    /// One storey of one arcade: the pilasters at both ends, the columns
    /// between and an arch over every bay.
    fn arcade(&self, parts: &mut Vec<Part>, storey: &Storey, level: usize, side: &str, line: f64) {
        let z = [line - ARCH_HALF_DEPTH, line + ARCH_HALF_DEPTH];
        for (end, x) in [
            ("west", [0.0, COLUMN_RADIUS]),
            ("east", [LENGTH - COLUMN_RADIUS, LENGTH]),
        ] {
            parts.push(Part {
                name: format!("pilaster_{level}_{side}_{end}"),
                material: "column",
                solid: Solid::Block(BoxSpec {
                    min: [x[0], storey.base, z[0]],
                    max: [x[1], storey.spring, z[1]],
                    divisions: [1; 3],
                }),
            });
        }
        for j in 1..self.bays {
            parts.push(Part {
                name: format!("column_{level}_{side}_{j}"),
                material: "column",
                solid: Solid::Column {
                    base: [self.bay_x(j), storey.base, line],
                    height: storey.spring - storey.base,
                },
            });
        }
        let rise = storey.top - CROWN - storey.spring;
        for j in 0..self.bays {
            parts.push(Part {
                name: format!("arch_{level}_{side}_{j}"),
                material: "arch",
                solid: Solid::Arch(ArchSpec {
                    x: [self.bay_x(j), self.bay_x(j + 1)],
                    inset: COLUMN_RADIUS,
                    z,
                    y: [storey.spring, storey.top],
                    rise,
                    segments: self.arch_segments,
                }),
            });
        }
    }

    /// A drape hanging from the roof slab in every other bay of both upper
    /// galleries, behind the arches.
    fn drapes(&self, parts: &mut Vec<Part>, upper: &Storey) {
        let (_, drop, _) = DRAPE;
        let colours = ["drape_red", "drape_green", "drape_blue"];
        let mut n = 0;
        for (side, line) in ["south", "north"].into_iter().zip(COLUMN_LINES) {
            let z = drape_z(line);
            for j in (1..self.bays).step_by(2) {
                let x0 = self.bay_x(j) + COLUMN_RADIUS + 150.0;
                let x1 = self.bay_x(j + 1) - COLUMN_RADIUS - 150.0;
                parts.push(Part {
                    name: format!("drape_{side}_{j}"),
                    material: colours[n % colours.len()],
                    solid: Solid::Block(BoxSpec {
                        min: [x0, upper.top - drop, z[0]],
                        max: [x1, upper.top, z[1]],
                        divisions: [1; 3],
                    }),
                });
                n += 1;
            }
        }
    }
}

/// The z range of the drapes behind the arcade on column line `line`: in
/// its upper gallery, a gap behind the arch blocks.
pub fn drape_z(line: f64) -> [f64; 2] {
    let (gap, _, thickness) = DRAPE;
    if line < 0.5 * WIDTH {
        let face = line - ARCH_HALF_DEPTH - gap;
        [face - thickness, face]
    } else {
        let face = line + ARCH_HALF_DEPTH + gap;
        [face, face + thickness]
    }
}

pub fn generate(params: Params) -> Scene {
    let mut mesh = Mesh::default();
    mesh.begin_object("floor", "floor", Closure::Open);
    add_horizontal_rect(&mut mesh, [0.0, LENGTH], [0.0, WIDTH], 0.0, true);
    for part in params.plan() {
        mesh.begin_object(part.name, part.material, Closure::Outward);
        match part.solid {
            Solid::Block(spec) => add_box(&mut mesh, &spec, &Placement::IDENTITY, Closure::Outward),
            Solid::Lattice(lines) => add_lattice_box(
                &mut mesh,
                &lines,
                &Placement::IDENTITY,
                Closure::Outward,
                |_, _| {},
                |_| true,
            ),
            Solid::Column { base, height } => add_cylinder(
                &mut mesh,
                base,
                COLUMN_RADIUS,
                height,
                params.segments,
                params.rings,
            ),
            Solid::Fountain {
                base,
                radius,
                height,
            } => add_cylinder(&mut mesh, base, radius, height, params.segments, 1),
            Solid::Arch(spec) => add_arch(&mut mesh, &spec),
        }
    }
    Scene {
        description: format!(
            "atrium: 35 x 16 x 16 m open court, two storeys of {} bays, columns {} x {}, arches {} segments",
            params.bays, params.segments, params.rings, params.arch_segments
        ),
        mesh,
        materials: vec![
            Material::diffuse("floor", [0.5, 0.47, 0.42]),
            Material::diffuse("wall", [0.6, 0.57, 0.52]),
            Material::diffuse("slab", [0.55, 0.53, 0.5]),
            Material::diffuse("column", [0.65, 0.62, 0.56]),
            Material::diffuse("arch", [0.62, 0.58, 0.5]),
            Material::diffuse("fountain", [0.45, 0.45, 0.45]),
            Material::diffuse("drape_red", [0.55, 0.12, 0.1]),
            Material::diffuse("drape_green", [0.12, 0.4, 0.15]),
            Material::diffuse("drape_blue", [0.12, 0.2, 0.5]),
        ],
        // In the court near the west end at eye height, looking east along
        // the long axis past the fountain.
        camera: Camera {
            eye: [1_500.0, 1_700.0, 0.5 * WIDTH],
            target: [LENGTH, 4_000.0, 0.5 * WIDTH],
            fov_y_deg: 60.0,
        },
        // The sun at 55° over the south arcade toward the east end: it lights
        // the north arcade's court face, a strip of the court floor and the
        // fountain, and the south arcade stands in its own shadow.
        lights: Lights::daylight(55.0, [3f64.sqrt(), -1.0]),
    }
}
