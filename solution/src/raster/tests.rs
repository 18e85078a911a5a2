//! Render tests against analytic answers: exact coverage of projected shapes,
//! perspective-correct interpolation from ray casting, clipping, depth, stereo,
//! glossy evaluation toward the eye and re-centring.

use super::*;
use crate::camera::{Camera, Fov, UpAxis};
use crate::format::{Header, ScalarType, SolveMode, SolveStats, Vertex};
use glam::DVec2;

const W: u32 = 64;
const H: u32 = 48;

pub(super) fn header() -> Header {
    Header {
        units_per_metre: 1.0,
        up_axis: UpAxis::PosY,
        recentre_offset: [0.0; 3],
        camera: Camera::default(),
        bounds_min: [-20.0; 3],
        bounds_max: [20.0; 3],
        partial: false,
        mode: SolveMode::Diffuse,
        stats: SolveStats::default(),
        settings_json: String::new(),
    }
}

fn solution(batches: Vec<Batch>) -> Solution {
    Solution {
        lighting: None,
        header: header(),
        batches,
        textures: Vec::new(),
    }
}

/// Eye at the origin looking down −z, +y up, 60° vertical field of view.
fn view(width: u32, height: u32) -> EyeView {
    EyeView {
        position: DVec3::ZERO,
        right: DVec3::X,
        up: DVec3::Y,
        forward: DVec3::NEG_Z,
        fov: Fov::symmetric(60f64.to_radians(), width, height),
        width,
        height,
    }
}

/// A triangle drawn with per-vertex order-0 coefficients `c` (radiance c·Y00).
#[derive(Clone, Copy)]
struct Tri {
    p: [DVec3; 3],
    c: [[f32; 3]; 3],
}

impl Tri {
    /// Orders the corners counter-clockwise as seen from `eye` (front-facing).
    fn facing(mut self, eye: DVec3) -> Tri {
        if self.normal().dot(eye - self.p[0]) < 0.0 {
            self.p.swap(1, 2);
            self.c.swap(1, 2);
        }
        self
    }

    fn normal(&self) -> DVec3 {
        (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0])
    }

    /// The vertex stage's output for corner k (f32, as the rasterizer gets it).
    fn radiance(&self, k: usize) -> [f64; 3] {
        self.c[k].map(|c| (c as f64 * sh::Y00) as f32 as f64)
    }

    /// Barycentric coordinates of a point in this triangle's plane.
    fn barycentric(&self, q: DVec3) -> [f64; 3] {
        let n = self.normal();
        let n2 = n.length_squared();
        let b0 = n.dot((self.p[2] - self.p[1]).cross(q - self.p[1])) / n2;
        let b1 = n.dot((self.p[0] - self.p[2]).cross(q - self.p[2])) / n2;
        [b0, b1, 1.0 - b0 - b1]
    }

    /// Where the ray through framebuffer point `px` meets the plane: distance
    /// along the view direction and the interpolated radiance (no inside test).
    fn on_plane(&self, view: &EyeView, px: DVec2) -> Option<(f64, [f64; 3], [f64; 3])> {
        let dir = view.pixel_ray(px); // unit component along `forward`
        let n = self.normal();
        let denom = n.dot(dir);
        if denom == 0.0 {
            return None;
        }
        let s = n.dot(self.p[0] - view.position) / denom;
        let b = self.barycentric(view.position + dir * s);
        let r = [0, 1, 2].map(|c| (0..3).map(|k| b[k] * self.radiance(k)[c]).sum());
        Some((s, b, r))
    }
}

/// One batch of unshared vertices, frame from each triangle's geometry.
fn batch(tris: &[Tri]) -> Batch {
    let mut b = Batch {
        representation: Representation::Sh { order: 0 },
        scalar: ScalarType::F32,
        vertices: Vec::new(),
        coefficients: Vec::new(),
        indices: Vec::new(),
        texturing: None,
    };
    for t in tris {
        let n = t.normal().normalize();
        let tangent = (t.p[1] - t.p[0]).normalize();
        for k in 0..3 {
            b.indices.push(b.vertices.len() as u32);
            b.vertices.push(Vertex {
                position: t.p[k].as_vec3().into(),
                normal: n.as_vec3().into(),
                tangent: tangent.as_vec3().into(),
            });
            b.coefficients.extend_from_slice(&t.c[k]);
        }
    }
    b
}

