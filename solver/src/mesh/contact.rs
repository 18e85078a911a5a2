//! Receivers conformed to contact lines: a polygon that another object touches
//! or covers is cut along the edges of the contact's footprint before meshing,
//! so that no element spans the line where the visible part of the receiver
//! meets the covered part.
//!
//! The Cornell box's floor is one quad that runs under both blocks (which
//! have no bottom face), and its light hangs 0.1 mm below the ceiling quad.
//! Meshed as one piece, a floor element that straddles a block's base has
//! corners under the block; those are hidden (`solve::hidden`) and display
//! their visible neighbours' radiance, one element away, so the visible floor
//! next to the block shows a value extended over an element's width instead
//! of its own (the dark rims round the blocks' bases in docs/lab/contact-cuts.md).
//! Conformed, the floor's elements next to the block have their corners on
//! the contact line, on the visible side, where they receive exactly.
//!
//! * **Footprints.** For a convex, flat receiver A, the vertices of other
//!   polygons that lie on A's plane (within [`CONTACT_TOLERANCE`] of the scene
//!   diagonal) and inside A are grouped by the object they belong to (the
//!   polygons connected through shared vertex positions), and each group's
//!   convex hull in A's plane is a footprint. A's own object (the walls that
//!   share the floor's corners) and polygons in A's very plane (a decal) do
//!   not count. The hull may over-cover a
//!   non-convex footprint; its inner piece is then partly visible, which the
//!   hidden-vertex probe decides per vertex, so that is harmless.
//! * **Cutting.** A is cut by the convex difference with each footprint: by
//!   each footprint edge's line in turn, keeping the piece outside it and
//!   going on with the rest; what is left is A ∩ footprint, the covered piece
//!   ([`Part::covered`]). A piece that does not overlap a footprint is not cut
//!   by its lines.
//! * **Seams.** The visible pieces are marked as one smooth surface (their
//!   corner normals are all A's normal), so the solution's seam pass
//!   (`solve::seams`) gives coincident vertices along their cuts one output
//!   vertex and resolves the T-junctions across them: no crack and no step
//!   in value opens along a cut. The covered piece stays a flat facet with
//!   its own vertices along the contact line, so the hidden vertices there are
//!   not averaged with the visible ones; a crack along that line could only
//!   show the covering object's base, which stands on it.
//! * **Shadow lines.** The visible parts are also cut along the lines that
//!   the occluder's edges standing on each footprint corner cast from the
//!   sun and each lamp (in both modes), and from each emitter vertex
//!   (directional mode, [`Cuts::ShadowLines`]) ([`cut_shadow_lines`]): a sun's
//!   or a lamp's two silhouette lines, its shadow's sides, through every part
//!   they cross, every other line through the parts at its corner only. The
//!   corner is then an apex where the radiance's limit depends on the side:
//!   each part keeps its own vertex there ([`Part::apexes`]), which the seam
//!   pass does not merge.
//!
//! Receivers left whole: non-convex polygons, smooth ones (their corner
//! normals would need interpolating), and polygons no other object touches.

use crate::scene::Scene;
use glam::{DVec2, DVec3};
use std::collections::HashMap;

mod points;

/// A point lies on a receiver's plane when it is within this fraction of the
/// scene diagonal of it. The Cornell box's light hangs 0.1 mm below its
/// ceiling, 1.04e-4 of the 961 mm diagonal, and must count as covering it;
/// twice that still leaves a gap no eye can see into.
pub const CONTACT_TOLERANCE: f64 = 2e-4;

/// Polygons within this fraction of the contact tolerance of a receiver's
/// plane at every vertex lie in it (rounding of the input's coordinates).
const COPLANAR: f64 = 1e-3;

/// A receiver touched by more objects than this stays whole. Cutting is
/// quadratic in the footprints (each one is cut through every piece so far),
/// and each cut line carries patches along its whole length: a floor under
/// 83,000 small boxes (the 1M-triangle scale scene) took over 13 minutes of
/// one core before its first shot. Such a receiver keeps the hidden-vertex
/// treatment (`solve/hidden.rs`), which every receiver had before the cuts.
/// The Cornell box's floor has two footprints and its ceiling one.
pub const MAX_FOOTPRINTS: usize = 64;

