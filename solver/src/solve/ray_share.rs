//! Visibility rays in proportion to what a shot can add to a receiver
//! (`full_rays_above`, issue 13: a shot whose cost follows what it changes).
//!
//! ## Why
//!
//! Late in a solve of many small patches, each shot comes from a dim patch
//! and adds to most receivers a sliver of the light they already hold; yet
//! flat progressive refinement traces the full `samples` rays to every one
//! of them, so the rays, not what they find, set the cost. Hanrahan, Salzman
//! and Aupperle (1991, §4) spend visibility effort on a link in proportion to
//! the energy it carries (their BF refinement); this is the same rule for a
//! shot's receivers, with the estimate kept unbiased.
//!
//! ## The rule
//!
//! With c = `full_rays_above`, a receiver whose *unoccluded* gain from the
//! shot, ΔL̂ = max_channel(Kd ⊙ U) · F̂, is at least c · L̂ (L̂: its radiance so
//! far plus Kd ⊙ the ambient term, the level it is heading for) gets all R
//! rays. Below that it gets R · ΔL̂ / (c · L̂) rays, rounded up to a divisor of
//! R, at least one: the stratified set's points j, j + s, j + 2s, … with
//! stride s = R / n and a random offset j < s. Each chosen point is uniform on
//! the source (uniform over the s strata of its block), so the visible
//! fraction stays unbiased; only its noise grows, and it grows only where the
//! shot's share of the receiver is small.
//!
//! ## The noise it adds
//!
//! A receiver's ΔL from n binary rays has variance at most ΔL̂² / (4n). With
//! n ≥ R ΔL̂ / (c L̂) that is at most ΔL̂ · c L̂ / (4R); summed over the shots
//! it is at most c L̂² / (4R), since their ΔL̂ sum to at most L̂. So the
//! relative standard error this adds to a vertex is at most √(c / 4R): 0.9%
//! at c = 0.01 and R = 32 when *all* of its light came through reduced shots
//! in deep penumbra, and far less in practice, where visibility is mostly all
//! or nothing (variance 0) and the bright first shots get every ray.
//!
//! ## What keeps every ray
//!
//! Recorded (emitter) shots, which later splits replay to new vertices and
//! which carry the direct light; receivers with no light yet (L̂ = 0); and
//! every shot when c = 0 (the default of `SolverSettings::base`, the
//! thesis's method; every preset sets 0.01, and the tests that compare the
//! diffuse solve with directional mode, which has no share, set 0). The
//! refinement test reads a reduced
//! receiver's k of n visible rays as k · R / n of R (`visible` keeps its
//! meaning, the visible share); its noise allowance, computed for R rays, is
//! then too small for such receivers, but their ΔL is below c of their level,
//! under every preset's split thresholds.

use glam::DVec3;

/// The share rule of one shot (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayShare {
    /// c: a receiver gets every ray when the shot's unoccluded gain is at
    /// least this fraction of its level.
    pub full_above: f64,
    /// The ambient term of this step (radiance, RGB).
    pub ambient: DVec3,
}

impl RayShare {
    /// The rule for `full_above` and this step's `ambient`; `None` (every
    /// ray) when `full_above` is 0 or not a positive number.
    pub fn new(full_above: f64, ambient: DVec3) -> Option<RayShare> {
        (full_above > 0.0 && full_above.is_finite()).then_some(RayShare {
            full_above,
            ambient,
        })
    }

    /// F_full: the unoccluded factor at and above which a receiver of
    /// reflectance `kd` with radiance so far `prior` gets every ray from a
    /// source of unshot radiance `unshot`. 0 (every ray) when the receiver
    /// holds no light yet or the shot carries none.
    pub fn full_factor(&self, prior: DVec3, kd: DVec3, unshot: DVec3) -> f64 {
        let level = (prior + kd * self.ambient).max_element();
        let gain = (kd * unshot).max_element();
        let f = self.full_above * level / gain;
        if f.is_finite() && f > 0.0 {
            f
        } else {
            0.0
        }
    }
}