/// Ray-cast reference: the front-facing triangle nearest along the ray through
/// `px` within `near..=far`, as (triangle index, radiance).
fn trace(
    tris: &[Tri],
    view: &EyeView,
    near: f64,
    far: f64,
    px: DVec2,
) -> Option<(usize, [f64; 3])> {
    let mut best: Option<(f64, usize, [f64; 3])> = None;
    for (index, t) in tris.iter().enumerate() {
        if t.normal().dot(view.position - t.p[0]) <= 0.0 {
            continue; // back face
        }
        let Some((s, b, r)) = t.on_plane(view, px) else {
            continue;
        };
        if s < near || s > far || b.iter().any(|&x| x < 0.0) {
            continue;
        }
        if best.is_none_or(|(s0, _, _)| s < s0) {
            best = Some((s, index, r));
        }
    }
    best.map(|(_, i, r)| (i, r))
}

/// Compares a render with [`trace`] at every pixel whose centre is at least
/// `1/64` pixel from any coverage boundary (there the answer is unambiguous:
/// snapping moves vertices by at most 1/512 pixel). Returns (checked pixels,
/// ambiguous pixels, the largest |render − perspective| / tolerance).
///
/// Tolerance on radiance: snapping can shift the interpolated value by the
/// screen-space gradient times the snap error, bounded by 4·|∇r|·(1/256 px);
/// plus f32 rounding (1e-6 relative).
fn check_against_trace(
    image: &Image,
    tris: &[Tri],
    view: &EyeView,
    near: f64,
    far: f64,
) -> (usize, usize) {
    let delta = 1.0 / 64.0;
    let (mut checked, mut ambiguous) = (0, 0);
    for j in 0..view.height {
        for i in 0..view.width {
            let c = DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
            let hit = trace(tris, view, near, far, c);
            let unambiguous = [
                (-1.0, -1.0),
                (1.0, -1.0),
                (-1.0, 1.0),
                (1.0, 1.0),
                (0.0, 1.0),
                (1.0, 0.0),
                (0.0, -1.0),
                (-1.0, 0.0),
            ]
            .iter()
            .all(|&(dx, dy)| {
                trace(tris, view, near, far, c + DVec2::new(dx, dy) * delta).map(|h| h.0)
                    == hit.map(|h| h.0)
            });
            if !unambiguous {
                ambiguous += 1;
                continue;
            }
            checked += 1;
            assert_eq!(
                image.covered(i, j),
                hit.is_some(),
                "coverage of pixel ({i}, {j})"
            );
            let got = image.pixel(i, j);
            match hit {
                None => assert_eq!(got, [0.0; 3], "background at ({i}, {j})"),
                Some((t, want)) => {
                    let value = |p: DVec2| tris[t].on_plane(view, p).unwrap().2;
                    let (gx, gy) = (value(c + DVec2::X * 0.5), value(c - DVec2::X * 0.5));
                    let (hy, ly) = (value(c + DVec2::Y * 0.5), value(c - DVec2::Y * 0.5));
                    for ch in 0..3 {
                        let gradient =
                            ((gx[ch] - gy[ch]).powi(2) + (hy[ch] - ly[ch]).powi(2)).sqrt();
                        let tol = 4.0 * gradient / 256.0 + 1e-6 * want[ch].abs();
                        assert!(
                            (got[ch] as f64 - want[ch]).abs() <= tol,
                            "pixel ({i}, {j}) channel {ch}: {} vs {} (tol {tol})",
                            got[ch],
                            want[ch]
                        );
                    }
                }
            }
        }
    }
    (checked, ambiguous)
}

/// World point seen at framebuffer position `px` at distance `d` along the view.
fn at(view: &EyeView, px: (f64, f64), d: f64) -> DVec3 {
    view.position + view.pixel_ray(DVec2::new(px.0, px.1)) * d
}

/// A quad (two triangles) facing the eye with corners at framebuffer positions
/// `x0..x1 × y0..y1` at distance `d`, radiance coefficient `c` everywhere.
fn screen_quad(
    view: &EyeView,
    (x0, y0, x1, y1): (f64, f64, f64, f64),
    d: f64,
    c: [f32; 3],
) -> [Tri; 2] {
    let (a, b, cc, dd) = (
        at(view, (x0, y1), d),
        at(view, (x1, y1), d),
        at(view, (x1, y0), d),
        at(view, (x0, y0), d),
    );
    [
        Tri {
            p: [a, b, cc],
            c: [c; 3],
        }
        .facing(view.position),
        Tri {
            p: [a, cc, dd],
            c: [c; 3],
        }
        .facing(view.position),
    ]
}

