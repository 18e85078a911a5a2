//! Shared helpers of the runtime's GPU tests: the Vulkan device (lavapipe unless
//! the caller chose another ICD), synthetic solutions with known coefficients,
//! and image comparison with failure artefacts.
#![allow(dead_code)]

use glam::DVec3;
use runtime::gpu::{Gpu, GpuDesc};
use solution::camera::{Camera, UpAxis};
use solution::format::{Batch, Header, Representation, ScalarType, Solution, SolveMode, Vertex};
use std::path::PathBuf;
use std::sync::Once;

/// Points the Vulkan loader at lavapipe when the caller did not choose an ICD
/// (scripts/test.sh exports the same), so tests behave alike on every machine.
pub fn use_lavapipe_unless_chosen() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        if std::env::var_os("VK_ICD_FILENAMES").is_none()
            && std::env::var_os("VK_DRIVER_FILES").is_none()
        {
            for dir in ["/usr/share/vulkan/icd.d", "/etc/vulkan/icd.d"] {
                if let Ok(entries) = std::fs::read_dir(dir) {
                    let mut found: Vec<PathBuf> = entries
                        .flatten()
                        .map(|e| e.path())
                        .filter(|p| {
                            p.file_name()
                                .and_then(|n| n.to_str())
                                .is_some_and(|n| n.starts_with("lvp_icd"))
                        })
                        .collect();
                    found.sort();
                    if let Some(icd) = found.first() {
                        // Set before any test thread loads Vulkan (inside Once).
                        std::env::set_var("VK_ICD_FILENAMES", icd);
                        return;
                    }
                }
            }
        }
    });
}

/// The GPU, with validation on. A missing device fails the test with the
/// message that names the Debian packages (never a skip).
pub fn gpu() -> Gpu {
    use_lavapipe_unless_chosen();
    match Gpu::new(&GpuDesc { validation: true }) {
        Ok(gpu) => gpu,
        Err(e) => panic!("no Vulkan device for the GPU tests: {e}"),
    }
}

/// Asserts the validation layer said nothing.
pub fn assert_validation_clean(gpu: &Gpu) {
    assert!(gpu.validation_enabled(), "validation layer not active");
    let log = gpu.validation_log();
    assert_eq!(
        log.count(),
        0,
        "validation messages:\n{}",
        log.messages().join("\n")
    );
}

pub fn header(bounds_min: [f32; 3], bounds_max: [f32; 3], camera: Camera) -> Header {
    Header {
        units_per_metre: 1.0,
        up_axis: UpAxis::PosY,
        recentre_offset: [0.0; 3],
        camera,
        bounds_min,
        bounds_max,
        partial: false,
        mode: SolveMode::Diffuse,
        stats: Default::default(),
        settings_json: String::new(),
    }
}

/// A planar rectangle `corner + u·s + v·t` (s, t in 0..1) subdivided `n × n`,
/// counter-clockwise seen from `normal = normalize(u × v)`, tangent `u`.
pub struct Quad {
    pub corner: DVec3,
    pub u: DVec3,
    pub v: DVec3,
    pub n: usize,
}

impl Quad {
    pub fn vertices_and_indices(&self) -> (Vec<Vertex>, Vec<u32>) {
        let normal = self.u.cross(self.v).normalize();
        let tangent = self.u.normalize();
        let mut vertices = Vec::new();
        for j in 0..=self.n {
            for i in 0..=self.n {
                let p = self.corner
                    + self.u * (i as f64 / self.n as f64)
                    + self.v * (j as f64 / self.n as f64);
                vertices.push(Vertex {
                    position: p.as_vec3().to_array(),
                    normal: normal.as_vec3().to_array(),
                    tangent: tangent.as_vec3().to_array(),
                });
            }
        }
        let row = self.n as u32 + 1;
        let mut indices = Vec::new();
        for j in 0..self.n as u32 {
            for i in 0..self.n as u32 {
                let a = j * row + i;
                indices.extend_from_slice(&[a, a + 1, a + row + 1, a, a + row + 1, a + row]);
            }
        }
        (vertices, indices)
    }
}

