//! Texture coordinates of a planar polygon as an affine map of position.
//!
//! A planar polygon's UVs (OBJ `vt`) are fitted once, at import, by an affine
//! map uv(p) = base + ((p − origin)·du, (p − origin)·dv) in the polygon's
//! plane: exact for a triangle and for any polygon whose UVs are an affine
//! image of it (a rectangle mapped to a rectangle), least squares otherwise
//! (a quad mapped to a trapezoid, which no planar interpolation reproduces;
//! a warning says so). Every point the mesher creates on the polygon then gets
//! its UV from its position, so neither the mesh nor the cleaning (which
//! removes repeated and collinear corners, leaving the map unchanged) has to
//! carry UVs.

use glam::{DMat3, DVec2, DVec3};

/// The affine UV map of a planar polygon (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvMap {
    pub origin: DVec3,
    pub du: DVec3,
    pub dv: DVec3,
    pub base: DVec2,
}

/// How far the fit misses the given UVs, relative to their span, before a
/// polygon's UVs are reported as not affine: 1e-6 is far above the rounding
/// of UVs written with 6 decimals relative to a span of 1 … far below a
/// visible distortion.
pub const AFFINE_TOLERANCE: f64 = 1e-4;

impl UvMap {
    pub fn at(&self, p: DVec3) -> DVec2 {
        let d = p - self.origin;
        self.base + DVec2::new(d.dot(self.du), d.dot(self.dv))
    }

    /// Fits the map to `vertices` (planar, normal `normal`) and their `uvs`.
    /// Returns the map and the largest miss relative to the UV span; `None`
    /// when the UVs are not finite or the polygon has fewer than 3 vertices.
    pub fn fit(vertices: &[DVec3], uvs: &[DVec2], normal: DVec3) -> Option<(UvMap, f64)> {
        if vertices.len() < 3 || vertices.len() != uvs.len() || !uvs.iter().all(|t| t.is_finite()) {
            return None;
        }
        let origin = vertices.iter().sum::<DVec3>() / vertices.len() as f64;
        let e1 = normal.any_orthonormal_vector();
        let e2 = normal.cross(e1);
        let q: Vec<DVec2> = vertices
            .iter()
            .map(|p| DVec2::new((*p - origin).dot(e1), (*p - origin).dot(e2)))
            .collect();
        // Normal equations of uv ≈ base + B q in the unknowns (base, B row).
        let mut ata = DMat3::ZERO;
        let (mut atu, mut atv) = (DVec3::ZERO, DVec3::ZERO);
        for (qi, t) in q.iter().zip(uvs) {
            let row = DVec3::new(1.0, qi.x, qi.y);
            ata += DMat3::from_cols(row * row.x, row * row.y, row * row.z);
            atu += row * t.x;
            atv += row * t.y;
        }
        if ata.determinant().abs()
            <= f64::EPSILON * ata.to_cols_array().iter().map(|x| x * x).sum::<f64>()
        {
            return None;
        }
        let inverse = ata.inverse();
        let (cu, cv) = (inverse * atu, inverse * atv);
        let map = UvMap {
            origin,
            du: e1 * cu.y + e2 * cu.z,
            dv: e1 * cv.y + e2 * cv.z,
            base: DVec2::new(cu.x, cv.x),
        };
        let lo = uvs
            .iter()
            .fold(DVec2::splat(f64::INFINITY), |a, b| a.min(*b));
        let hi = uvs
            .iter()
            .fold(DVec2::splat(f64::NEG_INFINITY), |a, b| a.max(*b));
        let span = (hi - lo).max_element().max(f64::MIN_POSITIVE);
        let miss = vertices
            .iter()
            .zip(uvs)
            .map(|(p, t)| (map.at(*p) - *t).abs().max_element())
            .fold(0.0, f64::max);
        map.is_finite().then_some((map, miss / span))
    }

    fn is_finite(&self) -> bool {
        self.origin.is_finite()
            && self.du.is_finite()
            && self.dv.is_finite()
            && self.base.is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_triangle_is_fitted_exactly_and_a_trapezoid_is_reported() {
        let tri = [
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, -3.0),
        ];
        let uvs = [
            DVec2::new(0.1, 0.2),
            DVec2::new(0.9, 0.2),
            DVec2::new(0.1, 0.7),
        ];
        let (map, miss) = UvMap::fit(&tri, &uvs, DVec3::Y).unwrap();
        assert!(miss < 1e-12);
        // The midpoint of the first edge maps to the midpoint of its UVs.
        assert!((map.at(DVec3::new(1.0, 0.0, 0.0)) - DVec2::new(0.5, 0.2)).length() < 1e-12);
        let quad = [
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let rect = [DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
        assert!(UvMap::fit(&quad, &rect, DVec3::Z).unwrap().1 < 1e-12);
        let trapezoid = [
            DVec2::ZERO,
            DVec2::X,
            DVec2::new(0.7, 1.0),
            DVec2::new(0.3, 1.0),
        ];
        assert!(UvMap::fit(&quad, &trapezoid, DVec3::Z).unwrap().1 > AFFINE_TOLERANCE);
        let collapsed = [DVec2::ZERO; 4];
        // All UVs equal is a valid (constant) map.
        assert!(UvMap::fit(&quad, &collapsed, DVec3::Z).unwrap().1 < 1e-12);
        let nan = [DVec2::NAN, DVec2::X, DVec2::ONE, DVec2::Y];
        assert!(UvMap::fit(&quad, &nan, DVec3::Z).is_none());
    }
}