/// Shadow lines are cut only when the emitters have at most this many
/// vertices in all (the Cornell box's light has 4): each adds a line at every
/// footprint corner.
pub const MAX_SHADOW_LIGHT_VERTICES: usize = 16;

/// A piece of a receiver after cutting, counter-clockwise about the
/// receiver's normal.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    pub vertices: Vec<DVec3>,
    /// Inside a footprint: covered by the object that touches the receiver.
    pub covered: bool,
    /// The footprint corners among this part's vertices that shadow lines
    /// leave from ([`cut_shadow_lines`]): there the radiance's limit depends
    /// on the direction of approach, so the part keeps its own vertex.
    pub apexes: Vec<DVec3>,
}

/// How receivers are cut before meshing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cuts {
    /// Every receiver whole.
    None,
    /// Along contact lines (this module's cuts).
    Contacts,
    /// Along contact lines, and along the shadow lines that leave each
    /// footprint corner ([`cut_shadow_lines`]).
    ShadowLines,
}

impl Cuts {
    /// The cuts a solve with `settings` makes. The emitters' shadow lines
    /// are cut in directional mode only (the sun's and the lamps' in both,
    /// [`ShadowCasters`]: their shadows are hard): there they take the glossy Cornell box's floor
    /// camera from 7.50% to 4.40% MARE at `final` (9.60% to 5.97% at
    /// `medium`), while in diffuse mode they made the Cornell box's `final`
    /// worse (1.44% → 1.52%, past its 1.5% target; errors of 12–40% at the
    /// foot of the short block's front face) for a gain at `medium` (2.32% →
    /// 2.20%): docs/lab/glossy-shadow-lines.md, "Glossy: shadow lines at contact corners".
    pub fn for_settings(settings: &crate::settings::SolverSettings) -> Cuts {
        if settings.whole_receivers {
            Cuts::None
        } else if settings.mode == solution::format::SolveMode::Directional {
            Cuts::ShadowLines
        } else {
            Cuts::Contacts
        }
    }
}

/// For every polygon of `scene`, its parts, or `None` where it stays whole.
pub fn conform(scene: &Scene, cuts: Cuts) -> Vec<Option<Vec<Part>>> {
    conform_observed(scene, cuts, &mut crate::progress::Quiet)
}

/// [`conform`], reporting to `observer` ([`crate::progress::Pass::ContactCuts`]).
/// The receivers are cut in parallel, chunk by chunk, in the scene's order.
pub fn conform_observed(
    scene: &Scene,
    cuts: Cuts,
    observer: &mut dyn crate::progress::Observer,
) -> Vec<Option<Vec<Part>>> {
    use rayon::prelude::*;
    let pass = crate::progress::Pass::ContactCuts;
    let count = scene.polygons.len();
    observer.advance(pass, 0, count as u64);
    let diagonal = crate::mesh::sizing::scene_diagonal(scene);
    if cuts == Cuts::None || !(diagonal.is_finite() && diagonal > 0.0) || count < 2 {
        observer.advance(pass, count as u64, count as u64);
        return vec![None; count];
    }
    let tol = CONTACT_TOLERANCE * diagonal;
    let context = Context {
        scene,
        objects: objects(scene, tol),
        tree: vertex_tree(scene),
        casters: ShadowCasters::of(scene, cuts),
        tol,
    };
    let mut out = Vec::with_capacity(count);
    for start in (0..count).step_by(crate::progress::CHUNK) {
        let end = (start + crate::progress::CHUNK).min(count);
        let chunk: Vec<Option<Vec<Part>>> = (start..end)
            .into_par_iter()
            .map_init(Vec::new, |near, index| context.parts_of(index, near))
            .collect();
        out.extend(chunk);
        observer.advance(pass, end as u64, count as u64);
    }
    out
}

/// What cutting one receiver reads.
struct Context<'s> {
    scene: &'s Scene,
    objects: Vec<usize>,
    tree: points::PointTree,
    casters: ShadowCasters,
    tol: f64,
}