#[test]
fn constant_quad_covers_exactly_its_projected_rectangle() {
    let view = view(W, H);
    let c = [2.0f32, 0.5, 0.25];
    let value = c.map(|c| (c as f64 * sh::Y00) as f32);
    // Corners at arbitrary sub-pixel positions, then exactly on pixel centres (where
    // the top-left rule decides: left/top borders in, right/bottom out).
    for (rect, columns, rows) in [
        ((10.3, 7.8, 52.7, 40.2), 10..=52, 8..=39),
        ((20.5, 10.5, 40.5, 30.5), 20..=39, 10..=29),
    ] {
        let image = render(
            &solution(vec![batch(&screen_quad(&view, rect, 5.0, c))]),
            &view,
            &RenderOptions::default(),
        )
        .unwrap();
        for j in 0..H {
            for i in 0..W {
                let inside = columns.contains(&i) && rows.contains(&j);
                // A constant attribute interpolates to itself: the exact value.
                let want = if inside { value } else { [0.0; 3] };
                assert_eq!(image.pixel(i, j), want, "pixel ({i}, {j}) of {rect:?}");
                assert_eq!(image.covered(i, j), inside);
            }
        }
    }
}

#[test]
fn interpolation_is_perspective_correct() {
    // A floor triangle receding from 2 to 20 units, radiance 1, 2, 10 (× Y00) at
    // its corners: seen at a slant, perspective-correct and screen-affine
    // interpolation differ by far more than the tolerance.
    let (width, height) = (96, 72);
    let view = view(width, height);
    let tri = Tri {
        p: [
            DVec3::new(-3.0, -1.0, -2.0),
            DVec3::new(3.0, -1.0, -2.0),
            DVec3::new(0.0, -1.0, -20.0),
        ],
        c: [[1.0; 3], [2.0; 3], [10.0; 3]],
    }
    .facing(view.position);
    let (near, far) = (0.1, 100.0);
    let options = RenderOptions {
        clip_planes: Some((near, far)),
        ..Default::default()
    };
    let image = render(&solution(vec![batch(&[tri])]), &view, &options).unwrap();
    let (checked, ambiguous) = check_against_trace(&image, &[tri], &view, near, far);
    assert!(
        checked > 1000 && ambiguous < checked / 10,
        "{checked} checked, {ambiguous} ambiguous"
    );
    // The test can fail: screen-affine interpolation is far off at some pixel.
    let projected = tri.p.map(|p| view.project_to_pixel(p).unwrap());
    let mut largest_gap: f64 = 0.0;
    for j in 0..height {
        for i in 0..width {
            if !image.covered(i, j) {
                continue;
            }
            let c = DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
            let area = |a: DVec2, b: DVec2, p: DVec2| (b - a).perp_dot(p - a);
            let total = area(projected[0], projected[1], projected[2]);
            let l = [
                area(projected[1], projected[2], c) / total,
                area(projected[2], projected[0], c) / total,
                area(projected[0], projected[1], c) / total,
            ];
            let affine: f64 = (0..3).map(|k| l[k] * tri.radiance(k)[0]).sum();
            largest_gap = largest_gap.max((affine - image.pixel(i, j)[0] as f64).abs());
        }
    }
    assert!(
        largest_gap > 0.2,
        "affine and perspective interpolation differ by only {largest_gap}"
    );
}

#[test]
fn triangles_crossing_the_near_and_far_planes_draw_their_visible_part() {
    let view = view(W, H);
    let (near, far) = (0.5, 8.0);
    let eye = view.position;
    // A floor from behind the eye (z = +3) to beyond the far plane (z = −12), and
    // a sloping ceiling from behind the eye down to 4 units ahead whose near-plane
    // cut runs across the middle of the image.
    let tris = [
        Tri {
            p: [
                DVec3::new(-4.0, -1.0, 3.0),
                DVec3::new(4.0, -1.0, 3.0),
                DVec3::new(0.0, -1.0, -12.0),
            ],
            c: [[1.0, 2.0, 3.0], [4.0, 2.0, 1.0], [0.5, 6.0, 2.0]],
        }
        .facing(eye),
        Tri {
            p: [
                DVec3::new(-1.5, 0.25, 0.5),
                DVec3::new(1.5, 0.25, 0.5),
                DVec3::new(0.0, -0.5, -4.0),
            ],
            c: [[3.0, 1.0, 1.0], [1.0, 3.0, 1.0], [1.0, 1.0, 3.0]],
        }
        .facing(eye),
    ];
    let options = RenderOptions {
        clip_planes: Some((near, far)),
        ..Default::default()
    };
    let image = render(&solution(vec![batch(&tris)]), &view, &options).unwrap();
    let (checked, ambiguous) = check_against_trace(&image, &tris, &view, near, far);
    // Ambiguous pixels are those within 1/64 px of a boundary: a few per boundary
    // line crossing the 64-pixel-wide image.
    assert!(
        checked + ambiguous == (W * H) as usize && ambiguous < 300,
        "{ambiguous} ambiguous"
    );
    // Both the near cut of the ceiling and the far cut of the floor are visible:
    // some rows hold the ceiling, some the background between them, some floor.
    let rows_with = |t: usize| {
        (0..H)
            .filter(|&j| {
                (0..W).any(|i| {
                    trace(
                        &tris,
                        &view,
                        near,
                        far,
                        DVec2::new(i as f64 + 0.5, j as f64 + 0.5),
                    )
                    .map(|h| h.0)
                        == Some(t)
                })
            })
            .count()
    };
    assert!(rows_with(0) > 5 && rows_with(1) > 5);
    assert!(
        (0..W).all(|i| !image.covered(i, 0)),
        "top row lies above the near cut of the ceiling"
    );
}

