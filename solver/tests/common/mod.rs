//! Helpers shared by the solver's integration tests. Each test crate uses a
//! subset of them.
#![allow(dead_code)]

use solver::scene::{load_scene, smooth_scene, ImportOptions, Scene};
use solver::settings::SolverSettings;
use std::path::Path;

/// The Cornell box scene at `path` as `solver solve` prepares it: millimetres,
/// meshed by the preset's sizes, smooth groups.
pub fn cornell_scene(path: &Path, settings: &SolverSettings) -> Scene {
    let options = ImportOptions {
        units_per_metre: Some(1000.0),
        ..Default::default()
    };
    let mut scene = load_scene(path, &options).unwrap().scene;
    smooth_scene(&mut scene, settings.crease_angle);
    scene
}

/// What a texture may add to the error against the path-traced truth over
/// the same scene untextured (or with a flat emitter), under the same solve,
/// renderer and truth noise: the pixels that straddle a texel edge differ by
/// the reconstruction (trilinear box texels in the rasterizer, bilinear in
/// the path tracer), and each patch shoots or reflects its texels' mean.
pub const TEXTURE_ALLOWANCE: f64 = 0.03;

/// The textured comparisons' rule: the textured MARE is within
/// [`TEXTURE_ALLOWANCE`] of the untextured `baseline`'s, and a `control` that
/// ignores the texture (or replaces it by its mean), when given, scores more
/// than three times that bound, so the comparison sees the texture.
pub fn assert_texture_shown(label: &str, textured: f64, baseline: f64, control: Option<f64>) {
    let bound = baseline + TEXTURE_ALLOWANCE;
    assert!(
        textured <= bound,
        "{label}: textured MARE {textured:.4} vs untextured {baseline:.4} (bound {bound:.4})"
    );
    if let Some(control) = control {
        assert!(
            control > 3.0 * bound,
            "{label}: the comparison must see the texture: ignoring it scores {control:.4}"
        );
    }
}
