use super::*;
use std::f64::consts::PI;

#[test]
fn direction_counts_round_trip_and_reject_non_cubes() {
    for k in [1, 2, 3, 8, 64, MAX_RESOLUTION] {
        let d = direction_count(k) as u32;
        assert_eq!(resolution_from_directions(d), Some(k));
    }
    for bad in [0, 5, 7, 12, 6 * 1025 * 1025 + 6, u32::MAX] {
        assert_eq!(resolution_from_directions(bad), None, "{bad}");
    }
}

#[test]
fn each_cell_centre_looks_up_exactly_its_own_cell() {
    for k in [1, 2, 3, 8] {
        for index in 0..direction_count(k) as u32 {
            let dir = cell_direction(k, index);
            assert!((dir.length() - 1.0).abs() < 1e-15);
            let weights = bilinear(k, dir);
            let own: f64 = weights
                .iter()
                .filter(|(i, _)| *i == index)
                .map(|(_, w)| w)
                .sum();
            // Exact in f64 up to the rounding of (u + 1)·k/2 − ½: 1e-12.
            assert!((own - 1.0).abs() < 1e-12, "k {k} cell {index}: {weights:?}");
        }
    }
}

#[test]
fn cell_solid_angles_tile_the_sphere() {
    for k in [1, 2, 5, 16] {
        let total: f64 = (0..direction_count(k) as u32)
            .map(|i| cell_solid_angle(k, i))
            .sum();
        // The antiderivative is exact; only rounding of 6k² atan sums remains.
        assert!((total - 4.0 * PI).abs() < 1e-12, "k {k}: {total}");
    }
    // One face of the k = 1 cube is a sixth of the sphere.
    assert!((cell_solid_angle(1, 0) - 4.0 * PI / 6.0).abs() < 1e-14);
}

#[test]
fn cell_solid_angle_matches_midpoint_quadrature_of_the_face_jacobian() {
    // dΩ = du dv / (1 + u² + v²)^{3/2}; a 400 × 400 midpoint rule over one cell of
    // the k = 4 cube has error ~ h²/24 · |f''| ≈ 1e-7 of the cell's angle.
    let k = 4;
    for index in [0u32, 5, 15] {
        let j = index % k;
        let i = (index / k) % k;
        let h = 2.0 / f64::from(k);
        let (u0, v0) = (-1.0 + h * f64::from(j), -1.0 + h * f64::from(i));
        let n = 400;
        let step = h / f64::from(n);
        let mut sum = 0.0;
        for a in 0..n {
            for b in 0..n {
                let u = u0 + (f64::from(a) + 0.5) * step;
                let v = v0 + (f64::from(b) + 0.5) * step;
                sum += step * step / (1.0 + u * u + v * v).powf(1.5);
            }
        }
        let exact = cell_solid_angle(k, index);
        assert!((sum - exact).abs() < 1e-6 * exact, "{sum} vs {exact}");
    }
}

#[test]
fn bilinear_weights_are_a_partition_of_unity() {
    let mut rng = Lcg(7);
    for k in [1, 2, 3, 10] {
        for _ in 0..2000 {
            let dir = rng.direction();
            let weights = bilinear(k, dir);
            let sum: f64 = weights.iter().map(|(_, w)| w).sum();
            assert!((sum - 1.0).abs() < 1e-14);
            for (index, w) in weights {
                assert!((0.0..=1.0).contains(&w));
                assert!(u64::from(index) < direction_count(k));
            }
        }
    }
}

