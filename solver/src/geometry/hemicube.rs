//! Hemicube form factors (radiosity lecture notes, "The Hemicube method"; Immel, Cohen and Greenberg 1986, "The global cube",
//! after Cohen and Greenberg 1985).
//!
//! A hemicube of half-side 1 sits on a point with its top face at height 1 above
//! it, along the point's normal. The top face is divided into R × R square cells
//! and each of the four sides into R × R/2 (the sides only cover the upper half
//! of the cube), 3R² cells in all, each of side h = 2/R. The scene's polygons are
//! projected onto the five faces with a depth test, so each cell holds the
//! nearest polygon seen through it (an *item buffer*); the form factor from the
//! point to a polygon is the sum of the *delta form factors* of the cells that
//! hold it (radiosity lecture notes). The five frusta partition the upper hemisphere exactly, so in
//! a closed scene the factors sum to one.
//!
//! ## Delta form factors
//!
//! The radiosity lecture notes give the midpoint values ΔF = ΔA / (π (x² + y² + 1)²) on the top face and
//! ΔF = z ΔA / (π (y² + z² + 1)²) on a side. Here each cell's delta form factor
//! is instead the *exact* factor from the point to the cell, computed once per
//! resolution by Lambert's contour formula
//! ([`super::formfactor::point_to_polygon`]). The midpoint values differ from
//! the exact ones by O(h²) relative (a unit test checks it against the radiosity lecture notes'
//! formulas) and make a closed scene sum to 1 + O(h²); the exact ones sum to
//! one within f64 rounding, so the only error left is the item buffer's.
//!
//! ## Item buffer: rasterised, not ray-cast
//!
//! The radiosity lecture notes offer both: a ray per cell through its centre (nearest hit), or
//! projecting each polygon onto the faces with a z-buffer. The polygons are
//! rasterised here, because
//! * the answer needed is *which* polygon is nearest, and the solver's
//!   [`super::visibility::Occluder`] is an any-hit structure (it answers "is
//!   this segment blocked", not "what is hit first"); and
//! * with n targets and 3R² cells, rasterisation costs O(n + covered cells)
//!   per hemicube, against 3R² tree walks for ray casting: for the few hundred
//!   patches and R ≤ 512 the solver uses, a rasterised hemicube is the cheaper
//!   one.
//!
//! Each target is clipped (in f64) to each face's frustum (four planes through
//! the hemicube's centre, and for a side the base plane), projected, and filled
//! by cell centres with inclusive edge tests: a cell whose centre lies on an
//! edge shared by two polygons is written by both and kept by the nearer, so
//! no cell between abutting polygons is left empty. The depth of a polygon at
//! a cell is the exact distance along the face's axis to the polygon's plane
//! through the cell's centre (its reciprocal is linear across the face).
//! Targets seen from behind are drawn too (they hide what is behind them) but
//! flagged with [`BACK_FACE`]: a one-sided polygon gives nothing to a point
//! behind it. Targets in, or behind, the hemicube's base plane (the receiving
//! polygon itself) and targets whose plane passes through the centre (seen
//! edge-on) are skipped.
//!
//! The same buffer answers visibility for shooting (the solver's
//! `--method hemicube`): [`ItemBuffer::segment_visible`] takes the
//! polygons the cells around a point's direction hold as candidate occluders
//! and tests each exactly against the segment to the point, as Haines and
//! Greenberg's light buffer does (1986).
//!
//! ## Accuracy against R
//!
//! A cell is counted whole for the polygon seen through its centre, so the
//! error comes from the cells that a polygon's projected outline crosses.
//! Where an edge runs along the cell grid (a hemicube whose axes line up with
//! a box-shaped room's walls), every cell along it is misjudged by the same
//! strip, up to h/2 wide: the error is O(h), at most (h/2) × the projected
//! outline length × the density 1/π (a test checks this bound). Rotated off
//! the edges' directions, the errors along an edge cancel and fall faster:
//! measured root-mean-square errors over 16 rotations, for a parallel and a
//! perpendicular rectangle of F ≈ 0.1 and 0.19, are 5e-3 and 3e-3 at R = 16,
//! 2e-4 and 6e-4 at R = 64, 1.3e-5 and 1.5e-4 at R = 256. Callers that build
//! many hemicubes therefore rotate each one about its normal by a different
//! angle (the up hint), which turns the grid-aligned bias into noise that
//! averages out over patches. The aliasing Immel, Cohen and Greenberg 1986 warns about is a different
//! thing again: a polygon smaller than a cell may be missed, or counted as a
//! whole cell; that error shrinks only once the cells are smaller than the
//! polygon's projection.

