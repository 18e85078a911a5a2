//! Hidden vertices in directional output: the SH form of
//! [`crate::solve::hidden::fill_hidden`].
//!
//! A hidden vertex (under a block, above a hanging light; see
//! `solve/hidden.rs`) receives nothing, so its radiance coefficients stay at
//! zero. Drawn as they are, every element that straddles a contact line
//! interpolates toward that dark inside, for every direction the SH is
//! evaluated in: on a glossy floor the rim round a block's base shows from
//! every eye. So a hidden vertex is shown with the mean of its known
//! neighbours' coefficient vectors, ring by ring outward from the visible
//! ones, exactly as the diffuse output does with its radiance.
//!
//! Averaging coefficient vectors is averaging the radiance functions they
//! stand for (SH evaluation is linear), which is meaningful only within one
//! frame: a display triangle lies in one polygon, and every vertex of a
//! polygon shares its surface's order and frame (module documentation of
//! `directional.rs`, "Frames on smooth surfaces"), so neighbours along the
//! display triangles always agree; a neighbour whose block has another
//! length is skipped all the same, so that no two frames are ever mixed.

use std::ops::Range;

/// The coefficients to display: `values` (per vertex `v` the block
/// `range(v)`), except at hidden vertices, which take the mean of their
/// already-known neighbours' blocks along the display `triangles`, ring by
/// ring outward from the visible ones. A vertex with no path to a visible one
/// keeps its own block. For order-0 blocks this is `fill_hidden` on c₀₀.
pub fn fill_hidden_coefficients(
    triangles: &[[u32; 3]],
    hidden: &[bool],
    vertex_count: usize,
    range: impl Fn(usize) -> Range<usize>,
    values: &[f64],
) -> Vec<f64> {
    let mut value = values.to_vec();
    if !hidden.iter().any(|&h| h) {
        return value;
    }
    let mut known: Vec<bool> = (0..vertex_count)
        .map(|v| !hidden.get(v).copied().unwrap_or(false))
        .collect();
    let mut sum = vec![0.0; values.len()];
    let mut count = vec![0u32; vertex_count];
    loop {
        for t in triangles {
            for (i, &a) in t.iter().enumerate() {
                let a = a as usize;
                if known[a] {
                    continue;
                }
                let into = range(a);
                for &b in [t[(i + 1) % 3], t[(i + 2) % 3]].iter() {
                    let b = b as usize;
                    let from = range(b);
                    if !known[b] || from.len() != into.len() {
                        continue;
                    }
                    for (s, x) in sum[into.clone()].iter_mut().zip(&value[from]) {
                        *s += x;
                    }
                    count[a] += 1;
                }
            }
        }
        let mut filled = false;
        for v in 0..vertex_count {
            if count[v] == 0 {
                continue;
            }
            let n = count[v] as f64;
            let block = range(v);
            for (x, s) in value[block.clone()].iter_mut().zip(&mut sum[block]) {
                *x = *s / n;
                *s = 0.0;
            }
            known[v] = true;
            count[v] = 0;
            filled = true;
        }
        if !filled {
            return value;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solve::hidden::fill_hidden;
    use glam::DVec3;

    /// The strip of `hidden.rs`'s fill test:
    ///   0 - 1 - 2 - 3
    ///   |   |   |   |
    ///   4 - 5 - 6 - 7   (0 and 4 visible)
    const TRIS: [[u32; 3]; 6] = [
        [0, 4, 5],
        [0, 5, 1],
        [1, 5, 6],
        [1, 6, 2],
        [2, 6, 7],
        [2, 7, 3],
    ];
    const HIDDEN: [bool; 8] = [false, true, true, true, false, true, true, true];

    #[test]
    fn order_zero_blocks_fill_as_the_diffuse_output() {
        // A consistency check against `fill_hidden` (the same ring rule on
        // RGB radiance): on order-0 blocks the two must agree to rounding.
        let radiance: Vec<DVec3> = (0..8)
            .map(|v| DVec3::new(1.0 + v as f64, 0.5 * v as f64, 2.0 - 0.1 * v as f64))
            .collect();
        let flat: Vec<f64> = radiance.iter().flat_map(|l| l.to_array()).collect();
        let shown = fill_hidden_coefficients(&TRIS, &HIDDEN, 8, |v| 3 * v..3 * v + 3, &flat);
        let expected = fill_hidden(&TRIS, &HIDDEN, &radiance);
        for v in 0..8 {
            let got = DVec3::from_slice(&shown[3 * v..3 * v + 3]);
            assert!((got - expected[v]).abs().max_element() < 1e-12, "{v}");
        }
    }

    #[test]
    fn higher_order_blocks_average_every_coefficient() {
        // Blocks of 12 values (order 1, RGB): the visible vertices carry
        // distinct functions; each hidden vertex's block is the same mean of
        // them for every coefficient, so evaluating it in any direction gives
        // the mean of the neighbours' radiance in that direction.
        let block = |v: usize| 12 * v..12 * v + 12;
        let mut values = vec![0.0; 96];
        for k in 0..12 {
            values[k] = 1.0 + k as f64; // vertex 0
            values[48 + k] = 2.0 * k as f64 - 3.0; // vertex 4
        }
        let shown = fill_hidden_coefficients(&TRIS, &HIDDEN, 8, block, &values);
        for k in 0..12 {
            let (a, b) = (values[k], values[48 + k]);
            // Ring 1: vertex 1 sees only 0; vertex 5 sees 0 twice and 4 once.
            assert_eq!(shown[12 + k], a);
            assert!((shown[60 + k] - (2.0 * a + b) / 3.0).abs() < 1e-12);
            // Visible blocks are untouched.
            assert_eq!(shown[k], a);
            assert_eq!(shown[48 + k], b);
        }
        // Nothing hidden: the values unchanged.
        assert_eq!(
            fill_hidden_coefficients(&TRIS, &[false; 8], 8, block, &values),
            values
        );
    }

    #[test]
    fn neighbours_of_another_order_are_skipped() {
        // Vertex 1 (hidden, order 1) touches 0 (order 0) and 5 (hidden,
        // order 1), which touches 4 (order 1, visible): it must take 4's
        // block through 5, never a 3-value block read as 12.
        let ranges = [0..3, 3..15, 15..18, 18..21, 21..33, 33..45, 45..48, 48..51];
        let mut values = vec![7.0; 51];
        values[3..15].fill(0.0);
        values[33..45].fill(0.0);
        for (k, x) in values[21..33].iter_mut().enumerate() {
            *x = k as f64;
        }
        let hidden = [false, true, false, false, false, true, false, false];
        let shown = fill_hidden_coefficients(&TRIS, &hidden, 8, |v| ranges[v].clone(), &values);
        assert_eq!(&shown[33..45], &values[21..33]);
        assert_eq!(&shown[3..15], &values[21..33]);
    }
}
