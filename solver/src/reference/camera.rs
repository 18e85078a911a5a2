//! Camera rays with `runtime screenshot`'s conventions ([`EyeView`]): pixel
//! (i, j) (column i, row j, row 0 at the top) covers the framebuffer square
//! `[i, i+1) × [j, j+1)`, whose centre `(i + 0.5, j + 0.5)` is where the
//! rasterizers sample it; the path tracer averages over the whole square (a box
//! filter).

use glam::{DVec2, DVec3};
use solution::camera::EyeView;

/// The eye ray through framebuffer position `(i + du, j + dv)`, `du, dv ∈ [0, 1)`:
/// origin and unit direction, in the view's (re-centred) coordinates.
pub fn pixel_ray(view: &EyeView, i: u32, j: u32, du: f64, dv: f64) -> (DVec3, DVec3) {
    let dir = view.pixel_ray(DVec2::new(i as f64 + du, j as f64 + dv));
    (view.position, dir.normalize())
}

#[cfg(test)]
mod tests {
    use super::*;
    use solution::camera::Camera;

    /// The ray through a pixel's centre projects back onto that centre, and the
    /// image's top-left pixel looks up and to the left.
    #[test]
    fn centre_rays_project_to_pixel_centres() {
        let camera = Camera {
            eye: [0.0, 1.0, 5.0],
            target: [0.0, 1.0, 0.0],
            width: 8,
            height: 6,
            ..Camera::default()
        };
        let view = camera.mono_view(DVec3::ZERO);
        let (o, d) = pixel_ray(&view, 0, 0, 0.5, 0.5);
        let p = view.project_to_pixel(o + d * 3.0).unwrap();
        // f64 rounding of a few-pixel coordinate.
        assert!((p - DVec2::new(0.5, 0.5)).length() < 1e-12, "{p}");
        assert!(d.dot(view.up) > 0.0 && d.dot(view.right) < 0.0);
    }
}