use super::formfactor::point_to_polygon;
use super::polygon::{clip_to_halfspace, is_convex, newell_normal, ray_triangle, triangulate};
use glam::{DVec2, DVec3};

/// The largest resolution accepted: 3 · 2048² cells, 12.6 million, about
/// 150 MB of item buffer and delta table.
pub const MAX_RESOLUTION: u32 = 2048;

/// The golden angle, radians: callers that build many hemicubes rotate the
/// k-th about its normal by k times this, which spreads the rotations evenly
/// (see "Accuracy against R").
pub const GOLDEN_ANGLE: f64 = 2.399_963_229_728_653;

/// A cell that holds no polygon.
pub const NO_ITEM: u32 = u32::MAX;

/// Set on a cell's item when the polygon is seen from behind: it hides what is
/// behind it but a one-sided polygon sends nothing to this side.
pub const BACK_FACE: u32 = 1 << 31;

/// Targets seen closer to the base plane than this fraction of their extent
/// lie in it (the receiving polygon and its coplanar neighbours) and are
/// skipped; a plane passing within this fraction of the centre is seen
/// edge-on and skipped too.
const PLANE_TOLERANCE: f64 = 1e-9;

/// A bad hemicube resolution.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum HemicubeError {
    #[error(
        "hemicube resolution {0} is out of range: an even number of cells per side \
         from 2 to {MAX_RESOLUTION}"
    )]
    Resolution(u32),
}

/// Checks a resolution: even (the sides are R × R/2), 2 to [`MAX_RESOLUTION`].
pub fn check_resolution(resolution: u32) -> Result<(), HemicubeError> {
    if (2..=MAX_RESOLUTION).contains(&resolution) && resolution.is_multiple_of(2) {
        Ok(())
    } else {
        Err(HemicubeError::Resolution(resolution))
    }
}

/// The hemicube's orientation: `w` along the normal, `u` and `v` across it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub centre: DVec3,
    pub u: DVec3,
    pub v: DVec3,
    pub w: DVec3,
}

impl Frame {
    /// A frame at `centre` with `w` = `normal` normalised and `u` = `up_hint`
    /// made orthogonal to it (any orthogonal direction when the hint is
    /// parallel to the normal or zero). The rotation about the normal changes
    /// only the aliasing, never the expected factor. `None` for a zero or
    /// non-finite normal or centre.
    pub fn new(centre: DVec3, normal: DVec3, up_hint: DVec3) -> Option<Frame> {
        let w = normal.normalize_or_zero();
        if w == DVec3::ZERO || !centre.is_finite() {
            return None;
        }
        let hint = up_hint - w * w.dot(up_hint);
        let u = if hint.is_finite() && hint.length_squared() > 1e-24 * up_hint.length_squared() {
            hint.normalize()
        } else {
            w.any_orthonormal_vector()
        };
        Some(Frame {
            centre,
            u,
            v: w.cross(u),
            w,
        })
    }

    /// `p` in the frame's coordinates (x along u, y along v, z along w).
    #[inline]
    pub fn local(&self, p: DVec3) -> DVec3 {
        let d = p - self.centre;
        DVec3::new(d.dot(self.u), d.dot(self.v), d.dot(self.w))
    }
}

/// The five faces: the top (index 0) and the sides toward +u, −u, +v, −v.
const FACES: usize = 5;

/// Local coordinates to a face's (a, b, d): d along the face's outward axis,
/// a across it, b up it (for a side, b is the height along the normal). Each
/// map is a signed permutation, so it preserves dot products.
#[inline]
fn to_face(face: usize, p: DVec3) -> DVec3 {
    match face {
        0 => DVec3::new(p.x, p.y, p.z),
        1 => DVec3::new(p.y, p.z, p.x),
        2 => DVec3::new(p.y, p.z, -p.x),
        3 => DVec3::new(p.x, p.z, p.y),
        _ => DVec3::new(p.x, p.z, -p.y),
    }
}

