//! Progressive-refinement radiosity with ray-cast vertex form factors, automatic
//! meshing and spherical-harmonic directional radiance, after Remington (1992,
//! `shared/seeds/000`), and the solution file that the runtime walks through.
//!
//! The library is split by a feature so that the runtime links only what it needs:
//!
//! * always built: [`format`] (the solution file), [`sh`] (spherical-harmonic
//!   evaluation), [`cube`] (001's global-cube lookup), [`camera`] and [`raster`] (a small CPU rasterizer used by
//!   `--preview` and by the runtime's reference renderer);
//! * feature `solve` (default): [`scene`] (importers), [`geometry`] (form factors and
//!   visibility), [`mesh`], [`brdf`], [`solve`] and the command line in [`cli`].
//!
//! **Architecture Invariant:** this crate never depends on `ash`, `openxr` or `winit`.

pub mod camera;
pub mod cube;
pub mod format;
pub mod raster;
pub mod sh;

#[cfg(feature = "solve")]
pub mod brdf;
#[cfg(feature = "solve")]
pub mod cli;
#[cfg(feature = "solve")]
pub mod geometry;
#[cfg(feature = "solve")]
pub mod mesh;
#[cfg(feature = "solve")]
pub mod reference;
#[cfg(feature = "solve")]
pub mod scene;
#[cfg(feature = "solve")]
pub mod settings;
#[cfg(feature = "solve")]
pub mod solve;
