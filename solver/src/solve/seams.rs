//! One output vertex per position on a smooth surface, and seams without
//! T-junctions across its polygons.
//!
//! The mesh keys vertices by (surface, parametric position), so two polygons of
//! one smooth surface (`scene::smooth`) each have their own vertex where they
//! meet. For the solution file:
//!
//! * **Merging.** Mesh vertices of smooth surfaces that coincide within
//!   [`crate::scene::SMOOTH_TOLERANCE`] × the mesh's bounding-box diagonal, have
//!   the same material and the same shading normal (dot ≥ 1 − 1e-9) become one
//!   output vertex. The shading-normal test is what keeps creases sharp: across
//!   a crease the two polygons' normals at the shared position differ, inside a
//!   smooth group both interpolate the same corner normals. Its radiance is the
//!   area-weighted mean of the merged vertices' (weights: a third or a quarter
//!   of each leaf element that has the vertex as a corner), which differ only
//!   by the receiving points' inward steps and sampling noise.
//! * **T-junctions across polygons.** Adaptive subdivision refines each polygon
//!   on its own, so a vertex of one polygon can lie inside an edge of its
//!   neighbour's display triangle. Such a vertex is inserted into the
//!   neighbour's triangulation: the triangle is fanned from its opposite corner
//!   to the points on that edge. Both sides of a polygon edge then run through
//!   the same output vertices, so they interpolate the same piecewise-linear
//!   radiance and no crack (in position or in value) can open. The inserted
//!   vertex carries its own solved radiance: the neighbour gains detail rather
//!   than the vertex losing it (the alternative, overwriting it with the
//!   neighbour edge's linear interpolation, would erase the shadow edge that made
//!   it split).
//!
//! * **UV seams.** On a textured smooth surface, coincident vertices whose
//!   texture coordinates differ (a seam of the UV layout) stay separate
//!   output vertices, so each side keeps its own UVs, but they get the same
//!   radiance (E/π): the mean over every vertex at the position. Limitation:
//!   T-junctions along a UV seam are not repaired across it (its two sides
//!   have different output vertices), so an adaptive split on one side only
//!   can leave a value step there.
//!
//! * **Both outputs.** The pass is generic over the per-vertex value: the
//!   diffuse output's RGB radiance and the directional output's SH
//!   coefficient vectors, as blocks of one flat array
//!   ([`SharedVertices::merge_values`]). Averaging coefficient vectors
//!   averages the radiance functions they stand for, but only within one
//!   frame: the directional output writes its SH in each polygon's frame, so
//!   it merges only the pieces that `mesh::contact` cuts one polygon into
//!   (they share its normal, tangent, material and SH order), and vertices of
//!   different polygons keep their own output vertices even on one smooth
//!   surface ([`Merge::WithinPolygons`]; `directional.rs`, "Frames on smooth
//!   surfaces").
//!
//! Flat facets (no corner normals) are left exactly as the mesh has them, so a
//! scene without smooth surfaces gives the same vertices, in the same order,
//! and the same triangles as before.

use crate::mesh::Mesh;
use crate::scene::IntMap;
use crate::scene::SMOOTH_TOLERANCE;
use glam::DVec3;
use std::ops::Range;

/// Two shading normals are the same when their dot product is at least this:
/// far above the rounding of normalising the same interpolation (1e-15), far
/// below the smallest crease (a 0.1° difference is 1.5e-6).
const SAME_NORMAL: f64 = 1.0 - 1e-9;

/// The output vertices: which mesh vertex each comes from, where each mesh
/// vertex went, and which vertices share their lighting (the vertices at one
/// position: across a UV seam they are several output vertices).
pub(crate) struct SharedVertices {
    /// Per mesh vertex, its output vertex.
    pub output_of: Vec<u32>,
    /// Per output vertex, the first mesh vertex merged into it (its position,
    /// normal and surface frame).
    pub representative: Vec<u32>,
    /// Per mesh vertex, its lighting group (the vertices whose values are
    /// averaged, [`SharedVertices::merge_values`]).
    light_group: Vec<u32>,
    /// Per lighting group, its first mesh vertex, whose block receives the
    /// group's mean.
    light_first: Vec<u32>,
    /// Per output vertex, its lighting group.
    light_of: Vec<u32>,
    /// Per output vertex on a smooth polygon's boundary: the polygon edges it
    /// lies on, as (edge, parameter along it from the edge's first end).
    on_edges: IntMap<u32, Vec<(EdgeKey, f64)>>,
    /// Per polygon edge, its points sorted by parameter.
    edge_points: IntMap<EdgeKey, Vec<(f64, u32)>>,
}

/// A polygon edge of a smooth surface by its end points' output vertices, the
/// smaller first.
type EdgeKey = (u32, u32);