/// Which face a local direction (z ≥ 0) goes through.
#[inline]
fn face_of(p: DVec3) -> usize {
    let (ax, ay) = (p.x.abs(), p.y.abs());
    if p.z >= ax && p.z >= ay {
        0
    } else if ax >= ay {
        if p.x >= 0.0 {
            1
        } else {
            2
        }
    } else if p.y >= 0.0 {
        3
    } else {
        4
    }
}

/// Rows, and the first cell's index, of each face in the buffers.
#[inline]
fn face_layout(resolution: usize, face: usize) -> (usize, usize) {
    let side_cells = resolution * resolution / 2;
    if face == 0 {
        (resolution, 0)
    } else {
        (
            resolution / 2,
            resolution * resolution + (face - 1) * side_cells,
        )
    }
}

/// Offset of b in cell units: the top face's b runs over [−1, 1], a side's over
/// [0, 1].
#[inline]
fn b_origin(face: usize) -> f64 {
    if face == 0 {
        1.0
    } else {
        0.0
    }
}

/// The delta form factors of one resolution (see the module documentation).
#[derive(Clone, Debug)]
pub struct Hemicube {
    resolution: u32,
    /// R × R, row-major, row 0 at b = −1.
    top: Vec<f64>,
    /// R/2 × R, row-major, row 0 at the base; the same for all four sides.
    side: Vec<f64>,
}

impl Hemicube {
    /// Computes the exact delta form factors of every cell. Costs about
    /// 3R² contour integrals (≈ 0.1 s at R = 512).
    pub fn new(resolution: u32) -> Result<Hemicube, HemicubeError> {
        check_resolution(resolution)?;
        let r = resolution as usize;
        let h = 2.0 / resolution as f64;
        // Each cell as a polygon in the frame of a hemicube at the origin with
        // normal +z, wound to face the origin.
        let exact = |corners: [DVec3; 4]| {
            let mut poly = corners.to_vec();
            let centroid = poly.iter().copied().sum::<DVec3>() / 4.0;
            if newell_normal(&poly).dot(centroid) > 0.0 {
                poly.reverse();
            }
            point_to_polygon(DVec3::ZERO, DVec3::Z, &poly)
        };
        let mut top = Vec::with_capacity(r * r);
        for row in 0..r {
            let (b0, b1) = (row as f64 * h - 1.0, (row + 1) as f64 * h - 1.0);
            for col in 0..r {
                let (a0, a1) = (col as f64 * h - 1.0, (col + 1) as f64 * h - 1.0);
                top.push(exact([
                    DVec3::new(a0, b0, 1.0),
                    DVec3::new(a1, b0, 1.0),
                    DVec3::new(a1, b1, 1.0),
                    DVec3::new(a0, b1, 1.0),
                ]));
            }
        }
        let mut side = Vec::with_capacity(r * r / 2);
        for row in 0..r / 2 {
            let (b0, b1) = (row as f64 * h, (row + 1) as f64 * h);
            for col in 0..r {
                let (a0, a1) = (col as f64 * h - 1.0, (col + 1) as f64 * h - 1.0);
                // The +u side: local (x, y, z) = (d, a, b) with d = 1.
                side.push(exact([
                    DVec3::new(1.0, a0, b0),
                    DVec3::new(1.0, a1, b0),
                    DVec3::new(1.0, a1, b1),
                    DVec3::new(1.0, a0, b1),
                ]));
            }
        }
        Ok(Hemicube {
            resolution,
            top,
            side,
        })
    }

    /// Cells per side of the top face.
    pub fn resolution(&self) -> u32 {
        self.resolution
    }

    /// 3R²: the top's R² and the four sides' R²/2 each.
    pub fn cell_count(&self) -> usize {
        3 * self.top.len()
    }

    /// The delta form factor of buffer cell `index` (see [`ItemBuffer`] for the
    /// layout).
    #[inline]
    pub fn delta(&self, index: usize) -> f64 {
        let r2 = self.top.len();
        if index < r2 {
            self.top[index]
        } else {
            self.side[(index - r2) % self.side.len()]
        }
    }

