//! What the tools (`tools/sweep`, `tools/scenegen`'s scale bench), the solver's
//! benches and the end-to-end tests need alike, written once:
//!
//! - [`child`]: running a child program and measuring it alone (wall time,
//!   its own CPU seconds and peak resident set, from `wait4(2)`);
//! - [`svg`]: the pieces of a hand-written SVG plot (axes that map values to
//!   pixels, the log-log page with its decade grid, polylines);
//! - [`host`]: this process's own CPU seconds and the CPU's model name;
//! - [`metrics`]: the relative L2 error of a signal against a reference.
//!
//! It depends on nothing of the project's, so that the solver's benches can use
//! it without a dependency cycle.

// Shipped code: Clippy checks clippy.toml's lists here (ARCHITECTURE.md's invariants).
#![cfg_attr(not(test), warn(clippy::disallowed_methods, clippy::disallowed_macros))]
#![cfg_attr(not(test), warn(clippy::too_many_lines))]

pub mod child;
pub mod host;
pub mod metrics;
pub mod svg;
