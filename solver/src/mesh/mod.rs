//! Meshing for progressive refinement (Remington 1992, §3.3–3.4): polygons into patches,
//! patches into quadtrees of elements, with one shared table of vertices.
//!
//! * Each input polygon becomes a *surface* with one frame (design notes, "Local
//!   frames and SH"): n = its Newell normal, t = its first edge made orthogonal
//!   to n, b = n × t.
//! * A convex quad is split into N × N patches bilinearly; a triangle into N²
//!   triangles by its edge grid; any other polygon is triangulated first
//!   ([`crate::geometry::polygon::triangulate`], a fan for convex ones) and each
//!   triangle split like a triangle. N is the polygon's own `patches`, else
//!   size-driven or the flat setting's ([`sizing`]).
//! * Every patch is the root of a quadtree: a quad element splits into four by
//!   its edge midpoints and its centre, a triangle into four by its edge
//!   midpoints.
//! * Vertices are keyed by their exact parametric position on the surface
//!   ([`param::VertexKey`]), so neighbouring elements and patches of one
//!   polygon share them, and a vertex a finer neighbour put on a coarser
//!   element's edge (a T-vertex) is found by key when the coarse element is
//!   triangulated for display ([`triangulate`]).
//!
//! Positions are re-centred scene units in f64. The mesh knows nothing of
//! radiance; the solver keeps per-vertex and per-patch arrays indexed by the ids
//! handed out here, which are assigned in a deterministic order (creation order),
//! and a log of splits lets a checkpoint rebuild the same mesh exactly.

pub mod contact;
pub mod param;
pub mod sizing;
pub mod triangulate;

use crate::geometry::polygon;
use crate::scene::{Scene, SourceRef};
use glam::DVec3;
pub use param::{Piece, PieceKind, VertexKey, MAX_PATCHES_PER_SIDE, SUBDIVISION_BITS};
pub use sizing::{PatchRule, Sizing};
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Marks an element without children.
pub const NO_CHILD: u32 = u32::MAX;

/// One input polygon, re-centred, with its frame and patch grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    /// Index into `Scene::polygons`.
    pub polygon: usize,
    /// Index into `Scene::materials`.
    pub material: usize,
    /// Re-centred vertices, counter-clockwise seen from the front.
    pub vertices: Vec<DVec3>,
    pub normal: DVec3,
    pub tangent: DVec3,
    pub bitangent: DVec3,
    pub area: f64,
    pub patches_per_side: u32,
    /// The smallest element's longest edge, scene units; `None`: the flat
    /// rule's floor, a fixed fraction of `area` (Remington 1992; [`sizing`]),
    /// for fixed patch counts.
    pub min_element_size: Option<f64>,
    /// Parametric denominator `N · 2^SUBDIVISION_BITS`.
    pub denominator: u32,
    /// Unit shading normals at the polygon's corners on a smooth surface
    /// (`scene::smooth`); `None` for a flat facet.
    pub corner_normals: Option<Vec<DVec3>>,
    /// Re-centred points of the boundary (contact pieces' shadow apexes,
    /// [`contact::Part::apexes`]) where the radiance's limit depends on the
    /// side it is approached from: the surface's vertex there is never merged
    /// with a sibling piece's in the output (`solve/seams.rs`).
    pub apexes: Vec<DVec3>,
}

/// A vertex shared by every element of its surface that has it as a corner.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshVertex {
    pub position: DVec3,
    pub surface: u32,
    /// A point inside an element that has this vertex as a corner (that
    /// element's centroid): receiving points on element boundaries are evaluated
    /// a small step toward it (design notes, "Form factors").
    pub inward: DVec3,
    pub key: VertexKey,
    /// Unit shading normal: its surface's corner normals interpolated at its
    /// parametric position (bilinear on a quad, barycentric on a triangle
    /// piece, then normalised), or the surface normal on a flat facet. The
    /// solver receives with it; coincident vertices of a smooth surface get
    /// the same one from both polygons, since both interpolate the same two
    /// corner normals along their shared edge.
    pub normal: DVec3,
}