    /// An empty item buffer of this resolution.
    pub fn buffer(&self) -> ItemBuffer {
        ItemBuffer::with_resolution(self.resolution)
    }

    /// The form factor from a differential area at `centre` with unit normal
    /// `normal` to each of `targets` (counter-clockwise seen from their front),
    /// with hidden surfaces removed: `out[k]` is the sum of the delta form
    /// factors of the cells where target k is the nearest polygon, front side
    /// toward the centre. `up_hint` orients the hemicube about the normal.
    /// A zero or non-finite normal gives all zeros.
    pub fn form_factors_from<P: AsRef<[DVec3]>>(
        &self,
        centre: DVec3,
        normal: DVec3,
        up_hint: DVec3,
        targets: &[P],
    ) -> Vec<f64> {
        let mut out = vec![0.0; targets.len()];
        if let Some(frame) = Frame::new(centre, normal, up_hint) {
            let mut buffer = self.buffer();
            buffer.render(&frame, targets);
            self.accumulate(&buffer, &mut out);
        }
        out
    }

    /// Adds the delta form factor of every cell of `buffer` to its front-facing
    /// item's entry of `out` (entries beyond `out` are ignored). The buffer must
    /// have this hemicube's resolution.
    pub fn accumulate(&self, buffer: &ItemBuffer, out: &mut [f64]) {
        debug_assert_eq!(buffer.resolution, self.resolution);
        for (index, &item) in buffer.items.iter().enumerate() {
            if item & BACK_FACE == 0 {
                if let Some(slot) = out.get_mut(item as usize) {
                    *slot += self.delta(index);
                }
            }
        }
    }
}

/// The radiosity lecture notes' midpoint delta form factor of buffer cell `index` at resolution `r`:
/// ΔA / (π (x² + y² + 1)²) on the top face, z ΔA / (π (y² + z² + 1)²) on a side,
/// at the cell's centre. Kept to check the exact values against.
pub fn midpoint_delta(resolution: u32, index: usize) -> f64 {
    let r = resolution as usize;
    let h = 2.0 / resolution as f64;
    let area = h * h;
    let (face, row, col) = cell_position(r, index);
    let a = (col as f64 + 0.5) * h - 1.0;
    let b = (row as f64 + 0.5) * h - b_origin(face);
    let q = a * a + b * b + 1.0;
    let numerator = if face == 0 { area } else { b * area };
    numerator / (std::f64::consts::PI * q * q)
}

/// (face, row, col) of buffer cell `index` at resolution `r`.
fn cell_position(r: usize, index: usize) -> (usize, usize, usize) {
    if index < r * r {
        (0, index / r, index % r)
    } else {
        let side = r * r / 2;
        let rest = index - r * r;
        (1 + rest / side, (rest % side) / r, rest % r)
    }
}

/// What the direction to a point finds in an [`ItemBuffer`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lookup {
    /// Index of the cell the direction passes through.
    pub cell: usize,
    /// Its face (0 top, 1..=4 sides), row and column.
    pub face: usize,
    pub row: usize,
    pub col: usize,
    /// The point's coordinate along the face's axis.
    pub depth: f64,
}

/// The item buffer of one hemicube: per cell, the nearest target and its
/// depth. Layout: the top face's R × R cells row-major (row 0 at b = −1), then
/// the sides toward +u, −u, +v, −v, R/2 × R each, row 0 at the base.
#[derive(Clone, Debug)]
pub struct ItemBuffer {
    resolution: u32,
    frame: Option<Frame>,
    items: Vec<u32>,
    /// Reciprocal of the item's depth along the face's axis; 0 where empty.
    inverse_depth: Vec<f64>,
    local: Vec<DVec3>,
    pieces: Vec<[usize; 3]>,
    clip_a: Vec<DVec3>,
    clip_b: Vec<DVec3>,
    screen: Vec<DVec2>,
    /// Per target: its plane in the frame's coordinates, n · x = offset (zero
    /// for targets that were skipped), and its triangles in `triangles`.
    planes: Vec<(DVec3, f64)>,
    spans: Vec<(usize, usize)>,
    triangles: Vec<[DVec3; 3]>,
}

