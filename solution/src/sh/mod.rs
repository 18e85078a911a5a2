//! Real spherical harmonics in a vertex's local frame: the basis every directional
//! radiance in the solution file is expanded in (design notes, "Local frames and SH").
//!
//! Convention (fixed by the solution format):
//!
//! * real, orthonormal on the unit sphere: `∫ Y_lm Y_l'm' dω = δ_ll' δ_mm'`;
//! * index `k = l² + l + m` ([`index`]); `(L + 1)²` functions up to order `L`;
//! * `m < 0` are sine terms, `m > 0` cosine terms, **no Condon–Shortley phase**:
//!   `Y_1,−1 = √(3/4π)·y`, `Y_1,0 = √(3/4π)·z`, `Y_1,1 = √(3/4π)·x`;
//! * directions are in the vertex frame: `z` = normal n, `x` = tangent t,
//!   `y` = b = n × t; θ is measured from n and φ from t toward b.
//!
//! Explicitly, with `P̄_lm` the associated Legendre function normalised so that
//! `Y_l0 = P̄_l0(cos θ)`:
//!
//! ```text
//! Y_lm = √2 · P̄_lm(cos θ) · cos(mφ)    m > 0
//! Y_l0 =      P̄_l0(cos θ)
//! Y_lm = √2 · P̄_l|m|(cos θ) · sin(|m|φ) m < 0
//! ```
//!
//! **How it is computed.** Remington 1992 (App. G) builds `Y_lm` from factorial ratios
//! `d_lm = 2(l−m)!/(l+m)!`, which overflow f32 at 35! and f64 at 171!. Here the
//! normalisation is folded into the recurrences instead, and the factor `sin^m θ` is
//! kept together with `e^{imφ}` as `(x + iy)^m = sin^m θ · e^{imφ}`, so that
//!
//! * `Q_mm = √((2m+1)/(2m)) · Q_{m−1,m−1}`, `Q_00 = 1/√(4π)`;
//! * `Q_{m+1,m} = √(2m+3) · z · Q_mm`;
//! * `Q_lm = a_lm (z Q_{l−1,m} − b_lm Q_{l−2,m})`, `a_lm = √((4l²−1)/(l²−m²))`,
//!   `b_lm = √(((l−1)²−m²)/(4(l−1)²−1))`;
//! * `C_m + i S_m = (x + iy)^m` by `C_{m+1} = x C_m − y S_m`, `S_{m+1} = x S_m + y C_m`;
//!
//! with `P̄_lm = Q_lm sin^m θ` and `Y_l,±m = √2 · Q_lm · (C_m | S_m)`. `Q_lm` is a
//! polynomial in `z`, so there is no division by `sin θ` and the poles are ordinary
//! points. The forward recurrence in `l` is the standard stable one. `Q_lm` is
//! largest at the poles, where it is `√((2l+1)/(4π)) · √((l+m)!/(l−m)!)/(2^m m!)`:
//! at most 1e4.7 at `l = 25`, 1e12.9 at `l = 64`, 1e20.4 at `l = 100` — far inside
//! the f64 range and inside f32's up to `l ≈ 190`. `sin^m θ` simply underflows to 0
//! near the poles, where the true value is below 1e-300.
//!
//! **Precision.** f64 evaluation agrees with the closed forms to 1e-12 and satisfies
//! orthonormality and the addition theorem to 1e-10 up to `L = 64` (tests below).
//! [`eval_basis_f32`] repeats the same recurrences in f32, as the vertex shader does;
//! [`f32_basis_tolerance`] bounds its difference from f64.

mod legendre;

pub use legendre::{gauss_legendre, gauss_legendre_on, legendre_all, legendre_with_derivative};

use glam::{DVec3, Vec3};
use std::f64::consts::PI;
use std::sync::OnceLock;

/// Index of `Y_lm` in a coefficient vector: `l² + l + m`, for `|m| ≤ l`.
#[inline]
pub fn index(l: u32, m: i32) -> usize {
    debug_assert!(
        m.unsigned_abs() <= l,
        "sh::index: |m| = {} > l = {l}",
        m.abs()
    );
    let l = l as i64;
    (l * l + l + m as i64) as usize
}

