//! The solver against the ground truth: the Cornell box solved at the draft preset,
//! shown by `runtime screenshot --mono` at 512² and box-filtered 8 × 8 to 64² (so
//! each pixel is the mean radiance over its footprint, as the truth's are), against
//! a 64 × 64 truth committed as a fixture.
//!
//! The fixture was made by the path tracer, which shares only the importer and the
//! BVH with the solver (and was itself checked against Mitsuba 3, docs/accuracy.md):
//!
//! ```sh
//! cargo run --release -p solver -- reference config/cornell_box.toml \
//!     -o tests/fixtures/cornell_truth_64.exr --size 64x64 --target-error 0.005 --seed 1
//! ```
//!
//! Both binaries must be built first (`cargo build -p solver -p runtime`, which
//! `cargo test --workspace` does). The runtime renders on lavapipe unless a Vulkan
//! driver is chosen.

use solver::compare::metrics::reference_noise;

mod common;
use common::cornell_against_truth;

/// Bound on the draft preset's MARE against the truth. Measured (docs/accuracy.md,
/// release build): 9.01% (seed 1) and 8.91% (seed 2) before hidden receivers
/// were treated as hidden (`solver/src/solve/hidden.rs`), 8.49% and 8.01% since.
/// Tightened from 10.5% to 10%: the same margin of 1.5 points over the worse
/// seed covers the truth's noise (0.5% per pixel) and other lavapipe versions'
/// rasterization (the debug build differs from the release one by rounding
/// only); a change that makes draft visibly less accurate fails, and one that
/// makes it more accurate should tighten this bound.
const DRAFT_MARE_BOUND: f64 = 0.10;

/// Bound on the draft image mean's relative bias: measured −2.46% (seed 1) and
/// −2.47% (seed 2) before hidden receivers, −1.68% and −1.72% since (the floor
/// patches next to the blocks and the ceiling patches round the light no
/// longer shoot a mean diluted by their hidden vertices). What remains is
/// mostly the light draft's 2% stop threshold leaves unshot (−0.73% with
/// `--threshold 0.002`). Tightened from 4% to 3%, a margin of 1.3 points. The
/// mean is energy, independent of where the light lands, so it guards the
/// transport rather than the meshing.
const DRAFT_MEAN_BOUND: f64 = 0.03;

#[test]
fn draft_cornell_box_matches_the_path_traced_truth() {
    let dir = tempfile::tempdir().unwrap();
    let (summary, truth) = cornell_against_truth(dir.path(), "box", &["--preset", "draft"]);
    let noise = reference_noise(&truth.image, truth.standard_error.as_deref().unwrap());
    eprintln!(
        "draft vs truth: MARE {:.4}, mean signed {:+.4}, relative RMSE {:.4}, means {:.5} / {:.5}; \
         truth noise {:.4}",
        summary.mare,
        summary.mean_signed_relative_error,
        summary.relative_rmse,
        summary.test_mean,
        summary.reference_mean,
        noise
    );

    // The truth's own noise. `solver reference` stopped at 0.49% (its luminance
    // estimate); `reference_noise` adds the three channels' standard errors, an
    // upper bound (0.51% for this fixture).
    assert!(noise <= 0.0055, "the fixture's noise is {noise}");
    assert!(
        summary.mare <= DRAFT_MARE_BOUND,
        "draft MARE {:.4} against the truth exceeds {DRAFT_MARE_BOUND}",
        summary.mare
    );
    let mean_bias = summary.test_mean / summary.reference_mean - 1.0;
    assert!(
        mean_bias.abs() <= DRAFT_MEAN_BOUND,
        "draft image mean is {mean_bias:+.4} of the truth's (bound {DRAFT_MEAN_BOUND})"
    );
}