/// A node of a patch's quadtree. Corners are counter-clockwise.
#[derive(Clone, Debug, PartialEq)]
pub struct Element {
    pub patch: u32,
    /// 0 for the patch itself.
    pub depth: u8,
    /// 3 (triangle) or 4 (quad).
    pub corner_count: u8,
    pub corners: [u32; 4],
    /// Piece-local parametric corners (integers over the surface denominator).
    pub uv: [[u32; 2]; 4],
    /// Index of the first of four consecutive children, or [`NO_CHILD`].
    pub first_child: u32,
    pub area: f64,
}

impl Element {
    pub fn is_leaf(&self) -> bool {
        self.first_child == NO_CHILD
    }
    pub fn corners(&self) -> &[u32] {
        &self.corners[..self.corner_count as usize]
    }
}

/// A shooting unit: a user-level subdivision of a polygon (Remington 1992, §3.3).
#[derive(Clone, Debug, PartialEq)]
pub struct Patch {
    pub surface: u32,
    pub piece: u32,
    /// Its root element.
    pub root: u32,
    pub corners: [DVec3; 4],
    pub corner_count: u8,
    pub area: f64,
}

impl Patch {
    /// The patch as a polygon (counter-clockwise), e.g. a source for form factors.
    pub fn polygon(&self) -> &[DVec3] {
        &self.corners[..self.corner_count as usize]
    }
}

/// A vertex created by a split, with the vertices whose average interpolates
/// the radiance of earlier shots at it (Remington 1992, §3.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NewVertex {
    pub id: u32,
    pub parents: [u32; 4],
    pub parent_count: u8,
    /// Its parametric position in the piece of the element that created it.
    pub uv: [u32; 2],
}

impl NewVertex {
    pub fn parents(&self) -> &[u32] {
        &self.parents[..self.parent_count as usize]
    }
}

/// Why a scene cannot be meshed.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    #[error("{at}: {patches} patches per side is too many (at most {max})", max = MAX_PATCHES_PER_SIDE)]
    TooManyPatches { at: SourceRef, patches: u32 },
    #[error("{at}: material index {material} does not exist (the scene has {count} materials)")]
    BadMaterial {
        at: SourceRef,
        material: usize,
        count: usize,
    },
    #[error("the mesh would exceed 2^32 - 1 vertices or elements")]
    TooLarge,
    #[error("checkpoint split log names element {0}, which is not a leaf of this mesh")]
    BadSplit(u32),
}

/// FxHash (as in rustc): the vertex table is looked up on every split and every
/// display triangulation, and its keys are small integers that need no
/// DoS-resistant hashing. Iteration order is never used, so the hasher cannot
/// affect results.
#[derive(Default, Clone, Copy)]
pub struct FxHasher(u64);

impl Hasher for FxHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }
    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.write_u64(i as u64);
    }
    #[inline]
    fn write_u8(&mut self, i: u8) {
        self.write_u64(i as u64);
    }
    #[inline]
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }
    #[inline]
    fn write_isize(&mut self, i: isize) {
        self.write_u64(i as u64);
    }
    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
}

type VertexTable = HashMap<VertexKey, u32, BuildHasherDefault<FxHasher>>;

/// For a child's corner slot that may hold a new vertex: (slot, the vertices
/// whose average interpolates it, how many of them).
type ParentSlot = (u32, [u32; 4], u8);

/// A child to create: its parametric corners and its [`ParentSlot`]s.
type ChildSpec = ([[u32; 2]; 4], Vec<ParentSlot>);

/// What [`Mesh::add_surface`] needs to know of a surface.
struct SurfaceSpec {
    polygon: usize,
    material: usize,
    /// Re-centred, counter-clockwise about `normal`.
    vertices: Vec<DVec3>,
    normal: DVec3,
    tangent: DVec3,
    patches_per_side: u32,
    min_element_size: Option<f64>,
    corner_normals: Option<Vec<DVec3>>,
    apexes: Vec<DVec3>,
}

