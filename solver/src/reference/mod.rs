//! The reference renderer behind `solver reference`: an unbiased path tracer of
//! the same scenes and physics as the radiosity solver, the project's ground
//! truth. Pure: no files, no terminal (the command line is in
//! `cli/reference.rs`).
//!
//! Physics, as the solver's (design notes, "Units and conventions" and
//! "Directional mode"): one-sided polygons (back faces are black but block
//! light); Lambertian emitters of radiance `emission` toward the front; Kd
//! Lambertian reflection; in directional mode Ks times the exact glossy lobe of
//! Remington (1992, eq. 4.2) with `C_R` from a converged quadrature of the
//! thesis's normalization ([`lobe`]); in diffuse mode Ks is
//! ignored. The sun, the sky and point or spot lamps (`crate::light`) light
//! it as they light the solver's receivers ([`lights`]).
//!
//! Modules, one job each:
//! * [`lobe`]: the exact glossy lobe, its `C_R` table and its importance sampler;
//! * [`bsdf`]: a material's reflection (Kd + Ks lobe), evaluation, mixture sampling;
//! * [`emitters`]: sampling points on emitters by power and area;
//! * [`lights`]: the sun, the sky and the lamps: what escaping rays see, and
//!   their next-event samples;
//! * [`scene`]: the prepared scene (surfaces, BVH, materials, names);
//! * [`integrator`]: path tracing with next-event estimation and MIS (Veach 1997);
//! * [`camera`]: eye rays with `runtime screenshot`'s pixel conventions;
//! * [`image`]: per-pixel sums, standard errors, parallel deterministic passes.

pub mod bsdf;
pub mod camera;
pub mod emitters;
pub mod image;
pub mod integrator;
pub mod lights;
pub mod lobe;
pub mod scene;
pub mod shading;

#[cfg(test)]
mod light_tests;
#[cfg(test)]
mod tests;

pub use image::{id_buffers, Accumulator, PixelSums};
pub use integrator::Integrator;
pub use scene::{Physics, RenderScene};
