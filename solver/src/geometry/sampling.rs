//! Deterministic random numbers and stratified sampling of source polygons
//! (Remington 1992, §6.2: "a jittered sampling of the source").
//!
//! Every random decision in the solver draws from an [`Rng`] created for that
//! decision's identity (seed, shot, receiving vertex, ...), never from a shared
//! generator, so results do not depend on the thread count or scheduling.

use super::polygon::newell_normal;
use glam::DVec3;

/// SplitMix64's output function: a bijective 64-bit mixer (Steele, Lea and
/// Flood 2014). Used to turn structured ids (0, 1, 2, ...) into well-spread
/// seeds and to combine ids.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Combines two ids into one stream id (order matters), e.g.
/// `stream_id(shot, vertex)`.
#[inline]
pub fn stream_id(a: u64, b: u64) -> u64 {
    mix64(mix64(a) ^ b.rotate_left(32))
}

/// PCG32 (XSH-RR, O'Neill 2014): 64-bit state, 32-bit output, period 2^64 per
/// stream. Small, fast and statistically sound for sampling.
///
/// `Rng::new(seed, stream)` gives independent-looking sequences for different
/// streams; the stream id is mixed first because PCG streams with related
/// increments are correlated.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

const PCG_MULT: u64 = 6_364_136_223_846_793_005;

impl Rng {
    /// A generator for `(seed, stream)`; the same pair always gives the same
    /// sequence.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = Rng {
            state: 0,
            inc: (mix64(stream ^ 0x5851_F42D_4C95_7F2D) << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(mix64(seed));
        rng.next_u32();
        rng
    }

    /// The next 32 uniformly distributed bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// The next 64 uniformly distributed bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        ((self.next_u32() as u64) << 32) | self.next_u32() as u64
    }

    /// Uniform in [0, 1) with 53 random bits.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// Appends `n` stratified, jittered points, uniformly distributed over the
/// convex polygon `polygon`, to `out` (cleared first).
///
/// The unit square is split into `n` cells of equal area (rows of equal cell
/// counts ±1, row heights proportional to their counts so every cell has area
/// 1/n), one jittered point per cell, and mapped to the polygon by a continuous,
/// area-preserving map: u runs around the fan triangles (v0, v_i, v_{i+1}) in
/// proportion to their areas, and v runs from v0 outwards with radius √v, i.e.
/// x = v0 + √v · (lerp(v_i, v_{i+1}, t) − v0), t = u rescaled within triangle i.
/// Equal-area cells in the square give equal-area strata on the polygon.
///
/// A degenerate (zero-area) polygon yields `n` copies of its vertex average, so
/// callers always get `n` points; an empty polygon yields none.
pub fn stratified_points(polygon: &[DVec3], n: u32, rng: &mut Rng, out: &mut Vec<DVec3>) {
    out.clear();
    if polygon.is_empty() || n == 0 {
        return;
    }
    out.reserve(n as usize);
    let normal = newell_normal(polygon);
    let count = polygon.len();
    // Cumulative fan areas (twice the area, projected on the normal so that
    // slightly non-planar polygons still sum to the Newell area).
    let v0 = polygon[0];
    let mut cumulative = [0.0f64; 64];
    let mut heap: Vec<f64>;
    let cum: &mut [f64] = if count <= 64 {
        &mut cumulative[..count.saturating_sub(2)]
    } else {
        heap = vec![0.0; count - 2];
        &mut heap
    };
    let mut total = 0.0;
    for i in 1..count.saturating_sub(1) {
        let twice = (polygon[i] - v0)
            .cross(polygon[i + 1] - v0)
            .dot(normal)
            .max(0.0);
        total += twice;
        cum[i - 1] = total;
    }
    if !total.is_finite() || total <= 0.0 {
        let centre = polygon.iter().copied().sum::<DVec3>() / count as f64;
        out.extend(std::iter::repeat_n(centre, n as usize));
        return;
    }
    stratified_square(n, rng, |u, v| {
        out.push(map_square_to_fan(polygon, cum, total, u, v))
    });
}

/// Calls `f(u, v)` for `n` jittered points of the unit square, one in each
/// of `n` equal-area cells: ⌊√n⌋ rows of ⌊n/rows⌋ or one more cells. Each
/// point draws u, then v, from `rng`. Through an area-preserving map the
/// cells become equal strata of a polygon ([`stratified_points`]) or of a
/// solid angle (`solid_angle::stratified_solid_angle_points`).
pub fn stratified_square(n: u32, rng: &mut Rng, mut f: impl FnMut(f64, f64)) {
    if n == 0 {
        return;
    }
    let rows = (n as f64).sqrt().floor().max(1.0) as u32;
    let base = n / rows;
    let extra = n % rows;
    let mut v_start = 0.0;
    for row in 0..rows {
        let cells = base + u32::from(row < extra);
        let height = cells as f64 / n as f64;
        for cell in 0..cells {
            let u = (cell as f64 + rng.next_f64()) / cells as f64;
            let v = v_start + rng.next_f64() * height;
            f(u, v);
        }
        v_start += height;
    }
}