/// Diffuse radiance of the test room at a point: smooth and different per
/// channel, so interpolation and channel order both matter.
pub fn diffuse_radiance(p: DVec3) -> [f64; 3] {
    [
        0.6 + 0.3 * (0.7 * p.x).sin(),
        0.5 + 0.2 * (0.5 * p.z).cos(),
        0.3 + 0.1 * p.y,
    ]
}

/// The test room, in file coordinates: floor y = 0 over x, z ∈ [−4, 4], a back
/// wall at z = −4 and side walls at x = ±4 (height 3), all facing inward.
pub fn room_quads(n: usize) -> Vec<Quad> {
    vec![
        // Floor: normal +y = u × v with u = +x, v = −z.
        Quad {
            corner: DVec3::new(-4.0, 0.0, 4.0),
            u: DVec3::new(8.0, 0.0, 0.0),
            v: DVec3::new(0.0, 0.0, -8.0),
            n,
        },
        // Back wall: normal +z.
        Quad {
            corner: DVec3::new(-4.0, 0.0, -4.0),
            u: DVec3::new(8.0, 0.0, 0.0),
            v: DVec3::new(0.0, 3.0, 0.0),
            n,
        },
        // Left wall x = −4: normal +x = u × v with u = −z... (0,0,−8)×(0,3,0) = (24,0,0).
        Quad {
            corner: DVec3::new(-4.0, 0.0, 4.0),
            u: DVec3::new(0.0, 0.0, -8.0),
            v: DVec3::new(0.0, 3.0, 0.0),
            n,
        },
        // Right wall x = +4: normal −x: (0,0,8)×(0,3,0) = (−24,0,0).
        Quad {
            corner: DVec3::new(4.0, 0.0, -4.0),
            u: DVec3::new(0.0, 0.0, 8.0),
            v: DVec3::new(0.0, 3.0, 0.0),
            n,
        },
    ]
}

pub const ROOM_MIN: [f32; 3] = [-4.0, 0.0, -4.0];
pub const ROOM_MAX: [f32; 3] = [4.0, 3.0, 4.0];

/// A camera inside the room whose view crosses the image edges, and whose floor
/// passes under the eye, through the near plane.
pub fn room_camera(width: u32, height: u32) -> Camera {
    Camera {
        eye: [0.3, 1.2, 2.5],
        target: [-0.4, 0.6, -2.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 70.0,
        width,
        height,
    }
}

/// A diffuse (L = 0) room: c00 = radiance / Y00 per vertex.
pub fn diffuse_room(n: usize) -> Solution {
    let mut batch = Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertices: Vec::new(),
        coefficients: Vec::new(),
        indices: Vec::new(),
        texturing: None,
    };
    for quad in room_quads(n) {
        let (vertices, indices) = quad.vertices_and_indices();
        let base = batch.vertices.len() as u32;
        for v in &vertices {
            let l = diffuse_radiance(DVec3::from(v.position.map(f64::from)));
            batch
                .coefficients
                .extend(l.iter().map(|x| (x / solution::sh::Y00) as f32));
        }
        batch.vertices.extend(vertices);
        batch.indices.extend(indices.iter().map(|i| i + base));
    }
    Solution {
        lighting: None,
        header: header(ROOM_MIN, ROOM_MAX, room_camera(256, 256)),
        batches: vec![batch],
        textures: Vec::new(),
    }
}

/// The light the glossy floor reflects.
pub const LIGHT: DVec3 = DVec3::new(0.0, 2.8, -3.0);

