//! Directional output across contact cuts: the SH form of the diffuse
//! output's seam pass (`solve/seams.rs`) for the pieces that `mesh::contact`
//! cuts a receiver into.
//!
//! Each visible piece of a cut receiver is a surface of its own, refined on
//! its own, so along a cut both sides have their own vertices (same position)
//! and a vertex of one side can lie inside an edge of the other side's
//! display triangle (a T-junction, which shows as a step in value). The
//! pieces of one polygon share its frame (normal and tangent, set once per
//! polygon by `Mesh::with_contacts`), its material and hence its SH order, so
//! their coefficient vectors stand for radiance functions in one frame and may
//! be averaged: coincident vertices become one output vertex carrying the
//! area-weighted mean of their blocks (averaging coefficient vectors averages
//! the radiance functions; weights as the diffuse pass's, a third or a quarter
//! of each leaf element with the vertex as a corner), and each T-junction is
//! resolved by fanning the triangle to the vertices on its edge.
//!
//! Vertices of different polygons never merge, even on one smooth surface:
//! their frames differ (`directional.rs`, "Frames on smooth surfaces"), and
//! each keeps its own vertex as before.

use crate::mesh::Mesh;
use crate::solve::seams::{share_vertices_within_polygons, vertex_weights, SharedVertices};
use std::ops::Range;

/// The output vertices of directional mode and their coefficients: per
/// output vertex `o`, the weighted mean of the blocks (`range(v)` of
/// `values`) of the mesh vertices merged into it, in the layout of `values`
/// at its representative's block (other blocks are left as they were).
/// `values` is taken and changed in place: a copy of every coefficient would
/// add 8 bytes a coefficient to the output's peak (`budget.rs`, "output").
pub(super) fn share_coefficients(
    mesh: &Mesh,
    range: impl Fn(usize) -> Range<usize>,
    values: Vec<f64>,
) -> (SharedVertices, Vec<f64>) {
    let shared = share_vertices_within_polygons(mesh);
    let merged = mean_blocks(
        &shared.output_of,
        &shared.representative,
        &vertex_weights(mesh),
        range,
        values,
    );
    (shared, merged)
}

/// `values` with each representative's block replaced by the weighted mean of
/// the blocks of every vertex mapped to its output vertex (every mean is
/// summed before any block is written, so changing `values` in place is safe). A block whose
/// length differs from the representative's is skipped (never the case for
/// pieces of one polygon; kept so that no two layouts are ever mixed).
fn mean_blocks(
    output_of: &[u32],
    representative: &[u32],
    weight: &[f64],
    range: impl Fn(usize) -> Range<usize>,
    mut values: Vec<f64>,
) -> Vec<f64> {
    // Only outputs that gathered more than one vertex change.
    let mut members = vec![0u32; representative.len()];
    for &o in output_of {
        members[o as usize] += 1;
    }
    if members.iter().all(|&m| m <= 1) {
        return values;
    }
    let mut sum: Vec<Vec<f64>> = vec![Vec::new(); representative.len()];
    let mut total = vec![0.0; representative.len()];
    for (v, &o) in output_of.iter().enumerate() {
        let o = o as usize;
        if members[o] <= 1 {
            continue;
        }
        let into = range(representative[o] as usize);
        let from = range(v);
        if from.len() != into.len() {
            continue;
        }
        // A vertex no leaf has as a corner still counts, a little.
        let w = weight[v].max(f64::MIN_POSITIVE);
        let s = &mut sum[o];
        if s.is_empty() {
            s.resize(into.len(), 0.0);
        }
        for (acc, x) in s.iter_mut().zip(&values[from]) {
            *acc += w * x;
        }
        total[o] += w;
    }
    for (o, s) in sum.iter().enumerate() {
        if s.is_empty() {
            continue;
        }
        let into = range(representative[o] as usize);
        for (x, acc) in values[into].iter_mut().zip(s) {
            *x = acc / total[o];
        }
    }
    values
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merged_blocks_are_the_weighted_mean_of_every_coefficient() {
        // Vertices 0 and 2 merge into output 0 (weights 1 and 3), vertex 1
        // is alone; blocks of 4 values. The mean is taken per coefficient,
        // so it is the mean of the radiance functions in every direction.
        let block = |v: usize| 4 * v..4 * v + 4;
        let values: Vec<f64> = (0..12).map(|k| k as f64).collect();
        let merged = mean_blocks(&[0, 1, 0], &[0, 1], &[1.0, 5.0, 3.0], block, values.clone());
        for k in 0..4 {
            let expected = (values[k] + 3.0 * values[8 + k]) / 4.0;
            assert!((merged[k] - expected).abs() < 1e-12, "{k}");
            // The lone vertex and the non-representative block are untouched.
            assert_eq!(merged[4 + k], values[4 + k]);
            assert_eq!(merged[8 + k], values[8 + k]);
        }
    }

    #[test]
    fn blocks_of_another_length_are_never_mixed() {
        // Vertex 1 (a 3-value block) maps to the same output as vertex 0 (a
        // 12-value block): it must be skipped, leaving vertex 0's block.
        let ranges = [0..12, 12..15];
        let values: Vec<f64> = (0..15).map(|k| 1.0 + k as f64).collect();
        let merged = mean_blocks(
            &[0, 0],
            &[0],
            &[1.0, 1.0],
            |v| ranges[v].clone(),
            values.clone(),
        );
        assert_eq!(merged, values);
    }
}
