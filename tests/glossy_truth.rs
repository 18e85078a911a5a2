//! The directional (glossy) solver against the ground truth: the sweep's glossy
//! room (`config/glossy_floor.toml`: a glossy floor, Kd 0.2, Ks 0.6, α = 0.1,
//! under a small bright light) solved in directional mode, shown by `runtime
//! screenshot --mono` at 320 × 240 from the sweep's two cameras and box-filtered
//! 8 × 8 to the committed 40 × 30 truths (`tools/sweep/fixtures/`, whose README
//! gives the `solver reference` commands: 0.50% noise, about 70,000 samples per
//! pixel each).
//!
//! The path tracer shares only the importer and the BVH with the solver, and
//! samples the thesis's exact lobe (Remington 1992, eq. 4.2), where the solver
//! carries a windowed SH expansion of it: this is the one test of the glossy
//! transport (lobe, SH storage, directional shooting, the runtime's per-vertex
//! evaluation toward the eye) against an independent answer.
//!
//! Both binaries must be built first (`cargo build -p solver -p runtime`, which
//! `cargo test --workspace` does). The runtime renders on lavapipe unless a Vulkan
//! driver is chosen.

use solver::compare::flip::{default_pixels_per_degree, flip, Variant};
use solver::compare::image::LoadedImage;
use solver::compare::metrics::{error_by_id, reference_noise, summarize, Summary};
use std::path::Path;
use std::process::Command;

mod common;
use common::{binary, lavapipe, run};

/// A fixed camera of the sweep's glossy room (`tools/sweep/src/points.rs`).
struct View {
    name: &'static str,
    eye: [f64; 3],
    target: [f64; 3],
    fixture: &'static str,
}

const VIEWS: [View; 2] = [
    View {
        name: "front",
        eye: [0.0, 0.6, 1.8],
        target: [0.0, 0.0, 0.0],
        fixture: "tools/sweep/fixtures/glossy_front_40x30.exr",
    },
    View {
        name: "side",
        eye: [1.2, 0.4, 0.2],
        target: [-0.6, 0.0, -1.2],
        fixture: "tools/sweep/fixtures/glossy_side_40x30.exr",
    },
];

/// One view's comparison: the whole image, the glossy floor alone, HDR-FLIP.
struct Measured {
    summary: Summary,
    floor_mare: f64,
    floor_signed: f64,
    flip: f64,
    noise: f64,
}

/// Solves the glossy room with `solve_args` into `dir/name.sol` and compares
/// each view with its truth.
fn glossy_room_against_truth(dir: &Path, name: &str, solve_args: &[&str]) -> Vec<Measured> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let solution = dir.join(format!("{name}.sol"));
    run(
        Command::new(binary("solver"))
            .arg("solve")
            .arg(root.join("config/glossy_floor.toml"))
            .args(solve_args)
            .arg("-o")
            .arg(&solution),
        "solver solve",
    );
    let read = solver::compare::read::read_image;
    VIEWS
        .iter()
        .map(|view| {
            let prefix = dir.join(format!("{name}-{}", view.name));
            let v = |a: [f64; 3]| a.map(|x| x.to_string());
            let mut screenshot = Command::new(binary("runtime"));
            lavapipe(&mut screenshot);
            run(
                screenshot
                    .arg("screenshot")
                    .arg(&solution)
                    .args(["--mono", "--size", "320x240", "--fov-y", "60"])
                    .arg("--eye")
                    .args(v(view.eye))
                    .arg("--target")
                    .args(v(view.target))
                    .args(["--up", "0", "1", "0", "--out"])
                    .arg(&prefix),
                "runtime screenshot",
            );
            let truth: LoadedImage = read(&root.join(view.fixture)).unwrap();
            let shown = read(&prefix.with_extension("exr")).unwrap();
            let factor = shown
                .image
                .supersampling_factor(truth.image.width, truth.image.height)
                .expect("the screenshot is 8× the truth's size");
            let test = shown.image.box_downsample(factor);
            let materials = truth
                .material_id
                .as_ref()
                .expect("the truth's material ids");
            let floor = error_by_id(&test, &truth.image, materials)
                .into_iter()
                .find(|g| g.name == "glossy_floor")
                .expect("the glossy floor is in view");
            Measured {
                summary: summarize(&test, &truth.image),
                floor_mare: floor.mare,
                floor_signed: floor.mean_signed,
                flip: flip(
                    &test,
                    &truth.image,
                    Variant::Hdr,
                    default_pixels_per_degree(),
                )
                .unwrap()
                .mean as f64,
                noise: reference_noise(&truth.image, truth.standard_error.as_deref().unwrap()),
            }
        })
        .collect()
}

