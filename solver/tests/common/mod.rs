//! Helpers shared by the solver's integration tests.

use solver::scene::{load_scene, smooth_scene, ImportOptions, Scene};
use solver::settings::SolverSettings;
use std::path::Path;

/// The Cornell box scene at `path` as `solver solve` prepares it: millimetres,
/// default patches unless the preset sizes them, smooth groups.
pub fn cornell_scene(path: &Path, settings: &SolverSettings) -> Scene {
    let options = ImportOptions {
        units_per_metre: Some(1000.0),
        ..Default::default()
    };
    let mut scene = load_scene(path, &options).unwrap().scene;
    if settings.patch_size.is_none() {
        scene.fill_default_patches(settings.patches);
    }
    smooth_scene(&mut scene, settings.crease_angle);
    scene
}