impl Context<'_> {
    /// Polygon `index`'s parts, or `None` where it stays whole; `near` is
    /// scratch.
    fn parts_of(&self, index: usize, near: &mut Vec<(u32, u32)>) -> Option<Vec<Part>> {
        let (scene, tol) = (self.scene, self.tol);
        let polygon = &scene.polygons[index];
        let v = &polygon.vertices;
        if v.len() < 3
            || polygon.vertex_normals.is_some()
            || !v.iter().all(|p| p.is_finite())
            || !crate::geometry::polygon::is_convex(v)
        {
            return None;
        }
        let frame = Frame::new(v)?;
        let footprints = footprints(self, index, &frame, near)?;
        if footprints.is_empty() {
            return None;
        }
        let outline: Vec<DVec2> = v.iter().map(|&p| frame.project(p)).collect();
        let mut parts = cut(&outline, &footprints, tol);
        let groups = self.casters.seen_from(&frame, tol);
        let mut corners = Vec::new();
        if !groups.is_empty() {
            (parts, corners) = cut_shadow_lines(parts, &footprints, &groups, tol);
        }
        (parts.len() > 1).then(|| {
            parts
                .into_iter()
                .map(|(ring, covered)| Part {
                    apexes: corners
                        .iter()
                        .filter(|&&c| !covered && ring.iter().any(|&q| (q - c).length() <= tol))
                        .map(|&c| frame.lift(c))
                        .collect(),
                    // The receiver's own corners are kept bit for bit
                    // (they meet other polygons' corners); new ones are
                    // lifted from the plane.
                    vertices: ring
                        .iter()
                        .map(|&q| {
                            outline
                                .iter()
                                .position(|&o| (o - q).length() <= 1e-6 * tol)
                                .map_or_else(|| frame.lift(q), |k| v[k])
                        })
                        .collect(),
                    covered,
                })
                .collect()
        })
    }
}

/// What casts the shadow lines cut at footprint corners: the emitters'
/// vertices (directional mode, at most [`MAX_SHADOW_LIGHT_VERTICES`] in
/// all), and in both modes the lamps (points, as many) and the sun (a
/// direction). A lamp or the sun casts a hard shadow whose sides leave the
/// corners of whatever stands on a receiver (a column's umbra on a sunlit
/// floor), which refinement cannot find when no vertex lies inside it.
struct ShadowCasters {
    emitter_vertices: Vec<DVec3>,
    lamps: Vec<DVec3>,
    /// Toward the sun, unit.
    sun: Option<DVec3>,
}

impl ShadowCasters {
    fn of(scene: &Scene, cuts: Cuts) -> ShadowCasters {
        // Each emitter vertex adds a line at every footprint corner, and a
        // receiver's parts grow with the lines: a scene lit by many
        // polygons keeps the contact cuts alone.
        let mut emitter_vertices: Vec<DVec3> = scene
            .polygons
            .iter()
            .filter(|p| {
                cuts == Cuts::ShadowLines
                    && scene
                        .materials
                        .get(p.material)
                        .is_some_and(|m| m.emission != DVec3::ZERO)
            })
            .flat_map(|p| p.vertices.iter().copied())
            .collect();
        if emitter_vertices.len() > MAX_SHADOW_LIGHT_VERTICES {
            emitter_vertices.clear();
        }
        let mut lamps: Vec<DVec3> = scene.lights.lamps.iter().map(|l| l.position).collect();
        if lamps.len() > MAX_SHADOW_LIGHT_VERTICES {
            lamps.clear();
        }
        ShadowCasters {
            emitter_vertices,
            lamps,
            sun: scene.lights.sun.as_ref().map(|s| s.direction()),
        }
    }

    /// The casters above a receiver's plane, projected on it, in groups
    /// whose lines are cut together: the emitter's vertices, each lamp, the
    /// sun (as its shadow's direction).
    fn seen_from(&self, frame: &Frame, tol: f64) -> Vec<Caster> {
        let above = |p: &&DVec3| frame.height(**p) > tol;
        let mut groups = Vec::new();
        let emitter: Vec<DVec2> = self
            .emitter_vertices
            .iter()
            .filter(above)
            .map(|&p| frame.project(p))
            .collect();
        if !emitter.is_empty() {
            groups.push(Caster::Points(emitter));
        }
        for lamp in self.lamps.iter().filter(above) {
            groups.push(Caster::Points(vec![frame.project(*lamp)]));
        }
        if let Some(sun) = self.sun.filter(|s| s.dot(frame.n) > 0.0) {
            let along = DVec2::new(sun.dot(frame.t), sun.dot(frame.b));
            if let Some(away) = (-along).try_normalize() {
                groups.push(Caster::Direction(away));
            }
        }
        groups
    }
}