/// Inverse of [`index`]: the `(l, m)` of coefficient `k`.
pub fn degree_order(k: usize) -> (u32, i32) {
    let mut l = (k as f64).sqrt() as usize;
    // Correct a possible off-by-one of the floating square root.
    while l * l > k {
        l -= 1;
    }
    while (l + 1) * (l + 1) <= k {
        l += 1;
    }
    (l as u32, (k - l * l) as i32 - l as i32)
}

/// Number of coefficients (per channel) up to order `order` inclusive: `(L + 1)²`.
#[inline]
pub fn coefficient_count(order: u32) -> usize {
    let n = order as usize + 1;
    n * n
}

/// Orders up to this one share one cached table of recurrence factors (about
/// 130 KB); higher orders compute the factors on the fly.
const CACHED_ORDER: u32 = 128;

/// Recurrence factors `(a_lm, b_lm)` for `0 ≤ m ≤ l`, at `l(l+1)/2 + m`. For `l = m`
/// the entry holds the diagonal factor `√((2m+1)/(2m))` (1 for m = 0) and for
/// `l = m + 1` the factor `√(2m+3)`; `b` is unused there.
fn factor_table() -> &'static [(f64, f64)] {
    static TABLE: OnceLock<Vec<(f64, f64)>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let n = CACHED_ORDER as usize + 1;
        let mut t = vec![(0.0, 0.0); n * (n + 1) / 2];
        for l in 0..=CACHED_ORDER {
            for m in 0..=l {
                t[tri(l, m)] = factors(l, m);
            }
        }
        t
    })
}

#[inline]
fn tri(l: u32, m: u32) -> usize {
    let l = l as usize;
    l * (l + 1) / 2 + m as usize
}

/// The recurrence factors of one `(l, m)`, `m ≤ l` (see [`factor_table`]).
#[inline]
fn factors(l: u32, m: u32) -> (f64, f64) {
    let (lf, mf) = (l as f64, m as f64);
    if l == m {
        if m == 0 {
            (1.0, 0.0)
        } else {
            (((2.0 * mf + 1.0) / (2.0 * mf)).sqrt(), 0.0)
        }
    } else if l == m + 1 {
        ((2.0 * mf + 3.0).sqrt(), 0.0)
    } else {
        let a = ((4.0 * lf * lf - 1.0) / (lf * lf - mf * mf)).sqrt();
        let l1 = lf - 1.0;
        let b = ((l1 * l1 - mf * mf) / (4.0 * l1 * l1 - 1.0)).sqrt();
        (a, b)
    }
}

/// `1/√(4π)`: `Y_00`, the value of a constant function's basis.
pub const Y00: f64 = 0.282_094_791_773_878_14;

/// Evaluates every `Y_lm` with `l ≤ order` at the local direction `dir`, writing
/// `out[index(l, m)]`.
///
/// `dir` need not be exactly unit length: it is normalised first (a zero or
/// non-finite direction is treated as the normal, +z, so the output is always
/// finite). Valid and finite for any order the caller can allocate; tested to 100.
///
/// # Panics
/// If `out.len() < coefficient_count(order)` (a programming error).
pub fn eval_basis(order: u32, dir: DVec3, out: &mut [f64]) {
    let count = coefficient_count(order);
    assert!(
        out.len() >= count,
        "sh::eval_basis: need {count} slots, got {}",
        out.len()
    );
    let d = dir.try_normalize().unwrap_or(DVec3::Z);
    if order <= 16 {
        eval_on_stack::<17>(order, d, out);
    } else if order <= 40 {
        eval_on_stack::<41>(order, d, out);
    } else if order <= CACHED_ORDER {
        eval_on_stack::<{ CACHED_ORDER as usize + 1 }>(order, d, out);
    } else {
        let n = order as usize + 1;
        let mut rows = vec![0.0f64; 4 * n];
        let (c, rest) = rows.split_at_mut(n);
        let (s, rest) = rest.split_at_mut(n);
        let (q1, q2) = rest.split_at_mut(n);
        eval_rows(order, d, factors, c, s, q1, q2, out);
    }
}

/// [`eval_rows`] with its four rows on the stack (`N ≥ order + 1`, a size tier so
/// that a low order does not pay for zeroing rows sized for order 128).
fn eval_on_stack<const N: usize>(order: u32, d: DVec3, out: &mut [f64]) {
    let n = order as usize + 1;
    let mut rows = [[0.0f64; N]; 4];
    let [c, s, q1, q2] = &mut rows;
    let table = factor_table();
    eval_rows(
        order,
        d,
        |l, m| table[tri(l, m)],
        &mut c[..n],
        &mut s[..n],
        &mut q1[..n],
        &mut q2[..n],
        out,
    );
}

