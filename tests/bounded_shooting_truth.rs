//! Bounded shooting (`solver/src/solve/cluster.rs`) against flat progressive
//! refinement, both held to the committed 64 × 64 path-traced truth of the
//! Cornell box (`tests/fixtures/cornell_truth_64.exr`, see
//! `tests/cornell_truth.rs` for how it was made and how images are compared):
//! the draft preset solved each way, shown by `runtime screenshot --mono` at
//! 512² and box-filtered 8 × 8 to the truth's pixels.
//!
//! Both binaries must be built first (`cargo build -p solver -p runtime`).

use std::path::Path;

mod common;
use common::cornell_against_truth;

/// How much worse than flat shooting's MARE bounded shooting may be, in
/// absolute MARE. It is set by the seed-to-seed spread of the draft solve's
/// own MARE (8.91% to 9.01% with seeds 1 and 2, docs/accuracy.md: 0.1
/// points), doubled for the two solves compared here, plus the bounded
/// method's own allowance: each shot may move a bounded surface by at most
/// the tolerance, and the draft's ~260 shots spread such errors over surfaces
/// far from or tangent to their sources. The test runs bounded shooting at
/// 10× the default tolerance (1e-3), where it skips ~250 receivers a shot
/// (at the default, 1e-4, draft bounds almost none and the test would compare
/// flat with itself). Measured: flat 9.01%, bounded 9.11%
/// (docs/benchmarks.md, "Bounded shooting"); with the non-uniform shooters,
/// at the settings below, flat 7.04%, bounded 7.30%.
const MARE_ALLOWANCE: f64 = 0.004;

fn mare(dir: &Path, shooting: &str) -> f64 {
    // The draft mesh at the old draft preset's rays and threshold (2 rays, 2%),
    // where the allowance below was measured: the truth-chosen draft (8 rays,
    // 0.5%) shoots ~400 times instead of ~260, and at 10× the default
    // tolerance bounded shooting then measured 6.22% against flat's 5.57%
    // (docs/accuracy.md, "Presets against the truth"), more than this
    // allowance, which was set for the shot count below. Without the ambient
    // term, which files now carry at convergence: it is a display estimate of
    // the light neither method has shot, not part of the transport compared.
    let args = [
        "--preset",
        "draft",
        "--samples",
        "2",
        "--threshold",
        "0.02",
        "--no-ambient",
        "--shooting",
        shooting,
    ];
    let tolerance = ["--shooting-tolerance", "0.001"];
    let (summary, _) = cornell_against_truth(dir, shooting, &[&args[..], &tolerance].concat());
    eprintln!(
        "{shooting} draft vs truth: MARE {:.4}, mean signed {:+.4}, relative RMSE {:.4}",
        summary.mare, summary.mean_signed_relative_error, summary.relative_rmse
    );
    summary.mare
}

#[test]
fn bounded_shooting_is_as_accurate_as_flat_against_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let flat = mare(dir.path(), "flat");
    let bounded = mare(dir.path(), "bounded");
    assert!(
        bounded <= flat + MARE_ALLOWANCE,
        "bounded MARE {bounded:.4} exceeds flat's {flat:.4} + {MARE_ALLOWANCE}"
    );
}
