//! Visibility throughput of the project's own BVH (the occluder), one thread.
//!
//!     cargo bench -p solver --bench visibility [-- --quick] [-- --only WORD]
//!
//! Workload (the solver's, `common/workload.rs`): receiving points on the scene's
//! surfaces, each offset off its surface by the scene epsilon, each casting 64
//! segments to stratified, jittered samples of a source polygon. Two sources: the
//! Cornell box light (narrow, coherent packets) and random wall/floor patches that
//! the receiver faces (wide packets, as when a reflector shoots). Two scenes: the
//! Cornell box (32 triangles) and a generated one of > 100k triangles (the box
//! with a tessellated terrain floor and a sphere).
//!
//! The same segments through third-party BVHs (obvhs, Embree) are traced by
//! `tools/bvh-compare`, a separate crate outside the workspace so that their
//! dependencies stay out of this workspace's lock file (see docs/benchmarks.md).
//!
//! Figures are M segments per second on one core: the best of several passes
//! by wall time (the machine is shared, so the best pass is the least
//! disturbed one), and the mean over all passes by the thread's CPU time
//! (steadier when the load average exceeds the core count).

#[path = "common/workload.rs"]
mod workload;

use glam::DVec3;
use std::path::Path;
use workload::Scene;

fn main() {
    workload::print_machine();
    let (quick, only) = workload::parse_args();
    let cornell = workload::load_cornell_box(&Path::new(env!("CARGO_MANIFEST_DIR")).join(".."));
    let big = workload::generated_scene(&cornell);
    for scene in [&cornell, &big] {
        run_scene(scene, quick, &only);
    }
}

fn run_scene(scene: &Scene, quick: bool, only: &[String]) {
    let (occ, workloads) = workload::prepare(scene, quick);
    for w in &workloads {
        let budget = workload::begin_workload(w, quick);
        let report = |name: &str, count: &dyn Fn(DVec3, &[DVec3]) -> u32| {
            let label = format!("{} {} {}", scene.name, w.name, name);
            if only.iter().all(|o| label.contains(o.as_str())) {
                workload::report(w, budget, name, count);
            }
        };
        report("own BVH4, packets of 64 (count_visible)", &|o, t| {
            occ.count_visible(o, t)
        });
        // The solver's medium and draft presets trace 16 and 4 samples per
        // receiver: the same segments as smaller packets, for comparison with
        // Embree's packets of 16 (tools/bvh-compare) on equal terms.
        report("own BVH4, packets of 16", &|o, t| {
            t.chunks(16).map(|c| occ.count_visible(o, c)).sum()
        });
        report("own BVH4, packets of 4", &|o, t| {
            t.chunks(4).map(|c| occ.count_visible(o, c)).sum()
        });
        report("own BVH4, single rays (visible)", &|o, t| {
            t.iter().filter(|&&x| occ.visible(o, x)).count() as u32
        });
    }
}
