//! Exact parametric positions on a surface, and the vertex keys built from them.
//!
//! Every mesh vertex lies at a dyadic parametric position of its surface: the patch
//! grid (N × N per polygon) refined by quadtree splits. Positions are integers
//! over a fixed denominator `D = N · 2^SUBDIVISION_BITS`, so two elements that
//! meet at a point compute the same key for it, exactly, and share the vertex
//! (Remington 1992, §3.4: "it is desirable to only store information for each vertex once").
//!
//! A surface is either one convex quad, parameterised bilinearly by (s, t), or a
//! set of triangular pieces (a triangle, or the triangulation of any other
//! polygon), each parameterised by barycentric weights over the polygon's own
//! vertices. The barycentric key is canonical (weights sorted by polygon vertex
//! index, zero weights dropped), so a point on a diagonal shared by two pieces has
//! the same key from both sides and the pieces share their vertices.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Quadtree levels available below a patch. Settings cap `max_depth` at 16
/// (`SolverSettings::validate`); the extra bits keep midpoints exact even so.
pub const SUBDIVISION_BITS: u32 = 20;

/// The largest patch count per side a polygon may ask for: `N · 2^20` must fit
/// the u32 parametric coordinates with room for the midpoint sums.
pub const MAX_PATCHES_PER_SIDE: u32 = 1024;

/// Where a vertex is, exactly, on its surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum VertexKey {
    /// Bilinear parameters `(s, t) / D` of a quad surface: `s` runs from vertex 0
    /// toward vertex 1, `t` from vertex 0 toward vertex 3.
    Quad { surface: u32, s: u32, t: u32 },
    /// Barycentric weights `w / D` over polygon vertices, sorted by vertex index,
    /// unused entries `(u32::MAX, 0)`.
    Bary {
        surface: u32,
        weights: [(u32, u32); 3],
    },
}

impl VertexKey {
    pub fn surface(&self) -> u32 {
        match *self {
            VertexKey::Quad { surface, .. } | VertexKey::Bary { surface, .. } => surface,
        }
    }

    /// The position of this key on a surface with polygon `vertices` and
    /// denominator `denominator`. The arithmetic depends only on the key, so equal
    /// keys give bit-identical positions whichever element asks.
    pub fn position(&self, vertices: &[DVec3], denominator: u32) -> DVec3 {
        let d = denominator as f64;
        match *self {
            VertexKey::Quad { s, t, .. } => {
                let (s, t) = (s as f64 / d, t as f64 / d);
                // Bilinear map; exact at the corners and linear along every edge
                // and iso-line, so element edges are straight in space.
                crate::geometry::polygon::bilinear(vertices, s, t)
            }
            VertexKey::Bary { weights, .. } => {
                let mut p = DVec3::ZERO;
                for (index, w) in weights {
                    if w > 0 {
                        p += vertices[index as usize] * (w as f64 / d);
                    }
                }
                p
            }
        }
    }
}

/// How a piece of a surface is parameterised.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PieceKind {
    /// The whole (convex) quad surface, bilinear in (s, t).
    Quad,
    /// A triangle of polygon vertices `[a, b, c]` (counter-clockwise); the local
    /// coordinates (u, v) are the weights of `b` and `c`, the weight of `a` is
    /// `D − u − v`.
    Triangle([u32; 3]),
}

/// A parameterised piece of a surface: patches are laid out on its grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Piece {
    pub surface: u32,
    pub kind: PieceKind,
}

impl Piece {
    /// The canonical key of the piece-local position `uv` (integers over `D`).
    pub fn key(&self, uv: [u32; 2], denominator: u32) -> VertexKey {
        match self.kind {
            PieceKind::Quad => VertexKey::Quad {
                surface: self.surface,
                s: uv[0],
                t: uv[1],
            },
            PieceKind::Triangle([a, b, c]) => {
                let mut entries = [(a, denominator - uv[0] - uv[1]), (b, uv[0]), (c, uv[1])];
                for e in entries.iter_mut() {
                    if e.1 == 0 {
                        *e = (u32::MAX, 0);
                    }
                }
                entries.sort_unstable();
                VertexKey::Bary {
                    surface: self.surface,
                    weights: entries,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_diagonal_points_get_one_key_from_both_pieces() {
        // Polygon 0..4 fanned into (0,1,2) and (0,2,3). On the diagonal 0–2 the
        // first piece has u = 0 (vertex 1's weight is zero) and the second has
        // v = 0 (vertex 3's weight is zero).
        let d = 8u32;
        let first = Piece {
            surface: 0,
            kind: PieceKind::Triangle([0, 1, 2]),
        };
        let second = Piece {
            surface: 0,
            kind: PieceKind::Triangle([0, 2, 3]),
        };
        for w in 0..=d {
            assert_eq!(first.key([0, w], d), second.key([w, 0], d));
        }
        // A corner of the polygon has one key whatever piece names it.
        assert_eq!(first.key([0, 0], d), second.key([0, 0], d));
        assert_ne!(first.key([1, 0], d), second.key([0, 1], d));
    }

    #[test]
    fn positions_are_exact_at_corners_and_midpoints() {
        let quad = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(4.0, 0.0, 0.0),
            DVec3::new(3.0, 2.0, 0.0),
            DVec3::new(1.0, 2.0, 0.0),
        ];
        let d = 4u32 << SUBDIVISION_BITS;
        let key = |s: u32, t: u32| VertexKey::Quad { surface: 0, s, t };
        assert_eq!(key(0, 0).position(&quad, d), quad[0]);
        assert_eq!(key(d, d).position(&quad, d), quad[2]);
        // Midpoint of the bottom edge and the bilinear centre.
        assert_eq!(key(d / 2, 0).position(&quad, d), DVec3::new(2.0, 0.0, 0.0));
        assert_eq!(
            key(d / 2, d / 2).position(&quad, d),
            DVec3::new(2.0, 1.0, 0.0)
        );
        let tri = Piece {
            surface: 0,
            kind: PieceKind::Triangle([0, 1, 2]),
        };
        let p = tri.key([d / 2, d / 2], d).position(&quad, d);
        assert_eq!(p, (quad[1] + quad[2]) * 0.5);
    }
}
