//! The Gauss–Seidel solver's memory bound refuses a scene before anything of
//! the matrix's size is allocated.
//!
//! This test binary installs a global allocator that records, per thread, the
//! largest single allocation and the total allocated, so the refusals can be
//! shown to allocate nothing of the n² matrix's size.

use glam::DVec3;
use solution::camera::UpAxis;
use solver::scene::{Material, Polygon, Scene, SourceRef};
use solver::settings::{Preset, SolverSettings};
use solver::solve::gauss_seidel::{
    matrix_bytes, solve_gauss_seidel, GaussSeidelError, GaussSeidelLimits,
};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Tracking;

thread_local! {
    // `const` initialisation: reading them never allocates, so the allocator
    // may use them.
    static LARGEST: Cell<usize> = const { Cell::new(0) };
    static TOTAL: Cell<usize> = const { Cell::new(0) };
}

fn note(size: usize) {
    // `try_with` fails only while the thread is being torn down.
    let _ = LARGEST.try_with(|largest| largest.set(largest.get().max(size)));
    let _ = TOTAL.try_with(|total| total.set(total.get().saturating_add(size)));
}

// SAFETY: every method forwards to `System` with the arguments it received, so
// `Tracking` upholds `GlobalAlloc`'s contract exactly as `System` does; `note`
// does not allocate.
unsafe impl GlobalAlloc for Tracking {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: forwarded unchanged (see the impl's comment).
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note(layout.size());
        // SAFETY: forwarded unchanged.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note(new_size);
        // SAFETY: forwarded unchanged.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: forwarded unchanged.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Tracking = Tracking;

/// (result, largest single allocation, total allocated) of `f` on this thread.
fn tracked<T>(f: impl FnOnce() -> T) -> (T, usize, usize) {
    LARGEST.with(|l| l.set(0));
    TOTAL.with(|t| t.set(0));
    let out = f();
    (out, LARGEST.with(|l| l.get()), TOTAL.with(|t| t.get()))
}

fn scene(polygons: Vec<Vec<DVec3>>, patches: u32) -> Scene {
    Scene {
        lights: Default::default(),
        polygons: polygons
            .into_iter()
            .enumerate()
            .map(|(i, vertices)| Polygon {
                vertices,
                vertex_normals: None,
                uv_map: None,
                material: 0,
                patches,
                sizes: Default::default(),
                source: SourceRef {
                    item: format!("polygon {i}"),
                    ..Default::default()
                },
            })
            .collect(),
        materials: vec![Material {
            name: "lamp".into(),
            kd: DVec3::splat(0.5),
            ks: DVec3::ZERO,
            alpha: 1.0,
            emission: DVec3::ONE,
            diffuse_texture: None,
            emission_texture: None,
            folded_texture: None,
        }],
        units_per_metre: 1.0,
        up_axis: UpAxis::PosY,
        camera: None,
        recentre_offset: DVec3::ZERO,
        warnings: Vec::new(),
    }
}

/// A pair of facing polygons of the given outline, at z = 0 (facing +z) and
/// z = 1 (facing −z).
fn facing_pair(outline: &[[f64; 2]]) -> Vec<Vec<DVec3>> {
    let low: Vec<DVec3> = outline
        .iter()
        .map(|p| DVec3::new(p[0], p[1], 0.0))
        .collect();
    let mut high: Vec<DVec3> = outline
        .iter()
        .map(|p| DVec3::new(p[0], p[1], 1.0))
        .collect();
    high.reverse();
    vec![low, high]
}

/// The scenes below give every polygon its patch count.
fn settings() -> SolverSettings {
    let mut s = SolverSettings::preset(Preset::Draft);
    s.hemicube_resolution = 16;
    s
}

#[test]
fn the_tracker_sees_allocations() {
    // Without this, the bounds below could pass because nothing was recorded.
    let (v, largest, total) = tracked(|| vec![7u8; 123_457]);
    assert_eq!(v.len(), 123_457);
    assert!(largest >= 123_457 && total >= 123_457);
}

#[test]
fn a_huge_scene_is_refused_before_meshing_with_almost_no_allocation() {
    // Two squares of 256 × 256 patches: 131 072 patches, 68.7 GB of factors. Meshing alone would allocate hundreds of MB; the refusal must
    // come from the count before meshing, so the whole call allocates next to
    // nothing (measured: 8 bytes, in the settings check; 4 KiB allowed).
    let s = scene(
        facing_pair(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
        256,
    );
    let (settings, limits) = (settings(), GaussSeidelLimits::default());
    let (result, largest, total) = tracked(|| solve_gauss_seidel(&s, &settings, &limits));
    match result {
        Err(GaussSeidelError::MatrixTooLarge { patches, bytes, .. }) => {
            assert_eq!(patches, 2 * 256 * 256);
            assert_eq!(bytes, matrix_bytes(patches));
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    println!("refusal before meshing: {total} bytes allocated in all, largest {largest}");
    assert!(
        total < 4096,
        "allocated {total} bytes in all (largest {largest})"
    );
}

#[test]
fn the_exact_count_after_meshing_refuses_before_the_matrix_is_allocated() {
    // Non-convex quads (darts) are meshed as two triangles, so the count before
    // meshing (one piece per quad, a lower bound) is half the mesh's: with
    // 16 × 16 patches, 512 counted, 1024 meshed. A bound between their
    // matrices (1 MiB and 4 MiB) passes the first check and must stop the
    // second, before the 4 MiB matrix exists: the largest allocation stays far
    // below it (the mesh's own arrays are O(n), well under 1 MiB here).
    let dart = [[0.0, 0.0], [4.0, 0.0], [1.0, 1.0], [0.0, 4.0]];
    let s = scene(facing_pair(&dart), 16);
    let limits = GaussSeidelLimits {
        max_matrix_bytes: 2_000_000,
        ..Default::default()
    };
    let settings = settings();
    let (result, largest, _) = tracked(|| solve_gauss_seidel(&s, &settings, &limits));
    match result {
        Err(GaussSeidelError::MatrixTooLarge {
            patches,
            bytes,
            limit,
        }) => {
            assert_eq!(patches, 1024);
            assert_eq!(bytes, 1024 * 1024 * 4);
            assert_eq!(limit, 2_000_000);
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
    println!("refusal after meshing: largest allocation {largest} bytes");
    assert!(
        (largest as u128) < matrix_bytes(1024) / 4,
        "largest allocation {largest} bytes"
    );
}