/// A uniform grid of output vertices for coincidence queries: cells 2·tol
/// wide, so every point within tol of a query lies in the 2 × 2 × 2 block of
/// cells nearest to it.
struct Grid {
    tol: f64,
    cells: IntMap<(i64, i64, i64), Vec<u32>>,
}

impl Grid {
    /// Per axis, the cell of `p` first and then its nearer neighbour; the
    /// cell of `p` itself is `(x[0], y[0], z[0])`.
    fn block(&self, p: DVec3) -> [[i64; 2]; 3] {
        let scaled = p / (2.0 * self.tol);
        let cell = scaled.floor();
        let near = |axis: usize| -> [i64; 2] {
            let c = cell[axis] as i64;
            if scaled[axis] - cell[axis] < 0.5 {
                [c, c - 1]
            } else {
                [c, c + 1]
            }
        };
        [near(0), near(1), near(2)]
    }

    /// The first output vertex near `p` that `matches`, else `None`.
    fn find(&self, p: DVec3, matches: impl Fn(u32) -> bool) -> Option<u32> {
        let [xs, ys, zs] = self.block(p);
        for x in xs {
            for y in ys {
                for z in zs {
                    if let Some(ids) = self.cells.get(&(x, y, z)) {
                        if let Some(&id) = ids.iter().find(|&&id| matches(id)) {
                            return Some(id);
                        }
                    }
                }
            }
        }
        None
    }

    fn insert(&mut self, p: DVec3, id: u32) {
        let [x, y, z] = self.block(p);
        self.cells.entry((x[0], y[0], z[0])).or_default().push(id);
    }
}

/// Two texture coordinates are the same display vertex when they differ by at
/// most this (1e-7 of a texture repeat: far below a texel of the largest
/// texture read, 1/16384, far above the rounding of one affine map evaluated
/// at one position from two polygons' fits).
const SAME_UV: f64 = 1e-7;

/// Each mesh vertex's share of the displayed area: a third or a quarter of
/// every leaf element that has it as a corner (the weights of the merged
/// vertices' mean).
fn vertex_weights(mesh: &Mesh) -> Vec<f64> {
    let mut weight = vec![0.0; mesh.vertices.len()];
    for e in mesh.elements.iter().filter(|e| e.is_leaf()) {
        for &c in e.corners() {
            weight[c as usize] += e.area / e.corners().len() as f64;
        }
    }
    weight
}

/// Which vertices of smooth surfaces may share an output vertex: the values
/// they carry decide it.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Merge {
    /// Any surfaces' (the diffuse output's RGB radiance, which has no frame).
    AcrossPolygons,
    /// Only those of surfaces cut from one input polygon (`mesh::contact`'s
    /// pieces, which share its normal and tangent), and T-junctions are
    /// resolved only across those pieces: the directional output writes its
    /// SH in its polygon's frame, and no value of one frame may be averaged
    /// with, or interpolated as, a value of another.
    WithinPolygons,
}

/// What [`SharedVertices::merge_values`] writes for a vertex alone in its
/// lighting group.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Lone {
    /// Its own value, bit for bit (the directional output).
    Kept,
    /// Its value weighted and divided by its weight again, as for a merged
    /// group: (0 + x·w)/w, which can differ from x in the last bit. The
    /// diffuse output has always written this; kept so that its solution
    /// files stay byte-identical (dropping it changes them, a commit of its
    /// own).
    Reweighted,
}