impl ItemBuffer {
    /// An empty buffer. Callers check the resolution first
    /// ([`check_resolution`]); an invalid one is clamped to the nearest valid.
    pub fn with_resolution(resolution: u32) -> ItemBuffer {
        let resolution = (resolution.clamp(2, MAX_RESOLUTION) / 2) * 2;
        let cells = 3 * (resolution as usize).pow(2);
        ItemBuffer {
            resolution,
            frame: None,
            items: vec![NO_ITEM; cells],
            inverse_depth: vec![0.0; cells],
            local: Vec::new(),
            pieces: Vec::new(),
            clip_a: Vec::new(),
            clip_b: Vec::new(),
            screen: Vec::new(),
            planes: Vec::new(),
            spans: Vec::new(),
            triangles: Vec::new(),
        }
    }

    pub fn resolution(&self) -> u32 {
        self.resolution
    }

    /// Per cell: the index of the nearest target, with [`BACK_FACE`] set when
    /// it is seen from behind, or [`NO_ITEM`].
    pub fn items(&self) -> &[u32] {
        &self.items
    }

    /// The depth (along the face's axis) of the item in `cell`; infinite when
    /// the cell is empty.
    pub fn depth(&self, cell: usize) -> f64 {
        let inv = self.inverse_depth[cell];
        if inv > 0.0 {
            inv.recip()
        } else {
            f64::INFINITY
        }
    }

    /// The frame of the last render.
    pub fn frame(&self) -> Option<&Frame> {
        self.frame.as_ref()
    }

    /// Empties the buffer and forgets its frame: every lookup fails.
    pub fn clear(&mut self) {
        self.frame = None;
        self.items.fill(NO_ITEM);
        self.inverse_depth.fill(0.0);
        self.planes.clear();
        self.spans.clear();
        self.triangles.clear();
    }

    /// Clears the buffer and draws `targets` (item k is `targets[k]`; at most
    /// 2³¹ − 1 targets, the rest are ignored) as seen from `frame`.
    pub fn render<P: AsRef<[DVec3]>>(&mut self, frame: &Frame, targets: &[P]) {
        self.frame = Some(*frame);
        self.items.fill(NO_ITEM);
        self.inverse_depth.fill(0.0);
        let count = targets.len().min(BACK_FACE as usize - 1);
        self.planes.clear();
        self.planes.resize(count, (DVec3::ZERO, 0.0));
        self.spans.clear();
        self.spans.resize(count, (0, 0));
        self.triangles.clear();
        for (k, target) in targets.iter().enumerate().take(count) {
            self.draw(frame, target.as_ref(), k as u32);
        }
    }

    fn draw(&mut self, frame: &Frame, polygon: &[DVec3], index: u32) {
        if polygon.len() < 3 {
            return;
        }
        self.local.clear();
        self.local.extend(polygon.iter().map(|&p| frame.local(p)));
        if !self.local.iter().all(|p| p.is_finite()) {
            return;
        }
        let reach = self.local.iter().map(|p| p.length()).fold(0.0, f64::max);
        let height = self.local.iter().map(|p| p.z).fold(f64::MIN, f64::max);
        if reach <= 0.0 || height <= PLANE_TOLERANCE * reach {
            return;
        }
        let normal = newell_normal(&self.local);
        let normal_length = normal.length();
        if normal_length == 0.0 {
            return;
        }
        let centroid = self.local.iter().copied().sum::<DVec3>() / self.local.len() as f64;
        // The polygon's plane is normal · x = offset; the centre (the origin)
        // is in front when offset < 0.
        let offset = normal.dot(centroid);
        if offset.abs() <= PLANE_TOLERANCE * normal_length * reach {
            return;
        }
        self.planes[index as usize] = (normal, offset);
        self.pieces.clear();
        triangulate(&self.local, &mut self.pieces);
        let first = self.triangles.len();
        for &[i, j, k] in &self.pieces {
            self.triangles
                .push([self.local[i], self.local[j], self.local[k]]);
        }
        self.spans[index as usize] = (first, self.pieces.len());
        let item = if offset < 0.0 {
            index
        } else {
            index | BACK_FACE
        };
        // A convex polygon is drawn whole, any other as its triangles.
        let convex = is_convex(&self.local);
        self.pieces.clear();
        if !convex {
            triangulate(&self.local, &mut self.pieces);
            if self.pieces.is_empty() {
                return;
            }
        }
        for face in 0..FACES {
            let plane = to_face(face, normal);
            if convex {
                self.clip_a.clear();
                self.clip_a
                    .extend(self.local.iter().map(|&p| to_face(face, p)));
                self.fill(face, plane, offset, item);
            } else {
                for t in 0..self.pieces.len() {
                    let [i, j, k] = self.pieces[t];
                    self.clip_a.clear();
                    self.clip_a.extend(
                        [self.local[i], self.local[j], self.local[k]].map(|p| to_face(face, p)),
                    );
                    self.fill(face, plane, offset, item);
                }
            }
        }
    }

