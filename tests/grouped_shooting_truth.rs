//! Grouped shooters (`solver/src/solve/group_shot.rs`) against one patch per
//! shot, both held to the committed 64 × 64 path-traced truth of the Cornell
//! box (`tests/fixtures/cornell_truth_64.exr`, see `tests/cornell_truth.rs` for
//! how it was made and how images are compared): the draft preset solved each
//! way, shown by `runtime screenshot --mono` at 512² and box-filtered 8 × 8 to
//! the truth's pixels.
//!
//! Both binaries must be built first (`cargo build -p solver -p runtime`).

use std::path::Path;

mod common;
use common::cornell_against_truth;

/// How much worse than the patch shooter's MARE grouped shooting may be, in
/// absolute MARE. Measured at draft (seeds 1 and 2, docs/lab/grouped-shooters.md,
/// "Grouped shooters"): patch 3.79% / 4.13%, grouped 4.36% / 4.29%, a
/// difference of +0.57 and +0.16 points, and the draft's own seed-to-seed
/// spread is 0.34 points (docs/lab/grouped-shooters.md). The allowance is the larger
/// measured difference plus that spread, 0.9 points: grouping trades some
/// noise (a member gets its share of a receiver's rays, not all of them) for
/// 20× fewer shots, and the test guards against more than that. Shooting the
/// members uniformly instead of by quadrants measured 5.10% / 5.22%, 1.3
/// points worse, and fails it. Since the cluster tree (`group_tree.rs`,
/// 4 December 2026) grouped measures 3.69% against the patch shooter's
/// 3.69%; the allowance is kept, not tightened, because one seed per side
/// cannot resolve less than the draft's seed spread. Grouped is now every
/// preset's shooter (draft 3.19% / 3.25% against the patch shooter's 3.69%
/// / 3.73%), so this test holds the default to the patch shooter it replaced.
const MARE_ALLOWANCE: f64 = 0.009;

fn mare(dir: &Path, shooters: &str) -> f64 {
    let args = ["--preset", "draft", "--shooters", shooters];
    let (summary, _) = cornell_against_truth(dir, shooters, &args);
    eprintln!(
        "{shooters} draft vs truth: MARE {:.4}, mean signed {:+.4}, relative RMSE {:.4}",
        summary.mare, summary.mean_signed_relative_error, summary.relative_rmse
    );
    summary.mare
}

#[test]
fn grouped_shooting_is_as_accurate_as_patch_shooting_against_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let patch = mare(dir.path(), "patch");
    let grouped = mare(dir.path(), "grouped");
    assert!(
        grouped <= patch + MARE_ALLOWANCE,
        "grouped MARE {grouped:.4} exceeds the patch shooter's {patch:.4} + {MARE_ALLOWANCE}"
    );
}
