//! Textured surfaces in the global-cube gather: the E/π representation and
//! the ∫ρE reflection of the other solves (`solve/textured.rs`), on the
//! cube's fixed mesh.
//!
//! A surface with a diffuse texture and UVs stores per vertex its incident
//! light E/π (irradiance over π), which does not depend on the texture: a
//! diffuse vertex's one RGB value is E/π (emission is not in it), a glossy
//! vertex keeps three more values after its cube, and its cube holds only
//! the untextured part (emission and the glossy lobe of its Ks).
//!
//! A textured patch reflects its integral of ρ · E/π over its area, with
//! ρ = Kd ⊙ texture(uv): the progressive solver's RGB gather weights
//! w_u = Kd ⊙ ∫ ρ λ_u dA over the patch's display triangles (each integrated
//! exactly over its UV triangle at the mip level [`crate::texture`] picks),
//! divided by the patch's area, so its radiance toward a receiver is
//!
//!   L_s = Le_s + Σ_u (w_u / A_s) ⊙ E_u/π  (+ its vertices' glossy cubes),
//!
//! exactly ∫ ρ E/π dA / A_s for E interpolated linearly, as displayed. Each
//! patch so reflects what its own texels reflect, not the texture's mean.
//!
//! **Error bounds.** The unknowns now mix radiance and E/π, which a patch
//! turns into radiance through weights that do not sum to 1. The sweep's
//! change, the convergence test and γ are therefore measured in a weighted
//! ∞-norm: an E/π value of vertex u counts times its scale c_u, the largest
//! ratio of its RGB to its area weight over its patches and channels (an
//! upper bound on the reflectance of the texels next to it). Then a textured
//! source's RGB part is at most 1 in that norm (w_u ≤ c_u × u's area weight),
//! and a textured receiver's row is c_v Σ F. A glossy textured source counts
//! its cube and its E/π part separately (a gain up to 2), so scenes with
//! glossy textured surfaces can report γ ≥ 1 and an infinite bound.

use crate::mesh::Mesh;
use crate::solve::Solver;
use glam::DVec3;

/// What a textured vertex carries besides its values.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct VertexTexture {
    /// The mean reflectance of the texels around the vertex: its RGB gather
    /// weights over its area weights, summed over its patches. The display
    /// of a cube batch, which cannot be textured, and the power sums use it.
    pub reflectance: DVec3,
    /// c_v of the module notes: the largest RGB-to-area weight ratio over
    /// the vertex's patches and channels.
    pub scale: f64,
    /// Its surface's emission, which a diffuse textured vertex's value does
    /// not hold.
    pub emission: DVec3,
}

/// The textured part of a cube solve: empty vectors when no surface is
/// textured, so an untextured solve holds nothing more.
#[derive(Clone, Debug, Default)]
pub(super) struct CubeTexturing {
    /// Per patch: its RGB gather weights over its area (empty for an
    /// untextured patch).
    pub patch_weights: Vec<Vec<(u32, DVec3)>>,
    /// Per patch: its gain in the weighted norm (module notes): Σ_u w_u / (A
    /// c_u), largest channel, plus 1 when its vertices also carry cubes.
    pub patch_gain: Vec<f64>,
    /// Per vertex: `Some` on a textured surface.
    pub vertices: Vec<Option<VertexTexture>>,
}

