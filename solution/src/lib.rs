//! The contract between the solver and the runtime: everything both programs must
//! agree on, and nothing else.
//!
//! * [`atomic`]: the one atomic file writer every program's output goes through;
//! * [`format`]: the solution file (in-memory types, byte layout, the atomic writer,
//!   the memory-mapped validating reader, `describe` for `solver info`);
//! * [`sh`]: real orthonormal spherical harmonics in f64, and the f32 twin that the
//!   vertex shader mirrors;
//! * [`cube`]: the global cube of Immel, Cohen and Greenberg (1986): cell directions,
//!   exact cell solid angles, and the bilinear lookup toward the eye in f64 and in the
//!   f32 twin that `shaders/scene_cube.vert` mirrors;
//! * [`camera`]: cameras, up axes and per-eye views in the Vulkan convention;
//! * [`raster`]: tone curves and the small CPU reference rasterizer that the solver's
//!   `--preview` and the runtime's GPU-versus-CPU tests share;
//! * [`texture`]: mip chains and Vulkan's trilinear filter for textured batches
//!   (the runtime uploads these levels; the reference renderer samples them);
//! * [`view`]: what the solver's default-view chooser and the runtime share: the
//!   standing eye height and the chooser's figures, the triangle BVH, and the
//!   test room.
//!
//! **Architecture Invariant:** this crate depends on neither the solver nor the
//! runtime, nor on `ash`, `openxr` or `winit`; the runtime depends on it and never on
//! the solver (checked by `scripts/test.sh` with `cargo tree -p runtime`).

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

pub mod atomic;
pub mod camera;
pub mod cube;
pub mod format;
pub mod raster;
pub mod sh;
pub mod texture;
pub mod view;