/// Merges the coincident vertices of smooth surfaces (see the module
/// comment) that `merge` allows, given texture coordinates `uv(surface,
/// position)` (solver coordinates; `None` where untextured): vertices that
/// would merge but whose UVs differ (a UV seam) stay separate display
/// vertices in one lighting group, so that each shows the lighting (the
/// area-weighted mean, [`SharedVertices::merge_values`]) of all the vertices
/// at that position: a seam splits the texture but not the light.
pub(crate) fn share_vertices(
    mesh: &Mesh,
    uv: &dyn Fn(u32, DVec3) -> Option<glam::DVec2>,
    merge: Merge,
) -> SharedVertices {
    let within_polygon = merge == Merge::WithinPolygons;
    // Whether two surfaces' vertices may share an output vertex.
    let same_frame = |a: u32, b: u32| {
        !within_polygon || mesh.surfaces[a as usize].polygon == mesh.surfaces[b as usize].polygon
    };
    // Whether mesh vertex `r` has the UV that `surface` has at `p`.
    let same_uv = |r: u32, surface: u32, p: DVec3| {
        let r = &mesh.vertices[r as usize];
        match (uv(r.surface, r.position), uv(surface, p)) {
            (Some(x), Some(y)) => (x - y).abs().max_element() <= SAME_UV,
            (None, None) => true,
            _ => false,
        }
    };
    let n = mesh.vertices.len();
    let smooth = |v: usize| {
        mesh.surfaces[mesh.vertices[v].surface as usize]
            .corner_normals
            .is_some()
    };
    let tol = SMOOTH_TOLERANCE * mesh_diagonal(mesh);
    let pinned: Vec<bool> = mesh
        .vertices
        .iter()
        .map(|v| at_apex(&mesh.surfaces[v.surface as usize], v.position, tol))
        .collect();
    let mut grid = Grid {
        tol: tol.max(f64::MIN_POSITIVE),
        cells: IntMap::default(),
    };
    // Lighting groups (merged ignoring UVs) and their first vertex.
    let mut light_grid = Grid {
        tol: grid.tol,
        cells: IntMap::default(),
    };
    let mut light_first: Vec<u32> = Vec::new();
    let mut light_of: Vec<u32> = Vec::with_capacity(n);
    let mut light_group: Vec<u32> = Vec::with_capacity(n);
    let mut output_of = Vec::with_capacity(n);
    let mut representative: Vec<u32> = Vec::with_capacity(n);
    for v in 0..n {
        let vertex = &mesh.vertices[v];
        let material = mesh.surfaces[vertex.surface as usize].material;
        // A vertex at a shadow apex merges only within its own surface.
        let coincides = |id: u32| {
            let r = &mesh.vertices[id as usize];
            (r.surface == vertex.surface || !(pinned[v] || pinned[id as usize]))
                && same_frame(r.surface, vertex.surface)
                && mesh.surfaces[r.surface as usize].material == material
                && (r.position - vertex.position).length() <= tol
                && r.normal.dot(vertex.normal) >= SAME_NORMAL
        };
        let (found, light) = if smooth(v) {
            let found = grid.find(vertex.position, |o| {
                let r = representative[o as usize];
                coincides(r) && same_uv(r, vertex.surface, vertex.position)
            });
            let light = light_grid.find(vertex.position, |g| coincides(light_first[g as usize]));
            (found, light)
        } else {
            (None, None)
        };
        let light = light.unwrap_or_else(|| {
            let g = light_first.len() as u32;
            light_first.push(v as u32);
            if smooth(v) {
                light_grid.insert(vertex.position, g);
            }
            g
        });
        let o = match found {
            Some(o) => o,
            None => {
                let o = representative.len() as u32;
                representative.push(v as u32);
                light_of.push(light);
                if smooth(v) {
                    grid.insert(vertex.position, o);
                }
                o
            }
        };
        output_of.push(o);
        light_group.push(light);
    }
    let mut shared = SharedVertices {
        output_of,
        representative,
        light_group,
        light_first,
        light_of,
        on_edges: IntMap::default(),
        edge_points: IntMap::default(),
    };
    index_polygon_edges(mesh, &grid, tol, &same_uv, &same_frame, &mut shared);
    shared
}