/// The recurrences of [`eval_basis`], degree by degree so that each degree's
/// `2l + 1` outputs are written contiguously. `q1`/`q2` hold the rows `l − 1` and
/// `l − 2` of `Q̃_lm` (`Q_lm`, times √2 for m ≥ 1, folded in at the first diagonal
/// step); `c`/`s` hold `(x + iy)^m`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn eval_rows<'q>(
    order: u32,
    d: DVec3,
    fac: impl Fn(u32, u32) -> (f64, f64),
    c: &mut [f64],
    s: &mut [f64],
    mut q1: &'q mut [f64],
    mut q2: &'q mut [f64],
    out: &mut [f64],
) {
    let (x, y, z) = (d.x, d.y, d.z);
    c[0] = 1.0;
    s[0] = 0.0;
    for m in 1..=order as usize {
        c[m] = x * c[m - 1] - y * s[m - 1];
        s[m] = x * s[m - 1] + y * c[m - 1];
    }
    q1[0] = Y00;
    out[0] = Y00;
    for l in 1..=order {
        let lu = l as usize;
        // m ≤ l − 2: the three-term recurrence, written over row l − 2 in place.
        for m in 0..lu.saturating_sub(1) {
            let (a, b) = fac(l, m as u32);
            q2[m] = a * (z * q1[m] - b * q2[m]);
        }
        // m = l − 1 and m = l from the previous diagonal.
        let diag = q1[lu - 1];
        q2[lu - 1] = fac(l, l - 1).0 * z * diag;
        let mut d_fac = fac(l, l).0;
        if l == 1 {
            d_fac *= std::f64::consts::SQRT_2;
        }
        q2[lu] = d_fac * diag;
        std::mem::swap(&mut q1, &mut q2);
        let centre = lu * lu + lu;
        out[centre] = q1[0];
        for m in 1..=lu {
            out[centre + m] = q1[m] * c[m];
            out[centre - m] = q1[m] * s[m];
        }
    }
}

/// The f32 twin of [`eval_basis`]: the same recurrences, every operation in f32,
/// with the recurrence factors computed in f32 per term as a shader loop would
/// (`sqrt` of an f32 quotient of small integers). It exists so that tests can state
/// how far the vertex shader's evaluation may be from the solver's f64 one; see
/// [`f32_basis_tolerance`].
///
/// # Panics
/// If `out.len() < coefficient_count(order)`.
pub fn eval_basis_f32(order: u32, dir: Vec3, out: &mut [f32]) {
    let count = coefficient_count(order);
    assert!(
        out.len() >= count,
        "sh::eval_basis_f32: need {count} slots, got {}",
        out.len()
    );
    let d = dir.try_normalize().unwrap_or(Vec3::Z);
    let (x, y, z) = (d.x, d.y, d.z);
    let sqrt2 = std::f32::consts::SQRT_2;
    let (mut c, mut s) = (1.0_f32, 0.0_f32);
    let mut q_mm = Y00 as f32;
    for m in 0..=order {
        let mf = m as f32;
        if m > 0 {
            q_mm *= ((2.0 * mf + 1.0) / (2.0 * mf)).sqrt();
            let c_next = x * c - y * s;
            s = x * s + y * c;
            c = c_next;
        }
        let mi = m as i32;
        let mut write = |l: u32, q: f32| {
            if m == 0 {
                out[index(l, 0)] = q;
            } else {
                out[index(l, mi)] = sqrt2 * q * c;
                out[index(l, -mi)] = sqrt2 * q * s;
            }
        };
        write(m, q_mm);
        if m == order {
            break;
        }
        let mut q_prev = q_mm;
        let mut q = (2.0 * mf + 3.0).sqrt() * z * q_mm;
        write(m + 1, q);
        for l in m + 2..=order {
            let lf = l as f32;
            let a = ((4.0 * lf * lf - 1.0) / (lf * lf - mf * mf)).sqrt();
            let l1 = lf - 1.0;
            let b = ((l1 * l1 - mf * mf) / (4.0 * l1 * l1 - 1.0)).sqrt();
            let q_next = a * (z * q - b * q_prev);
            q_prev = q;
            q = q_next;
            write(l, q);
        }
    }
}

