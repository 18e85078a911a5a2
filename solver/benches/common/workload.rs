//! The visibility workload shared by `solver/benches/visibility.rs` (the
//! project's own BVH) and `tools/bvh-compare` (the same segments through obvhs
//! and Embree): scenes, receivers, segments, and the timing loop.

#![allow(dead_code)]

use glam::DVec3;
use solver::geometry::polygon::newell_normal;
use solver::geometry::sampling::{stratified_points, Rng};
use solver::geometry::visibility::Occluder;
use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

pub const SAMPLES: usize = 64;

/// A scene: polygons, the index of the light polygon, and the cumulative
/// areas of the non-light polygons (to pick surface points by area).
pub struct Scene {
    pub name: String,
    pub polygons: Vec<Vec<DVec3>>,
    pub light: usize,
    pub area_cum: Vec<f64>,
}

impl Scene {
    pub fn new(name: String, polygons: Vec<Vec<DVec3>>, light: usize) -> Scene {
        let mut acc = 0.0;
        let area_cum = polygons
            .iter()
            .enumerate()
            .map(|(i, p)| {
                if i != light {
                    acc += newell_normal(p).length();
                }
                acc
            })
            .collect();
        Scene {
            name,
            polygons,
            light,
            area_cum,
        }
    }
}

/// One workload: per receiver an origin and SAMPLES targets.
pub struct Workload {
    pub name: &'static str,
    pub origins: Vec<DVec3>,
    pub targets: Vec<DVec3>,
}

impl Workload {
    pub fn rays(&self) -> usize {
        self.targets.len()
    }
}

/// Runs `count` over the workload repeatedly for about `budget` and prints the
/// best pass's rate and the number of visible segments.
pub fn report(w: &Workload, budget: Duration, name: &str, count: &dyn Fn(DVec3, &[DVec3]) -> u32) {
    let pass = || {
        let mut visible = 0u64;
        for (i, &o) in w.origins.iter().enumerate() {
            visible += count(
                black_box(o),
                black_box(&w.targets[i * SAMPLES..(i + 1) * SAMPLES]),
            ) as u64;
        }
        visible
    };
    let visible = pass(); // warm-up
    let mut best = f64::INFINITY;
    let started = Instant::now();
    // The kernel updates a thread's CPU time at scheduler ticks (every few
    // ms), about the length of one pass: so the CPU-time rate is taken over
    // all passes together (mean), where that granularity is negligible.
    let cpu_start = thread_cpu_seconds();
    let mut passes = 0;
    while passes < 3 || started.elapsed() < budget {
        let t = Instant::now();
        black_box(pass());
        best = best.min(t.elapsed().as_secs_f64());
        passes += 1;
    }
    let cpu_rate = match (cpu_start, thread_cpu_seconds()) {
        (Some(a), Some(b)) if b > a => (w.rays() * passes) as f64 / (b - a) / 1e6,
        _ => f64::NAN,
    };
    println!(
        "   {:<44} {:>10.2} {:>10.2} {:>10}",
        name,
        w.rays() as f64 / best / 1e6,
        cpu_rate,
        visible
    );
}

/// CPU time this thread has run, from Linux's /proc/thread-self/schedstat
/// (nanoseconds). On a shared machine the wall time of a pass includes time
/// the thread waited for a core; the CPU time does not, so the rate by CPU
/// time is the steadier figure when the load average is above the core count.
/// `None` where the file does not exist.
pub fn thread_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// Receivers on every polygon but the light (area-weighted), offset off their
/// surface, facing the light and in front of it; 64 samples of the light each.
pub fn light_workload(scene: &Scene, occ: &Occluder, receivers: usize) -> Workload {
    let light = &scene.polygons[scene.light];
    let light_n = newell_normal(light).normalize();
    let light_c = light.iter().copied().sum::<DVec3>() / light.len() as f64;
    let mut w = Workload {
        name: "light: 64 samples of the Cornell light",
        origins: Vec::new(),
        targets: Vec::new(),
    };
    let mut rng = Rng::new(1, 0);
    let mut samples = Vec::new();
    let mut attempts = 0;
    while w.origins.len() < receivers && attempts < receivers * 100 {
        attempts += 1;
        let (p, n) = random_surface_point(scene, &mut rng, occ.scene_epsilon());
        if n.dot(light_c - p) <= 0.0 || light_n.dot(p - light_c) <= 0.0 {
            continue;
        }
        let mut srng = Rng::new(2, w.origins.len() as u64);
        stratified_points(light, SAMPLES as u32, &mut srng, &mut samples);
        w.origins.push(p);
        w.targets.extend_from_slice(&samples);
    }
    w
}