/// Records, for every vertex of a smooth polygon that lies on one of its
/// polygon's edges, that edge and its parameter along it.
fn index_polygon_edges(
    mesh: &Mesh,
    grid: &Grid,
    tol: f64,
    same_uv: &dyn Fn(u32, u32, DVec3) -> bool,
    same_frame: &dyn Fn(u32, u32) -> bool,
    shared: &mut SharedVertices,
) {
    // The output vertex at each corner of each smooth surface (`None` for a
    // surface with a corner that is no mesh vertex: its seams are left as
    // meshed).
    let corner_ids: Vec<Option<Vec<u32>>> = mesh
        .surfaces
        .iter()
        .enumerate()
        .map(|(index, s)| {
            let normals = s.corner_normals.as_ref()?;
            s.vertices
                .iter()
                .zip(normals)
                .map(|(&p, &normal)| {
                    grid.find(p, |o| {
                        let id = shared.representative[o as usize];
                        let r = &mesh.vertices[id as usize];
                        let pinned = at_apex(s, p, tol)
                            || at_apex(&mesh.surfaces[r.surface as usize], r.position, tol);
                        (r.surface == index as u32 || !pinned)
                            && same_frame(r.surface, index as u32)
                            && mesh.surfaces[r.surface as usize].material == s.material
                            && (r.position - p).length() <= tol
                            && r.normal.dot(normal) >= SAME_NORMAL
                            && same_uv(id, index as u32, p)
                    })
                })
                .collect()
        })
        .collect();
    // The smooth surfaces cut from one input polygon along contact lines
    // (`mesh::contact`) meet along cuts whose ends need not be corners of
    // both sides: a vertex is looked for on the edges of all of them.
    let mut siblings: IntMap<usize, Vec<u32>> = IntMap::default();
    for (index, s) in mesh.surfaces.iter().enumerate() {
        if corner_ids[index].is_some() {
            siblings.entry(s.polygon).or_default().push(index as u32);
        }
    }
    // A polygon cut into many pieces (a floor under a hundred cylinders: 6,000
    // pieces) would have each of its vertices test every piece's edges;
    // its pieces' edges go into a grid instead.
    let grids: IntMap<usize, EdgeGrid> = siblings
        .iter()
        .filter(|(_, pieces)| pieces.len() > EdgeGrid::MIN_PIECES)
        .map(|(&polygon, pieces)| (polygon, EdgeGrid::new(mesh, pieces, tol)))
        .collect();
    let mut near = Vec::new();
    for (v, vertex) in mesh.vertices.iter().enumerate() {
        if corner_ids[vertex.surface as usize].is_none() {
            continue;
        }
        let o = shared.output_of[v];
        let own = mesh.surfaces[vertex.surface as usize].polygon;
        let material = mesh.surfaces[vertex.surface as usize].material;
        near.clear();
        match grids.get(&own) {
            Some(grid) => near.extend_from_slice(grid.near(vertex.position)),
            None => {
                for &surface in &siblings[&own] {
                    let count = mesh.surfaces[surface as usize].vertices.len() as u32;
                    near.extend((0..count).map(|i| (surface, i)));
                }
            }
        }
        // In surface and edge order, as a scan of every sibling records them.
        near.sort_unstable();
        for &(surface, i) in &near {
            let s = &mesh.surfaces[surface as usize];
            let Some(corners) = &corner_ids[surface as usize] else {
                continue;
            };
            if s.material == material {
                record_on_edge(s, corners, i as usize, vertex.position, o, tol, shared);
            }
        }
    }
    for points in shared.edge_points.values_mut() {
        points.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        points.dedup_by_key(|p| p.1);
    }
}

/// The edges of one polygon's many pieces (`mesh::contact`) in a uniform
/// grid: each edge is listed in every cell that a point within the tolerance
/// of it can lie in, so the edges that pass within the tolerance of a point
/// are among those of the point's cell.
struct EdgeGrid {
    cell: f64,
    cells: IntMap<(i64, i64, i64), Vec<(u32, u32)>>,
}

impl EdgeGrid {
    /// Polygons with more pieces than this get a grid.
    const MIN_PIECES: usize = 16;

    fn new(mesh: &crate::mesh::Mesh, pieces: &[u32], tol: f64) -> EdgeGrid {
        let points = || {
            pieces
                .iter()
                .flat_map(|&s| mesh.surfaces[s as usize].vertices.iter().copied())
        };
        let lo = points().fold(DVec3::splat(f64::INFINITY), DVec3::min);
        let hi = points().fold(DVec3::splat(f64::NEG_INFINITY), DVec3::max);
        // About one piece per cell of the polygon's extent.
        let extent = (hi - lo).max_element();
        let cell = (extent / (pieces.len() as f64).sqrt()).max(4.0 * tol);
        let mut grid = EdgeGrid {
            cell,
            cells: IntMap::default(),
        };
        for &surface in pieces {
            let corners = &mesh.surfaces[surface as usize].vertices;
            for i in 0..corners.len() {
                let (a, b) = (corners[i], corners[(i + 1) % corners.len()]);
                grid.insert_edge(a, b, tol, (surface, i as u32));
            }
        }
        grid
    }

    /// Lists `edge` (from `a` to `b`) in every cell within `tol` of it.
    ///
    /// The edge is walked in steps of at most half a cell. A point within
    /// `tol` of the edge is within `tol` plus half a step of the nearest
    /// sample, so the box of that reach round each sample holds its cell;
    /// the reach is at most half a cell (`cell ≥ 4·tol`), so each box
    /// touches at most 2 × 2 × 2 cells. An edge thus costs cells in
    /// proportion to its length in cells, in any direction: listing its
    /// whole bounding box instead costs the cube of that on a polygon tilted
    /// off every axis (a long edge of a finely cut sloping roof would fill
    /// a cube of cells).
    fn insert_edge(&mut self, a: DVec3, b: DVec3, tol: f64, edge: (u32, u32)) {
        let steps = ((b - a).length() / (0.5 * self.cell)).ceil().max(1.0);
        // Mesh vertices are finite, so `steps` is too; the cap only bounds
        // the loop should that ever fail.
        let steps = steps.min(1e9) as u32;
        let reach = DVec3::splat(0.5 * (b - a).length() / f64::from(steps) + tol);
        for k in 0..=steps {
            let p = a.lerp(b, f64::from(k) / f64::from(steps));
            let (from, to) = (self.key(p - reach), self.key(p + reach));
            for x in from.0..=to.0 {
                for y in from.1..=to.1 {
                    for z in from.2..=to.2 {
                        let list = self.cells.entry((x, y, z)).or_default();
                        // The samples of one edge come one after another, so
                        // a cell that already lists it lists it last.
                        if list.last() != Some(&edge) {
                            list.push(edge);
                        }
                    }
                }
            }
        }
    }

