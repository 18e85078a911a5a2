//! Lights that are not glowing polygons: the sun, the sky, and photometric
//! lamps (issue 41). Pure, like the rest of the solver core: parsers take
//! text the importers read, and every function returns values or errors.
//!
//! Units: the solver's radiance is radiometric, RGB W·sr⁻¹·m⁻² per channel,
//! as a material's `Ke`. A photometric value X (cd, lx, cd·m⁻²) with colour c
//! becomes c · X / 683 per channel (`units.rs`): the colour is a filter, and
//! a white light's RGB luminance is X / 683, as glTF's specification has it.

pub mod ies;
pub mod sky;
pub mod sun;
pub mod units;