impl CubeTexturing {
    /// The textured patches and vertices of `solver`'s mesh (`glossy`: per
    /// surface, whether it stores cubes; `emission`: per surface, its Le).
    pub fn new(solver: &Solver, glossy: &[bool], emission: &[DVec3]) -> CubeTexturing {
        let mesh = solver.mesh();
        if !solver.texturing.any() || solver.patch_rgb_weights.is_empty() {
            return CubeTexturing::default();
        }
        let n = mesh.vertices.len();
        let mut rgb_sum = vec![DVec3::ZERO; n];
        let mut area_sum = vec![0.0; n];
        let mut scale = vec![0.0f64; n];
        let mut patch_weights = Vec::with_capacity(mesh.patches.len());
        for p in 0..mesh.patches.len() {
            let rgb = &solver.patch_rgb_weights[p];
            let area = solver.patch_weights(p as u32);
            let total: f64 = area.iter().map(|e| e.1).sum();
            if rgb.is_empty() || total <= 0.0 {
                patch_weights.push(Vec::new());
                continue;
            }
            // Both lists are merged per vertex in vertex order, from the same
            // display triangles.
            for &(v, w) in rgb {
                let a = area
                    .binary_search_by_key(&v, |e| e.0)
                    .map_or(0.0, |k| area[k].1);
                rgb_sum[v as usize] += w;
                area_sum[v as usize] += a;
                if a > 0.0 {
                    scale[v as usize] = scale[v as usize].max(w.max_element() / a);
                }
            }
            patch_weights.push(rgb.iter().map(|&(v, w)| (v, w / total)).collect());
        }
        let vertices: Vec<Option<VertexTexture>> = (0..n)
            .map(|v| {
                let surface = mesh.vertices[v].surface;
                solver.texturing.get(surface)?;
                let reflectance = if area_sum[v] > 0.0 {
                    rgb_sum[v] / area_sum[v]
                } else {
                    DVec3::ZERO
                };
                Some(VertexTexture {
                    reflectance,
                    scale: scale[v],
                    emission: emission[surface as usize],
                })
            })
            .collect();
        let patch_gain = patch_weights
            .iter()
            .enumerate()
            .map(|(p, w)| {
                if w.is_empty() {
                    return 1.0;
                }
                let mut gain = DVec3::ZERO;
                for &(u, w) in w {
                    let c = vertices[u as usize].map_or(0.0, |t| t.scale);
                    if c > 0.0 {
                        gain += w / c;
                    }
                }
                let cubes = glossy[mesh.patches[p].surface as usize];
                gain.max_element() + if cubes { 1.0 } else { 0.0 }
            })
            .collect();
        CubeTexturing {
            patch_weights,
            patch_gain,
            vertices,
        }
    }

    /// Vertex `v`'s texturing, if it is on a textured surface.
    pub fn vertex(&self, v: u32) -> Option<&VertexTexture> {
        self.vertices.get(v as usize)?.as_ref()
    }

    /// Patch `p`'s RGB weights over its area, if it is textured.
    pub fn patch(&self, p: u32) -> Option<&[(u32, DVec3)]> {
        let w = self.patch_weights.get(p as usize)?;
        (!w.is_empty()).then_some(w.as_slice())
    }

    /// Patch `p`'s gain in the weighted norm (1 for an untextured patch).
    pub fn gain(&self, p: u32) -> f64 {
        self.patch_gain.get(p as usize).copied().unwrap_or(1.0)
    }

    /// The largest of vertex `v`'s `values` in the sweep's norm: c_v times
    /// its E/π values, its radiance values as they are.
    pub fn largest(&self, v: u32, values: &[f64]) -> f64 {
        let largest = |x: &[f64]| x.iter().fold(0.0f64, |m, &x| m.max(x.abs()));
        match self.vertex(v) {
            Some(t) => {
                let cells = values.len() - 3;
                largest(&values[..cells]).max(t.scale * largest(&values[cells..]))
            }
            None => largest(values),
        }
    }

    /// Bytes held per textured vertex and RGB weight entry, for the memory
    /// estimate.
    pub fn bytes(mesh: &Mesh, entries: u64) -> u128 {
        let vertex = std::mem::size_of::<Option<VertexTexture>>() as u128;
        let entry = std::mem::size_of::<(u32, DVec3)>() as u128;
        mesh.vertices.len() as u128 * vertex + entries as u128 * entry
    }
}

/// E/π of a textured vertex from its values: the last three (its one RGB
/// value when diffuse, the three after its cube when glossy).
pub(super) fn irradiance_over_pi(values: &[f64]) -> DVec3 {
    DVec3::from_slice(&values[values.len() - 3..])
}
