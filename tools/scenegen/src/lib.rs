//! Scale scenes for issue 13 and the benchmark that solves them.
//!
//! Three families, each generated at a requested triangle count (within ±20%):
//! [`cornell`] (the Cornell box with K small boxes), [`spheres`] (a closed
//! room of tessellated spheres and cylinders) and [`floorplan`] (a grid of
//! rooms with thick walls and doors). Scenes are millimetres, +y up, written as
//! OBJ + MTL + a TOML scene config ([`scene`]). [`bench`] drives the release
//! `solver` over families × sizes × presets and reports cost and growth.

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

pub mod bench;
pub mod cornell;
pub mod floorplan;
pub mod mesh;
pub mod primitives;
pub mod rng;
pub mod scene;
pub mod spheres;

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
}

impl Family {
    pub const ALL: [Family; 3] = [Family::CornellBoxes, Family::SpheresRoom, Family::FloorPlan];

    pub fn name(self) -> &'static str {
        match self {
            Family::CornellBoxes => "cornell-boxes",
            Family::SpheresRoom => "spheres-room",
            Family::FloorPlan => "floor-plan",
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