/// One group of shadow casters as seen in a receiver's plane.
enum Caster {
    /// Points (projected): the lines leave a corner away from each.
    Points(Vec<DVec2>),
    /// A light at infinity: the lines leave every corner along this
    /// direction.
    Direction(DVec2),
}

impl Caster {
    /// The directions of the shadow lines from corner `c`.
    fn directions(&self, c: DVec2) -> Vec<DVec2> {
        match self {
            Caster::Points(points) => points
                .iter()
                .filter_map(|&l| (c - l).try_normalize())
                .collect(),
            Caster::Direction(d) => vec![*d],
        }
    }
}

/// A receiver's plane: its first vertex and an orthonormal frame (t, b, n)
/// with n its Newell normal, so that counter-clockwise about n is
/// counter-clockwise in (t, b).
struct Frame {
    origin: DVec3,
    t: DVec3,
    b: DVec3,
    n: DVec3,
}

impl Frame {
    fn new(v: &[DVec3]) -> Option<Frame> {
        let n = crate::geometry::polygon::newell_normal(v).try_normalize()?;
        let t = (0..v.len())
            .map(|i| {
                let e = v[(i + 1) % v.len()] - v[i];
                (e - n * n.dot(e)).normalize_or_zero()
            })
            .find(|t| *t != DVec3::ZERO)?;
        Some(Frame {
            origin: v[0],
            t,
            b: n.cross(t),
            n,
        })
    }
    fn project(&self, p: DVec3) -> DVec2 {
        let d = p - self.origin;
        DVec2::new(d.dot(self.t), d.dot(self.b))
    }
    fn lift(&self, q: DVec2) -> DVec3 {
        self.origin + self.t * q.x + self.b * q.y
    }
    fn height(&self, p: DVec3) -> f64 {
        (p - self.origin).dot(self.n)
    }
}