#[test]
fn depth_test_hides_the_far_quad_in_either_draw_order() {
    let view = view(W, H);
    let near_quad = screen_quad(&view, (20.2, 14.6, 44.4, 33.1), 3.0, [5.0; 3]);
    let far_quad = screen_quad(&view, (8.3, 5.5, 55.9, 42.2), 6.0, [1.0, 2.0, 3.0]);
    let options = RenderOptions {
        clip_planes: Some((0.1, 50.0)),
        ..Default::default()
    };
    let tris: Vec<Tri> = near_quad.iter().chain(&far_quad).copied().collect();
    let first = render(&solution(vec![batch(&tris)]), &view, &options).unwrap();
    let reversed: Vec<Tri> = tris.iter().rev().copied().collect();
    let second = render(&solution(vec![batch(&reversed)]), &view, &options).unwrap();
    assert_eq!(first, second, "draw order must not matter");
    let (checked, _) = check_against_trace(&first, &tris, &view, 0.1, 50.0);
    assert!(checked > 2500);
    // The near quad's value inside its rectangle, the far quad's around it.
    assert_eq!(first.pixel(32, 24), [(5.0 * sh::Y00) as f32; 3]);
    assert_eq!(
        first.pixel(12, 24),
        [1.0, 2.0, 3.0].map(|c: f64| (c * sh::Y00) as f32)
    );
}

#[test]
fn stereo_pair_shifts_by_ipd_f_over_d() {
    let cam = Camera {
        eye: [0.0, 0.0, 0.0],
        target: [0.0, 0.0, -1.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 60.0,
        width: 256,
        height: 192,
    };
    let ipd = 0.3;
    let views = cam.stereo_views(ipd, DVec3::ZERO);
    let (f, _) = views[0].focal_lengths_px();
    for d in [2.0, 4.0, 9.0] {
        // A square 1 × 1 unit, centred ahead at distance d.
        let corners =
            [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)].map(|(x, y)| DVec3::new(x, y, -d));
        let tris = [
            Tri {
                p: [corners[0], corners[1], corners[2]],
                c: [[1.0; 3]; 3],
            },
            Tri {
                p: [corners[0], corners[2], corners[3]],
                c: [[1.0; 3]; 3],
            },
        ];
        let scene = solution(vec![batch(&tris)]);
        let first_column = |v: &EyeView| {
            let image = render(&scene, v, &RenderOptions::default()).unwrap();
            (0..image.width)
                .find(|&i| image.covered(i, image.height / 2))
                .unwrap() as f64
        };
        let shift = first_column(&views[0]) - first_column(&views[1]);
        // Pixel quantisation of each edge: ±1 px on the difference.
        assert!(
            (shift - ipd * f / d).abs() <= 1.0,
            "d = {d}: shift {shift}, expected {}",
            ipd * f / d
        );
    }
}

