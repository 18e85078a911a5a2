//! Sky portals (issue 41): openings, such as windows, through which the sky
//! lights an interior. A portal is no surface: rays pass through it. It
//! tells a receiver where to look for the sky, so that behind a window most
//! sky samples go through the window instead of into the walls.
//!
//! A receiver samples points uniformly by area on a portal it faces; as
//! directions, their density per solid angle is d² / (A |cos θ_p|), with d
//! the distance to the point and θ_p the angle at the portal (Pharr, Jakob
//! and Humphreys, *Physically Based Rendering*, 3rd ed. 2016, §5.5.1, the
//! change of variables from area to solid angle). The solver combines these
//! samples with cosine-distributed ones by Veach's (1997, §9.2) balance
//! heuristic, so the estimate stays unbiased for receivers the portals do
//! not serve (outdoors) and for sky that enters elsewhere.

use glam::DVec3;

/// A portal is out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PortalError {
    #[error("a portal needs 3 or 4 corners, it has {0}")]
    Corners(usize),
    #[error("a portal corner is not finite")]
    NotFinite,
    #[error("the portal has no area (its corners are in a line or coincide)")]
    NoArea,
    #[error("the portal's corners are not in one plane (off it by {0:.3e} of its size)")]
    NotPlanar(f64),
}

/// A planar convex opening: a triangle or a quadrilateral.
#[derive(Debug, Clone, PartialEq)]
pub struct Portal {
    corners: Vec<DVec3>,
    /// Unit normal (either side: rays cross both ways).
    normal: DVec3,
    area: f64,
    /// Found in the geometry (`portal_detect.rs`), not declared.
    detected: bool,
}

impl Portal {
    /// A portal through `corners` (3 or 4, in order around it, in one plane
    /// to 1e-6 of its size).
    pub fn new(corners: &[DVec3]) -> Result<Self, PortalError> {
        if !(3..=4).contains(&corners.len()) {
            return Err(PortalError::Corners(corners.len()));
        }
        if !corners.iter().all(|c| c.is_finite()) {
            return Err(PortalError::NotFinite);
        }
        let c = corners;
        // Newell's normal: twice the vector area, for any planar polygon.
        let twice: DVec3 = (0..c.len()).map(|i| c[i].cross(c[(i + 1) % c.len()])).sum();
        let area = 0.5 * twice.length();
        let size = (0..c.len())
            .map(|i| (c[(i + 1) % c.len()] - c[i]).length())
            .fold(0.0, f64::max);
        if area.is_nan() || area <= 1e-12 * size * size {
            return Err(PortalError::NoArea);
        }
        let normal = twice / (2.0 * area);
        let off = c
            .iter()
            .map(|p| (*p - c[0]).dot(normal).abs())
            .fold(0.0, f64::max);
        if off > 1e-6 * size {
            return Err(PortalError::NotPlanar(off / size));
        }
        Ok(Portal {
            corners: corners.to_vec(),
            normal,
            area,
            detected: false,
        })
    }

    /// The same portal, marked as found in the geometry.
    pub fn into_detected(self) -> Portal {
        Portal {
            detected: true,
            ..self
        }
    }

    /// Whether the portal was found in the geometry, not declared.
    pub fn is_detected(&self) -> bool {
        self.detected
    }

    pub fn corners(&self) -> &[DVec3] {
        &self.corners
    }

    pub fn area(&self) -> f64 {
        self.area
    }

    pub fn normal(&self) -> DVec3 {
        self.normal
    }

    pub fn centre(&self) -> DVec3 {
        self.corners.iter().copied().sum::<DVec3>() / self.corners.len() as f64
    }

    /// The same portal moved by `-offset`.
    pub fn moved(&self, offset: DVec3) -> Portal {
        Portal {
            corners: self.corners.iter().map(|c| *c - offset).collect(),
            ..self.clone()
        }
    }