/// Patches, elements and vertices of every surface.
#[derive(Clone, Debug)]
pub struct Mesh {
    pub surfaces: Vec<Surface>,
    pub pieces: Vec<Piece>,
    pub patches: Vec<Patch>,
    pub elements: Vec<Element>,
    pub vertices: Vec<MeshVertex>,
    /// Polygons left out because they have fewer than 3 vertices, zero area or
    /// non-finite coordinates (indices into `Scene::polygons`).
    pub skipped: Vec<usize>,
    /// Every split, in order: replaying it on a fresh mesh rebuilds this one.
    pub split_log: Vec<u32>,
    /// Per piece, its patches (contiguous).
    pub piece_patches: Vec<std::ops::Range<u32>>,
    table: VertexTable,
}

impl Mesh {
    /// Meshes every polygon of `scene` into patches (each a one-element
    /// quadtree), positions re-centred by subtracting `offset`, by the flat
    /// rule: `default_patches` per side for polygons whose `patches` is 0.
    pub fn new(scene: &Scene, offset: DVec3, default_patches: u32) -> Result<Mesh, MeshError> {
        Self::with_sizing(scene, offset, &Sizing::flat(default_patches))
    }

    /// Meshes every polygon of `scene` into patches (each a one-element
    /// quadtree), positions re-centred by subtracting `offset`, with patch
    /// counts and smallest elements from `sizing`.
    pub fn with_sizing(scene: &Scene, offset: DVec3, sizing: &Sizing) -> Result<Mesh, MeshError> {
        let parts = contact::conform(scene, contact::Cuts::Contacts);
        Self::with_contacts(scene, offset, sizing, &parts, &mut crate::progress::Quiet)
    }

    /// [`Self::with_sizing`], with each polygon cut into `parts[index]` where
    /// that is `Some` ([`contact::conform`]; a missing entry leaves the
    /// polygon whole), reporting to `observer`.
    pub fn with_contacts(
        scene: &Scene,
        offset: DVec3,
        sizing: &Sizing,
        parts: &[Option<Vec<contact::Part>>],
        observer: &mut dyn crate::progress::Observer,
    ) -> Result<Mesh, MeshError> {
        let mut mesh = Mesh {
            surfaces: Vec::new(),
            pieces: Vec::new(),
            patches: Vec::new(),
            elements: Vec::new(),
            vertices: Vec::new(),
            skipped: Vec::new(),
            split_log: Vec::new(),
            piece_patches: Vec::new(),
            table: VertexTable::default(),
        };
        let count = scene.polygons.len() as u64;
        for (index, poly) in scene.polygons.iter().enumerate() {
            if index % crate::progress::CHUNK == 0 {
                observer.advance(crate::progress::Pass::Meshing, index as u64, count);
            }
            if poly.material >= scene.materials.len() {
                return Err(MeshError::BadMaterial {
                    at: poly.source.clone(),
                    material: poly.material,
                    count: scene.materials.len(),
                });
            }
            let n = sizing.patches_per_side(poly);
            if n > MAX_PATCHES_PER_SIDE {
                return Err(MeshError::TooManyPatches {
                    at: poly.source.clone(),
                    patches: n,
                });
            }
            let vertices: Vec<DVec3> = poly.vertices.iter().map(|&v| v - offset).collect();
            let newell = polygon::newell_normal(&vertices);
            let area = 0.5 * newell.length();
            if vertices.len() < 3
                || !vertices.iter().all(|v| v.is_finite())
                || !area.is_finite()
                || area <= 0.0
            {
                mesh.skipped.push(index);
                continue;
            }
            let normal = newell / (2.0 * area);
            // t = the first edge of non-zero length, made orthogonal to n.
            let tangent = (0..vertices.len())
                .map(|i| {
                    let e = vertices[(i + 1) % vertices.len()] - vertices[i];
                    (e - normal * normal.dot(e)).normalize_or_zero()
                })
                .find(|t| *t != DVec3::ZERO)
                .unwrap_or_else(|| normal.any_orthonormal_vector());
            let corner_normals = poly
                .vertex_normals
                .as_ref()
                .filter(|c| c.len() == vertices.len() && c.iter().all(|n| n.is_finite()))
                .cloned();
            let spec =
                |vertices: Vec<DVec3>, patches_per_side, corner_normals, apexes| SurfaceSpec {
                    polygon: index,
                    material: poly.material,
                    vertices,
                    normal,
                    tangent,
                    patches_per_side,
                    min_element_size: sizing.min_element_size(poly),
                    corner_normals,
                    apexes,
                };
            match parts.get(index).and_then(Option::as_ref) {
                None => mesh.add_surface(spec(vertices, n, corner_normals, Vec::new())),
                Some(parts) => {
                    for part in parts {
                        let vertices: Vec<DVec3> =
                            part.vertices.iter().map(|&v| v - offset).collect();
                        let n = sizing.patches_per_side_of_part(poly, &part.vertices);
                        // The visible parts share their seams as one smooth
                        // surface would (`contact`, "Seams").
                        let corners = (!part.covered).then(|| vec![normal; vertices.len()]);
                        let apexes = part.apexes.iter().map(|&a| a - offset).collect();
                        mesh.add_surface(spec(vertices, n, corners, apexes));
                    }
                }
            }
        }
        for piece_index in 0..mesh.pieces.len() {
            mesh.add_patches(piece_index as u32)?;
        }
        observer.advance(crate::progress::Pass::Meshing, count, count);
        Ok(mesh)
    }