#[test]
fn glossy_vertex_radiance_follows_sh_toward_each_eye() {
    // One order-3 vertex P on the plane z = 0 (normal +z, tangent +x). For each eye
    // the triangle is built so that P projects exactly onto a pixel centre as the
    // top-left corner of its triangle: that pixel's barycentrics are (1, 0, 0) and
    // it shows P's own radiance, which must be `sh::eval_rgb` toward that eye.
    let order = 3;
    let n = sh::coefficient_count(order);
    let coefficients: Vec<f32> = (0..n * 3)
        .map(|k| {
            if k < 3 {
                4.0
            } else {
                0.9 * ((k as f32) * 0.77).sin()
            }
        })
        .collect();
    let p = DVec3::new(0.3, -0.2, 0.0);
    let (normal, tangent) = (DVec3::Z, DVec3::X);
    let eyes = [
        (DVec3::new(0.0, 0.0, 5.0), (20, 14)),
        (DVec3::new(3.0, -2.0, 2.0), (31, 20)),
        (DVec3::new(-4.0, 1.5, 1.0), (12, 30)),
    ];
    let mut seen = Vec::new();
    for (eye, pixel) in eyes {
        // Look at a point so that P lands on pixel centre `pixel`.
        let cam = Camera {
            eye: eye.into(),
            target: p.into(),
            up: [0.0, 0.0, 1.0],
            fov_y_deg: 60.0,
            width: W,
            height: H,
        };
        let mut v = cam.mono_view(DVec3::ZERO);
        let centre = DVec2::new(pixel.0 as f64 + 0.5, pixel.1 as f64 + 0.5);
        // Shift the eye along the plane of the image so that P moves to `centre`.
        let d = (p - v.position).dot(v.forward);
        let offset = v.pixel_ray(centre) * d - (p - v.position);
        v.position -= offset;
        let at_plane = |px: DVec2| {
            // Where the ray through px meets z = 0.
            let dir = v.pixel_ray(px);
            v.position + dir * (-v.position.z / dir.z)
        };
        let q1 = at_plane(centre + DVec2::new(12.0, 0.0));
        let q2 = at_plane(centre + DVec2::new(0.0, 9.0));
        let positions = [p, q1, q2];
        let mut batch = Batch {
            representation: Representation::Sh { order },
            scalar: ScalarType::F32,
            vertices: positions
                .iter()
                .map(|q| Vertex {
                    position: q.as_vec3().into(),
                    normal: normal.as_vec3().into(),
                    tangent: tangent.as_vec3().into(),
                })
                .collect(),
            coefficients: [
                coefficients.clone(),
                coefficients.clone(),
                coefficients.clone(),
            ]
            .concat(),
            indices: vec![0, 1, 2],
            texturing: None,
        };
        if (q1 - p).cross(q2 - p).dot(normal) < 0.0 {
            batch.indices = vec![0, 2, 1];
        }
        let p32 = DVec3::from(batch.vertices[0].position.map(f64::from));
        let image = render(&solution(vec![batch]), &v, &RenderOptions::default()).unwrap();
        let want = sh::eval_rgb(
            order,
            &coefficients,
            sh::to_local((v.position - p32).normalize(), normal, tangent),
        );
        let got = image.pixel(pixel.0, pixel.1);
        for c in 0..3 {
            // λ = (1, 0, 0) exactly in integer edge functions: the value passes
            // through r·(1/w)/(1/w), one f64 rounding, then the f32 store.
            assert!(
                (got[c] as f64 - want[c]).abs() <= 1e-6 * want[c].abs(),
                "eye {eye}: {got:?} vs {want:?}"
            );
        }
        seen.push(got);
    }
    // The eyes see clearly different radiance (the test is not trivially passed by
    // a constant).
    assert!(
        (seen[0][0] - seen[1][0]).abs() > 0.05 && (seen[1][0] - seen[2][0]).abs() > 0.05,
        "{seen:?}"
    );
}

#[test]
fn order_cap_drops_the_higher_bands() {
    let order = 2;
    let n = sh::coefficient_count(order);
    let coefficients: Vec<f32> = (0..n * 3).map(|k| if k < 3 { 3.0 } else { 1.0 }).collect();
    let view = view(W, H);
    let quad = screen_quad(&view, (10.0, 10.0, 50.0, 40.0), 4.0, [0.0; 3]);
    let mut b = batch(&quad);
    b.representation = Representation::Sh { order };
    b.coefficients = (0..b.vertices.len())
        .flat_map(|_| coefficients.clone())
        .collect();
    let capped = RenderOptions {
        max_order: Some(0),
        ..Default::default()
    };
    let scene = solution(vec![b]);
    let flat = render(&scene, &view, &capped).unwrap();
    assert_eq!(flat.pixel(30, 25), [(3.0 * sh::Y00) as f32; 3]);
    let full = render(&scene, &view, &RenderOptions::default()).unwrap();
    assert!((full.pixel(30, 25)[0] - flat.pixel(30, 25)[0]).abs() > 0.01);
}

#[test]
fn back_faces_are_culled_unless_asked() {
    let view = view(W, H);
    let mut quad = screen_quad(&view, (10.0, 10.0, 50.0, 40.0), 4.0, [1.0; 3]);
    for t in &mut quad {
        t.p.swap(1, 2);
    }
    let scene = solution(vec![batch(&quad)]);
    let culled = render(&scene, &view, &RenderOptions::default()).unwrap();
    assert!(culled.depth.iter().all(|&d| d == 1.0));
    let both = RenderOptions {
        cull_back_faces: false,
        ..Default::default()
    };
    let drawn = render(&scene, &view, &both).unwrap();
    assert_eq!(drawn.depth.iter().filter(|&&d| d < 1.0).count(), 40 * 30);
}