/// Per polygon, the object it belongs to: polygons joined through vertices at
/// the same position (within `tol`, by a grid of `tol`-wide cells, so a pair
/// that straddles a cell boundary may be missed; that only splits an object's
/// footprint in two hulls).
fn objects(scene: &Scene, tol: f64) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..scene.polygons.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut first: HashMap<[i64; 3], usize> = HashMap::new();
    for (index, polygon) in scene.polygons.iter().enumerate() {
        for p in &polygon.vertices {
            let key = cell(*p, tol);
            let other = *first.entry(key).or_insert(index);
            let (a, b) = (root(&mut parent, index), root(&mut parent, other));
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    (0..parent.len()).map(|i| root(&mut parent, i)).collect()
}

fn cell(p: DVec3, size: f64) -> [i64; 3] {
    let c = (p / size).floor();
    [c.x as i64, c.y as i64, c.z as i64]
}

/// Every finite polygon vertex of the scene, in a k-d tree ([`points`]).
fn vertex_tree(scene: &Scene) -> points::PointTree {
    let (points, items) = scene
        .polygons
        .iter()
        .enumerate()
        .flat_map(|(i, polygon)| {
            polygon
                .vertices
                .iter()
                .enumerate()
                .map(move |(k, &p)| (p, (i as u32, k as u32)))
        })
        .unzip();
    points::PointTree::new(points, items)
}

/// The footprints on receiver `index`: per touching object, the convex hull
/// (counter-clockwise, in the receiver's plane) of its vertices on the plane
/// and inside the receiver; `None` when more than [`MAX_FOOTPRINTS`] objects
/// touch it (it stays whole, and no hull is computed).
fn footprints(
    context: &Context,
    index: usize,
    frame: &Frame,
    near: &mut Vec<(u32, u32)>,
) -> Option<Vec<Vec<DVec2>>> {
    let (scene, objects, tol) = (context.scene, &context.objects, context.tol);
    let v = &scene.polygons[index].vertices;
    let (lo, hi) = v
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let query = points::Query {
        lo: lo - DVec3::splat(tol),
        hi: hi + DVec3::splat(tol),
        origin: frame.origin,
        normal: frame.n,
        tol,
    };
    context.tree.near(&query, near);
    let outline: Vec<DVec2> = v.iter().map(|&p| frame.project(p)).collect();
    let mut by_object: HashMap<usize, Vec<DVec2>> = HashMap::new();
    let mut coplanar: HashMap<u32, bool> = HashMap::new();
    for &(polygon, vertex) in near.iter() {
        // The receiver's own object (the walls that share the floor's
        // corners) is meshed as its input joins it.
        if objects[polygon as usize] == objects[index] {
            continue;
        }
        // A polygon in the receiver's very plane (a decal, overlapping
        // tiles) is the same surface, not a cover; the Cornell box's light,
        // 0.1 mm off its ceiling, is not in it.
        let same_plane = *coplanar.entry(polygon).or_insert_with(|| {
            scene.polygons[polygon as usize]
                .vertices
                .iter()
                .all(|&p| frame.height(p).abs() <= COPLANAR * tol)
        });
        if same_plane {
            continue;
        }
        let p = scene.polygons[polygon as usize].vertices[vertex as usize];
        if frame.height(p).abs() > tol {
            continue;
        }
        let q = frame.project(p);
        if inside(&outline, q, tol) {
            by_object
                .entry(objects[polygon as usize])
                .or_default()
                .push(q);
        }
    }
    if by_object.len() > MAX_FOOTPRINTS {
        return None;
    }
    let mut keys: Vec<usize> = by_object.keys().copied().collect();
    keys.sort_unstable();
    let area = ring_area(&outline);
    let hulls = keys
        .into_iter()
        .filter_map(|k| {
            let hull = convex_hull(&by_object[&k]);
            // A hull of a point or a segment (a wall's base on the floor's
            // edge) covers nothing.
            (hull.len() >= 3 && ring_area(&hull) > 1e-9 * area).then_some(hull)
        })
        .collect();
    Some(hulls)
}

/// Whether `q` is inside the counter-clockwise convex `ring`, or within `tol`
/// outside it.
fn inside(ring: &[DVec2], q: DVec2, tol: f64) -> bool {
    (0..ring.len()).all(|i| {
        let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
        let d = b - a;
        d.perp_dot(q - a) >= -tol * d.length()
    })
}

fn ring_area(ring: &[DVec2]) -> f64 {
    0.5 * (0..ring.len())
        .map(|i| ring[i].perp_dot(ring[(i + 1) % ring.len()]))
        .sum::<f64>()
}

/// Andrew's monotone chain: the convex hull, counter-clockwise, without
/// collinear points.
pub(crate) fn convex_hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut p = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut hull: Vec<DVec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2 {
                let (a, b) = (hull[hull.len() - 2], hull[hull.len() - 1]);
                if (b - a).perp_dot(q - a) <= 0.0 {
                    hull.pop();
                } else {
                    break;
                }
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// `outline` (convex, counter-clockwise) cut by each footprint in turn: the
/// pieces outside every footprint and the covered pieces, each with whether it
/// is covered. Pieces with (near) zero area are dropped.
fn cut(outline: &[DVec2], footprints: &[Vec<DVec2>], tol: f64) -> Vec<(Vec<DVec2>, bool)> {
    let floor = 1e-9 * ring_area(outline).abs();
    let snap = 1e-6 * tol.max(f64::MIN_POSITIVE);
    let mut parts = vec![(outline.to_vec(), false)];
    for hull in footprints {
        let mut next = Vec::with_capacity(parts.len() + hull.len());
        for (part, covered) in parts {
            // Only a piece that overlaps the footprint is cut by its lines.
            let mut rest = part.clone();
            for i in 0..hull.len() {
                rest = clip(&rest, hull[i], hull[(i + 1) % hull.len()], snap);
            }
            if covered || ring_area(&rest) <= floor {
                next.push((part, covered));
                continue;
            }
            let mut rest = part;
            for i in 0..hull.len() {
                let (a, b) = (hull[i], hull[(i + 1) % hull.len()]);
                let outside = clip(&rest, b, a, snap);
                if ring_area(&outside) > floor {
                    next.push((outside, false));
                }
                rest = clip(&rest, a, b, snap);
            }
            next.push((rest, true));
        }
        parts = next;
    }
    parts
}

/// The uncovered parts cut along the shadow lines that leave each footprint
/// corner, and the corners where a line split a part (the apexes).
///
/// An occluder's edge that stands on the receiver at a footprint corner casts,
/// from each emitter vertex, a shadow line through the corner, directed away
/// from the vertex's projection onto the plane. Between the extreme lines lies
/// the edge's penumbra, which narrows to nothing at the corner, so near it the
/// radiance steps from umbra to light within a fraction of any element. With
/// an element edge on every line, Gouraud shading interpolates each wedge
/// between the lines from its own vertices; and since the radiance's limit at
/// the corner itself depends on the wedge it is approached from (lit on one
/// side, dark in the umbra), every part meeting there keeps its own vertex
/// at the apex, received a step inside the part (`Surface::apexes`,
/// `solve/seams.rs`). Corners under the emitter (its vertices spread over a
/// right angle or more as seen from the corner) get no lines: there the
/// edge's shadow is not a narrow wedge.
fn cut_shadow_lines(
    mut parts: Vec<(Vec<DVec2>, bool)>,
    footprints: &[Vec<DVec2>],
    casters: &[Caster],
    tol: f64,
) -> (Vec<(Vec<DVec2>, bool)>, Vec<DVec2>) {
    let mut apexes = Vec::new();
    let snap = 1e-6 * tol.max(f64::MIN_POSITIVE);
    let floor = 1e-9 * parts.iter().map(|(r, _)| ring_area(r).abs()).sum::<f64>();
    for hull in footprints {
        for &c in hull {
            let mut split = false;
            for caster in casters {
                let directions = caster.directions(c);
                if !narrow(&directions) {
                    continue;
                }
                for &d in &directions {
                    let cut;
                    // A sun's or a lamp's shadow has sharp sides; an
                    // emitter's lines bound penumbrae, at their corners.
                    let sharp = directions.len() == 1;
                    let reach = if sharp && silhouette(hull, c, d, tol) {
                        Reach::Through
                    } else {
                        Reach::Corner
                    };
                    (parts, cut) = cut_ray(parts, c, d, reach, snap, floor);
                    split |= cut;
                }
            }
            // Lines that only run into the footprint split nothing, and the
            // corner stays an ordinary vertex.
            if split {
                apexes.push(c);
            }
        }
    }
    (parts, apexes)
}

/// Whether `directions` spread over less than a right angle: the corner is
/// not under the emitter they come from, so its edge's shadow is a narrow
/// wedge. (One direction always is.)
fn narrow(directions: &[DVec2]) -> bool {
    let Some(&first) = directions.first() else {
        return false;
    };
    let angle = |d: DVec2| first.perp_dot(d).atan2(first.dot(d));
    let (lo, hi) = directions
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &d| {
            (lo.min(angle(d)), hi.max(angle(d)))
        });
    hi - lo < std::f64::consts::FRAC_PI_2
}

/// How far a shadow line cuts ([`cut_ray`]).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Reach {
    /// The parts at its corner only: a line inside the shadow, between
    /// the silhouette's two, bounds no umbra far from the corner.
    Corner,
    /// Every part it runs through: a silhouette line is the umbra's side
    /// all along, and the contact cut's pieces (long wedges that fan out
    /// from a round footprint) cross it far from the corner
    /// (docs/lab/lights-atrium.md, "Column bases").
    Through,
}