/// The rays for a receiver whose unoccluded factor is `factor`, when
/// `full_factor` earns all `samples` (see the module documentation): the
/// smallest divisor of `samples` at or above samples · factor / full_factor,
/// at least 1; `samples` when `full_factor` is 0.
pub fn rays_for(samples: u32, factor: f64, full_factor: f64) -> u32 {
    if samples <= 1 || full_factor <= 0.0 || factor >= full_factor || factor.is_nan() {
        return samples;
    }
    let wanted = (samples as f64 * factor / full_factor).ceil().max(1.0) as u32;
    (wanted..=samples)
        .find(|n| samples.is_multiple_of(*n))
        .unwrap_or(samples)
}

/// Copies points j, j + s, … (s = `all.len()` / n, j = `offset` mod s) of
/// `all` into `out`: n points of a stratified set, one per block of s strata.
pub fn strided(all: &[glam::DVec3], n: u32, offset: u32, out: &mut Vec<glam::DVec3>) {
    out.clear();
    let n = (n as usize).clamp(1, all.len().max(1));
    let stride = (all.len() / n).max(1);
    let j = offset as usize % stride;
    out.extend(all.iter().skip(j).step_by(stride).take(n));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every ray at and above the full factor, at least one below, and only
    /// divisors of the sample count in between.
    #[test]
    fn rays_are_divisors_in_proportion() {
        assert_eq!(rays_for(32, 1.0, 0.0), 32);
        assert_eq!(rays_for(32, 2.0, 1.0), 32);
        assert_eq!(rays_for(32, 1.0, 1.0), 32);
        assert_eq!(rays_for(32, 0.5, 1.0), 16);
        assert_eq!(rays_for(32, 0.3, 1.0), 16); // 9.6 → 16
        assert_eq!(rays_for(32, 0.2, 1.0), 8); // 6.4 → 8
        assert_eq!(rays_for(32, 1e-9, 1.0), 1);
        assert_eq!(rays_for(24, 0.2, 1.0), 6); // 4.8 → 6
        assert_eq!(rays_for(7, 0.5, 1.0), 7); // a prime keeps every ray
        assert_eq!(rays_for(7, 0.01, 1.0), 1);
        assert_eq!(rays_for(1, 0.01, 1.0), 1);
        assert_eq!(rays_for(8, f64::NAN, 1.0), 8);
    }

    /// A strided subset takes one point from each block of s, at the offset.
    #[test]
    fn strided_subsets_take_one_point_a_block() {
        let all: Vec<DVec3> = (0..8).map(|i| DVec3::splat(i as f64)).collect();
        let mut out = Vec::new();
        strided(&all, 2, 3, &mut out);
        assert_eq!(out, vec![DVec3::splat(3.0), DVec3::splat(7.0)]);
        strided(&all, 8, 5, &mut out);
        assert_eq!(out, all);
        strided(&all, 1, 13, &mut out);
        assert_eq!(out, vec![DVec3::splat(5.0)]);
    }

    /// The full factor scales with the level (prior plus reflected ambient)
    /// and inversely with the shot's gain; no light yet means every ray.
    #[test]
    fn the_full_factor_follows_the_level() {
        let share = RayShare::new(0.01, DVec3::splat(0.1)).expect("on");
        let kd = DVec3::splat(0.5);
        let f = share.full_factor(DVec3::splat(1.0), kd, DVec3::splat(2.0));
        assert!((f - 0.01 * 1.05 / 1.0).abs() < 1e-15, "{f}");
        let none = RayShare::new(0.01, DVec3::ZERO).expect("on");
        assert_eq!(none.full_factor(DVec3::ZERO, kd, DVec3::ONE), 0.0);
        assert_eq!(share.full_factor(DVec3::ONE, kd, DVec3::ZERO), 0.0);
        assert!(RayShare::new(0.0, DVec3::ONE).is_none());
    }
}