#[test]
fn scene_translated_by_a_million_renders_identically_after_the_offset() {
    // The stored (re-centred) positions are the same; only the header's offset and
    // camera differ by 1e6. Subtracting the offset in f64 leaves an eye error of
    // ~1e-10 units, far below the 1/512-pixel snapping step, so coverage is
    // identical and radiance agrees to f32 rounding (1e-6 relative).
    let mut cam = Camera {
        eye: [0.4, 0.3, 2.0],
        target: [0.0, 0.0, -3.0],
        up: [0.0, 1.0, 0.0],
        fov_y_deg: 60.0,
        width: W,
        height: H,
    };
    let base_view = cam.mono_view(DVec3::ZERO);
    let mut quad = screen_quad(&base_view, (5.0, 6.0, 58.0, 41.0), 4.0, [0.0; 3]).to_vec();
    quad.extend(screen_quad(
        &base_view,
        (15.0, 12.0, 40.0, 30.0),
        2.0,
        [2.0, 1.0, 0.5],
    ));
    let mut b = batch(&quad);
    // Make the first quad glossy (order 2) so that the eye direction matters.
    let order = 2;
    let n = sh::coefficient_count(order);
    b.representation = Representation::Sh { order };
    b.coefficients = (0..b.vertices.len())
        .flat_map(|v| {
            (0..n * 3).map(move |k| {
                if k < 3 {
                    3.0
                } else {
                    0.5 * ((v * 7 + k) as f32).cos()
                }
            })
        })
        .collect();
    let plain = render(
        &solution(vec![b.clone()]),
        &base_view,
        &RenderOptions::default(),
    )
    .unwrap();
    let offset = DVec3::new(1e6, -1e6, 1e6);
    let mut moved = solution(vec![b]);
    moved.header.recentre_offset = offset.into();
    cam.eye = (DVec3::from(cam.eye) + offset).into();
    cam.target = (DVec3::from(cam.target) + offset).into();
    moved.header.camera = cam;
    let moved_view = moved
        .header
        .camera
        .mono_view(DVec3::from(moved.header.recentre_offset));
    let image = render(&moved, &moved_view, &RenderOptions::default()).unwrap();
    assert_eq!(
        image.depth.iter().map(|&d| d < 1.0).collect::<Vec<_>>(),
        plain.depth.iter().map(|&d| d < 1.0).collect::<Vec<_>>()
    );
    let diff = compare(&plain, &image).unwrap();
    assert!(diff.max_abs < 1e-6, "{diff:?}");
    assert!(plain.covered(32, 24) && plain.mean_radiance() > 0.1);
}

#[test]
fn unsupported_and_malformed_batches_are_refused() {
    let view = view(W, H);
    let quad = screen_quad(&view, (10.0, 10.0, 50.0, 40.0), 4.0, [1.0; 3]);
    let good = batch(&quad);
    let options = RenderOptions::default();
    // A cube whose D is not 6k² (12 = 6·2 is not 6 times a square).
    let mut cube = good.clone();
    cube.representation = Representation::Cube { directions: 12 };
    cube.coefficients = vec![0.0; cube.vertices.len() * 12 * 3];
    assert!(matches!(
        render(&solution(vec![good.clone(), cube.clone()]), &view, &options),
        Err(RenderError::CubeDirections {
            batch: 1,
            directions: 12
        })
    ));
    assert!(matches!(
        shade_vertices(&cube, 0, DVec3::Z, true),
        Err(RenderError::CubeDirections { .. })
    ));
    // A valid cube with a short value array.
    cube.representation = Representation::Cube { directions: 24 };
    assert!(matches!(
        render(&solution(vec![cube]), &view, &options),
        Err(RenderError::CoefficientCount { batch: 0, .. })
    ));
    let mut short = good.clone();
    short.coefficients.pop();
    assert!(matches!(
        render(&solution(vec![short]), &view, &options),
        Err(RenderError::CoefficientCount { .. })
    ));
    let mut bad_index = good.clone();
    bad_index.indices[4] = 99;
    assert!(matches!(
        render(&solution(vec![bad_index]), &view, &options),
        Err(RenderError::IndexOutOfRange {
            position: 4,
            index: 99,
            ..
        })
    ));
    let mut ragged = good.clone();
    ragged.indices.pop();
    assert!(matches!(
        render(&solution(vec![ragged]), &view, &options),
        Err(RenderError::IndexCount { .. })
    ));
    // Corrupt positions draw nothing rather than panicking.
    let mut nan = good.clone();
    nan.vertices[0].position[0] = f32::NAN;
    assert!(render(&solution(vec![nan]), &view, &options).is_ok());
    // Empty solution: black image.
    let empty = render(&solution(vec![]), &view, &options).unwrap();
    assert!(empty.pixels.iter().all(|p| *p == [0.0; 3]));
    // Hostile image sizes and views.
    let huge = EyeView {
        width: 16384,
        height: 16384,
        ..view
    };
    assert!(matches!(
        render(&solution(vec![]), &huge, &options),
        Err(RenderError::ImageSize { .. })
    ));
    let zero = EyeView { width: 0, ..view };
    assert!(matches!(
        render(&solution(vec![]), &zero, &options),
        Err(RenderError::ImageSize { .. })
    ));
    let skewed = EyeView {
        right: DVec3::new(1.0, 0.5, 0.0),
        ..view
    };
    assert!(matches!(
        render(&solution(vec![]), &skewed, &options),
        Err(RenderError::View(_))
    ));
    let clip = RenderOptions {
        clip_planes: Some((0.0, 1.0)),
        ..options
    };
    assert!(matches!(
        render(&solution(vec![]), &view, &clip),
        Err(RenderError::ClipPlanes { .. })
    ));
}