fn report(what: &str, measured: &[Measured]) {
    for (view, m) in VIEWS.iter().zip(measured) {
        eprintln!(
            "{what} {}: MARE {:.4}, mean signed {:+.4}, HDR-FLIP {:.4}, floor MARE {:.4} \
             (signed {:+.4}), means {:.5} / {:.5}; truth noise {:.4}",
            view.name,
            m.summary.mare,
            m.summary.mean_signed_relative_error,
            m.flip,
            m.floor_mare,
            m.floor_signed,
            m.summary.test_mean,
            m.summary.reference_mean,
            m.noise
        );
    }
}

/// The solve: the `draft` preset, what a first look at a scene uses. The glossy
/// room's directional solve costs about 2.5–2.8 CPU s in release (L = 21 on
/// the floor, about 1,600 elements); `medium` (47 CPU s) is too slow for CI.
const SOLVE_ARGS: [&str; 2] = ["--preset", "draft"];

/// Bound on each view's MARE against its truth. With grouped shooters in
/// directional mode (6 December 2026, docs/lab/glossy-grouped-shooters.md):
/// front 6.89% (seed 1) and 6.54% (seed 2); patch by patch, measured (3 December 2026,
/// glossy receivers sampling sources by solid angle; dev build, which gives
/// the release figures to the printed digits): front 6.52% (seed 1) and
/// 6.31% (seed 2), side 4.51% and 3.66%. With equal shares of area samples
/// they were 11.26% / 12.91% and 10.01% / 10.55%, under the bound of 15%
/// this test had then (docs/lab/glossy-solid-angle-samples.md, "Glossy: samples by solid angle").
/// Two points over the worse seed cover the draft preset's seed-to-seed
/// spread, the truths' 0.5% noise and other lavapipe versions'
/// rasterization. Ignoring Ks (a diffuse solve) measures 56.7% / 43.9%; a
/// floor whose Ks is made diffuse (Kd + Ks, no lobe: the same energy, no
/// highlight) 40.3% / 53.9%.
const MARE_BOUND: f64 = 0.085;

/// Bound on the glossy floor's own MARE in each view: measured front 7.7%
/// and 7.4%, side 4.0% and 3.9% (seeds 1 and 2; 11.1% / 14.5% and 9.6% /
/// 10.3% with equal shares), with about the same margin as above. Ks
/// ignored: 73.9% / 57.5%; Ks made diffuse: 60.9% / 97.0%.
const FLOOR_MARE_BOUND: f64 = 0.10;

/// Bound on each view's image mean against the truth's: measured −3.4% and
/// −4.7% (front, seeds 1 and 2), −0.6% and −0.7% (side); with equal shares
/// −4.56% / −2.44% and −5.25% / −6.17%. Ks ignored: −72% / −47%. Three
/// points over the worst seed.
const MEAN_BOUND: f64 = 0.08;

#[test]
fn glossy_room_matches_the_path_traced_truth() {
    let dir = tempfile::tempdir().unwrap();
    let measured = glossy_room_against_truth(dir.path(), "glossy", &SOLVE_ARGS);
    report("directional", &measured);
    for (view, m) in VIEWS.iter().zip(&measured) {
        // The truths' own noise: `solver reference` stopped at 0.50%;
        // `reference_noise` adds the channels' standard errors (an upper bound,
        // 0.53% for these fixtures).
        assert!(
            m.noise <= 0.006,
            "{}: the fixture's noise is {}",
            view.name,
            m.noise
        );
        assert!(
            m.summary.mare <= MARE_BOUND,
            "{}: MARE {:.4} against the truth exceeds {MARE_BOUND}",
            view.name,
            m.summary.mare
        );
        assert!(
            m.floor_mare <= FLOOR_MARE_BOUND,
            "{}: the glossy floor's MARE {:.4} exceeds {FLOOR_MARE_BOUND}",
            view.name,
            m.floor_mare
        );
        let mean_bias = m.summary.test_mean / m.summary.reference_mean - 1.0;
        assert!(
            mean_bias.abs() <= MEAN_BOUND,
            "{}: image mean is {mean_bias:+.4} of the truth's (bound {MEAN_BOUND})",
            view.name
        );
    }
}
