//! The speed/accuracy sweep of issue 7, as a library so that its pieces are unit
//! tested: child-process measurement ([`child`]), error metrics and the Pareto
//! front ([`metrics`]), the triangles that draw a shadow edge
//! ([`edge_elements`]), a plane's radiance as drawn ([`floor_probe`]), the per-vertex reference lookup ([`lookup`]), EXR input
//! ([`image`]) and the SVG plot ([`svg`]). The binary (`src/main.rs`) holds the
//! sweep's points and writes `docs/tradeoffs.md`.

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

pub mod child;
pub mod edge_elements;
pub mod floor_probe;
pub mod image;
pub mod lookup;
pub mod metrics;
pub mod svg;
