//! Re-centring in f64 (design notes, "Units and conventions"): the bounding-box
//! centre of every input position is subtracted before anything is stored, so a
//! scene far from the origin keeps its precision when the solution stores f32.

use super::raw::RawPolygon;
use glam::DVec3;

/// The bounding box of all polygon vertices, `None` when there are none.
pub(crate) fn bounds(polygons: &[RawPolygon]) -> Option<(DVec3, DVec3)> {
    let mut vertices = polygons.iter().flat_map(|p| p.vertices.iter().copied());
    let first = vertices.next()?;
    Some(vertices.fold((first, first), |(lo, hi), v| (lo.min(v), hi.max(v))))
}

/// Subtracts the bounding-box centre from every vertex; returns the centre (the
/// offset the solution header keeps) and the box's diagonal (the scene size that
/// relative tolerances use).
pub(crate) fn recentre(polygons: &mut [RawPolygon]) -> (DVec3, f64) {
    let Some((lo, hi)) = bounds(polygons) else {
        return (DVec3::ZERO, 0.0);
    };
    let centre = (lo + hi) * 0.5;
    for polygon in polygons.iter_mut() {
        for v in &mut polygon.vertices {
            *v -= centre;
        }
    }
    (centre, (hi - lo).length())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SourceRef;

    fn polygon(vertices: Vec<DVec3>) -> RawPolygon {
        RawPolygon {
            vertices,
            normals: None,
            material: 0,
            patches: None,
            sizes: Default::default(),
            object: None,
            source: SourceRef::default(),
            uvs: None,
        }
    }

    #[test]
    fn centre_of_the_box_is_subtracted() {
        let mut polygons = vec![
            polygon(vec![DVec3::new(1.0, 2.0, 3.0), DVec3::new(5.0, 2.0, 3.0)]),
            polygon(vec![DVec3::new(1.0, 10.0, -3.0)]),
        ];
        let (offset, diagonal) = recentre(&mut polygons);
        assert_eq!(offset, DVec3::new(3.0, 6.0, 0.0));
        assert_eq!(diagonal, (16.0f64 + 64.0 + 36.0).sqrt());
        assert_eq!(polygons[1].vertices[0], DVec3::new(-2.0, 4.0, -3.0));
        assert_eq!(recentre(&mut []), (DVec3::ZERO, 0.0));
    }
}
