//! The exact integral of a box-reconstructed texture level over a UV triangle
//! (see the module notes of [`super`]).

use super::{Level, Texture, MAX_CELLS};
use glam::{DVec2, DVec3};

/// The integral of the albedo ρ over a UV triangle, divided by its UV area.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Integral {
    /// The mean albedo over the triangle.
    pub mean: DVec3,
    /// Per corner, the mean of ρ times the corner's barycentric weight: they
    /// sum to `mean`, and are `mean / 3` each for a uniform texture. Times the
    /// triangle's area in the scene, `corner[k] · E_k` is corner k's share of
    /// ∫ ρ E dA when E is interpolated linearly (Gouraud) over the triangle.
    pub corner: [DVec3; 3],
    /// The pyramid level integrated (0 = full resolution).
    pub level: usize,
}

impl Integral {
    fn uniform(rho: DVec3, level: usize) -> Integral {
        Integral {
            mean: rho,
            corner: [rho / 3.0; 3],
            level,
        }
    }
}

/// UV triangles with less area than this (in texels² of level 0) have no
/// reliable barycentric frame; their albedo is the bilinear sample at the
/// centroid.
const DEGENERATE_TEXELS: f64 = 1e-9;

pub(super) fn integrate(texture: &Texture, uv: [DVec2; 3]) -> Integral {
    let (w0, h0) = (
        texture.levels[0].width as f64,
        texture.levels[0].height as f64,
    );
    let lo = uv[0].min(uv[1]).min(uv[2]);
    let hi = uv[0].max(uv[1]).max(uv[2]);
    let span = hi - lo;
    let uv_area = 0.5 * (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs();
    // NaN areas count as degenerate, hence the comparison's form.
    let texels = uv_area * w0 * h0;
    if texels.is_nan() || texels <= DEGENERATE_TEXELS || !span.is_finite() {
        let centroid = (uv[0] + uv[1] + uv[2]) / 3.0;
        if !centroid.is_finite() {
            return Integral::uniform(texture.mean(), texture.levels.len() - 1);
        }
        return Integral::uniform(texture.bilinear(centroid), 0);
    }
    // The finest level whose cells under the bounding box number at most
    // MAX_CELLS (+1 per axis for the partial cells at the ends).
    let cells = |l: &Level| (span.x * l.width as f64 + 1.0) * (span.y * l.height as f64 + 1.0);
    let Some(level) = texture.levels.iter().position(|l| cells(l) <= MAX_CELLS) else {
        // The triangle spans more than MAX_CELLS repeats of the whole
        // texture: its mean is the texture's within the partial repeats at
        // its border, a fraction ~ perimeter / area < 4 / √MAX_CELLS.
        return Integral::uniform(texture.mean(), texture.levels.len() - 1);
    };
    let l = &texture.levels[level];
    // Texel coordinates of the level: x right, y down (v = 1 is row 0).
    let to_texel = |p: DVec2| DVec2::new(p.x * l.width as f64, (1.0 - p.y) * l.height as f64);
    let t = uv.map(to_texel);
    let frame = Barycentric::new(t);
    let (tlo, thi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
    let mut mean = DVec3::ZERO;
    let mut corner = [DVec3::ZERO; 3];
    let mut polygon = Vec::with_capacity(8);
    let mut scratch = Vec::with_capacity(8);
    for j in tlo.y.floor() as i64..thi.y.ceil() as i64 {
        for i in tlo.x.floor() as i64..thi.x.ceil() as i64 {
            polygon.clear();
            polygon.extend_from_slice(&t);
            clip_to_cell(&mut polygon, &mut scratch, i as f64, j as f64);
            let Some((area, centroid)) = area_and_centroid(&polygon) else {
                continue;
            };
            let rho = l.texel(i, j) * area;
            mean += rho;
            let lambda = frame.at(centroid);
            for k in 0..3 {
                corner[k] += rho * lambda[k];
            }
        }
    }
    let total = frame.area;
    Integral {
        mean: mean / total,
        corner: corner.map(|c| c / total),
        level,
    }
}

/// Barycentric coordinates in a triangle (texel coordinates).
struct Barycentric {
    a: DVec2,
    ab: DVec2,
    ac: DVec2,
    /// (b − a) × (c − a), signed.
    det: f64,
    /// The triangle's area, |det| / 2.
    area: f64,
}

impl Barycentric {
    fn new([a, b, c]: [DVec2; 3]) -> Barycentric {
        let (ab, ac) = (b - a, c - a);
        let det = ab.perp_dot(ac);
        Barycentric {
            a,
            ab,
            ac,
            det,
            area: 0.5 * det.abs(),
        }
    }

    fn at(&self, p: DVec2) -> [f64; 3] {
        let ap = p - self.a;
        let s = ap.perp_dot(self.ac) / self.det;
        let t = self.ab.perp_dot(ap) / self.det;
        [1.0 - s - t, s, t]
    }
}

/// Clips `polygon` to the cell [x, x + 1] × [y, y + 1] (Sutherland and
/// Hodgman 1974), in place; `scratch` is reused storage.
fn clip_to_cell(polygon: &mut Vec<DVec2>, scratch: &mut Vec<DVec2>, x: f64, y: f64) {
    // Each half-plane as (axis, bound, keep the side above the bound).
    let planes = [
        (0, x, true),
        (0, x + 1.0, false),
        (1, y, true),
        (1, y + 1.0, false),
    ];
    for (axis, bound, above) in planes {
        if polygon.is_empty() {
            return;
        }
        let inside = |p: DVec2| {
            if above {
                p[axis] >= bound
            } else {
                p[axis] <= bound
            }
        };
        scratch.clear();
        for k in 0..polygon.len() {
            let (p, q) = (polygon[k], polygon[(k + 1) % polygon.len()]);
            let (pin, qin) = (inside(p), inside(q));
            if pin {
                scratch.push(p);
            }
            if pin != qin {
                let s = (bound - p[axis]) / (q[axis] - p[axis]);
                let mut cut = p + (q - p) * s;
                cut[axis] = bound;
                scratch.push(cut);
            }
        }
        std::mem::swap(polygon, scratch);
    }
}

/// The area and centroid of a simple polygon (shoelace formula); `None` when
/// it has no area.
fn area_and_centroid(polygon: &[DVec2]) -> Option<(f64, DVec2)> {
    if polygon.len() < 3 {
        return None;
    }
    let origin = polygon[0];
    let mut twice = 0.0;
    let mut moment = DVec2::ZERO;
    for k in 1..polygon.len() - 1 {
        let (p, q) = (polygon[k] - origin, polygon[k + 1] - origin);
        let cross = p.perp_dot(q);
        twice += cross;
        moment += (p + q) * cross;
    }
    if twice == 0.0 {
        return None;
    }
    let centroid = origin + moment / (3.0 * twice);
    Some((0.5 * twice.abs(), centroid))
}