/// Largest `|Y_lm|` over the sphere for degree `l` is at most `√((2l+1)/(4π))`
/// (Unsöld's theorem: `Σ_m Y_lm² = (2l+1)/(4π)` everywhere).
pub fn envelope(l: u32) -> f64 {
    ((2.0 * l as f64 + 1.0) / (4.0 * PI)).sqrt()
}

/// Relative tolerance of the f32 basis:
/// `|Y_lm^f32(d) − Y_lm^f64(d)| ≤ F32_BASIS_REL_TOLERANCE · (l + 1)² · envelope(l)`
/// where both evaluate the same f32 direction `d` (the f64 path sees it widened).
///
/// Derivation: an f32 direction is unit length only to ~ε = 2⁻²⁴ ≈ 6.0e-8, and
/// normalising it in f32 moves it by ~ε again. `Y_lm` written as a polynomial in
/// `(x, y, z)` has derivatives up to ~`l(l+1)/2 · envelope(l)` per unit of a
/// coordinate (Markov's inequality; `P_l'(1) = l(l+1)/2`), so that input rounding
/// alone changes `Y_lm` by ~`ε · (l+1)²/2 · envelope(l)`, and it dominates the
/// recurrences' own rounding, which grows only linearly in `l` (≈ 5 roundings per
/// step, and the forward recurrence does not amplify them). Measured over 20 000
/// random and special directions up to `L = 32` (test
/// `f32_matches_f64_within_stated_tolerance` prints it per `l`): at most
/// 0.95·ε·(l+1)²·envelope(l), near the poles. The constant is 4ε, a 4× margin that
/// also covers a GLSL `sqrt`/`inversesqrt` of a few ulp and fused multiply–adds.
/// At `L = 25` this is 1.6e-4 of the envelope; at `L = 64`, 1.0e-3; at `L = 100`, 2.4e-3.
pub const F32_BASIS_REL_TOLERANCE: f64 = 4.0 * f32::EPSILON as f64 / 2.0;

/// Absolute tolerance for one f32 basis value of degree `l` (see
/// [`F32_BASIS_REL_TOLERANCE`]). For radiance `Σ c_k Y_k` the shader's error is then
/// at most `Σ_k |c_k| · f32_basis_tolerance(l_k)` plus the f32 rounding of the sum.
pub fn f32_basis_tolerance(l: u32) -> f64 {
    let l1 = l as f64 + 1.0;
    F32_BASIS_REL_TOLERANCE * l1 * l1 * envelope(l)
}

/// Radiance toward local direction `dir` of one vertex's RGB coefficients laid out
/// as in the solution file, `coefficients[k * 3 + c]` (k = SH index, c = channel).
///
/// Coefficients beyond `3 · coefficient_count(order)` are ignored; if the slice is
/// shorter, the missing ones count as zero (so a malformed batch cannot panic here;
/// the format reader checks sizes before this is reached).
pub fn eval_rgb(order: u32, coefficients: &[f32], dir: DVec3) -> [f64; 3] {
    let mut basis = vec![0.0; coefficient_count(order)];
    eval_rgb_with(order, coefficients, dir, &mut basis)
}

/// [`eval_rgb`] with a caller-provided scratch buffer of at least
/// `coefficient_count(order)` values, for loops over many vertices.
///
/// # Panics
/// If `scratch` is too short.
pub fn eval_rgb_with(
    order: u32,
    coefficients: &[f32],
    dir: DVec3,
    scratch: &mut [f64],
) -> [f64; 3] {
    eval_basis(order, dir, scratch);
    let count = coefficient_count(order);
    let mut rgb = [0.0; 3];
    // Chunks of one coefficient's RGB; a short slice simply ends the sum early.
    for (c, y) in coefficients.chunks_exact(3).zip(&scratch[..count]) {
        rgb[0] += f64::from(c[0]) * y;
        rgb[1] += f64::from(c[1]) * y;
        rgb[2] += f64::from(c[2]) * y;
    }
    rgb
}

/// [`eval_rgb`] clamped at zero per channel: what the renderer shows. A truncated
/// glossy lobe rings slightly negative (at most 6.6e-4 of its peak at the default
/// error target, docs/sh-bands.md); clamping never increases the error against the
/// true lobe and adds at most that negative share of light.
pub fn eval_rgb_clamped(order: u32, coefficients: &[f32], dir: DVec3) -> [f64; 3] {
    eval_rgb(order, coefficients, dir).map(|v| v.max(0.0))
}