    /// Adds a surface and its pieces: the whole convex quad, or the
    /// triangles of any other polygon.
    fn add_surface(&mut self, spec: SurfaceSpec) {
        let area = polygon::area(&spec.vertices);
        if area.is_nan() || area <= 0.0 {
            return;
        }
        let surface = self.surfaces.len() as u32;
        let normal = spec.normal;
        self.surfaces.push(Surface {
            polygon: spec.polygon,
            material: spec.material,
            normal,
            tangent: spec.tangent,
            bitangent: normal.cross(spec.tangent),
            area,
            patches_per_side: spec.patches_per_side,
            min_element_size: spec.min_element_size,
            denominator: spec.patches_per_side << SUBDIVISION_BITS,
            corner_normals: spec.corner_normals,
            vertices: spec.vertices,
            apexes: spec.apexes,
        });
        let s = &self.surfaces[surface as usize];
        if s.vertices.len() == 4 && strictly_convex(&s.vertices, normal) {
            self.pieces.push(Piece {
                surface,
                kind: PieceKind::Quad,
            });
        } else {
            let mut fan = Vec::new();
            polygon::triangulate(&s.vertices, &mut fan);
            for t in &fan {
                let tri = [s.vertices[t[0]], s.vertices[t[1]], s.vertices[t[2]]];
                // Zero-area pieces (collinear input vertices) would only
                // create degenerate patches.
                if polygon::area(&tri) > 1e-14 * area {
                    self.pieces.push(Piece {
                        surface,
                        kind: PieceKind::Triangle([t[0] as u32, t[1] as u32, t[2] as u32]),
                    });
                }
            }
        }
    }

