//! Scale scenes for issue 13 and the benchmark that solves them.
//!
//! Three families lit by emissive polygons, each generated at a requested
//! triangle count (within ±20%): [`cornell`] (the Cornell box with K small
//! boxes), [`spheres`] (a closed room of tessellated spheres and cylinders)
//! and [`floorplan`] (a grid of rooms with thick walls and doors); and a
//! two daylit ones lit by a sun and a sky (issue 41): [`atrium`] (a
//! Sponza-sized open court with two storeys of arcades) and [`window_room`]
//! (a closed room with one window); [`emissive_body`], a room lit only
//! by a finely tessellated emitting body, ToyCar's case (issue 42); and
//! [`office`], the floor plan furnished, for the set-up's cost (issue 42).
//! Scenes are millimetres, +y up,
//! written as OBJ + MTL + a TOML scene config ([`scene`]). [`bench`] drives
//! the release `solver` over families × sizes × presets and reports cost and
//! growth; its default families are [`Family::ALL`], the emitter-lit three.
//! [`glossy`] (`scenegen --glossy NAME[=KS,NS]`) makes chosen materials of any
//! family glossy (MTL `Ks`, `Ns`; the config then sets `mode = "directional"`),
//! for glossy scale scenes (issue 43).

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

pub mod arch;
pub mod atrium;
pub mod bench;
pub mod cornell;
pub mod emissive_body;
pub mod floorplan;
pub mod glossy;
pub mod mesh;
pub mod office;
pub mod primitives;
pub mod rng;
pub mod scene;
pub mod spheres;
pub mod window_room;

#[cfg(test)]
mod daylit_tests;
#[cfg(test)]
mod glossy_tests;
#[cfg(test)]
mod tests;

use anyhow::bail;

/// How far the generated count may be from the requested one.
pub const COUNT_TOLERANCE: f64 = 0.2;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Family {
    /// The Cornell box with K small boxes on the floor.
    CornellBoxes,
    /// A closed room with tessellated spheres and cylinders.
    SpheresRoom,
    /// A grid of rooms with thick walls, doors and one light per room.
    FloorPlan,
    /// The floor plan's rooms furnished with cabinets, shelves, desks and
    /// chairs standing on the floors and against the walls (contacts).
    Office,
    /// A 35 × 16 × 16 m open court with two storeys of arcades, lit by sun and
    /// sky (65 000 triangles by default, about 1 300 at least).
    Atrium,
    /// A closed 5.5 m room lit by sun and sky through one window, with two
    /// boxes (300 triangles by default).
    WindowRoom,
    /// A closed 10 × 4 × 8 m room lit only by a car-sized rounded body whose
    /// every facet emits, as ToyCar's emissive body (20 000 triangles by
    /// default).
    EmissiveBody,
}

impl Family {
    /// The scale benchmark's families (its default, and every family the
    /// generic tests check at 1k and 10k triangles). The daylit families,
    /// which the tests check at their own sizes, are left out: adding them would change the benchmark's default figures,
    /// and the atrium has no 1k scene.
    pub const ALL: [Family; 3] = [Family::CornellBoxes, Family::SpheresRoom, Family::FloorPlan];

    pub fn name(self) -> &'static str {
        match self {
            Family::CornellBoxes => "cornell-boxes",
            Family::SpheresRoom => "spheres-room",
            Family::FloorPlan => "floor-plan",
            Family::Office => "office",
            Family::Atrium => "atrium",
            Family::WindowRoom => "window-room",
            Family::EmissiveBody => "emissive-body",
        }
    }

    /// `--triangles` when it is not given: the atrium at Sponza's size, the
    /// window room small.
    pub fn default_triangles(self) -> usize {
        match self {
            Family::Atrium => 65_000,
            Family::WindowRoom => 300,
            Family::EmissiveBody => 20_000,
            _ => 1_000,
        }
    }
}

/// The family's scene nearest `triangles`; an error when no parameter lands
/// within [`COUNT_TOLERANCE`] (too small a request for the family's fixed part).
/// `seed` places the Cornell boxes; the other families are regular.
pub fn generate(family: Family, triangles: usize, seed: u64) -> anyhow::Result<scene::Scene> {
    if triangles == 0 || triangles > 50_000_000 {
        bail!("--triangles must be between 1 and 50 000 000, is {triangles}");
    }
    let scene = match family {
        Family::CornellBoxes => cornell::generate(cornell::boxes_for(triangles), seed),
        Family::SpheresRoom => spheres::generate(spheres::Params::for_triangles(triangles)),
        Family::FloorPlan => floorplan::generate(floorplan::Params::for_triangles(triangles)),
        Family::Office => office::generate(office::Params::for_triangles(triangles)),
        Family::Atrium => atrium::generate(atrium::Params::for_triangles(triangles)),
        Family::WindowRoom => window_room::generate(window_room::Params::for_triangles(triangles)),
        Family::EmissiveBody => {
            emissive_body::generate(emissive_body::Params::for_triangles(triangles))
        }
    };
    let actual = scene.mesh.triangle_count();
    let error = (actual as f64 - triangles as f64).abs() / triangles as f64;
    if error > COUNT_TOLERANCE {
        bail!(
            "{}: the nearest scene to {triangles} triangles has {actual} ({:.0}% off, more than {:.0}%)",
            family.name(),
            100.0 * error,
            100.0 * COUNT_TOLERANCE
        );
    }
    Ok(scene)
}