/// A glossy floor of order `order` (a lobe about the mirror direction of
/// [`LIGHT`] at each vertex, from the exact Legendre expansion of a Phong-like
/// lobe), plus the diffuse walls as a second batch.
pub fn glossy_room(n: usize, order: u32) -> Solution {
    let quads = room_quads(n);
    let mut floor = Batch {
        representation: Representation::Sh { order },
        scalar: ScalarType::F32,
        vertices: Vec::new(),
        coefficients: Vec::new(),
        indices: Vec::new(),
        texturing: None,
    };
    let (vertices, indices) = quads[0].vertices_and_indices();
    let zonal = lobe_zonal(order);
    let count = solution::sh::coefficient_count(order);
    let mut rotated = vec![0.0; count];
    for v in &vertices {
        let pos = DVec3::from(v.position.map(f64::from));
        let to_light = (LIGHT - pos).normalize();
        // Mirror direction in the floor's frame (n = +y, t = +x, b = n × t = −z).
        let (nrm, tan) = (DVec3::Y, DVec3::X);
        let r = 2.0 * to_light.dot(nrm) * nrm - to_light;
        let local = solution::sh::to_local(r, nrm, tan);
        solution::sh::zonal_rotated(order, &zonal, local, &mut rotated);
        let base = diffuse_radiance(pos);
        for (k, lobe) in rotated.iter().enumerate() {
            for b in base {
                let diffuse = if k == 0 {
                    0.3 * b / solution::sh::Y00
                } else {
                    0.0
                };
                floor.coefficients.push((diffuse + 2.0 * lobe) as f32);
            }
        }
    }
    floor.vertices = vertices;
    floor.indices = indices;
    let mut walls = diffuse_room(n);
    // Drop the diffuse floor (the first quad's vertices and triangles).
    let floor_vertices = (n + 1) * (n + 1);
    let floor_triangles = 6 * n * n;
    let w = &mut walls.batches[0];
    w.vertices.drain(..floor_vertices);
    w.coefficients.drain(..floor_vertices * 3);
    w.indices.drain(..floor_triangles);
    for i in &mut w.indices {
        *i -= floor_vertices as u32;
    }
    let mut solution = walls;
    solution.header.mode = SolveMode::Directional;
    solution.batches.push(floor);
    solution
}

/// Writes actual/expected/difference images into a temp folder and returns its
/// path (for failure messages).
/// The test room of `common` with its floor as a global-cube batch: each vertex
/// holds, in every cell direction ω (local frame), 0.3 × the room's diffuse
/// radiance plus a lobe 2·max(0, ω·r)^12 about the mirror direction r of
/// `LIGHT` — the same floor as `glossy_room`, but sampled on the
/// cube's directions instead of expanded in SH. The walls stay one L = 0 batch.
pub fn cube_room(n: usize, resolution: u32) -> Solution {
    let quads = room_quads(n);
    let (vertices, indices) = quads[0].vertices_and_indices();
    let directions = 6 * resolution * resolution;
    let cells: Vec<DVec3> = (0..directions)
        .map(|d| solution::cube::cell_direction(resolution, d))
        .collect();
    let mut coefficients = Vec::with_capacity(vertices.len() * cells.len() * 3);
    for v in &vertices {
        let pos = DVec3::from(v.position.map(f64::from));
        let to_light = (LIGHT - pos).normalize();
        // The floor's frame: n = +y, t = +x (Quad), so b = n × t = −z.
        let (nrm, tan) = (DVec3::Y, DVec3::X);
        let r = 2.0 * to_light.dot(nrm) * nrm - to_light;
        let local_r = solution::sh::to_local(r, nrm, tan);
        let base = diffuse_radiance(pos);
        for cell in &cells {
            let lobe = 2.0 * cell.dot(local_r).max(0.0).powi(12);
            for b in base {
                coefficients.push((0.3 * b + lobe) as f32);
            }
        }
    }
    let floor = Batch {
        representation: Representation::Cube { directions },
        scalar: ScalarType::F32,
        vertices,
        coefficients,
        indices,
        texturing: None,
    };
    // The walls: the diffuse room without its floor (the first quad).
    let mut walls = diffuse_room(n);
    let floor_vertices = (n + 1) * (n + 1);
    let w = &mut walls.batches[0];
    w.vertices.drain(..floor_vertices);
    w.coefficients.drain(..floor_vertices * 3);
    w.indices.drain(..6 * n * n);
    for i in &mut w.indices {
        *i -= floor_vertices as u32;
    }
    let mut solution = walls;
    solution.header.mode = SolveMode::Directional;
    // The cube batch first in the file: the renderer reorders draws (L = 0
    // pipeline, then cubes), which must not change the picture.
    solution.batches.insert(0, floor);
    solution
}