/// Whether the line through footprint corner `c` along `d` has the whole
/// footprint `hull` on one side (within `tol`): it is a side of the shadow.
fn silhouette(hull: &[DVec2], c: DVec2, d: DVec2, tol: f64) -> bool {
    let side = |v: DVec2| d.perp_dot(v - c);
    hull.iter().all(|&v| side(v) <= tol) || hull.iter().all(|&v| side(v) >= -tol)
}

/// Whether the ray from `c` along `d` runs into the convex `part`: the line
/// crosses its interior, and every point of that crossing lies ahead of `c`
/// (within `eps`; the line's other half, toward the light, is no shadow's
/// edge).
fn ray_enters(part: &[DVec2], c: DVec2, d: DVec2, eps: f64) -> bool {
    let side = |i: usize| d.perp_dot(part[i] - c);
    let (lo, hi) = (0..part.len())
        .map(side)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
            (lo.min(s), hi.max(s))
        });
    if !(lo < -eps && hi > eps) {
        return false;
    }
    // Where the line crosses the part's edges, as distances along it.
    let crossings = (0..part.len()).filter_map(|i| {
        let j = (i + 1) % part.len();
        let (a, b) = (side(i), side(j));
        ((a < 0.0) != (b < 0.0)).then(|| (part[i] + (part[j] - part[i]) * (a / (a - b)) - c).dot(d))
    });
    crossings.fold(f64::INFINITY, f64::min) >= -eps
}

