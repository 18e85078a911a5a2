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

/// Bound on the draft preset's MARE against the truth. Measured (docs/lab/first-accuracy-study.md,
/// release build): 9.01% (seed 1) and 8.91% (seed 2) before hidden receivers
/// were treated as hidden (`solver/src/solve/hidden.rs`), 8.49% and 8.01% after,
/// 7.04% and 7.56% with the non-uniform shooters. The draft preset is now the
/// truth-chosen one (8 rays, threshold 0.5%, the ambient term written at
/// convergence; docs/lab/presets.md, "Presets against the truth"): 5.57% (seed 1,
/// release and this debug build alike) and 5.93% (seed 2). Tightened from 10%
/// to 7%: the two seeds differ by 0.36 points, and the margin over the worse
/// seed, 1.07 points, is three times that, which also covers the truth's noise
/// (0.5% per pixel) and another lavapipe's rasterization of the light's border
/// row (about 0.3 points, docs/benchmarks.md, "Time to accuracy"). A change
/// that makes draft visibly less accurate fails. With receivers cut along
/// contact lines (`solver/src/mesh/contact.rs`) draft measures 3.79%, 4.13%
/// and 4.11% (seeds 1, 2, 3; docs/lab/contact-cuts.md, "After the contact cuts"), so
/// the bound is tightened again, to 5.5%: the seeds spread over 0.34 points,
/// and the margin over the worst, 1.37 points, is four times that, for the
/// same truth noise and rasterization allowances as before. With the ambient
/// term weighted by enclosure (`solver/src/solve/enclosure.rs`) draft
/// measures 3.56%, 3.98% and 3.87% (docs/lab/ambient-term.md, "The ambient term
/// weighted by enclosure"), and the bound is 5%: the margin over the worst
/// seed, 1.02 points, still covers the seeds' spread (0.42 points) plus the
/// truth noise and rasterization allowances (0.8 points). With grouped
/// shooters in every preset (docs/lab/grouped-shooters.md, "Grouped shooters by
/// default") draft measures 3.19%, 3.25% and 3.66% (seeds 1, 2, 3, release):
/// the bound stays at 5%, since the seeds now spread over 0.47 points and the
/// margin over the worst, 1.34 points, is just that spread plus the same 0.8
/// points of truth noise and rasterization.
const DRAFT_MARE_BOUND: f64 = 0.05;

/// Bound on the draft image mean's relative bias: measured −2.46% / −2.47%
/// (seeds 1 / 2) at first, −1.68% / −1.72% with hidden receivers, and now,
/// with the ambient term carrying the light the 0.5% threshold leaves unshot,
/// −0.44% / −0.49% (−0.45% in this debug build; −0.89% without the term);
/// −0.75% / −0.80% with the term weighted by enclosure, which moves some of
/// it off the surfaces that face the open front; −0.53% / −0.59% / −0.78%
/// (seeds 1, 2, 3) with grouped shooters.
/// Tightened from 3% to 1.25%: the seeds differ by 0.05 points, so the margin
/// of 0.76 points over the worse seed is set by the rasterizer instead (the
/// light's border row, its brightest pixels, moves the mean by a few tenths
/// between rasterizers). The mean is energy, independent of where the light
/// lands, so it guards the transport and the ambient term rather than the
/// meshing.
const DRAFT_MEAN_BOUND: f64 = 0.0125;

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