/// The area-preserving map of [`stratified_points`] from (u, v) ∈ [0, 1)² to
/// the fan of `polygon`.
fn map_square_to_fan(polygon: &[DVec3], cum: &[f64], total: f64, u: f64, v: f64) -> DVec3 {
    let target = u * total;
    // Few triangles per polygon: a linear scan beats a binary search.
    let mut tri = 0;
    while tri + 1 < cum.len() && cum[tri] <= target {
        tri += 1;
    }
    let lo = if tri == 0 { 0.0 } else { cum[tri - 1] };
    let width = cum[tri] - lo;
    let t = if width > 0.0 {
        ((target - lo) / width).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let v0 = polygon[0];
    let edge_point = polygon[tri + 1].lerp(polygon[tri + 2], t);
    v0 + (edge_point - v0) * v.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rng_is_deterministic_and_streams_differ() {
        let mut a = Rng::new(42, 7);
        let mut b = Rng::new(42, 7);
        let mut c = Rng::new(42, 8);
        let xs: Vec<u32> = (0..8).map(|_| a.next_u32()).collect();
        let ys: Vec<u32> = (0..8).map(|_| b.next_u32()).collect();
        let zs: Vec<u32> = (0..8).map(|_| c.next_u32()).collect();
        assert_eq!(xs, ys);
        assert_ne!(xs, zs);
        // Uniform in [0, 1): the mean of 1e5 draws is 0.5 within 5 standard
        // errors (σ/√n = 0.2887/316 ≈ 9e-4).
        let mut r = Rng::new(1, 0);
        let mean = (0..100_000).map(|_| r.next_f64()).sum::<f64>() / 1e5;
        assert!((mean - 0.5).abs() < 5.0 * 9.2e-4, "mean {mean}");
    }

    #[test]
    fn stratified_points_are_uniform_on_a_quad_and_inside_it() {
        // A trapezoid: mapping errors would show as a biased centroid.
        let quad = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(4.0, 0.0, 0.0),
            DVec3::new(3.0, 2.0, 0.0),
            DVec3::new(1.0, 2.0, 0.0),
        ];
        // Exact centroid of the trapezoid (area 6): x = 2 by symmetry,
        // y = h (b + 2a) / (3 (a + b)) with a = 2 (top), b = 4 (bottom), h = 2.
        let centroid = DVec3::new(2.0, 2.0 * (4.0 + 4.0) / (3.0 * 6.0), 0.0);
        let mut rng = Rng::new(3, 0);
        let mut pts = Vec::new();
        let mut sum = DVec3::ZERO;
        let trials = 200;
        for _ in 0..trials {
            stratified_points(&quad, 37, &mut rng, &mut pts);
            assert_eq!(pts.len(), 37);
            for p in &pts {
                assert!(
                    p.y >= 0.0
                        && p.y <= 2.0
                        && p.x >= 0.5 * p.y - 1e-12
                        && p.x <= 4.0 - 0.5 * p.y + 1e-12
                );
                sum += *p;
            }
        }
        let mean = sum / (trials * 37) as f64;
        // Stratification makes the estimate far tighter than i.i.d. sampling
        // (σ ≈ 0.9 / √7400 ≈ 0.01); 0.01 is a loose bound.
        assert!(
            (mean - centroid).length() < 0.01,
            "mean {mean} vs {centroid}"
        );
    }

    #[test]
    fn each_stratum_gets_one_point() {
        // With n = 16 on the unit square (one triangle pair), the 4 × 4 cells of
        // the parameter square map to equal-area strata: each quarter of the
        // square's area in u (fan angle) holds exactly n/4 points... for a square
        // the fan's u-split is at the diagonal, so count points below it.
        let square = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let mut rng = Rng::new(9, 1);
        let mut pts = Vec::new();
        for _ in 0..50 {
            stratified_points(&square, 16, &mut rng, &mut pts);
            let below = pts.iter().filter(|p| p.y < p.x).count();
            assert_eq!(below, 8, "{pts:?}");
        }
    }

    #[test]
    fn degenerate_polygons_give_n_points() {
        let line = vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        let mut rng = Rng::new(0, 0);
        let mut pts = Vec::new();
        stratified_points(&line, 5, &mut rng, &mut pts);
        assert_eq!(pts.len(), 5);
        assert!(pts.iter().all(|p| p.is_finite()));
    }
}