/// Receivers as above, each sampling a random patch (a 1/16 piece of a wall,
/// floor or ceiling polygon) that faces it: wider, less coherent packets.
pub fn patch_workload(scene: &Scene, occ: &Occluder, receivers: usize) -> Workload {
    let mut w = Workload {
        name: "patches: 64 samples of a facing wall patch",
        origins: Vec::new(),
        targets: Vec::new(),
    };
    let mut rng = Rng::new(3, 0);
    let mut samples = Vec::new();
    // The room's five big polygons (the first five of both scenes).
    let mut attempts = 0;
    while w.origins.len() < receivers && attempts < receivers * 100 {
        attempts += 1;
        let (p, n) = random_surface_point(scene, &mut rng, occ.scene_epsilon());
        let wall = &scene.polygons[(rng.next_u32() % 5) as usize];
        let patch = sub_patch(
            wall,
            (rng.next_u32() % 4) as usize,
            (rng.next_u32() % 4) as usize,
        );
        let pn = newell_normal(&patch).normalize();
        let pc = patch.iter().copied().sum::<DVec3>() / patch.len() as f64;
        if n.dot(pc - p) <= 0.0 || pn.dot(p - pc) <= 0.0 {
            continue;
        }
        let mut srng = Rng::new(4, w.origins.len() as u64);
        stratified_points(&patch, SAMPLES as u32, &mut srng, &mut samples);
        w.origins.push(p);
        w.targets.extend_from_slice(&samples);
    }
    w
}

/// Quad `q` split bilinearly into 4 × 4; piece (i, j).
pub fn sub_patch(q: &[DVec3], i: usize, j: usize) -> Vec<DVec3> {
    let at = |u: f64, v: f64| {
        let a = q[0].lerp(q[1], u);
        let b = q[3].lerp(q[2], u);
        a.lerp(b, v)
    };
    let (u0, u1, v0, v1) = (
        i as f64 / 4.0,
        (i + 1) as f64 / 4.0,
        j as f64 / 4.0,
        (j + 1) as f64 / 4.0,
    );
    vec![at(u0, v0), at(u1, v0), at(u1, v1), at(u0, v1)]
}

/// A uniformly random point on the scene's non-light polygons (by area),
/// offset along the polygon's normal by `eps`, with that normal.
pub fn random_surface_point(scene: &Scene, rng: &mut Rng, eps: f64) -> (DVec3, DVec3) {
    let cum = &scene.area_cum;
    let total = *cum.last().unwrap_or(&0.0);
    let x = rng.next_f64() * total;
    let i = cum
        .partition_point(|&c| c <= x)
        .min(scene.polygons.len() - 1);
    let poly = &scene.polygons[i];
    let mut pts = Vec::new();
    stratified_points(poly, 1, rng, &mut pts);
    let n = newell_normal(poly).normalize();
    (pts[0] + n * eps, n)
}

/// The Cornell box from `root`'s config/ or shared/scenes/ (`root` is the
/// workspace root) (a minimal OBJ reader: `v`
/// and `f`, the light being the faces after `usemtl light`).
pub fn load_cornell_box(root: &Path) -> Scene {
    let candidates = [
        root.join("config/cornell_box.obj"),
        root.join("../shared/scenes/cornell_box.obj"),
        root.join("shared/scenes/cornell_box.obj"),
    ];
    let path = candidates
        .iter()
        .find(|p| p.exists())
        .expect("cornell_box.obj in config/ or ../shared/scenes/");
    let text = std::fs::read_to_string(path).expect("read cornell_box.obj");
    let mut vertices = Vec::new();
    let mut polygons = Vec::new();
    let mut light = None;
    let mut in_light = false;
    for line in text.lines() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.take(3).map(|x| x.parse().expect("number")).collect();
                vertices.push(DVec3::new(c[0], c[1], c[2]));
            }
            Some("usemtl") => in_light = it.next() == Some("light"),
            Some("f") => {
                let poly: Vec<DVec3> = it
                    .map(|tok| {
                        let i: i64 = tok.split('/').next().unwrap().parse().expect("index");
                        let i = if i < 0 {
                            vertices.len() as i64 + i
                        } else {
                            i - 1
                        };
                        vertices[i as usize]
                    })
                    .collect();
                if in_light {
                    light = Some(polygons.len());
                }
                polygons.push(poly);
            }
            _ => {}
        }
    }
    Scene::new(
        format!("Cornell box ({})", path.display()),
        polygons,
        light.expect("a light face"),
    )
}