/// A GPU eye image as a CPU raster image, for `raster::compare`.
pub fn as_raster(eye: &runtime::render::EyeImage) -> solution::raster::Image {
    let mut image = solution::raster::Image::new(eye.width, eye.height);
    for (px, rgb) in image.pixels.iter_mut().zip(eye.radiance.chunks_exact(3)) {
        *px = [rgb[0], rgb[1], rgb[2]];
    }
    image
}

/// Tolerances of a GPU image against the CPU reference, relative to the
/// reference's mean radiance as `raster::compare` reports them.
#[derive(Clone, Copy, Debug)]
pub struct Tolerances {
    pub mean: f64,
    pub p99: f64,
    /// Fraction of pixels allowed above `raster::DEFAULT_DIFF_THRESHOLD`.
    pub fraction: f64,
}

/// Compares one GPU eye with the CPU reference of `solution` seen through
/// `view`; on failure writes actual/expected/difference images and panics
/// naming their folder.
pub fn assert_matches_cpu_reference(
    name: &str,
    solution: &Solution,
    view: &solution::camera::EyeView,
    eye: &runtime::render::EyeImage,
    tol: Tolerances,
) {
    use solution::raster;
    let expected = raster::render(solution, view, &raster::RenderOptions::default()).unwrap();
    let actual = as_raster(eye);
    let diff = raster::compare(&expected, &actual).unwrap();
    if !(diff.mean_abs <= tol.mean
        && diff.p99_abs <= tol.p99
        && diff.differing_fraction <= tol.fraction)
    {
        let flat = |img: &raster::Image| img.pixels.iter().flatten().copied().collect::<Vec<f32>>();
        let dir = write_failure_images(
            name,
            eye.width,
            eye.height,
            &flat(&actual),
            &flat(&expected),
        );
        panic!(
            "{name} differs from the CPU reference: {diff:?} (tolerances: {tol:?}); images in {}",
            dir.display()
        );
    }
    eprintln!("{name}: {diff:?}");
}

/// Centroid (framebuffer coordinates) of pixels whose red channel exceeds
/// `threshold`.
pub fn centroid(eye: &runtime::render::EyeImage, threshold: f32) -> glam::DVec2 {
    let mut sum = glam::DVec2::ZERO;
    let mut count = 0.0;
    for j in 0..eye.height {
        for i in 0..eye.width {
            let r = eye.radiance[((j * eye.width + i) * 3) as usize];
            if r > threshold {
                sum += glam::DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
                count += 1.0;
            }
        }
    }
    assert!(count > 0.0, "no pixel above {threshold}");
    sum / count
}

pub fn write_failure_images(
    name: &str,
    width: u32,
    height: u32,
    actual: &[f32],
    expected: &[f32],
) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("runtime-test-{name}-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let save = |file: &str, data: &[f32], gain: f32| {
        let mut img = image::RgbImage::new(width, height);
        for (i, px) in img.pixels_mut().enumerate() {
            for c in 0..3 {
                let v = data[i * 3 + c] * gain;
                px.0[c] = (runtime::render::tonemap::srgb_encode(v) * 255.0).round() as u8;
            }
        }
        let _ = img.save(dir.join(file));
    };
    let diff: Vec<f32> = actual
        .iter()
        .zip(expected)
        .map(|(a, e)| (a - e).abs())
        .collect();
    save("actual.png", actual, 1.0);
    save("expected.png", expected, 1.0);
    save("difference-x10.png", &diff, 10.0);
    dir
}