/// Cuts the parts that the ray from corner `c` along `d` runs into, as far
/// as `reach` says; returns the parts and whether any was split.
fn cut_ray(
    parts: Vec<(Vec<DVec2>, bool)>,
    c: DVec2,
    d: DVec2,
    reach: Reach,
    snap: f64,
    floor: f64,
) -> (Vec<(Vec<DVec2>, bool)>, bool) {
    let mut split = false;
    let mut next = Vec::with_capacity(parts.len() + 1);
    for (part, covered) in parts {
        // The corner lies on the part's boundary (a vertex, or on an edge:
        // the footprint's cut lines run past it), and the shadow line, a ray
        // from the corner, runs into the part (the line's other half, toward
        // the light, is no shadow's edge).
        let touches = (0..part.len())
            .any(|i| segment_distance(c, part[i], part[(i + 1) % part.len()]) <= 1e3 * snap);
        let step = 1e-3 * ring_area(&part).abs().sqrt();
        let enters = match reach {
            Reach::Corner => touches && inside_convex(&part, c + d * step),
            Reach::Through => ray_enters(&part, c, d, 1e3 * snap),
        };
        if covered || !enters {
            next.push((part, covered));
            continue;
        }
        let left = clip(&part, c, c + d, snap);
        let right = clip(&part, c + d, c, snap);
        if ring_area(&left) > floor && ring_area(&right) > floor {
            next.push((left, false));
            next.push((right, false));
            split = true;
        } else {
            next.push((part, false));
        }
    }
    (next, split)
}

/// Whether `p` lies strictly inside the convex counter-clockwise `ring`.
fn inside_convex(ring: &[DVec2], p: DVec2) -> bool {
    (0..ring.len()).all(|i| {
        let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
        (b - a).perp_dot(p - a) > 0.0
    })
}

/// The distance from `p` to the segment a–b.
fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).length()
}

/// The part of convex `ring` to the left of the directed line a → b (points
/// within `snap` of it count as on it), without repeated or collinear
/// vertices.
fn clip(ring: &[DVec2], a: DVec2, b: DVec2, snap: f64) -> Vec<DVec2> {
    let d = b - a;
    let length = d.length();
    if ring.is_empty() || length <= 0.0 {
        return Vec::new();
    }
    let side = |p: DVec2| {
        let s = d.perp_dot(p - a) / length;
        if s.abs() <= snap {
            0.0
        } else {
            s
        }
    };
    let mut out: Vec<DVec2> = Vec::with_capacity(ring.len() + 1);
    let mut prev = ring[ring.len() - 1];
    let mut prev_s = side(prev);
    for &cur in ring {
        let cur_s = side(cur);
        if (prev_s > 0.0 && cur_s < 0.0) || (prev_s < 0.0 && cur_s > 0.0) {
            let t = prev_s / (prev_s - cur_s);
            out.push(prev + (cur - prev) * t);
        }
        if cur_s >= 0.0 {
            out.push(cur);
        }
        prev = cur;
        prev_s = cur_s;
    }
    simplify(out, snap)
}

/// Drops repeated vertices and vertices on the line through their neighbours.
fn simplify(mut ring: Vec<DVec2>, snap: f64) -> Vec<DVec2> {
    let mut changed = true;
    while changed && ring.len() >= 3 {
        changed = false;
        for i in 0..ring.len() {
            let n = ring.len();
            let (a, b, c) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
            let ac = c - a;
            let straight = ac.length() <= snap
                || (b - a).length() <= snap
                || (ac.perp_dot(b - a) / ac.length()).abs() <= snap;
            if straight {
                ring.remove(i);
                changed = true;
                break;
            }
        }
    }
    if ring.len() < 3 {
        ring.clear();
    }
    ring
}

#[cfg(test)]
mod tests;