/// The Cornell box with its floor replaced by a tessellated terrain (a height
/// field of 2 × 230² triangles) and a sphere (5,120 triangles) hanging under the
/// light: > 100k triangles, with shadows from all of them.
pub fn generated_scene(cornell: &Scene) -> Scene {
    let mut polygons = cornell.polygons.clone();
    let light = cornell.light;
    let g = 230;
    let (sx, sz) = (556.0, 559.2);
    let height = |x: f64, z: f64| {
        25.0 + 20.0 * (x / 37.0).sin() * (z / 41.0).cos() + 8.0 * (x * z / 9000.0).sin()
    };
    let at = |i: usize, j: usize| {
        let (x, z) = (sx * i as f64 / g as f64, sz * j as f64 / g as f64);
        DVec3::new(x, height(x, z), z)
    };
    for i in 0..g {
        for j in 0..g {
            // Counter-clockwise seen from above (+y).
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            polygons.push(vec![a, c, b]);
            polygons.push(vec![a, d, c]);
        }
    }
    // An icosphere (4 subdivisions) of radius 70 under the light.
    let centre = DVec3::new(278.0, 330.0, 280.0);
    for tri in icosphere(4) {
        polygons.push(tri.iter().map(|&v| centre + v * 70.0).collect());
    }
    Scene::new("generated: box + terrain + sphere".into(), polygons, light)
}

pub fn icosphere(subdivisions: u32) -> Vec<[DVec3; 3]> {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let v = [
        DVec3::new(-1.0, t, 0.0),
        DVec3::new(1.0, t, 0.0),
        DVec3::new(-1.0, -t, 0.0),
        DVec3::new(1.0, -t, 0.0),
        DVec3::new(0.0, -1.0, t),
        DVec3::new(0.0, 1.0, t),
        DVec3::new(0.0, -1.0, -t),
        DVec3::new(0.0, 1.0, -t),
        DVec3::new(t, 0.0, -1.0),
        DVec3::new(t, 0.0, 1.0),
        DVec3::new(-t, 0.0, -1.0),
        DVec3::new(-t, 0.0, 1.0),
    ]
    .map(|x| x.normalize());
    let faces = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    let mut tris: Vec<[DVec3; 3]> = faces.iter().map(|f| [v[f[0]], v[f[1]], v[f[2]]]).collect();
    for _ in 0..subdivisions {
        tris = tris
            .iter()
            .flat_map(|[a, b, c]| {
                let ab = ((*a + *b) * 0.5).normalize();
                let bc = ((*b + *c) * 0.5).normalize();
                let ca = ((*c + *a) * 0.5).normalize();
                [[*a, ab, ca], [*b, bc, ab], [*c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    tris
}

/// Prints the machine's CPU and SIMD support (the figures depend on both).
pub fn print_machine() {
    println!("CPU: {}", bench_support::host::cpu_model());
    println!(
        "AVX2+FMA: {}",
        cfg!(target_arch = "x86_64")
            && std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
    );
}

/// `--quick` and the `--only WORD` filters (repeatable; all must match a
/// "scene workload method" label).
pub fn parse_args() -> (bool, Vec<String>) {
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    let only = args
        .windows(2)
        .filter(|w| w[0] == "--only")
        .map(|w| w[1].clone())
        .collect();
    (quick, only)
}

/// The occluder and the two workloads of a scene, with the occluder's build time
/// printed.
pub fn prepare(scene: &Scene, quick: bool) -> (Occluder, [Workload; 2]) {
    let start = Instant::now();
    let occ = Occluder::new(&scene.polygons);
    let build = start.elapsed();
    println!();
    println!(
        "== {}: {} polygons, {} triangles; occluder build {:.1} ms",
        scene.name,
        scene.polygons.len(),
        occ.triangle_count(),
        build.as_secs_f64() * 1e3
    );
    let receivers = if quick { 500 } else { 4000 };
    let workloads = [
        light_workload(scene, &occ, receivers),
        patch_workload(scene, &occ, receivers),
    ];
    (occ, workloads)
}

/// Prints a workload's heading and returns the time budget per method.
pub fn begin_workload(w: &Workload, quick: bool) -> Duration {
    println!(
        "-- {} ({} receivers × {SAMPLES} = {} segments)",
        w.name,
        w.origins.len(),
        w.rays()
    );
    println!(
        "   {:<44} {:>10} {:>10} {:>10}",
        "method", "M rays/s", "mean, CPU", "visible"
    );
    if quick {
        Duration::from_millis(200)
    } else {
        Duration::from_millis(1500)
    }
}
