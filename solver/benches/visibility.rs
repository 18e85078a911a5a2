//! Visibility throughput of the occluder against alternatives, one thread.
//!
//!     cargo bench -p solver --bench visibility
//!     cargo bench -p solver --bench visibility --features compare-obvhs,compare-embree
//!
//! Workload (the solver's): receiving points on the scene's surfaces, each
//! offset off its surface by the scene epsilon, each casting 64 segments to
//! stratified, jittered samples of a source polygon. Two sources: the Cornell
//! box light (narrow, coherent packets) and random wall/floor patches that the
//! receiver faces (wide packets, as when a reflector shoots). Two scenes: the
//! Cornell box (32 triangles) and a generated one of > 100k triangles (the box
//! with a tessellated terrain floor and a sphere). Every method traces exactly
//! the same segments; the visible counts are printed so that they can be
//! compared (f32 methods may differ on rays grazing an edge).
//!
//! Figures are M segments per second on one core: the best of several passes
//! by wall time (the machine is shared, so the best pass is the least
//! disturbed one), and the mean over all passes by the thread's CPU time
//! (steadier when the load average exceeds the core count).

use glam::DVec3;
use solver::geometry::polygon::newell_normal;
use solver::geometry::sampling::{stratified_points, Rng};
use solver::geometry::visibility::Occluder;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::{Duration, Instant};

const SAMPLES: usize = 64;

/// A scene: polygons, the index of the light polygon, and the cumulative
/// areas of the non-light polygons (to pick surface points by area).
struct Scene {
    name: String,
    polygons: Vec<Vec<DVec3>>,
    light: usize,
    area_cum: Vec<f64>,
}

