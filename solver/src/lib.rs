//! Progressive-refinement radiosity with ray-cast vertex form factors, automatic
//! meshing and spherical-harmonic directional radiance, after Remington (1992,
//! "A Radiosity Approach to Realistic Image Synthesis"), writing the solution file
//! that the runtime walks through.
//!
//! * [`scene`]: importers (OBJ + MTL, TOML scene, the thesis's legacy geometry and
//!   display files), cleaning, re-centring, welding;
//! * [`geometry`]: form factors, sampling, and the occlusion BVH;
//! * [`mesh`]: patches, quadtree elements, shared vertices, triangulation;
//! * [`brdf`]: the thesis's glossy lobe and its normalizations;
//! * [`texture`]: diffuse textures as linear mip pyramids, integrated over UV triangles;
//! * [`solve`]: progressive refinement, directional SH shooting, Gauss–Seidel and the
//!   global-cube gather;
//! * [`reference`]: the unbiased path tracer of `solver reference`, the ground truth;
//! * [`export`]: glTF 2.0 export of a solution (`solver export`);
//! * [`compare`]: `solver compare`'s image metrics (relative RMSE, MARE, HDR-FLIP);
//! * [`view`]: the default view of a scene that names no camera, stored as the
//!   header camera;
//! * [`settings`] and the command line in [`cli`].
//!
//! The file format, SH and cube evaluation, the camera and the CPU rasterizer are the
//! contract with the runtime and live in the `solution` crate.
//!
//! **Architecture Invariant:** this crate never depends on `ash`, `openxr` or `winit`.

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

pub mod brdf;
pub mod cli;
pub mod compare;
pub mod export;
pub mod geometry;
pub mod light;
pub mod mesh;
pub mod method;
pub mod progress;
pub mod reference;
pub mod scene;
pub mod settings;
pub mod solve;
pub mod texture;
pub mod view;
