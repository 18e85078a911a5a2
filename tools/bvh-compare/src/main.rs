//! The solver's visibility workload (`solver/benches/common/workload.rs`) traced
//! by the project's own BVH and by third-party ones, one thread:
//!
//!     cargo run --release --manifest-path tools/bvh-compare/Cargo.toml [-- --quick]
//!     cargo run --release --manifest-path tools/bvh-compare/Cargo.toml --features embree
//!
//! obvhs 0.4 (CWBVH, single rays) is on by default; Embree 3 (`rtcOccluded1` and
//! `rtcOccluded16`) needs `--features embree` and Debian's libembree-dev. This crate
//! is outside the root workspace (its own `[workspace]` table and lock file), so
//! none of these dependencies enter the project's build or its Cargo.lock. Every
//! method traces exactly the same segments; the visible counts are printed so that
//! they can be compared (f32 methods may differ on rays grazing an edge).
//!
//! A developer's benchmark on the bundled scenes, never run on a user's file: a
//! failing Embree call (no device, no memory) ends it with `expect`'s message.

#[path = "../../../solver/benches/common/workload.rs"]
mod workload;

use glam::DVec3;
use std::path::Path;
use workload::Scene;

fn main() {
    workload::print_machine();
    let (quick, only) = workload::parse_args();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let cornell = workload::load_cornell_box(&root);
    let big = workload::generated_scene(&cornell);
    for scene in [&cornell, &big] {
        run_scene(scene, quick, &only);
    }
}

fn run_scene(scene: &Scene, quick: bool, only: &[String]) {
    let (occ, workloads) = workload::prepare(scene, quick);
    #[cfg(feature = "obvhs")]
    let obvhs = obvhs_cmp::Obvhs::new(&scene.polygons);
    #[cfg(feature = "embree")]
    let embree_device = embree3::Device::new().expect("embree device");
    #[cfg(feature = "embree")]
    let embree = embree_cmp::Embree::new(&embree_device, &scene.polygons);
    #[cfg(any(feature = "obvhs", feature = "embree"))]
    let eps = occ.scene_epsilon();
    for w in &workloads {
        let budget = workload::begin_workload(w, quick);
        let report = |name: &str, count: &dyn Fn(DVec3, &[DVec3]) -> u32| {
            let label = format!("{} {} {}", scene.name, w.name, name);
            if only.iter().all(|o| label.contains(o.as_str())) {
                workload::report(w, budget, name, count);
            }
        };
        // The baseline: the project's own BVH on the same segments.
        report("own BVH4, packets of 64 (count_visible)", &|o, t| {
            occ.count_visible(o, t)
        });
        report("own BVH4, packets of 16", &|o, t| {
            t.chunks(16).map(|c| occ.count_visible(o, c)).sum()
        });
        report("own BVH4, single rays (visible)", &|o, t| {
            t.iter().filter(|&&x| occ.visible(o, x)).count() as u32
        });
        #[cfg(feature = "obvhs")]
        {
            println!("   (obvhs build {:.1} ms)", obvhs.build_ms);
            report("obvhs 0.4 CWBVH, single rays", &|o, t| {
                obvhs.count_visible(o, t, eps)
            });
        }
        #[cfg(feature = "embree")]
        {
            println!("   (embree build {:.1} ms)", embree.build_ms);
            report("Embree 3 rtcOccluded1, single rays", &|o, t| {
                embree.count_visible_1(o, t, eps)
            });
            report("Embree 3 rtcOccluded16, packets of 16", &|o, t| {
                embree.count_visible_16(o, t, eps)
            });
        }
    }
}

#[cfg(any(feature = "obvhs", feature = "embree"))]
/// Segment parameters shared by the comparisons: origin and direction relative
/// to `centre` in f32, and the window excluding `eps` at both ends.
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

#[cfg(any(feature = "obvhs", feature = "embree"))]
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

#[cfg(feature = "obvhs")]
mod obvhs_cmp {
    use super::*;
    use glam034::Vec3A;
    use obvhs::cwbvh::CwBvh;
    use obvhs::ray::Ray;
    use obvhs::triangle::Triangle;
    use std::time::{Duration, Instant};

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

#[cfg(feature = "embree")]
mod embree_cmp {
    use super::*;
    use embree3::{
        BufferUsage, Device, Format, GeometryKind, IntersectContext, Ray, Ray16, Scene as EScene,
        ValidMask, ValidMaskN,
    };
    use std::time::Instant;

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