    /// Clips the polygon in `clip_a` (face coordinates) to the face's frustum
    /// and fills the cells whose centres it covers.
    fn fill(&mut self, face: usize, plane: DVec3, offset: f64, item: u32) {
        // The frustum: |a| ≤ d, b ≤ d, and b ≥ −d (top) or b ≥ 0 (sides).
        let bottom = if face == 0 {
            DVec3::new(0.0, 1.0, 1.0)
        } else {
            DVec3::new(0.0, 1.0, 0.0)
        };
        for normal in [
            DVec3::new(-1.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(0.0, -1.0, 1.0),
            bottom,
        ] {
            clip_to_halfspace(&self.clip_a, DVec3::ZERO, normal, &mut self.clip_b);
            std::mem::swap(&mut self.clip_a, &mut self.clip_b);
            if self.clip_a.len() < 3 {
                return;
            }
        }
        let r = self.resolution as usize;
        let h = 2.0 / self.resolution as f64;
        let (rows, first) = face_layout(r, face);
        let b0 = b_origin(face);
        self.screen.clear();
        for p in &self.clip_a {
            if p.z <= 0.0 {
                // Only the centre itself has d = 0 inside the frustum.
                continue;
            }
            let (a, b) = ((p.x / p.z).clamp(-1.0, 1.0), (p.y / p.z).clamp(-b0, 1.0));
            self.screen.push(DVec2::new((a + 1.0) / h, (b + b0) / h));
        }
        let count = self.screen.len();
        if count < 3 {
            return;
        }
        let (y_lo, y_hi) = self
            .screen
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| {
                (lo.min(s.y), hi.max(s.y))
            });
        let row_lo = ((y_lo - 0.5).ceil().max(0.0)) as usize;
        let row_hi = (y_hi - 0.5).floor().min(rows as f64 - 1.0);
        if row_hi < 0.0 {
            return;
        }
        let row_hi = row_hi as usize;
        for row in row_lo..=row_hi {
            let y = row as f64 + 0.5;
            let mut x_lo = f64::INFINITY;
            let mut x_hi = f64::NEG_INFINITY;
            for i in 0..count {
                let (p, q) = (self.screen[i], self.screen[(i + 1) % count]);
                if (p.y <= y && q.y >= y) || (q.y <= y && p.y >= y) {
                    if p.y == q.y {
                        x_lo = x_lo.min(p.x.min(q.x));
                        x_hi = x_hi.max(p.x.max(q.x));
                    } else {
                        let x = p.x + (y - p.y) / (q.y - p.y) * (q.x - p.x);
                        x_lo = x_lo.min(x);
                        x_hi = x_hi.max(x);
                    }
                }
            }
            if x_lo > x_hi {
                continue;
            }
            let col_lo = ((x_lo - 0.5).ceil().max(0.0)) as usize;
            let col_hi = (x_hi - 0.5).floor().min(r as f64 - 1.0);
            if col_hi < 0.0 || (col_lo as f64) > col_hi {
                continue;
            }
            let b = y * h - b0;
            // 1/depth through the cell centre ω = (a, b, 1): (plane · ω) / offset,
            // linear in a.
            let base = (plane.y * b + plane.z) / offset;
            let step = plane.x / offset;
            let line = first + row * r;
            for col in col_lo..=col_hi as usize {
                let a = (col as f64 + 0.5) * h - 1.0;
                let inverse = base + step * a;
                let cell = line + col;
                if inverse > self.inverse_depth[cell] {
                    self.inverse_depth[cell] = inverse;
                    self.items[cell] = item;
                }
            }
        }
    }