/// Cube values that are affine in each face's coordinates: on the face of axis a
/// and sign s (index `face`), cell (i, j) holds `(A_f + B_f·u_j + C_f·v_i)·(1 +
/// ch/4)` for channel ch. Bilinear interpolation between evenly spaced cell
/// centres reproduces an affine function exactly, and clamping the continuous
/// cell coordinate to the border cells is clamping (u, v) to [u_0, u_{k−1}], so
/// the lookup toward any direction has the closed form of [`affine_cube_value`].
fn affine_coefficients(face: u32) -> [f64; 3] {
    let f = f64::from(face);
    [2.0 + 0.5 * f, 0.3 + 0.1 * f, -0.2 + 0.07 * f]
}

/// The values of one vertex (`values[d * 3 + c]`), laid out as
/// docs/solution-format.md ("Cube") defines: index (face·k + i)·k + j.
fn affine_cube_values(k: u32) -> Vec<f32> {
    let centre = |c: u32| -1.0 + (2.0 * f64::from(c) + 1.0) / f64::from(k);
    let mut values = Vec::new();
    for face in 0..6 {
        let [a, b, c] = affine_coefficients(face);
        for i in 0..k {
            for j in 0..k {
                let value = a + b * centre(j) + c * centre(i);
                for ch in 0..3 {
                    values.push((value * (1.0 + 0.25 * ch as f64)) as f32);
                }
            }
        }
    }
    values
}

/// The closed form of the lookup of [`affine_cube_values`] toward `dir` (local
/// frame, no ties between the largest components), from the format's
/// definition alone: the face is the axis of largest |component|, (u, v) the
/// projection onto it, clamped to the outermost cell centres.
fn affine_cube_value(k: u32, dir: DVec3) -> [f64; 3] {
    let d = dir.to_array();
    let a = dir.abs().to_array();
    let axis = if a[0] > a[1] && a[0] > a[2] {
        0
    } else if a[1] > a[2] {
        1
    } else {
        2
    };
    let face = axis as u32 * 2 + u32::from(d[axis] < 0.0);
    let (ua, va) = [(1, 2), (2, 0), (0, 1)][axis];
    let limit = 1.0 - 1.0 / f64::from(k);
    let u = (d[ua] / a[axis]).clamp(-limit, limit);
    let v = (d[va] / a[axis]).clamp(-limit, limit);
    let [fa, fb, fc] = affine_coefficients(face);
    let value = fa + fb * u + fc * v;
    [0, 1, 2].map(|ch| value * (1.0 + 0.25 * ch as f64))
}

/// A one-vertex cube batch at the origin with normal +z and tangent +x, so
/// that world directions are local ones.
fn cube_vertex(k: u32, values: Vec<f32>) -> Batch {
    Batch {
        representation: Representation::Cube {
            directions: 6 * k * k,
        },
        scalar: ScalarType::F32,
        vertices: vec![Vertex {
            position: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
            tangent: [1.0, 0.0, 0.0],
        }],
        coefficients: values,
        indices: vec![],
        texturing: None,
    }
}

#[test]
fn cube_vertex_stage_is_the_bilinear_lookup_on_every_face() {
    // Eyes toward every face, inside faces and within half a cell of their
    // edges (clamped), at several distances (the lookup is scale-free).
    let eyes = [
        DVec3::new(0.1, -0.2, 3.0),
        DVec3::new(0.97, 0.4, 1.0),
        DVec3::new(2.0, 0.3, -0.5),
        DVec3::new(-5.0, 1.2, 0.7),
        DVec3::new(0.2, 4.0, -3.1),
        DVec3::new(0.3, -1.0, 0.2),
        DVec3::new(-0.9, 0.95, -2.0),
        DVec3::new(0.05, 0.02, -0.5),
    ];
    for k in [1, 2, 5] {
        let batch = cube_vertex(k, affine_cube_values(k));
        let mut faces_seen = std::collections::BTreeSet::new();
        for eye in eyes {
            let got = shade_vertices(&batch, 0, eye, false).unwrap()[0];
            let want = affine_cube_value(k, eye);
            let a = eye.abs();
            faces_seen.insert(if a.x > a.y && a.x > a.z {
                0
            } else if a.y > a.z {
                1
            } else {
                2
            });
            for c in 0..3 {
                // The stored values are f32 (relative 6e-8 each); four of them
                // are blended with weights summing to 1 in f64, and the result
                // is stored as f32: 1e-6 of the value bounds both roundings.
                assert!(
                    (f64::from(got[c]) - want[c]).abs() <= 1e-6 * want[c].abs(),
                    "k = {k}, eye {eye}: {got:?} vs {want:?}"
                );
            }
        }
        assert_eq!(
            faces_seen.len(),
            3,
            "eyes should reach the x, y and z faces"
        );
    }
    // The order cap does not apply to cubes.
    let batch = cube_vertex(3, affine_cube_values(3));
    let eye = DVec3::new(0.4, 0.1, 1.0);
    assert_eq!(
        shade_vertices(&batch, 0, eye, true).unwrap(),
        shade_vertices(&batch, u32::MAX, eye, true).unwrap()
    );
}