#[test]
fn bilinear_lookup_reproduces_a_function_affine_on_the_face_inside_it() {
    // Bilinear interpolation is exact for f = a + b·u + c·v wherever the four
    // cells are distinct neighbours, i.e. at least half a cell from a face edge.
    let k = 8;
    let f = |u: f64, v: f64| 2.0 + 0.7 * u - 1.3 * v;
    let mut values = vec![0.0f32; direction_count(k) as usize * 3];
    for index in 0..direction_count(k) as u32 {
        // Face +z (face 4) holds the affine function; every other face zero.
        if index / (k * k) == 4 {
            let d = cell_direction(k, index);
            let (u, v) = (d.x / d.z, d.y / d.z);
            values[index as usize * 3..index as usize * 3 + 3].fill(f(u, v) as f32);
        }
    }
    let mut rng = Lcg(11);
    let half_cell = 1.0 / f64::from(k);
    for _ in 0..500 {
        let u = rng.uniform(-1.0 + half_cell, 1.0 - half_cell);
        let v = rng.uniform(-1.0 + half_cell, 1.0 - half_cell);
        let rgb = eval_rgb(k, &values, DVec3::new(u, v, 1.0));
        // Values are stored as f32: 1e-6 relative.
        assert!((rgb[0] - f(u, v)).abs() < 1e-6 * 4.0, "{u} {v}: {rgb:?}");
    }
}

#[test]
fn lookup_error_of_a_smooth_lobe_falls_as_the_resolution_grows() {
    // A smooth directional radiance (a broad lobe about a tilted axis); the
    // interpolation error over the upper hemisphere must fall at every step.
    let axis = DVec3::new(0.3, -0.2, 1.0).normalize();
    let radiance = |d: DVec3| (4.0 * (d.dot(axis) - 1.0)).exp();
    let mut previous = f64::INFINITY;
    for k in [2u32, 4, 8, 16, 32] {
        let values: Vec<f32> = (0..direction_count(k) as u32)
            .flat_map(|i| [radiance(cell_direction(k, i)) as f32; 3])
            .collect();
        let mut rng = Lcg(3);
        let mut worst: f64 = 0.0;
        for _ in 0..4000 {
            let mut d = rng.direction();
            d.z = d.z.abs();
            worst = worst.max((eval_rgb(k, &values, d)[0] - radiance(d)).abs());
        }
        assert!(worst < previous, "k {k}: {worst} !< {previous}");
        previous = worst;
    }
    // At k = 32 (6,144 directions) the lobe is within 2% of its peak everywhere.
    assert!(previous < 0.02, "{previous}");
}

#[test]
fn f32_lookup_matches_f64_to_single_precision() {
    let mut rng = Lcg(5);
    for k in [1, 4, 16, 64] {
        for _ in 0..2000 {
            let d = rng.direction();
            let wide = bilinear(k, d);
            let narrow = bilinear_f32(k, d.as_vec3());
            let project = |w: &[(u32, f64); 4]| {
                let mut cells: Vec<(u32, f64)> = w.to_vec();
                cells.sort_by_key(|c| c.0);
                cells
            };
            let a = project(&wide);
            let b = project(&narrow.map(|(i, w)| (i, f64::from(w))));
            // Away from face-selection ties the same cells are chosen; weights agree
            // to f32 rounding of (u + 1)·k/2 amplified by k: 1e-7 · 64 · 4 < 1e-4.
            for ((ia, wa), (ib, wb)) in a.iter().zip(&b) {
                if ia == ib {
                    assert!((wa - wb).abs() < 1e-4, "k {k} {d:?}: {a:?} vs {b:?}");
                }
            }
        }
    }
}

#[test]
fn zero_and_non_finite_directions_look_along_the_normal() {
    for dir in [DVec3::ZERO, DVec3::NAN, DVec3::new(f64::INFINITY, 0.0, 0.0)] {
        let k = 3;
        let weights = bilinear(k, dir);
        // The centre cell of face +z (face 4, row 1, column 1).
        let centre = (4 * k + 1) * k + 1;
        assert_eq!(weights[0], (centre, 1.0), "{dir:?}");
    }
}

/// A small deterministic generator for test directions (this module is built
/// without the `solve` feature, so it cannot use `geometry::sampling`).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }

    /// Uniform on the sphere (Archimedes: z uniform, azimuth uniform).
    fn direction(&mut self) -> DVec3 {
        let z = self.uniform(-1.0, 1.0);
        let phi = self.uniform(0.0, 2.0 * PI);
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}