    /// The cell through which the last render's centre sees `point`, and the
    /// point's depth along that face's axis. `None` when the point is below
    /// the base plane, at the centre, or nothing was rendered.
    pub fn lookup(&self, point: DVec3) -> Option<Lookup> {
        let frame = self.frame.as_ref()?;
        let p = frame.local(point);
        if !p.is_finite() || p.z < 0.0 || p == DVec3::ZERO {
            return None;
        }
        let face = face_of(p);
        let f = to_face(face, p);
        if f.z <= 0.0 {
            return None;
        }
        let r = self.resolution as usize;
        let h = 2.0 / self.resolution as f64;
        let (rows, first) = face_layout(r, face);
        let b0 = b_origin(face);
        let col = (((f.x / f.z + 1.0) / h).floor().max(0.0) as usize).min(r - 1);
        let row = (((f.y / f.z + b0) / h).floor().max(0.0) as usize).min(rows - 1);
        Some(Lookup {
            cell: first + row * r + col,
            face,
            row,
            col,
            depth: f.z,
        })
    }

    /// Whether the segment from the centre to `point` is unobstructed, judged
    /// against the candidates the buffer shows around it: the polygons held
    /// by the (2·radius + 1)² block of cells around the cell through which the
    /// centre sees `point` (clipped to that face), each tested exactly against
    /// the segment (against its triangles, ignoring crossings within `end_gap`
    /// scene units of either end, like the ray caster's end epsilon). `own`
    /// (the point's own polygon) is never an obstacle. `None` when the point cannot be looked up (below the
    /// base plane, at the centre, or nothing rendered).
    ///
    /// This is the item buffer used as Haines and Greenberg's light buffer: a
    /// cell's stored depth belongs to its central ray, up to a cell away from
    /// the segment, and near a surface seen at a grazing angle it differs
    /// from the point's depth by more than any fixed bias; the exact test has
    /// no such error. A wall meeting the point's surface at a room's corner, or
    /// the side of a box whose top the point lies on, fills cells next to the
    /// point but is not crossed by the segment, so it casts no false shadow;
    /// a polygon that does cross the segment is an occluder. What the buffer
    /// can still miss is an occluder that covers the segment's direction but
    /// no cell centre of the block, or that is hidden in each of those cells
    /// behind a nearer polygon that does not cross the segment: occluders
    /// thinner than about a cell.
    pub fn segment_visible(
        &self,
        point: DVec3,
        own: u32,
        radius: usize,
        end_gap: f64,
    ) -> Option<bool> {
        let hit = self.lookup(point)?;
        let frame = self.frame.as_ref()?;
        let p = frame.local(point);
        let r = self.resolution as usize;
        let (rows, first) = face_layout(r, hit.face);
        let mut last = NO_ITEM;
        for row in hit.row.saturating_sub(radius)..=(hit.row + radius).min(rows - 1) {
            for col in hit.col.saturating_sub(radius)..=(hit.col + radius).min(r - 1) {
                let item = self.items[first + row * r + col];
                if item == NO_ITEM || item == last {
                    continue;
                }
                last = item;
                let index = item & !BACK_FACE;
                if index != own && self.crosses(index as usize, p, end_gap) {
                    return Some(false);
                }
            }
        }
        Some(true)
    }

    /// Whether target `index` crosses the segment from the centre to `p`
    /// (frame coordinates), more than `end_gap` (scene units) from its ends.
    /// Tested against the target's triangles, which pass through its actual
    /// vertices: a slightly non-planar input polygon (the Cornell box's red
    /// wall is off by a millimetre) would otherwise be tested against its mean
    /// plane, which the neighbouring floor's edge does not lie on.
    fn crosses(&self, index: usize, p: DVec3, end_gap: f64) -> bool {
        let Some(&(start, count)) = self.spans.get(index) else {
            return false;
        };
        let length = p.length();
        if length == 0.0 {
            return false;
        }
        let margin = (end_gap / length).max(PLANE_TOLERANCE);
        self.triangles[start..start + count].iter().any(|t| {
            ray_triangle(DVec3::ZERO, p, t[0], t[1], t[2])
                .is_some_and(|s| s > margin && s < 1.0 - margin)
        })
    }
}

#[cfg(test)]
mod tests;