/// World direction to the local frame `(x, y, z) = (d·t, d·b, d·n)`, `b = n × t`.
///
/// `normal` and `tangent` must be unit length and orthogonal (the solver builds them
/// so; the runtime's f32 frames are orthogonal to ~1e-7, which changes a direction
/// by the same amount). See [`orthonormal_frame`] to repair an approximate frame.
#[inline]
pub fn to_local(dir_world: DVec3, normal: DVec3, tangent: DVec3) -> DVec3 {
    let bitangent = normal.cross(tangent);
    DVec3::new(
        dir_world.dot(tangent),
        dir_world.dot(bitangent),
        dir_world.dot(normal),
    )
}

/// Local direction back to world: `x·t + y·b + z·n`, the inverse of [`to_local`].
#[inline]
pub fn from_local(dir_local: DVec3, normal: DVec3, tangent: DVec3) -> DVec3 {
    let bitangent = normal.cross(tangent);
    tangent * dir_local.x + bitangent * dir_local.y + normal * dir_local.z
}

/// Gram–Schmidt: a unit normal and a unit tangent orthogonal to it, from approximate
/// ones. If `tangent` is (nearly) parallel to `normal`, a tangent is derived from a
/// fixed reference axis (world x, or world y when the normal is near x), the same way
/// everywhere, as the design notes ask for smooth vertices. Returns `None` only for
/// a zero or non-finite normal.
pub fn orthonormal_frame(normal: DVec3, tangent: DVec3) -> Option<(DVec3, DVec3)> {
    let n = normal.try_normalize()?;
    let t = (tangent - n * tangent.dot(n)).try_normalize().filter(|_| {
        // Reject a tangent that lost most of its length to the projection.
        (tangent - n * tangent.dot(n)).length() > 1e-6 * tangent.length()
    });
    let t = match t {
        Some(t) => t,
        None => {
            let reference = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
            (reference - n * reference.dot(n)).try_normalize()?
        }
    };
    Some((n, t))
}

/// SH coefficients of a function symmetric about `axis` (a local unit direction).
///
/// `zonal[l]` are the coefficients of that function when its axis is +z, i.e.
/// `f(ω) = Σ_l zonal[l] · Y_l0(ω)` for axis = z. Rotating the axis to `axis`
/// (addition theorem, `P_l(ω·r) = 4π/(2l+1) Σ_m Y_lm(ω) Y_lm(r)`, with
/// `Y_l0 = √((2l+1)/(4π)) P_l`) gives
///
/// ```text
/// out[index(l, m)] = zonal[l] · √(4π/(2l+1)) · Y_lm(axis)
/// ```
///
/// For the glossy lobe `g(μ0) = Σ a_l P_l(μ0)` (Remington 1992, eq. 4.4) the zonal coefficients
/// are `zonal[l] = a_l · √(4π/(2l+1))`, so `out = a_l · 4π/(2l+1) · Y_lm(r)`, the
/// design notes' `c_lm += ΔE · C_R · a_l · 4π/(2l+1) · Y_lm(r)` once scaled by
/// `ΔE · C_R`. Degrees beyond `zonal.len()` get 0. Overwrites `out[..count]`.
///
/// # Panics
/// If `out.len() < coefficient_count(order)`.
pub fn zonal_rotated(order: u32, zonal: &[f64], axis: DVec3, out: &mut [f64]) {
    eval_basis(order, axis, out);
    for l in 0..=order {
        let z = zonal.get(l as usize).copied().unwrap_or(0.0);
        let scale = z * (4.0 * PI / (2.0 * l as f64 + 1.0)).sqrt();
        for m in -(l as i32)..=(l as i32) {
            out[index(l, m)] *= scale;
        }
    }
}

/// Zonal coefficients `a_l · √(4π/(2l+1))` of a Legendre series `Σ a_l P_l(cos θ)`,
/// ready for [`zonal_rotated`].
pub fn zonal_from_legendre(legendre: &[f64]) -> Vec<f64> {
    legendre
        .iter()
        .enumerate()
        .map(|(l, a)| a * (4.0 * PI / (2.0 * l as f64 + 1.0)).sqrt())
        .collect()
}

#[cfg(test)]
mod tests;
