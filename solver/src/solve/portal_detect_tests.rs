//! Detected sky portals in a solve (issue 41, "Must show"): the skylight
//! room of `lights_tests.rs`, whose ceiling hole is found as a portal, is
//! lit as without portals within the noise and with less noise.

use super::lights_tests::{skylit_room, FloorNoise};
use super::*;
use crate::light::portal_detect::detect_portals;

/// The skylit room with the portals detection finds in it (the one hole).
fn detected_room(seed: u64) -> (Scene, SolverSettings) {
    let (mut scene, settings) = skylit_room(false, seed);
    let rings: Vec<&[DVec3]> = scene
        .polygons
        .iter()
        .map(|p| p.vertices.as_slice())
        .collect();
    // The room spans [0, 2] on each axis.
    let found = detect_portals(&rings, 2.0 * 3f64.sqrt());
    assert_eq!(found.portals.len(), 1, "{found:?}");
    // The hole is 0.6 m square: its area within rounding.
    assert!((found.portals[0].area() - 0.36).abs() < 1e-12);
    scene.lights.portals = found.portals;
    (scene, settings)
}

#[test]
fn a_detected_portal_gives_the_same_light_with_less_noise() {
    // As `a_portal_gives_the_same_light_with_less_noise`, with the portal
    // found in the geometry instead of declared: the floor under the
    // skylight is lit by a uniform sky of radiance 1 through it, each
    // vertex's exact direct light is ρ F to the hole; both means lie within
    // 4 standard errors of the exact mean, and the portal's noise is at
    // most half of cosine sampling's.
    let detected = FloorNoise::of(detected_room);
    let cosine = FloorNoise::of(|seed| skylit_room(false, seed));
    detected.compare("detected portal", &cosine);
}