    fn key(&self, p: DVec3) -> (i64, i64, i64) {
        let c = (p / self.cell).floor();
        (c.x as i64, c.y as i64, c.z as i64)
    }

    /// The (piece, edge index) pairs listed in `p`'s cell.
    fn near(&self, p: DVec3) -> &[(u32, u32)] {
        self.cells.get(&self.key(p)).map_or(&[], |l| l.as_slice())
    }
}

/// Records that output vertex `o` at `position` lies on edge `i` of surface
/// `s` (whose corners are the output vertices `corners`) if it passes within
/// `tol` of it, with its parameter along it.
fn record_on_edge(
    s: &crate::mesh::Surface,
    corners: &[u32],
    i: usize,
    position: DVec3,
    o: u32,
    tol: f64,
    shared: &mut SharedVertices,
) {
    let k = s.vertices.len();
    let (a, b) = (s.vertices[i], s.vertices[(i + 1) % k]);
    let (ia, ib) = (corners[i], corners[(i + 1) % k]);
    let edge = b - a;
    let length2 = edge.length_squared();
    if length2.is_nan() || length2 <= 0.0 {
        return;
    }
    let t = (position - a).dot(edge) / length2;
    if !(-1e-9..=1.0 + 1e-9).contains(&t) {
        return;
    }
    if (a + edge * t - position).length() > tol {
        return;
    }
    let (key, t) = if ia <= ib {
        ((ia, ib), t)
    } else {
        ((ib, ia), 1.0 - t)
    };
    let list = shared.on_edges.entry(o).or_default();
    if !list.iter().any(|(e, _)| *e == key) {
        list.push((key, t));
        shared.edge_points.entry(key).or_default().push((t, o));
    }
}

impl SharedVertices {
    /// The mesh vertex whose block holds output vertex `o`'s value once
    /// [`SharedVertices::merge_values`] has run: its lighting group's first.
    pub(crate) fn value_vertex(&self, o: usize) -> usize {
        self.light_first[self.light_of[o] as usize] as usize
    }

    /// Averages the values of each lighting group in place: per mesh vertex
    /// `v` the block `range(v)` of `values` (an RGB radiance, or a vector of
    /// SH coefficients per channel); the group's first vertex's block becomes
    /// the area-weighted mean of its members' blocks (weights: a third or a
    /// quarter of each leaf element that has the vertex as a corner), the
    /// other blocks are left as they were. Averaging coefficient vectors
    /// averages the radiance functions they stand for. `values` is changed in
    /// place: a copy of every coefficient would add 8 bytes a coefficient to
    /// the output's peak (`budget.rs`, "output").
    pub(crate) fn merge_values(
        &self,
        mesh: &Mesh,
        range: impl Fn(usize) -> Range<usize>,
        values: &mut [f64],
        lone: Lone,
    ) {
        let weight = vertex_weights(mesh);
        let groups = Groups {
            of: &self.light_group,
            first: &self.light_first,
        };
        mean_blocks(groups, &weight, range, values, lone);
    }

    /// The mesh's display triangles in output vertices, with the triangles of
    /// smooth surfaces fanned to the vertices other polygons put inside their
    /// edges (see the module comment). Counter-clockwise order is kept.
    pub(crate) fn triangles(&self, mesh_triangles: &[[u32; 3]]) -> Vec<[u32; 3]> {
        let mut out = Vec::with_capacity(mesh_triangles.len());
        let mut stack = Vec::new();
        for t in mesh_triangles {
            let mapped = t.map(|v| self.output_of[v as usize]);
            if self.edge_points.is_empty() {
                out.push(mapped);
                continue;
            }
            // Fanning a triangle with k₁, k₂, k₃ points inside its edges
            // makes 1 + k₁ + k₂ + k₃ triangles: the fan's new inner edges run
            // from an edge's points to the opposite corner, and carry points
            // only when that corner lies on the same polygon edge, a triangle
            // of zero area, which `split_once` leaves alone when all three
            // corners share one edge. Fans of such slivers did not end on 100k
            // triangles of spheres (gigabytes in the output), and the corner
            // test alone does not stop them there (measured: still killed
            // after 90 s), so the bound is what ends them: a triangle whose
            // fan would exceed it is kept whole.
            let bound = 1
                + (0..3)
                    .map(|k| self.points_between(mapped[k], mapped[(k + 1) % 3]).len())
                    .sum::<usize>();
            let start = out.len();
            stack.push(mapped);
            while let Some(tri) = stack.pop() {
                match self.split_once(tri) {
                    Some(parts) => stack.extend(parts.into_iter().rev()),
                    None => out.push(tri),
                }
                if out.len() - start + stack.len() > bound {
                    stack.clear();
                    out.truncate(start);
                    out.push(mapped);
                }
            }
        }
        out
    }