/// `solution` with every batch stored on disk as `storage`: f32, or IEEE half
/// with the writer's per-batch power-of-two scale
/// (`solution::format::f16_scale_for`). In memory the values stay f32; the
/// writer rounds them to half.
pub fn stored_as(solution: &Solution, storage: runtime::render::CoefficientStorage) -> Solution {
    let mut stored = solution.clone();
    for batch in &mut stored.batches {
        batch.scalar = match storage {
            runtime::render::CoefficientStorage::F32 => ScalarType::F32,
            runtime::render::CoefficientStorage::F16 => ScalarType::F16 {
                scale: solution::format::f16_scale_for(&batch.coefficients),
            },
        };
    }
    stored
}

/// Writes `solution` to a file in a new temporary folder (kept alive by the
/// returned guard) and maps it with every check, checksums included.
pub fn mapped(solution: &Solution) -> (tempfile::TempDir, solution::format::MappedSolution) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.sol");
    solution::format::write_solution(&path, solution).unwrap();
    let file = solution::format::MappedSolution::open(&path).unwrap();
    (dir, file)
}

/// The SH coefficients (per channel, index l² + l + m) of the zonal lobe
/// g(μ) = μ¹² for μ > 0, by Gauss–Legendre quadrature of its Legendre
/// expansion: the glossy lobe of [`glossy_room`] and [`city`].
fn lobe_zonal(order: u32) -> Vec<f64> {
    let (mu, w) = solution::sh::gauss_legendre(64);
    let mut legendre = vec![0.0; order as usize + 1];
    let mut p = vec![0.0; order as usize + 1];
    for (x, wx) in mu.iter().zip(&w) {
        let g = if *x > 0.0 { x.powf(12.0) } else { 0.0 };
        solution::sh::legendre_all(order, *x, &mut p);
        for l in 0..=order as usize {
            legendre[l] += (2 * l + 1) as f64 / 2.0 * g * p[l] * wx;
        }
    }
    solution::sh::zonal_from_legendre(&legendre)
}

