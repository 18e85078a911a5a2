//! Immel, Cohen and Greenberg's (1986) global cube (“A Radiosity Method for Non-Diffuse Environments”, `shared/seeds/001`): a vertex's
//! outgoing radiance stored on D = 6k² fixed directions, the centres of a k × k grid
//! of cells on each face of the cube [−1, 1]³ in the vertex's local frame, and looked
//! up toward the eye by bilinear interpolation between the four nearest cell centres.
//!
//! The basis is the one `docs/solution-format.md` defines for `basis_convention` 2:
//! faces in the order +x, −x, +y, −y, +z, −z; on the face of axis a with sign s the
//! in-face axes are (u, v) = (y, z), (z, x), (x, y) for a = x, y, z; cell (i, j) (row i
//! along v, column j along u) points along normalize(s·e_a + u_j·e_u + v_i·e_v) with
//! u_j = −1 + (2j+1)/k, v_i = −1 + (2i+1)/k; its index is (face·k + i)·k + j. Local
//! frames are the SH ones ([`crate::sh::to_local`]): x = t, y = b, z = n.
//!
//! Lookup (what the runtime's vertex shader and the CPU reference both do): the face
//! is the axis of largest |component| (ties go to x, then y, then z, so the choice is
//! the same in f32 and f64 for every direction not on a tie), the direction is
//! projected onto that face, and its continuous cell coordinate
//! x = (u + 1)·k/2 − ½ is clamped to [0, k − 1]: inside a face the four nearest cell
//! centres are blended bilinearly; within half a cell of a face edge the value is
//! held at the border cells' (no blending across faces, which keeps the shader a
//! handful of instructions; the error it adds is bounded by the radiance change over
//! half a cell, the same order as the bilinear error itself).
//!
//! The solver fills cubes, the runtime and the CPU
//! reference renderer read them.

use glam::{DVec3, Vec3};

/// Largest cells-per-face edge a solution file may declare (the format caps it).
pub const MAX_RESOLUTION: u32 = 1024;

/// Number of directions D = 6k² of a cube with `k` cells along a face edge.
pub fn direction_count(k: u32) -> u64 {
    6 * u64::from(k) * u64::from(k)
}

/// The `k ≥ 1` with 6k² = `directions`, if there is one. Not capped: the format
/// reader compares it with [`MAX_RESOLUTION`] itself, to name the right problem.
pub fn resolution_from_directions(directions: u32) -> Option<u32> {
    if directions == 0 || !directions.is_multiple_of(6) {
        return None;
    }
    let squared = directions / 6;
    let k = (f64::from(squared)).sqrt().round() as u32;
    (k.checked_mul(k) == Some(squared)).then_some(k)
}

/// Axis index (0 = x, 1 = y, 2 = z) and sign of face `face` (0..6).
fn face_axis(face: u32) -> (usize, f64) {
    (
        (face / 2) as usize,
        if face.is_multiple_of(2) { 1.0 } else { -1.0 },
    )
}

/// The in-face axes (u, v) of the face with normal axis `axis`.
fn in_face_axes(axis: usize) -> (usize, usize) {
    match axis {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    }
}

/// Centre of cell `c` along a face edge of `k` cells, in [−1, 1].
fn cell_centre(k: u32, c: u32) -> f64 {
    -1.0 + (2.0 * f64::from(c) + 1.0) / f64::from(k)
}

/// Unit direction (local frame) of cell `index` of a cube of resolution `k`.
///
/// # Panics
/// If `k` is 0 or `index ≥ 6k²` (callers iterate over `0..direction_count(k)`).
pub fn cell_direction(k: u32, index: u32) -> DVec3 {
    assert!(k >= 1 && u64::from(index) < direction_count(k));
    let j = index % k;
    let i = (index / k) % k;
    let face = index / (k * k);
    let (axis, sign) = face_axis(face);
    let (ua, va) = in_face_axes(axis);
    let mut d = [0.0; 3];
    d[axis] = sign;
    d[ua] = cell_centre(k, j);
    d[va] = cell_centre(k, i);
    DVec3::from(d).normalize()
}