    /// Where the ray from `origin` along unit `w` crosses the portal, as the
    /// distance along the ray; `None` when it misses (or runs in its plane).
    pub fn hit(&self, origin: DVec3, w: DVec3) -> Option<f64> {
        let denom = w.dot(self.normal);
        if denom.abs() < 1e-12 {
            return None;
        }
        let t = (self.corners[0] - origin).dot(self.normal) / denom;
        if t <= 0.0 {
            return None;
        }
        let p = origin + w * t;
        let n = self.corners.len();
        // Convex: inside when on the same side of every edge.
        let inside = (0..n).all(|i| {
            let (a, b) = (self.corners[i], self.corners[(i + 1) % n]);
            (b - a).cross(p - a).dot(self.normal) >= 0.0
        });
        inside.then_some(t)
    }

    /// The density per steradian, seen from `origin`, of the direction `w`
    /// (unit) when points are drawn uniformly by area on the portal: d² /
    /// (A |cos θ_p|) where the ray crosses it, else 0.
    pub fn direction_pdf(&self, origin: DVec3, w: DVec3) -> f64 {
        match self.hit(origin, w) {
            Some(t) => t * t / (self.area * w.dot(self.normal).abs()),
            None => 0.0,
        }
    }

    /// The solid angle the portal subtends from `origin`, approximated as
    /// A |cos θ_p| / d² to its centre (its weight among portals; not used
    /// where an exact value matters).
    pub fn approximate_solid_angle(&self, origin: DVec3) -> f64 {
        let to = self.centre() - origin;
        let d2 = to.length_squared();
        if d2 <= 0.0 {
            return 0.0;
        }
        (self.area * to.normalize().dot(self.normal).abs() / d2).min(2.0 * std::f64::consts::PI)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sampling::{stratified_points, Rng};

    fn window() -> Portal {
        Portal::new(&[
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ])
        .unwrap()
    }

    #[test]
    fn area_normal_and_hits() {
        let p = window();
        assert!((p.area() - 2.0).abs() < 1e-15);
        assert!((p.normal().z.abs() - 1.0).abs() < 1e-15);
        let origin = DVec3::new(1.0, 0.5, -3.0);
        assert!((p.hit(origin, DVec3::Z).unwrap() - 3.0).abs() < 1e-12);
        assert!(p.hit(origin, -DVec3::Z).is_none());
        assert!(p
            .hit(origin, DVec3::new(1.0, 0.0, 1.0).normalize())
            .is_none());
    }

    #[test]
    fn direction_pdf_integrates_to_one_over_the_portal() {
        // ∫ pdf dω over the directions through the portal is 1: by points
        // drawn by area, E[1/pdf_area→ω · pdf] = 1 exactly, so check the
        // solid angle instead: the mean of 1/pdf over area samples is the
        // portal's solid angle, which for a 2 × 1 rectangle seen on the
        // axis of a corner at distance h is atan(ab / (h √(a² + b² + h²)))
        // (the rectangle's solid-angle formula). Jittered stratification
        // of a smooth integrand errs by O(1/N) times its relative variation
        // (about 1 here) in 2D: 2.4e-4 for 4,096 points, so 5e-4.
        let p = window();
        let origin = DVec3::new(0.0, 0.0, -1.5);
        let mut rng = Rng::new(3, 4);
        let mut points = Vec::new();
        stratified_points(p.corners(), 4096, &mut rng, &mut points);
        let mean: f64 = points
            .iter()
            .map(|q| 1.0 / p.direction_pdf(origin, (*q - origin).normalize()))
            .sum::<f64>()
            / points.len() as f64;
        let (a, b, h) = (2.0f64, 1.0f64, 1.5f64);
        let exact = (a * b / (h * (a * a + b * b + h * h).sqrt())).atan();
        assert!((mean / exact - 1.0).abs() < 5e-4, "{mean} against {exact}");
    }

    #[test]
    fn bad_portals_are_refused() {
        assert_eq!(Portal::new(&[DVec3::ZERO; 2]), Err(PortalError::Corners(2)));
        assert_eq!(Portal::new(&[DVec3::ZERO; 4]), Err(PortalError::NoArea));
        let bent = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.5), DVec3::Y];
        assert!(matches!(Portal::new(&bent), Err(PortalError::NotPlanar(_))));
        let nan = [DVec3::ZERO, DVec3::X, DVec3::new(f64::NAN, 1.0, 0.0)];
        assert_eq!(Portal::new(&nan), Err(PortalError::NotFinite));
    }
}