    /// Lays out the N × N patch grid of one piece.
    fn add_patches(&mut self, piece_index: u32) -> Result<(), MeshError> {
        let piece = self.pieces[piece_index as usize];
        let n = self.surfaces[piece.surface as usize].patches_per_side;
        let step = 1u32 << SUBDIVISION_BITS;
        let mut cells: Vec<([[u32; 2]; 4], u8)> = Vec::new();
        match piece.kind {
            PieceKind::Quad => {
                for j in 0..n {
                    for i in 0..n {
                        let (u0, v0, u1, v1) = (i * step, j * step, (i + 1) * step, (j + 1) * step);
                        cells.push(([[u0, v0], [u1, v0], [u1, v1], [u0, v1]], 4));
                    }
                }
            }
            PieceKind::Triangle(_) => {
                for j in 0..n {
                    for i in 0..n - j {
                        let (u0, v0, u1, v1) = (i * step, j * step, (i + 1) * step, (j + 1) * step);
                        cells.push(([[u0, v0], [u1, v0], [u0, v1], [0, 0]], 3));
                        if i + j + 1 < n {
                            cells.push(([[u1, v0], [u1, v1], [u0, v1], [0, 0]], 3));
                        }
                    }
                }
            }
        }
        let first = self.patches.len() as u32;
        self.piece_patches.push(first..first + cells.len() as u32);
        for (uv, count) in cells {
            let patch = self.patches.len() as u32;
            let element = self.push_element(piece_index, patch, 0, uv, count, None)?;
            let e = &self.elements[element as usize];
            let mut corners = [DVec3::ZERO; 4];
            for (k, &c) in e.corners().iter().enumerate() {
                corners[k] = self.vertices[c as usize].position;
            }
            let area = e.area;
            self.patches.push(Patch {
                surface: piece.surface,
                piece: piece_index,
                root: element,
                corners,
                corner_count: count,
                area,
            });
        }
        Ok(())
    }

    /// Creates an element with corners at `uv`, creating missing vertices, and
    /// reports the new ones (with their interpolation parents) to `created`.
    fn push_element(
        &mut self,
        piece_index: u32,
        patch: u32,
        depth: u8,
        uv: [[u32; 2]; 4],
        count: u8,
        mut created: Option<(&mut Vec<NewVertex>, &[ParentSlot])>,
    ) -> Result<u32, MeshError> {
        let piece = self.pieces[piece_index as usize];
        let surface = &self.surfaces[piece.surface as usize];
        let denominator = surface.denominator;
        let mut corners = [0u32; 4];
        let mut positions = [DVec3::ZERO; 4];
        let mut fresh = [false; 4];
        for k in 0..count as usize {
            let key = piece.key(uv[k], denominator);
            let surface = &self.surfaces[piece.surface as usize];
            let (id, is_new) = match self.table.get(&key) {
                Some(&id) => (id, false),
                None => {
                    let id = u32::try_from(self.vertices.len()).map_err(|_| MeshError::TooLarge)?;
                    if id == u32::MAX {
                        return Err(MeshError::TooLarge);
                    }
                    let position = key.position(&surface.vertices, denominator);
                    let normal = surface
                        .corner_normals
                        .as_ref()
                        .and_then(|c| key.position(c, denominator).try_normalize())
                        .unwrap_or(surface.normal);
                    self.vertices.push(MeshVertex {
                        position,
                        surface: piece.surface,
                        inward: position,
                        key,
                        normal,
                    });
                    self.table.insert(key, id);
                    (id, true)
                }
            };
            corners[k] = id;
            positions[k] = self.vertices[id as usize].position;
            fresh[k] = is_new;
        }
        let centroid = positions[..count as usize].iter().copied().sum::<DVec3>() / count as f64;
        for k in 0..count as usize {
            if fresh[k] {
                let id = corners[k];
                self.vertices[id as usize].inward = centroid;
                if let Some((list, parents)) = created.as_mut() {
                    let (_, p, pc) = parents
                        .iter()
                        .copied()
                        .find(|(key_uv, _, _)| *key_uv == k as u32)
                        .unwrap_or((0, [id; 4], 1));
                    list.push(NewVertex {
                        id,
                        parents: p,
                        parent_count: pc,
                        uv: uv[k],
                    });
                }
            }
        }
        let area = if count == 3 {
            0.5 * (positions[1] - positions[0])
                .cross(positions[2] - positions[0])
                .length()
        } else {
            polygon::area(&positions)
        };
        let index = u32::try_from(self.elements.len()).map_err(|_| MeshError::TooLarge)?;
        if index == u32::MAX {
            return Err(MeshError::TooLarge);
        }
        self.elements.push(Element {
            patch,
            depth,
            corner_count: count,
            corners,
            uv,
            first_child: NO_CHILD,
            area,
        });
        Ok(index)
    }