/// Solid angle (sr) subtended by cell `index`: the exact integral of
/// dΩ = du dv / (1 + u² + v²)^{3/2} over the cell's square on the face, by its
/// antiderivative atan(uv / √(1 + u² + v²)). The 6k² cells sum to 4π (to ~1e-13).
pub fn cell_solid_angle(k: u32, index: u32) -> f64 {
    assert!(k >= 1 && u64::from(index) < direction_count(k));
    let j = index % k;
    let i = (index / k) % k;
    let edge = |c: u32| -1.0 + 2.0 * f64::from(c) / f64::from(k);
    let (u0, u1, v0, v1) = (edge(j), edge(j + 1), edge(i), edge(i + 1));
    let f = |u: f64, v: f64| (u * v / (1.0 + u * u + v * v).sqrt()).atan();
    f(u1, v1) - f(u0, v1) - f(u1, v0) + f(u0, v0)
}

/// Defines a bilinear lookup for one float width. The f64 version is the reference;
/// the f32 one is written the way `shaders/scene_cube.vert` computes it, so that tests
/// can bound the GPU's rounding against it. One body serves both so they cannot
/// drift apart.
macro_rules! define_bilinear {
    ($(#[$doc:meta])* $name:ident, $float:ty, $vec:ty) => {
        $(#[$doc])*
        ///
        /// # Panics
        /// If `k` is 0.
        pub fn $name(k: u32, dir: $vec) -> [(u32, $float); 4] {
            assert!(k >= 1);
            // A zero or non-finite direction looks along the local normal (+z), as
            // SH evaluation does.
            let dir = if dir.abs().max_element() > 0.0 && dir.is_finite() {
                dir
            } else {
                <$vec>::Z
            };
            // The face: the axis of largest |component|, ties to x, then y, then z.
            let a = dir.abs();
            let axis = if a.x >= a.y && a.x >= a.z {
                0
            } else if a.y >= a.z {
                1
            } else {
                2
            };
            let d = dir.to_array();
            let major = d[axis];
            let face = axis as u32 * 2 + u32::from(major < 0.0);
            let (ua, va) = in_face_axes(axis);
            let inv = 1.0 / major.abs();
            // One axis: the lower cell, the upper cell and the weight of the upper
            // one, the continuous coordinate clamped to the border cells.
            let kf = k as $float;
            let cells = |u: $float| {
                let x = ((u + 1.0) * 0.5 * kf - 0.5).clamp(0.0, kf - 1.0);
                let lower = (x.floor() as u32).min(k.saturating_sub(2));
                let upper = (lower + 1).min(k - 1);
                (lower, upper, x - lower as $float)
            };
            let (j0, j1, fu) = cells(d[ua] * inv);
            let (i0, i1, fv) = cells(d[va] * inv);
            let index = |i: u32, j: u32| (face * k + i) * k + j;
            [
                (index(i0, j0), (1.0 - fu) * (1.0 - fv)),
                (index(i0, j1), fu * (1.0 - fv)),
                (index(i1, j0), (1.0 - fu) * fv),
                (index(i1, j1), fu * fv),
            ]
        }
    };
}

define_bilinear!(
    /// The four cells nearest `dir` (local frame) and their bilinear weights, which
    /// sum to 1. At a cell centre the weight of that cell is 1.
    bilinear,
    f64,
    DVec3
);

define_bilinear!(
    /// The f32 twin of [`bilinear`], the shader's arithmetic.
    bilinear_f32,
    f32,
    Vec3
);

/// RGB radiance toward `dir` (local frame) from one vertex's cube values, laid out
/// `values[d * 3 + c]` as in a solution batch. Cells beyond the slice count as zero
/// (a malformed batch cannot panic here; the format reader checks sizes first).
pub fn eval_rgb(k: u32, values: &[f32], dir: DVec3) -> [f64; 3] {
    let mut rgb = [0.0; 3];
    for (index, weight) in bilinear(k, dir) {
        if weight == 0.0 {
            continue;
        }
        let base = index as usize * 3;
        if let Some(cell) = values.get(base..base + 3) {
            for (out, &value) in rgb.iter_mut().zip(cell) {
                *out += weight * f64::from(value);
            }
        }
    }
    rgb
}

#[cfg(test)]
mod tests;
