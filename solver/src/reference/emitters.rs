//! Next-event estimation's light sampling: pick an emitting polygon with
//! probability proportional to its power (area × the channel sum of its
//! radiance; the π of a Lambertian emitter is common to all), then a point
//! uniformly by area on it (triangles chosen by area, uniform barycentrics).

use crate::geometry::polygon::triangulate;
use glam::DVec3;

/// One emitting polygon, triangulated.
#[derive(Clone, Debug)]
struct Emitter {
    polygon: usize,
    triangles: Vec<[DVec3; 3]>,
    /// Cumulative triangle areas, ending at the polygon's area.
    cumulative: Vec<f64>,
}

/// A point sampled on an emitter.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    pub polygon: usize,
    pub point: DVec3,
    /// Density per unit area of this point (selection × 1/area).
    pub pdf_area: f64,
}

/// The scene's emitters and the distribution they are sampled from.
#[derive(Clone, Debug, Default)]
pub struct Emitters {
    emitters: Vec<Emitter>,
    /// Cumulative selection weights, ending at the total.
    cumulative: Vec<f64>,
    /// Per scene polygon: its density per unit area (0 for non-emitters).
    pdf_area_of: Vec<f64>,
}

impl Emitters {
    /// `polygons[i]` with emitted radiance `emission[i]`; zero-area polygons and
    /// those with zero emission are never sampled.
    pub fn new(polygons: &[&[DVec3]], emission: &[DVec3]) -> Emitters {
        let mut emitters = Vec::new();
        let mut weights = Vec::new();
        let mut tris = Vec::new();
        for (index, (p, le)) in polygons.iter().zip(emission).enumerate() {
            let power = le.element_sum();
            if !(power > 0.0 && power.is_finite()) {
                continue;
            }
            tris.clear();
            triangulate(p, &mut tris);
            let mut triangles = Vec::new();
            let mut cumulative = Vec::new();
            let mut area = 0.0;
            for t in &tris {
                let v = [p[t[0]], p[t[1]], p[t[2]]];
                let a = 0.5 * (v[1] - v[0]).cross(v[2] - v[0]).length();
                if a > 0.0 {
                    area += a;
                    triangles.push(v);
                    cumulative.push(area);
                }
            }
            if area > 0.0 {
                weights.push(power * area);
                emitters.push(Emitter {
                    polygon: index,
                    triangles,
                    cumulative,
                });
            }
        }
        let total: f64 = weights.iter().sum();
        let mut pdf_area_of = vec![0.0; polygons.len()];
        let mut cumulative = Vec::with_capacity(weights.len());
        let mut running = 0.0;
        for (e, w) in emitters.iter().zip(&weights) {
            running += w;
            cumulative.push(running);
            let area = *e.cumulative.last().unwrap_or(&0.0);
            pdf_area_of[e.polygon] = w / total / area;
        }
        Emitters {
            emitters,
            cumulative,
            pdf_area_of,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.emitters.is_empty()
    }

    /// Density per unit area with which [`Emitters::sample`] picks points on
    /// polygon `polygon` (0 if it is not an emitter).
    pub fn pdf_area(&self, polygon: usize) -> f64 {
        self.pdf_area_of.get(polygon).copied().unwrap_or(0.0)
    }

    /// A point from three uniforms in [0, 1); `None` when there is no emitter.
    pub fn sample(&self, u0: f64, u1: f64, u2: f64) -> Option<LightSample> {
        let e = &self.emitters[pick(&self.cumulative, u0)?];
        let t = pick(&e.cumulative, u1.fract())?;
        // Reuse u1 within the chosen triangle's share of the cumulative range:
        // uniform again, and independent of the choice.
        let lo = if t > 0 { e.cumulative[t - 1] } else { 0.0 };
        let area = *e.cumulative.last()?;
        let w = ((u1 * area - lo) / (e.cumulative[t] - lo)).clamp(0.0, 1.0);
        let [a, b, c] = e.triangles[t];
        // Uniform on the triangle: √ for the first coordinate (Shirley 1997).
        let r = w.sqrt();
        let point = a * (1.0 - r) + b * (r * (1.0 - u2)) + c * (r * u2);
        Some(LightSample {
            polygon: e.polygon,
            point,
            pdf_area: self.pdf_area_of[e.polygon],
        })
    }
}

/// The index whose cumulative range holds `u · total`.
fn pick(cumulative: &[f64], u: f64) -> Option<usize> {
    let total = *cumulative.last()?;
    let x = u * total;
    let i = cumulative.partition_point(|&c| c <= x);
    Some(i.min(cumulative.len() - 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_follow_power_and_area() {
        let square = |x: f64, s: f64| {
            vec![
                DVec3::new(x, 0.0, 0.0),
                DVec3::new(x + s, 0.0, 0.0),
                DVec3::new(x + s, s, 0.0),
                DVec3::new(x, s, 0.0),
            ]
        };
        let (a, b, c) = (square(0.0, 1.0), square(5.0, 2.0), square(10.0, 1.0));
        let polygons: Vec<&[DVec3]> = vec![&a, &b, &c];
        let emission = [DVec3::splat(1.0), DVec3::splat(1.0), DVec3::ZERO];
        let e = Emitters::new(&polygons, &emission);
        // Powers 1 : 4 → selection 0.2 : 0.8; density = selection / area.
        assert!((e.pdf_area(0) - 0.2).abs() < 1e-15);
        assert!((e.pdf_area(1) - 0.2).abs() < 1e-15);
        assert_eq!(e.pdf_area(2), 0.0);
        // Every sample lies on its polygon.
        for k in 0..1000 {
            let u = |m: u64| ((k * m) % 1000) as f64 / 1000.0;
            let s = e.sample(u(7), u(13), u(31)).unwrap();
            let p = polygons[s.polygon];
            let (lo, hi) = (p[0], p[2]);
            assert!(s.point.x >= lo.x - 1e-12 && s.point.x <= hi.x + 1e-12);
            assert!(s.point.y >= lo.y - 1e-12 && s.point.y <= hi.y + 1e-12);
        }
    }
}