    /// Splits leaf `element` into four children (quad: edge midpoints and centre;
    /// triangle: edge midpoints), appending the vertices this creates, with the
    /// corners that interpolate them, to `created` in id order. Returns the index
    /// of the first child. Midpoints that a finer neighbour already created are
    /// reused.
    pub fn split(&mut self, element: u32, created: &mut Vec<NewVertex>) -> Result<u32, MeshError> {
        let e = self
            .elements
            .get(element as usize)
            .filter(|e| e.is_leaf())
            .ok_or(MeshError::BadSplit(element))?
            .clone();
        if e.depth as u32 >= SUBDIVISION_BITS {
            return Err(MeshError::BadSplit(element));
        }
        let piece_index = self.patches[e.patch as usize].piece;
        let mid = |a: [u32; 2], b: [u32; 2]| [(a[0] + b[0]) / 2, (a[1] + b[1]) / 2];
        let c = e.uv;
        let k = e.corners;
        let depth = e.depth + 1;
        let first = self.elements.len() as u32;
        // Children are pushed in a fixed order; a new vertex is created by the
        // first child that names it, and `parents` maps a child's corner slot to
        // the interpolation parents of the vertex in that slot.
        if e.corner_count == 4 {
            let (m01, m12, m23, m30) = (
                mid(c[0], c[1]),
                mid(c[1], c[2]),
                mid(c[2], c[3]),
                mid(c[3], c[0]),
            );
            let centre = mid(c[0], c[2]);
            let all = [k[0], k[1], k[2], k[3]];
            let children: [ChildSpec; 4] = [
                (
                    [c[0], m01, centre, m30],
                    vec![
                        (1, [k[0], k[1], 0, 0], 2),
                        (2, all, 4),
                        (3, [k[3], k[0], 0, 0], 2),
                    ],
                ),
                ([m01, c[1], m12, centre], vec![(2, [k[1], k[2], 0, 0], 2)]),
                ([centre, m12, c[2], m23], vec![(3, [k[2], k[3], 0, 0], 2)]),
                ([m30, centre, m23, c[3]], vec![]),
            ];
            for (uv, parents) in children {
                self.push_element(
                    piece_index,
                    e.patch,
                    depth,
                    uv,
                    4,
                    Some((created, &parents)),
                )?;
            }
        } else {
            let (m01, m12, m20) = (mid(c[0], c[1]), mid(c[1], c[2]), mid(c[2], c[0]));
            let z = [0u32; 2];
            let children: [ChildSpec; 4] = [
                (
                    [c[0], m01, m20, z],
                    vec![(1, [k[0], k[1], 0, 0], 2), (2, [k[2], k[0], 0, 0], 2)],
                ),
                ([m01, c[1], m12, z], vec![(2, [k[1], k[2], 0, 0], 2)]),
                ([m20, m12, c[2], z], vec![]),
                ([m01, m12, m20, z], vec![]),
            ];
            for (uv, parents) in children {
                self.push_element(
                    piece_index,
                    e.patch,
                    depth,
                    uv,
                    3,
                    Some((created, &parents)),
                )?;
            }
        }
        self.elements[element as usize].first_child = first;
        self.split_log.push(element);
        Ok(first)
    }

    /// Replays a split log recorded by another mesh built from the same scene
    /// and settings.
    pub fn replay(&mut self, log: &[u32]) -> Result<(), MeshError> {
        let mut scratch = Vec::new();
        for &e in log {
            scratch.clear();
            self.split(e, &mut scratch)?;
        }
        Ok(())
    }

    /// The leaves of `patch`'s quadtree, depth first, appended to `out`.
    pub fn patch_leaves(&self, patch: u32, out: &mut Vec<u32>) {
        let mut stack = vec![self.patches[patch as usize].root];
        while let Some(e) = stack.pop() {
            let el = &self.elements[e as usize];
            if el.is_leaf() {
                out.push(e);
            } else {
                // Reverse so that children come out in order.
                for c in (0..4).rev() {
                    stack.push(el.first_child + c);
                }
            }
        }
    }