/// A synthetic city for the runtime at scale (docs/benchmarks.md, "Runtime at
/// scale"): `n × n` box buildings (four walls and a roof, each face `m × m`
/// cells, so 10·m² triangles and 5·(m + 1)² vertices per building) on a 10 m
/// grid with 4 m streets, heights 5–25 m from a hash of the block, standing on
/// a glossy ground of order 3 (`4n × 4n` cells). Every fourth building is glossy
/// at order 2 (its own batch); the rest are diffuse (order 0). Radiance is the
/// smooth [`diffuse_radiance`] plus, on glossy surfaces, the lobe of
/// [`glossy_room`] about the mirror direction of a sun 500 m up. The header
/// camera stands in a street at eye height near the city's centre, looking
/// down the street: most of the city is behind or beside it.
pub fn city(n: usize, m: usize) -> Solution {
    let half = 5.0 * n as f64;
    let sun = DVec3::new(0.3 * half, 500.0, 0.2 * half);
    let batch = |order| Batch {
        representation: Representation::Sh { order },
        scalar: ScalarType::F32,
        vertices: Vec::new(),
        coefficients: Vec::new(),
        indices: Vec::new(),
        texturing: None,
    };
    let (mut diffuse, mut glossy, mut ground) = (batch(0), batch(2), batch(3));
    let zonal = [(2, lobe_zonal(2)), (3, lobe_zonal(3))];
    let add = |target: &mut Batch, quad: Quad| {
        let (vertices, indices) = quad.vertices_and_indices();
        let base = target.vertices.len() as u32;
        let Representation::Sh { order } = target.representation else {
            unreachable!("the city's batches are SH")
        };
        let count = solution::sh::coefficient_count(order);
        let mut rotated = vec![0.0; count];
        for v in &vertices {
            let pos = DVec3::from(v.position.map(f64::from));
            let base_radiance = diffuse_radiance(pos * 0.1);
            if order == 0 {
                target
                    .coefficients
                    .extend(base_radiance.iter().map(|x| (x / solution::sh::Y00) as f32));
                continue;
            }
            let nrm = DVec3::from(v.normal.map(f64::from));
            let tan = DVec3::from(v.tangent.map(f64::from));
            let to_sun = (sun - pos).normalize();
            let r = 2.0 * to_sun.dot(nrm) * nrm - to_sun;
            let lobe = &zonal.iter().find(|(o, _)| *o == order).expect("lobe").1;
            solution::sh::zonal_rotated(
                order,
                lobe,
                solution::sh::to_local(r, nrm, tan),
                &mut rotated,
            );
            for (k, l) in rotated.iter().enumerate() {
                for b in base_radiance {
                    let d = if k == 0 {
                        0.3 * b / solution::sh::Y00
                    } else {
                        0.0
                    };
                    target.coefficients.push((d + 2.0 * l) as f32);
                }
            }
        }
        target.vertices.extend(vertices);
        target.indices.extend(indices.iter().map(|i| i + base));
    };
    add(
        &mut ground,
        Quad {
            corner: DVec3::new(-half, 0.0, half),
            u: DVec3::new(2.0 * half, 0.0, 0.0),
            v: DVec3::new(0.0, 0.0, -2.0 * half),
            n: 4 * n,
        },
    );
    for i in 0..n {
        for j in 0..n {
            let hash = ((i as f64 * 12.9898 + j as f64 * 78.233).sin() * 43758.5453)
                .fract()
                .abs();
            let h = 5.0 + 20.0 * hash;
            let (x0, z0) = (-half + 10.0 * i as f64 + 2.0, -half + 10.0 * j as f64 + 2.0);
            let (x1, z1) = (x0 + 6.0, z0 + 6.0);
            let (dx, dz) = (x1 - x0, z1 - z0);
            let target = if (i + 2 * j) % 4 == 0 {
                &mut glossy
            } else {
                &mut diffuse
            };
            // Outward normals u × v: roof +y, walls ±z and ±x.
            for (corner, u, v) in [
                (
                    DVec3::new(x0, h, z1),
                    DVec3::new(dx, 0.0, 0.0),
                    DVec3::new(0.0, 0.0, -dz),
                ),
                (
                    DVec3::new(x0, 0.0, z1),
                    DVec3::new(dx, 0.0, 0.0),
                    DVec3::new(0.0, h, 0.0),
                ),
                (
                    DVec3::new(x1, 0.0, z0),
                    DVec3::new(-dx, 0.0, 0.0),
                    DVec3::new(0.0, h, 0.0),
                ),
                (
                    DVec3::new(x1, 0.0, z1),
                    DVec3::new(0.0, 0.0, -dz),
                    DVec3::new(0.0, h, 0.0),
                ),
                (
                    DVec3::new(x0, 0.0, z0),
                    DVec3::new(0.0, 0.0, dz),
                    DVec3::new(0.0, h, 0.0),
                ),
            ] {
                add(target, Quad { corner, u, v, n: m });
            }
        }
    }
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for b in [&diffuse, &glossy, &ground] {
        for v in &b.vertices {
            for a in 0..3 {
                lo[a] = lo[a].min(v.position[a]);
                hi[a] = hi[a].max(v.position[a]);
            }
        }
    }
    // In the street west of the centre column of blocks, at eye height,
    // looking north (−z) down the street.
    let street_x = -half + 10.0 * (n / 2) as f64;
    let camera = Camera {
        eye: [street_x, 1.7, 0.0],
        target: [street_x, 1.7, -half],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 70.0,
        width: 512,
        height: 512,
    };
    let mut header = header(lo, hi, camera);
    header.mode = SolveMode::Directional;
    let batches = [diffuse, glossy, ground]
        .into_iter()
        .filter(|b| !b.indices.is_empty())
        .collect();
    Solution {
        lighting: None,
        header,
        batches,
        textures: Vec::new(),
    }
}