    /// `tri` fanned at the first of its edges that has points of a polygon
    /// edge strictly inside it, or `None`.
    fn split_once(&self, tri: [u32; 3]) -> Option<Vec<[u32; 3]>> {
        for k in 0..3 {
            let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            let inside = self.points_between(a, b);
            // A corner on the same polygon edge as the other two: the
            // triangle has no area, and fanning it would only make slivers.
            if inside.is_empty() || self.shares_an_edge(a, b, c) {
                continue;
            }
            let mut chain = Vec::with_capacity(inside.len() + 2);
            chain.push(a);
            chain.extend(inside);
            chain.push(b);
            return Some(chain.windows(2).map(|w| [w[0], w[1], c]).collect());
        }
        None
    }

    /// Whether `a`, `b` and `c` all lie on one polygon edge.
    fn shares_an_edge(&self, a: u32, b: u32, c: u32) -> bool {
        let on = |v: u32| self.on_edges.get(&v).map_or(&[][..], |e| e.as_slice());
        on(a).iter().any(|(edge, _)| {
            on(b).iter().any(|(e, _)| e == edge) && on(c).iter().any(|(e, _)| e == edge)
        })
    }

    /// The output vertices strictly between `a` and `b` on a polygon edge both
    /// lie on, ordered from `a` to `b`.
    fn points_between(&self, a: u32, b: u32) -> Vec<u32> {
        let (Some(ea), Some(eb)) = (self.on_edges.get(&a), self.on_edges.get(&b)) else {
            return Vec::new();
        };
        for &(edge, ta) in ea {
            let Some(&(_, tb)) = eb.iter().find(|(e, _)| *e == edge) else {
                continue;
            };
            let (lo, hi) = (ta.min(tb), ta.max(tb));
            // Parameters of distinct vertices differ by far more than this
            // (vertices closer than the merge tolerance are one vertex).
            let margin = 1e-9;
            let mut inside: Vec<u32> = self.edge_points[&edge]
                .iter()
                .filter(|(t, o)| *t > lo + margin && *t < hi - margin && *o != a && *o != b)
                .map(|(_, o)| *o)
                .collect();
            if ta > tb {
                inside.reverse();
            }
            if !inside.is_empty() {
                return inside;
            }
        }
        Vec::new()
    }
}

/// Lighting groups: per mesh vertex its group, per group its first vertex.
#[derive(Clone, Copy)]
struct Groups<'a> {
    of: &'a [u32],
    first: &'a [u32],
}

/// `values` with each group's first block replaced by the weighted mean of
/// the blocks of every vertex in the group (every mean is summed before any
/// merged block is written, so changing `values` in place is safe), and each
/// lone vertex's block as `lone` says. A block whose length differs from the
/// first's is skipped (never the case for pieces of one polygon; kept so
/// that no two layouts are ever mixed).
fn mean_blocks(
    groups: Groups,
    weight: &[f64],
    range: impl Fn(usize) -> Range<usize>,
    values: &mut [f64],
    lone: Lone,
) {
    let mut members = vec![0u32; groups.first.len()];
    for &g in groups.of {
        members[g as usize] += 1;
    }
    // Sums only for the groups of more than one vertex, one after another.
    let mut start = vec![0usize; groups.first.len()];
    let mut len = 0;
    for (g, &first) in groups.first.iter().enumerate() {
        if members[g] > 1 {
            start[g] = len;
            len += range(first as usize).len();
        }
    }
    let mut sum = vec![0.0; len];
    let mut total = vec![0.0; groups.first.len()];
    for (v, &g) in groups.of.iter().enumerate() {
        let g = g as usize;
        // A vertex no leaf has as a corner (none today) still counts, a little.
        let w = weight[v].max(f64::MIN_POSITIVE);
        if members[g] <= 1 {
            if lone == Lone::Reweighted {
                for x in &mut values[range(v)] {
                    *x = (0.0 + *x * w) / w;
                }
            }
            continue;
        }
        let into = range(groups.first[g] as usize);
        let from = range(v);
        if from.len() != into.len() {
            continue;
        }
        let s = &mut sum[start[g]..start[g] + into.len()];
        for (acc, x) in s.iter_mut().zip(&values[from]) {
            *acc += *x * w;
        }
        total[g] += w;
    }
    for (g, &first) in groups.first.iter().enumerate() {
        if members[g] <= 1 {
            continue;
        }
        let into = range(first as usize);
        let s = &sum[start[g]..start[g] + into.len()];
        for (x, acc) in values[into].iter_mut().zip(s) {
            *x = acc / total[g];
        }
    }
}