#[test]
fn cube_radiance_is_clamped_at_zero_unless_asked() {
    let k = 2;
    let values: Vec<f32> = affine_cube_values(k).iter().map(|v| -v).collect();
    let batch = cube_vertex(k, values);
    let eye = DVec3::new(0.2, 0.1, 2.0);
    let want = affine_cube_value(k, eye);
    assert_eq!(shade_vertices(&batch, 0, eye, true).unwrap()[0], [0.0; 3]);
    let raw = shade_vertices(&batch, 0, eye, false).unwrap()[0];
    for c in 0..3 {
        assert!((f64::from(raw[c]) + want[c]).abs() <= 1e-6 * want[c]);
    }
}

#[test]
fn cube_pixels_show_the_lookup_toward_each_eye() {
    // As in `glossy_vertex_radiance_follows_sh_toward_each_eye`: a vertex P on
    // z = 0 (normal +z, tangent +x) lands exactly on a pixel centre as the
    // top-left corner of its triangle, so that pixel shows P's own radiance,
    // which must be the closed-form lookup toward that eye: on the +z face
    // (eye above), and on the +x and −x faces (grazing eyes).
    let k = 4;
    let values = affine_cube_values(k);
    let p = DVec3::new(0.3, -0.2, 0.0);
    let eyes = [
        (DVec3::new(0.0, 0.0, 5.0), (20, 14)),
        (DVec3::new(3.0, -2.0, 2.0), (31, 20)),
        (DVec3::new(-4.0, 1.5, 1.0), (12, 30)),
    ];
    let mut seen = Vec::new();
    for (eye, pixel) in eyes {
        let cam = Camera {
            eye: eye.into(),
            target: p.into(),
            up: [0.0, 0.0, 1.0],
            fov_y_deg: 60.0,
            width: W,
            height: H,
        };
        let mut v = cam.mono_view(DVec3::ZERO);
        let centre = DVec2::new(pixel.0 as f64 + 0.5, pixel.1 as f64 + 0.5);
        let d = (p - v.position).dot(v.forward);
        v.position -= v.pixel_ray(centre) * d - (p - v.position);
        let at_plane = |px: DVec2| {
            let dir = v.pixel_ray(px);
            v.position + dir * (-v.position.z / dir.z)
        };
        let positions = [
            p,
            at_plane(centre + DVec2::new(12.0, 0.0)),
            at_plane(centre + DVec2::new(0.0, 9.0)),
        ];
        let mut batch = cube_vertex(k, [values.clone(), values.clone(), values.clone()].concat());
        batch.vertices = positions
            .iter()
            .map(|q| Vertex {
                position: q.as_vec3().into(),
                normal: [0.0, 0.0, 1.0],
                tangent: [1.0, 0.0, 0.0],
            })
            .collect();
        batch.indices = if (positions[1] - p).cross(positions[2] - p).z < 0.0 {
            vec![0, 2, 1]
        } else {
            vec![0, 1, 2]
        };
        let p32 = DVec3::from(batch.vertices[0].position.map(f64::from));
        let image = render(&solution(vec![batch]), &v, &RenderOptions::default()).unwrap();
        let want = affine_cube_value(k, v.position - p32);
        let got = image.pixel(pixel.0, pixel.1);
        for c in 0..3 {
            // f32 values, f64 blend, f32 store, one f64 rounding in the
            // perspective divide (see the SH test): 1e-6 relative.
            assert!(
                (f64::from(got[c]) - want[c]).abs() <= 1e-6 * want[c].abs(),
                "eye {eye}: {got:?} vs {want:?}"
            );
        }
        seen.push(got);
    }
    assert!(
        (seen[0][0] - seen[1][0]).abs() > 0.3 && (seen[1][0] - seen[2][0]).abs() > 0.3,
        "{seen:?}"
    );
}