impl Scene {
    fn new(name: String, polygons: Vec<Vec<DVec3>>, light: usize) -> Scene {
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
struct Workload {
    name: &'static str,
    origins: Vec<DVec3>,
    targets: Vec<DVec3>,
}

impl Workload {
    fn rays(&self) -> usize {
        self.targets.len()
    }
}

fn main() {
    println!("CPU: {}", cpu_model());
    println!(
        "AVX2+FMA: {}",
        cfg!(target_arch = "x86_64")
            && std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
    );
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    // `--only WORD`: run only the methods, scenes and workloads whose names
    // contain WORD (repeatable; all must match), e.g. for profiling.
    let only: Vec<String> = args
        .windows(2)
        .filter(|w| w[0] == "--only")
        .map(|w| w[1].clone())
        .collect();
    let cornell = load_cornell_box();
    let big = generated_scene(&cornell);
    for scene in [&cornell, &big] {
        run_scene(scene, quick, &only);
    }
}

fn run_scene(scene: &Scene, quick: bool, only: &[String]) {
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
    #[cfg(feature = "compare-obvhs")]
    let obvhs = obvhs_cmp::Obvhs::new(&scene.polygons);
    #[cfg(feature = "compare-embree")]
    let embree_device = embree3::Device::new().expect("embree device");
    #[cfg(feature = "compare-embree")]
    let embree = embree_cmp::Embree::new(&embree_device, &scene.polygons);
    for w in &workloads {
        let report =
            |w: &Workload, budget: Duration, name: &str, count: &dyn Fn(DVec3, &[DVec3]) -> u32| {
                let label = format!("{} {} {}", scene.name, w.name, name);
                if only.iter().all(|o| label.contains(o.as_str())) {
                    report(w, budget, name, count);
                }
            };
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
        let budget = if quick {
            Duration::from_millis(200)
        } else {
            Duration::from_millis(1500)
        };
        report(
            w,
            budget,
            "own BVH4, packets of 64 (count_visible)",
            &|o, t| occ.count_visible(o, t),
        );
        // The solver's medium and draft presets trace 16 and 4 samples per
        // receiver: the same segments as smaller packets, for comparison with
        // Embree's packets of 16 on equal terms.
        report(w, budget, "own BVH4, packets of 16", &|o, t| {
            t.chunks(16).map(|c| occ.count_visible(o, c)).sum()
        });
        report(w, budget, "own BVH4, packets of 4", &|o, t| {
            t.chunks(4).map(|c| occ.count_visible(o, c)).sum()
        });
        report(w, budget, "own BVH4, single rays (visible)", &|o, t| {
            t.iter().filter(|&&x| occ.visible(o, x)).count() as u32
        });
        #[cfg(feature = "compare-obvhs")]
        {
            println!("   (obvhs build {:.1} ms)", obvhs.build_ms);
            let eps = occ.scene_epsilon();
            report(w, budget, "obvhs 0.4 CWBVH, single rays", &|o, t| {
                obvhs.count_visible(o, t, eps)
            });
        }
        #[cfg(feature = "compare-embree")]
        {
            println!("   (embree build {:.1} ms)", embree.build_ms);
            let eps = occ.scene_epsilon();
            report(w, budget, "Embree 3 rtcOccluded1, single rays", &|o, t| {
                embree.count_visible_1(o, t, eps)
            });
            report(
                w,
                budget,
                "Embree 3 rtcOccluded16, packets of 16",
                &|o, t| embree.count_visible_16(o, t, eps),
            );
        }
    }
}

/// Runs `count` over the workload repeatedly for about `budget` and prints the
/// best pass's rate and the number of visible segments.
fn report(w: &Workload, budget: Duration, name: &str, count: &dyn Fn(DVec3, &[DVec3]) -> u32) {
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
fn thread_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// Receivers on every polygon but the light (area-weighted), offset off their
/// surface, facing the light and in front of it; 64 samples of the light each.
fn light_workload(scene: &Scene, occ: &Occluder, receivers: usize) -> Workload {
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
fn patch_workload(scene: &Scene, occ: &Occluder, receivers: usize) -> Workload {
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
fn sub_patch(q: &[DVec3], i: usize, j: usize) -> Vec<DVec3> {
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
fn random_surface_point(scene: &Scene, rng: &mut Rng, eps: f64) -> (DVec3, DVec3) {
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

/// The Cornell box from config/ or shared/scenes/ (a minimal OBJ reader: `v`
/// and `f`, the light being the faces after `usemtl light`).
fn load_cornell_box() -> Scene {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
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
fn generated_scene(cornell: &Scene) -> Scene {
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

fn icosphere(subdivisions: u32) -> Vec<[DVec3; 3]> {
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

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

/// Segment parameters shared by the comparisons: origin and direction relative
/// to `centre` in f32, and the window excluding `eps` at both ends.
#[cfg(any(feature = "compare-obvhs", feature = "compare-embree"))]
fn segment(centre: DVec3, o: DVec3, t: DVec3, eps: f64) -> ([f32; 3], [f32; 3], f32, f32) {
    let d = t - o;
    let len = d.length();
    let te = eps / len;
    let oc = o - centre;
    (
        [oc.x as f32, oc.y as f32, oc.z as f32],
        [d.x as f32, d.y as f32, d.z as f32],
        te as f32,
        (1.0 - te) as f32,
    )
}

#[cfg(any(feature = "compare-obvhs", feature = "compare-embree"))]
fn triangles_relative(polygons: &[Vec<DVec3>]) -> (DVec3, Vec<[[f32; 3]; 3]>) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in polygons {
        for &v in p {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let centre = (lo + hi) * 0.5;
    let mut out = Vec::new();
    let mut tris = Vec::new();
    for p in polygons {
        tris.clear();
        solver::geometry::polygon::triangulate(p, &mut tris);
        for t in &tris {
            out.push(t.map(|i| {
                let v = p[i] - centre;
                [v.x as f32, v.y as f32, v.z as f32]
            }));
        }
    }
    (centre, out)
}

#[cfg(feature = "compare-obvhs")]
mod obvhs_cmp {
    use super::*;
    use glam034::Vec3A;
    use obvhs::cwbvh::CwBvh;
    use obvhs::ray::Ray;
    use obvhs::triangle::Triangle;

    pub struct Obvhs {
        centre: DVec3,
        bvh: CwBvh,
        tris: Vec<Triangle>,
        pub build_ms: f64,
    }

    impl Obvhs {
        pub fn new(polygons: &[Vec<DVec3>]) -> Self {
            let (centre, raw) = triangles_relative(polygons);
            let tris: Vec<Triangle> = raw
                .iter()
                .map(|t| Triangle {
                    v0: Vec3A::from_array(t[0]),
                    v1: Vec3A::from_array(t[1]),
                    v2: Vec3A::from_array(t[2]),
                })
                .collect();
            let start = Instant::now();
            let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
                &tris,
                obvhs::BvhBuildParams::medium_build(),
                &mut Duration::default(),
            );
            let build_ms = start.elapsed().as_secs_f64() * 1e3;
            Obvhs {
                centre,
                bvh,
                tris,
                build_ms,
            }
        }

        pub fn count_visible(&self, o: DVec3, targets: &[DVec3], eps: f64) -> u32 {
            let mut n = 0;
            for &t in targets {
                let (org, dir, t0, t1) = segment(self.centre, o, t, eps);
                let ray = Ray::new(Vec3A::from_array(org), Vec3A::from_array(dir), t0, t1);
                let miss = self.bvh.ray_traverse_miss(ray, |ray, id| {
                    self.tris[self.bvh.primitive_indices[id] as usize].intersect(ray)
                });
                n += miss as u32;
            }
            n
        }
    }
}

#[cfg(feature = "compare-embree")]
mod embree_cmp {
    use super::*;
    use embree3::{
        BufferUsage, Device, Format, GeometryKind, IntersectContext, Ray, Ray16, Scene as EScene,
        ValidMask, ValidMaskN,
    };

    pub struct Embree<'a> {
        centre: DVec3,
        scene: EScene<'a>,
        pub build_ms: f64,
    }

    impl<'a> Embree<'a> {
        pub fn new(device: &'a Device, polygons: &[Vec<DVec3>]) -> Self {
            let (centre, raw) = triangles_relative(polygons);
            let start = Instant::now();
            let mut geom = device
                .create_geometry(GeometryKind::TRIANGLE)
                .expect("geometry");
            geom.set_new_buffer::<[f32; 3]>(
                BufferUsage::VERTEX,
                0,
                Format::FLOAT3,
                12,
                raw.len() * 3,
            )
            .expect("vertex buffer")
            .copy_from_slice(&raw.iter().flatten().copied().collect::<Vec<_>>());
            let indices: Vec<[u32; 3]> = (0..raw.len() as u32)
                .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
                .collect();
            geom.set_new_buffer::<[u32; 3]>(BufferUsage::INDEX, 0, Format::UINT3, 12, raw.len())
                .expect("index buffer")
                .copy_from_slice(&indices);
            let geom = geom.commit();
            let mut scene = device.create_scene().expect("scene");
            scene.attach_geometry(&geom);
            scene.commit();
            let build_ms = start.elapsed().as_secs_f64() * 1e3;
            Embree {
                centre,
                scene,
                build_ms,
            }
        }

        pub fn count_visible_1(&self, o: DVec3, targets: &[DVec3], eps: f64) -> u32 {
            let mut ctx = IntersectContext::coherent();
            let mut n = 0;
            for &t in targets {
                let (org, dir, t0, t1) = segment(self.centre, o, t, eps);
                let mut ray = Ray::segment(org, dir, t0, t1);
                n += (!self.scene.occluded(&mut ctx, &mut ray)) as u32;
            }
            n
        }

        pub fn count_visible_16(&self, o: DVec3, targets: &[DVec3], eps: f64) -> u32 {
            let mut ctx = IntersectContext::coherent();
            let mut n = 0;
            for chunk in targets.chunks(16) {
                let mut orgs = [[0.0f32; 3]; 16];
                let mut dirs = [[0.0f32; 3]; 16];
                let mut t0s = [0.0f32; 16];
                let mut t1s = [0.0f32; 16];
                let mut valid = ValidMaskN::<16>::all_active();
                for i in 0..16 {
                    if let Some(&t) = chunk.get(i) {
                        let (org, dir, t0, t1) = segment(self.centre, o, t, eps);
                        orgs[i] = org;
                        dirs[i] = dir;
                        t0s[i] = t0;
                        t1s[i] = t1;
                    } else {
                        valid.lanes_mut()[i] = ValidMask::Invalid;
                    }
                }
                let mut ray = Ray16::segment(orgs, dirs, t0s, t1s);
                self.scene.occluded16(&mut ctx, &mut ray, &valid);
                n += (0..chunk.len())
                    .filter(|&i| ray.tfar[i] != f32::NEG_INFINITY)
                    .count() as u32;
            }
            n
        }
    }
}