/// Whether `position` is one of `surface`'s shadow apexes (`Surface::apexes`),
/// where its vertex keeps its own output vertex: the radiance's limit there
/// differs between the pieces that meet at the point.
fn at_apex(surface: &crate::mesh::Surface, position: DVec3, tol: f64) -> bool {
    surface
        .apexes
        .iter()
        .any(|&a| (a - position).length() <= tol)
}

fn mesh_diagonal(mesh: &Mesh) -> f64 {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for v in &mesh.vertices {
        lo = lo.min(v.position);
        hi = hi.max(v.position);
    }
    if lo.x > hi.x {
        0.0
    } else {
        (hi - lo).length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_edge_grid_lists_every_piece_edge_near_a_point() {
        check_edge_grid(glam::DQuat::IDENTITY, 5);
    }

    #[test]
    fn an_edge_grid_on_a_tilted_polygon_lists_each_edge_along_its_length() {
        // Tilted off every axis, a long edge's bounding box spans many cells
        // along all three: with 8 × 8 boxes (the most a receiver is cut by,
        // `MAX_FOOTPRINTS`) the floor's 2-long edges are about 10 cells
        // long, and listing their boxes put one in 315 cells, over its bound
        // of 168.
        let tilt = glam::DQuat::from_axis_angle(DVec3::new(1.0, 0.4, 0.7).normalize(), 0.9);
        check_edge_grid(tilt, 8);
    }

    /// A 2 × 2 floor under `n` × `n` open boxes (four sides each, standing on
    /// it), turned by `rotation`, is cut along their footprints into many pieces.
    /// For every piece corner and for points along every edge, lifted off it
    /// by less than the tolerance, each edge within the tolerance (by brute
    /// force over all pieces) is in the point's cell. And each edge is listed
    /// in at most 8 cells per half cell of its length, plus 8 for its end.
    fn check_edge_grid(rotation: glam::DQuat, n: usize) {
        use crate::solve::tests::{material, scene_of};
        let p = |x: f64, y: f64, z: f64| rotation * DVec3::new(x, y, z);
        let mut polygons = vec![(
            vec![p(0., 0., 0.), p(0., 0., 2.), p(2., 0., 2.), p(2., 0., 0.)],
            0,
        )];
        let pitch = 2.0 / n as f64;
        for i in 0..n {
            for j in 0..n {
                let (a, b) = (pitch * (i as f64 + 0.25), pitch * (j as f64 + 0.25));
                let (c, d, h) = (a + 0.425 * pitch, b + 0.575 * pitch, 0.2);
                polygons.push((vec![p(a, 0., b), p(a, h, b), p(c, h, b), p(c, 0., b)], 0));
                polygons.push((vec![p(a, 0., d), p(c, 0., d), p(c, h, d), p(a, h, d)], 0));
                polygons.push((vec![p(a, 0., b), p(a, 0., d), p(a, h, d), p(a, h, b)], 0));
                polygons.push((vec![p(c, 0., b), p(c, h, b), p(c, h, d), p(c, 0., d)], 0));
            }
        }
        let scene = scene_of(polygons, vec![material("grey", 0.5, 1.0)], 1);
        let mesh = crate::mesh::Mesh::new(&scene, DVec3::ZERO, 1).unwrap();
        let pieces: Vec<u32> = (0..mesh.surfaces.len() as u32)
            .filter(|&s| mesh.surfaces[s as usize].polygon == 0)
            .collect();
        assert!(pieces.len() > EdgeGrid::MIN_PIECES, "{}", pieces.len());
        let tol = 1e-5;
        let grid = EdgeGrid::new(&mesh, &pieces, tol);
        let within = |q: DVec3, s: u32, i: usize| {
            let v = &mesh.surfaces[s as usize].vertices;
            let (a, b) = (v[i], v[(i + 1) % v.len()]);
            let t = ((q - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            (a + (b - a) * t - q).length() <= tol
        };
        let mut points = Vec::new();
        for &s in &pieces {
            let v = &mesh.surfaces[s as usize].vertices;
            for i in 0..v.len() {
                let (a, b) = (v[i], v[(i + 1) % v.len()]);
                for k in 0..=16 {
                    let lift = DVec3::new(0.3, 0.5, -0.8).normalize() * tol * (k % 3) as f64 / 3.0;
                    points.push(a + (b - a) * (k as f64 / 16.0) + lift);
                }
            }
        }
        let mut checked = 0;
        for q in points {
            let near = grid.near(q);
            for &s in &pieces {
                for i in 0..mesh.surfaces[s as usize].vertices.len() {
                    if within(q, s, i) {
                        assert!(near.contains(&(s, i as u32)), "edge {i} of {s} at {q}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 1000, "{checked}");
        let mut listed: std::collections::HashMap<(u32, u32), f64> = Default::default();
        for list in grid.cells.values() {
            for &edge in list {
                *listed.entry(edge).or_default() += 1.0;
            }
        }
        for (&(s, i), &cells) in &listed {
            let v = &mesh.surfaces[s as usize].vertices;
            let length = (v[(i as usize + 1) % v.len()] - v[i as usize]).length();
            let bound = 8.0 * ((length / (0.5 * grid.cell)).ceil().max(1.0) + 1.0);
            assert!(
                cells <= bound,
                "edge {i} of {s}: {cells} cells, bound {bound}"
            );
        }
    }

    /// Output vertices 0–3 on one polygon edge (0, 3) at parameters 0, ¼, ½
    /// and 1; vertex 4 off it.
    fn one_edge() -> SharedVertices {
        let edge: EdgeKey = (0, 3);
        let points = vec![(0.0, 0), (0.25, 1), (0.5, 2), (1.0, 3)];
        SharedVertices {
            output_of: (0..5).collect(),
            representative: (0..5).collect(),
            light_group: (0..5).collect(),
            light_first: (0..5).collect(),
            light_of: (0..5).collect(),
            on_edges: points.iter().map(|&(t, o)| (o, vec![(edge, t)])).collect(),
            edge_points: IntMap::from_iter([(edge, points)]),
        }
    }

    #[test]
    fn a_triangle_is_fanned_at_its_edge_points_and_a_sliver_is_kept_whole() {
        let shared = one_edge();
        // A proper triangle on the edge: fanned from its opposite corner.
        assert_eq!(
            shared.triangles(&[[0, 3, 4]]),
            vec![[0, 1, 4], [1, 2, 4], [2, 3, 4]]
        );
        // A triangle whose three corners lie on the edge has no area; fanned,
        // it became slivers with repeated corners, and on 100k triangles of
        // spheres such fans never ended. It is kept as it is.
        assert_eq!(shared.triangles(&[[0, 3, 1]]), vec![[0, 3, 1]]);
    }

    #[test]
    fn merged_blocks_are_the_weighted_mean_of_every_coefficient() {
        // Vertices 0 and 2 merge into group 0 (weights 1 and 3), vertex 1
        // is alone; blocks of 4 values. The mean is taken per coefficient,
        // so it is the mean of the radiance functions in every direction.
        let block = |v: usize| 4 * v..4 * v + 4;
        let values: Vec<f64> = (0..12).map(|k| k as f64).collect();
        let groups = Groups {
            of: &[0, 1, 0],
            first: &[0, 1],
        };
        let weight = [1.0, 5.0, 3.0];
        let mut merged = values.clone();
        mean_blocks(groups, &weight, block, &mut merged, Lone::Kept);
        for k in 0..4 {
            let expected = (values[k] + 3.0 * values[8 + k]) / 4.0;
            assert!((merged[k] - expected).abs() < 1e-12, "{k}");
            // The lone vertex and the block merged away are untouched.
            assert_eq!(merged[4 + k], values[4 + k]);
            assert_eq!(merged[8 + k], values[8 + k]);
        }
        // Reweighted, the lone vertex's block is (0 + x·w)/w: within a
        // rounding of x.
        let mut reweighted = values.clone();
        mean_blocks(groups, &weight, block, &mut reweighted, Lone::Reweighted);
        assert_eq!(reweighted[..4], merged[..4]);
        for k in 4..8 {
            assert!(
                (reweighted[k] - values[k]).abs() <= 1e-15 * values[k],
                "{k}"
            );
        }
    }

    #[test]
    fn blocks_of_another_length_are_never_mixed() {
        // Vertex 1 (a 3-value block) is in the same group as vertex 0 (a
        // 12-value block): it must be skipped, leaving vertex 0's block.
        let ranges = [0..12, 12..15];
        let values: Vec<f64> = (0..15).map(|k| 1.0 + k as f64).collect();
        let mut merged = values.clone();
        let groups = Groups {
            of: &[0, 0],
            first: &[0],
        };
        let range = |v: usize| ranges[v].clone();
        mean_blocks(groups, &[1.0, 1.0], range, &mut merged, Lone::Kept);
        assert_eq!(merged, values);
    }
}