    /// All leaf elements, in index order.
    pub fn leaves(&self) -> impl Iterator<Item = u32> + '_ {
        self.elements
            .iter()
            .enumerate()
            .filter(|(_, e)| e.is_leaf())
            .map(|(i, _)| i as u32)
    }

    /// The boundary of a leaf element: its corners and, between them, the
    /// vertices finer neighbours have put on its edges, counter-clockwise, each
    /// with its piece-local parametric position.
    pub fn leaf_boundary(&self, element: u32, out: &mut Vec<(u32, [i64; 2])>) {
        out.clear();
        let e = &self.elements[element as usize];
        let piece = self.pieces[self.patches[e.patch as usize].piece as usize];
        let denominator = self.surfaces[piece.surface as usize].denominator;
        let n = e.corner_count as usize;
        for k in 0..n {
            let (a, b) = (e.uv[k], e.uv[(k + 1) % n]);
            out.push((e.corners[k], [a[0] as i64, a[1] as i64]));
            self.hanging(&piece, denominator, a, b, out);
        }
    }

    /// Vertices strictly inside the segment a–b, in order from a. A finer
    /// neighbour along the segment always has the segment's midpoint as a
    /// corner, so the search stops where a midpoint is missing.
    fn hanging(
        &self,
        piece: &Piece,
        denominator: u32,
        a: [u32; 2],
        b: [u32; 2],
        out: &mut Vec<(u32, [i64; 2])>,
    ) {
        let (s0, s1) = (a[0] + b[0], a[1] + b[1]);
        if s0 % 2 != 0 || s1 % 2 != 0 || a == b {
            return;
        }
        let m = [s0 / 2, s1 / 2];
        if m == a || m == b {
            return;
        }
        if let Some(&id) = self.table.get(&piece.key(m, denominator)) {
            self.hanging(piece, denominator, a, m, out);
            out.push((id, [m[0] as i64, m[1] as i64]));
            self.hanging(piece, denominator, m, b, out);
        }
    }

    /// Triangles (vertex ids, counter-clockwise about the surface normal) of the
    /// displayed mesh of `patch`: each leaf triangulated with the T-vertices on
    /// its edges, so neighbouring leaves share every edge and no crack opens.
    pub fn patch_triangles(&self, patch: u32, out: &mut Vec<[u32; 3]>) {
        let mut leaves = Vec::new();
        self.patch_leaves(patch, &mut leaves);
        let mut boundary = Vec::new();
        let mut points = Vec::new();
        let mut work = Vec::new();
        let mut tris = Vec::new();
        for leaf in leaves {
            self.leaf_boundary(leaf, &mut boundary);
            if boundary.len() == self.elements[leaf as usize].corner_count as usize {
                // No T-vertices: the element itself (a quad as two triangles on
                // its shorter diagonal, which follows the surface best). A
                // square's diagonals tie; within a billionth they count as
                // tied and take 0–2, so rounding (a translated scene) cannot
                // choose the other: the choice sets the patches' gather
                // weights (test `translating_the_scene_by_1e6_gives_the_same_answer`).
                let c = &boundary;
                if c.len() == 3 {
                    out.push([c[0].0, c[1].0, c[2].0]);
                } else {
                    let p = |i: usize| self.vertices[c[i].0 as usize].position;
                    let (first, second) = (
                        (p(2) - p(0)).length_squared(),
                        (p(3) - p(1)).length_squared(),
                    );
                    if first <= second * (1.0 + 1e-9) {
                        out.push([c[0].0, c[1].0, c[2].0]);
                        out.push([c[0].0, c[2].0, c[3].0]);
                    } else {
                        out.push([c[1].0, c[2].0, c[3].0]);
                        out.push([c[1].0, c[3].0, c[0].0]);
                    }
                }
                continue;
            }
            points.clear();
            points.extend(boundary.iter().map(|b| b.1));
            tris.clear();
            triangulate::triangulate_convex(&points, &mut work, &mut tris);
            out.extend(
                tris.iter()
                    .map(|t| [boundary[t[0]].0, boundary[t[1]].0, boundary[t[2]].0]),
            );
        }
    }

    /// The display triangles of every patch, in patch order.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        let mut out = Vec::new();
        for p in 0..self.patches.len() {
            self.patch_triangles(p as u32, &mut out);
        }
        out
    }

    /// The patches whose closed region holds the piece-local point `uv` of piece
    /// `piece`, appended to `out`: the patches whose display triangulation a
    /// vertex there can change. A point on the piece's boundary of a surface
    /// made of several pieces may lie on a diagonal shared with another piece,
    /// so then every patch of the surface is reported.
    pub fn patches_at(&self, piece: u32, uv: [u32; 2], out: &mut Vec<u32>) {
        let p = self.pieces[piece as usize];
        let surface = &self.surfaces[p.surface as usize];
        let (d, n) = (surface.denominator, surface.patches_per_side);
        let on_piece_edge = match p.kind {
            PieceKind::Quad => uv[0] == 0 || uv[1] == 0 || uv[0] == d || uv[1] == d,
            PieceKind::Triangle(_) => uv[0] == 0 || uv[1] == 0 || uv[0] + uv[1] == d,
        };
        if on_piece_edge
            && self
                .pieces
                .iter()
                .filter(|q| q.surface == p.surface)
                .count()
                > 1
        {
            for (q, range) in self.pieces.iter().zip(&self.piece_patches) {
                if q.surface == p.surface {
                    out.extend(range.clone());
                }
            }
            return;
        }
        let start = self.piece_patches[piece as usize].start;
        let base = out.len();
        let step = 1u32 << SUBDIVISION_BITS;
        let (ci, cj) = ((uv[0] / step).min(n - 1), (uv[1] / step).min(n - 1));
        let contains = |patch: u32| {
            let e = &self.elements[self.patches[patch as usize].root as usize];
            let c = e.corner_count as usize;
            let q = [uv[0] as i64, uv[1] as i64];
            (0..c).all(|k| {
                let (a, b) = (e.uv[k], e.uv[(k + 1) % c]);
                let (ax, ay, bx, by) = (a[0] as i64, a[1] as i64, b[0] as i64, b[1] as i64);
                (bx - ax) * (q[1] - ay) - (by - ay) * (q[0] - ax) >= 0
            })
        };
        for j in cj.saturating_sub(1)..=cj {
            for i in ci.saturating_sub(1)..=ci {
                let candidates: [Option<u32>; 2] = match p.kind {
                    PieceKind::Quad => [Some(j * n + i), None],
                    PieceKind::Triangle(_) => {
                        if i + j >= n {
                            [None, None]
                        } else {
                            let row = 2 * n * j - j * j;
                            let down = (i + j + 1 < n).then_some(row + 2 * i + 1);
                            [Some(row + 2 * i), down]
                        }
                    }
                };
                for local in candidates.into_iter().flatten() {
                    if contains(start + local) && !out[base..].contains(&(start + local)) {
                        out.push(start + local);
                    }
                }
            }
        }
    }

    /// Number of leaf elements.
    pub fn leaf_count(&self) -> usize {
        self.elements.iter().filter(|e| e.is_leaf()).count()
    }
}

/// A quad is meshed bilinearly only when every corner turns strictly the same
/// way (a straight corner would give elements with a 180° angle).
pub(crate) fn strictly_convex(vertices: &[DVec3], normal: DVec3) -> bool {
    let n = vertices.len();
    let scale = (0..n)
        .map(|i| (vertices[(i + 1) % n] - vertices[i]).length_squared())
        .fold(0.0, f64::max);
    (0..n).all(|i| {
        let (a, b, c) = (vertices[i], vertices[(i + 1) % n], vertices[(i + 2) % n]);
        (b - a).cross(c - b).dot(normal) > 1e-9 * scale
    })
}

#[cfg(test)]
mod tests;
