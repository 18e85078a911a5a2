//! Cameras and the up axis, shared by the solver (`--preview`), the solution file
//! and the runtime.
//!
//! Conventions (design notes, "Units and conventions"): right-handed coordinates,
//! a camera is `eye`, `target`, `up` and a vertical field of view in degrees. User
//! facing positions (scene files, command-line flags, the camera stored in a
//! solution header) are in the scene's original coordinates; the solution's vertex
//! positions are re-centred, and `position_file = position_scene - recentre_offset`.

use glam::{DMat3, DMat4, DQuat, DVec2, DVec3, DVec4};
use serde::{Deserialize, Serialize};

/// The world axis that points up for the viewer (Remington 1992, appendix C allows y, -y, z, -z).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    /// +y (the default, and the Cornell box's).
    #[default]
    #[serde(rename = "y", alias = "+y")]
    PosY,
    #[serde(rename = "-y")]
    NegY,
    #[serde(rename = "z", alias = "+z")]
    PosZ,
    #[serde(rename = "-z")]
    NegZ,
}

impl UpAxis {
    /// The unit vector of this axis.
    pub fn vector(self) -> [f64; 3] {
        match self {
            UpAxis::PosY => [0.0, 1.0, 0.0],
            UpAxis::NegY => [0.0, -1.0, 0.0],
            UpAxis::PosZ => [0.0, 0.0, 1.0],
            UpAxis::NegZ => [0.0, 0.0, -1.0],
        }
    }

    /// The code stored in the solution file.
    pub fn code(self) -> u32 {
        match self {
            UpAxis::PosY => 0,
            UpAxis::NegY => 1,
            UpAxis::PosZ => 2,
            UpAxis::NegZ => 3,
        }
    }

    /// Inverse of [`UpAxis::code`]; `None` for an unknown code.
    pub fn from_code(code: u32) -> Option<Self> {
        Some(match code {
            0 => UpAxis::PosY,
            1 => UpAxis::NegY,
            2 => UpAxis::PosZ,
            3 => UpAxis::NegZ,
            _ => return None,
        })
    }

    /// Parses `y`, `+y`, `-y`, `z`, `+z`, `-z` (case-insensitive).
    pub fn parse(text: &str) -> Option<Self> {
        Some(match text.trim().to_ascii_lowercase().as_str() {
            "y" | "+y" => UpAxis::PosY,
            "-y" => UpAxis::NegY,
            "z" | "+z" => UpAxis::PosZ,
            "-z" => UpAxis::NegZ,
            _ => return None,
        })
    }
}

impl std::fmt::Display for UpAxis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            UpAxis::PosY => "+y",
            UpAxis::NegY => "-y",
            UpAxis::PosZ => "+z",
            UpAxis::NegZ => "-z",
        })
    }
}

/// A pinhole camera in scene units.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    pub up: [f64; 3],
    /// Vertical field of view in degrees.
    pub fov_y_deg: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Default for Camera {
    /// Looks down -z from +z, as OpenGL does; scenes should name their own camera.
    fn default() -> Self {
        Camera {
            eye: [0.0, 0.0, 1.0],
            target: [0.0, 0.0, 0.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 45.0,
            width: 512,
            height: 512,
        }
    }
}

// ---------------------------------------------------------------------------
// Eye views and projection (shared by the CPU rasterizer and the Vulkan runtime).
//
// Conventions, which the GPU renderer must follow exactly for its images to match
// the CPU reference pixel by pixel:
//
// * World: right-handed, in *file* coordinates (re-centred, as the solution's
//   vertex positions are). [`Camera::mono_view`] and [`Camera::stereo_views`]
//   subtract `header.recentre_offset` from the header camera.
// * View space (what [`EyeView::view_matrix`] maps to) is OpenXR's and OpenGL's:
//   +x right, +y up, the eye looks down -z.
// * Clip space (what [`EyeView::projection`] maps to) is Vulkan's: x right,
//   **y down**, depth `z/w` from 0 at the near plane to 1 at the far plane,
//   `w` = distance in front of the eye along the view direction. The y flip is in
//   the matrix, so the viewport has a positive height (`y = 0`, `height = h`).
// * Pixels: the viewport covers the whole image, framebuffer coordinate
//   `x_f = (x_ndc + 1) / 2 · width`, `y_f = (y_ndc + 1) / 2 · height`; pixel (i, j)
//   (column i, row j, row 0 at the top) is sampled at its centre
//   `(i + 0.5, j + 0.5)`, i.e. NDC `((i + 0.5) / w · 2 − 1, (j + 0.5) / h · 2 − 1)`.
// * Depth test LESS against a buffer cleared to 1.0; no depth clamp (geometry
//   beyond the far plane is clipped).
// * Front faces are counter-clockwise as seen from the side the normal points
//   to (design notes); after the y flip they are counter-clockwise on screen in
//   Vulkan's sense, so the pipeline uses `frontFace = COUNTER_CLOCKWISE`,
//   `cullMode = BACK`.
// ---------------------------------------------------------------------------

/// The smallest and largest vertical field of view a header camera may ask for,
/// degrees. Outside this range the projection degenerates (0°) or flips (180°).
pub const FOV_Y_DEG_RANGE: (f64, f64) = (0.01, 179.0);

/// The largest image side (pixels) a camera may ask for; the CPU rasterizer's
/// fixed-point arithmetic is sized for it, and it bounds allocations made from
/// an untrusted header.
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Why a camera cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CameraError {
    #[error("camera {field} is not finite: {value:?}")]
    NotFinite {
        field: &'static str,
        value: [f64; 3],
    },
    #[error("camera eye and target coincide at {eye:?}: no view direction")]
    EyeAtTarget { eye: [f64; 3] },
    #[error(
        "camera vertical field of view {fov_y_deg} degrees is outside {}..{} degrees",
        FOV_Y_DEG_RANGE.0,
        FOV_Y_DEG_RANGE.1
    )]
    FieldOfView { fov_y_deg: f64 },
    #[error("camera image size {width}x{height} is outside 1..={MAX_IMAGE_SIDE} pixels per side")]
    ImageSize { width: u32, height: u32 },
    #[error("interpupillary distance {ipd} is not a finite, non-negative length")]
    Ipd { ipd: f64 },
}

/// A field of view as four angles in radians from the view direction, with
/// OpenXR's signs (`XrFovf`): `left` and `down` are negative for an eye whose view
/// direction lies inside its frustum. Asymmetric values are allowed (XR eyes).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fov {
    pub left: f64,
    pub right: f64,
    pub up: f64,
    pub down: f64,
}

impl Fov {
    /// A symmetric field of view with vertical angle `fov_y` (radians, full angle)
    /// and the horizontal angle that keeps pixels square for `width × height`.
    pub fn symmetric(fov_y: f64, width: u32, height: u32) -> Fov {
        let tan_half_y = (0.5 * fov_y).tan();
        let tan_half_x = tan_half_y * width.max(1) as f64 / height.max(1) as f64;
        Fov {
            left: -tan_half_x.atan(),
            right: tan_half_x.atan(),
            up: tan_half_y.atan(),
            down: -tan_half_y.atan(),
        }
    }

    /// Tangents of the four angles: (left, right, up, down).
    pub fn tangents(&self) -> (f64, f64, f64, f64) {
        (
            self.left.tan(),
            self.right.tan(),
            self.up.tan(),
            self.down.tan(),
        )
    }
}

/// One eye's view: a pinhole at `position` with an orthonormal, right-handed
/// basis (`right × up = −forward`, i.e. `forward = up × right`), a possibly
/// asymmetric field of view and an image size. Everything in file coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeView {
    pub position: DVec3,
    /// Unit vector toward the image's +x (columns increase).
    pub right: DVec3,
    /// Unit vector toward the image's top (rows decrease).
    pub up: DVec3,
    /// Unit viewing direction.
    pub forward: DVec3,
    pub fov: Fov,
    pub width: u32,
    pub height: u32,
}

impl EyeView {
    /// A view from an OpenXR-style pose: `orientation` rotates view space
    /// (+x right, +y up, looking down −z) into the world.
    pub fn from_pose(
        position: DVec3,
        orientation: DQuat,
        fov: Fov,
        width: u32,
        height: u32,
    ) -> EyeView {
        let q = orientation.normalize();
        EyeView {
            position,
            right: q * DVec3::X,
            up: q * DVec3::Y,
            forward: q * DVec3::NEG_Z,
            fov,
            width,
            height,
        }
    }

    /// The rotation from view space to the world (the inverse of
    /// [`EyeView::from_pose`]'s construction).
    pub fn orientation(&self) -> DQuat {
        DQuat::from_mat3(&DMat3::from_cols(self.right, self.up, -self.forward))
    }

    /// World (file coordinates) to view space: +x right, +y up, looking down −z.
    pub fn view_matrix(&self) -> DMat4 {
        let (r, u, b) = (self.right, self.up, -self.forward);
        // Rows of the rotation are the basis vectors; translation moves the eye
        // to the origin.
        DMat4::from_cols(
            DVec4::new(r.x, u.x, b.x, 0.0),
            DVec4::new(r.y, u.y, b.y, 0.0),
            DVec4::new(r.z, u.z, b.z, 0.0),
            DVec4::new(
                -r.dot(self.position),
                -u.dot(self.position),
                -b.dot(self.position),
                1.0,
            ),
        )
    }

    /// View space to Vulkan clip space (y down, depth 0 at `near` .. 1 at `far`).
    /// `far` may be `f64::INFINITY` (depth = 1 − near / distance). With
    /// `t = tan` of the [`Fov`] angles and `d = −z_view` the distance along the
    /// view direction:
    ///
    /// ```text
    /// x_clip = (2 x − (t_r + t_l) d) / (t_r − t_l)
    /// y_clip = −(2 y − (t_u + t_d) d) / (t_u − t_d)
    /// z_clip = far / (far − near) · (d − near)
    /// w_clip = d
    /// ```
    pub fn projection(&self, near: f64, far: f64) -> DMat4 {
        let (tl, tr, tu, td) = self.fov.tangents();
        let (a, b) = if far.is_infinite() {
            (1.0, near)
        } else {
            (far / (far - near), far * near / (far - near))
        };
        // z_clip = a·d − b with d = −z_view.
        DMat4::from_cols(
            DVec4::new(2.0 / (tr - tl), 0.0, 0.0, 0.0),
            DVec4::new(0.0, -2.0 / (tu - td), 0.0, 0.0),
            DVec4::new((tr + tl) / (tr - tl), -(tu + td) / (tu - td), -a, -1.0),
            DVec4::new(0.0, 0.0, -b, 0.0),
        )
    }

    /// `projection(near, far) · view_matrix()`: world (file coordinates) to clip.
    /// The runtime uploads it as `as_mat4()`; positions are re-centred, so f32
    /// loses nothing the stored f32 positions had.
    pub fn view_projection(&self, near: f64, far: f64) -> DMat4 {
        self.projection(near, far) * self.view_matrix()
    }

    /// Focal lengths in pixels, `(f_x, f_y)`: a point at view-space `(x, y, −d)`
    /// lands `f_x · x / d` pixels right of the principal point. Equal for the
    /// symmetric views of [`Camera`] (square pixels).
    pub fn focal_lengths_px(&self) -> (f64, f64) {
        let (tl, tr, tu, td) = self.fov.tangents();
        (
            self.width as f64 / (tr - tl),
            self.height as f64 / (tu - td),
        )
    }

    /// Where the view direction pierces the image, in framebuffer coordinates
    /// (the image centre for a symmetric field of view).
    pub fn principal_point_px(&self) -> DVec2 {
        let (tl, tr, tu, td) = self.fov.tangents();
        DVec2::new(
            self.width as f64 * -tl / (tr - tl),
            self.height as f64 * tu / (tu - td),
        )
    }

    /// The framebuffer position (x right, y down, pixel (i, j) centred at
    /// `(i + 0.5, j + 0.5)`) of a world point, or `None` when the point is not in
    /// front of the eye. Exactly what the projection and the viewport transform
    /// compute, in f64.
    pub fn project_to_pixel(&self, world: DVec3) -> Option<DVec2> {
        let rel = world - self.position;
        let d = rel.dot(self.forward);
        if d <= 0.0 || !d.is_finite() {
            return None;
        }
        let (fx, fy) = self.focal_lengths_px();
        let c = self.principal_point_px();
        Some(DVec2::new(
            c.x + fx * rel.dot(self.right) / d,
            c.y - fy * rel.dot(self.up) / d,
        ))
    }

    /// The world direction (not normalised; unit component along `forward`) of the
    /// ray through framebuffer position `pixel`: the inverse of
    /// [`EyeView::project_to_pixel`].
    pub fn pixel_ray(&self, pixel: DVec2) -> DVec3 {
        let (fx, fy) = self.focal_lengths_px();
        let c = self.principal_point_px();
        self.forward + self.right * ((pixel.x - c.x) / fx) - self.up * ((pixel.y - c.y) / fy)
    }
}

/// Parses an image size `WIDTHxHEIGHT` (e.g. `1024x768`), each side a whole number
/// of pixels in `1..=MAX_IMAGE_SIDE`: the `--size` flag of every program that makes
/// images, so they accept and refuse the same sizes with the same message.
pub fn parse_image_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("size {text:?} is not WIDTHxHEIGHT (e.g. 1024x1024)"))?;
    let parse = |s: &str| {
        s.trim()
            .parse::<u32>()
            .ok()
            .filter(|&v| (1..=MAX_IMAGE_SIDE).contains(&v))
            .ok_or_else(|| {
                format!(
                    "size {text:?}: {s:?} is not a whole number of pixels in 1..={MAX_IMAGE_SIDE}"
                )
            })
    };
    Ok((parse(w)?, parse(h)?))
}

/// Near and far clip distances for viewing a scene whose (file-coordinate) bounds
/// are `bounds_min..bounds_max` from `eye`: both renderers call this so that they
/// clip identically.
///
/// `far` reaches 1% beyond the farthest corner of the bounds, so no geometry is
/// lost to the far plane. `near` is 1/1000 of the bounds' diagonal (a walker can
/// put the eye that close to a wall before it is clipped), or half the distance
/// from the eye to the bounds when the eye is outside and farther away, which
/// keeps `far / near` — and so the depth buffer's resolution, roughly
/// `6e-8 · d² / near` at distance `d` for a 32-bit float buffer — bounded.
pub fn clip_planes_for(eye: DVec3, bounds_min: DVec3, bounds_max: DVec3) -> (f64, f64) {
    const NEAR_FRACTION_OF_DIAGONAL: f64 = 1e-3;
    let lo = bounds_min.min(bounds_max);
    let hi = bounds_min.max(bounds_max);
    let diagonal = (hi - lo).length();
    let to_box = (eye - eye.clamp(lo, hi)).length();
    let farthest = (eye - lo).abs().max((eye - hi).abs()).length();
    let mut near = (NEAR_FRACTION_OF_DIAGONAL * diagonal).max(0.5 * to_box);
    if !(near > 0.0 && near.is_finite()) {
        // A point-sized (or empty, or non-finite) scene: any positive pair works,
        // scaled to the distance when there is one so that the point stays inside.
        near = if farthest > 0.0 && farthest.is_finite() {
            0.5 * farthest
        } else {
            1e-3
        };
    }
    let mut far = 1.01 * farthest + near;
    if !(far > near && far.is_finite()) {
        far = near * 1e3;
    }
    (near, far)
}

impl Camera {
    /// Checks that the camera can be used: finite vectors, eye ≠ target, a field of
    /// view within [`FOV_Y_DEG_RANGE`] and an image size within 1..=[`MAX_IMAGE_SIDE`].
    /// (An `up` parallel to the view direction is accepted: [`Camera::basis`] then
    /// picks a perpendicular one.)
    pub fn validate(&self) -> Result<(), CameraError> {
        for (field, value) in [("eye", self.eye), ("target", self.target), ("up", self.up)] {
            if value.iter().any(|v| !v.is_finite()) {
                return Err(CameraError::NotFinite { field, value });
            }
        }
        if DVec3::from(self.eye) == DVec3::from(self.target) {
            return Err(CameraError::EyeAtTarget { eye: self.eye });
        }
        if !(self.fov_y_deg >= FOV_Y_DEG_RANGE.0 && self.fov_y_deg <= FOV_Y_DEG_RANGE.1) {
            return Err(CameraError::FieldOfView {
                fov_y_deg: self.fov_y_deg,
            });
        }
        if self.width == 0
            || self.height == 0
            || self.width > MAX_IMAGE_SIDE
            || self.height > MAX_IMAGE_SIDE
        {
            return Err(CameraError::ImageSize {
                width: self.width,
                height: self.height,
            });
        }
        Ok(())
    }

    /// The camera's orthonormal basis `(right, up, forward)`: forward toward the
    /// target, right = forward × up, up re-orthogonalised (right-handed). It never
    /// fails: a degenerate camera (eye at target, non-finite values) looks down −z,
    /// and an `up` parallel to the view direction is replaced by the world axis
    /// least aligned with it. Call [`Camera::validate`] to report such cameras.
    pub fn basis(&self) -> (DVec3, DVec3, DVec3) {
        let forward = (DVec3::from(self.target) - DVec3::from(self.eye))
            .try_normalize()
            .unwrap_or(DVec3::NEG_Z);
        let up_hint = DVec3::from(self.up);
        let right = forward
            .cross(up_hint)
            .try_normalize()
            .filter(|_| up_hint.is_finite())
            .unwrap_or_else(|| forward.any_orthonormal_vector());
        let up = right.cross(forward);
        (right, up, forward)
    }

    /// The symmetric field of view of this camera for its image size.
    pub fn fov(&self) -> Fov {
        let fov_y = self
            .fov_y_deg
            .clamp(FOV_Y_DEG_RANGE.0, FOV_Y_DEG_RANGE.1)
            .to_radians();
        Fov::symmetric(fov_y, self.width, self.height)
    }

    /// The single-eye view, in file coordinates: `offset` (the solution header's
    /// `recentre_offset`) is subtracted from the eye position.
    pub fn mono_view(&self, offset: DVec3) -> EyeView {
        self.eye_at(0.0, offset)
    }

    /// Left and right eye views (in that order) for a mock or offscreen stereo
    /// pair (design notes, "Units and conventions"): the eyes sit at ∓`ipd / 2`
    /// (scene units: metres × `units_per_metre`) along the camera's right vector,
    /// with parallel view directions and the camera's symmetric field of view.
    /// A point at distance `d` along the view direction therefore appears
    /// `ipd · f / d` pixels further right in the left eye than in the right eye,
    /// with `f` from [`EyeView::focal_lengths_px`].
    pub fn stereo_views(&self, ipd_scene_units: f64, offset: DVec3) -> [EyeView; 2] {
        let half = 0.5 * ipd_scene_units;
        [self.eye_at(-half, offset), self.eye_at(half, offset)]
    }

    /// [`Camera::stereo_views`] after [`Camera::validate`] and a check that the
    /// IPD is finite and non-negative: for cameras and IPDs from user input.
    pub fn try_stereo_views(
        &self,
        ipd_scene_units: f64,
        offset: DVec3,
    ) -> Result<[EyeView; 2], CameraError> {
        self.validate()?;
        if !(ipd_scene_units.is_finite() && ipd_scene_units >= 0.0) {
            return Err(CameraError::Ipd {
                ipd: ipd_scene_units,
            });
        }
        Ok(self.stereo_views(ipd_scene_units, offset))
    }

    fn eye_at(&self, shift_right: f64, offset: DVec3) -> EyeView {
        let (right, up, forward) = self.basis();
        // Subtract the offset first, in f64, so that a camera far from the origin
        // keeps its precision relative to the re-centred scene.
        let position = (DVec3::from(self.eye) - offset) + right * shift_right;
        EyeView {
            position,
            right,
            up,
            forward,
            fov: self.fov(),
            width: self.width,
            height: self.height,
        }
    }
}

#[cfg(test)]
mod eye_view_tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            eye: [1.0, 2.0, 3.0],
            target: [0.5, 1.0, -4.0],
            up: [0.0, 1.0, 0.0],
            fov_y_deg: 60.0,
            width: 640,
            height: 480,
        }
    }

    /// Clip → framebuffer with the viewport transform documented above.
    fn to_pixel(view: &EyeView, near: f64, far: f64, p: DVec3) -> (DVec2, f64) {
        let clip = view.view_projection(near, far) * p.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        (
            DVec2::new(
                (ndc.x + 1.0) * 0.5 * view.width as f64,
                (ndc.y + 1.0) * 0.5 * view.height as f64,
            ),
            ndc.z,
        )
    }

    #[test]
    fn basis_is_orthonormal_and_right_handed() {
        let (r, u, f) = camera().basis();
        // Built from one normalisation and cross products: f64 rounding only.
        for v in [r, u, f] {
            assert!((v.length() - 1.0).abs() < 1e-14);
        }
        assert!(r.dot(u).abs() < 1e-14 && r.dot(f).abs() < 1e-14 && u.dot(f).abs() < 1e-14);
        assert!(
            (r.cross(u) + f).length() < 1e-14,
            "right × up must be −forward"
        );
        assert!(u.y > 0.0, "up keeps the hint's sense");
    }

    #[test]
    fn projection_matches_pixel_mapping_and_depth_range() {
        let view = camera().mono_view(DVec3::ZERO);
        let (near, far) = (0.1, 100.0);
        // The principal point: a point straight ahead lands on the image centre.
        let ahead = view.position + view.forward * 7.0;
        let (px, _) = to_pixel(&view, near, far, ahead);
        assert!((px - DVec2::new(320.0, 240.0)).length() < 1e-9);
        // Up in the world is toward row 0 (y down), right toward larger columns.
        let (up_px, _) = to_pixel(&view, near, far, ahead + view.up);
        let (right_px, _) = to_pixel(&view, near, far, ahead + view.right);
        assert!(up_px.y < 240.0 && (up_px.x - 320.0).abs() < 1e-9);
        assert!(right_px.x > 320.0 && (right_px.y - 240.0).abs() < 1e-9);
        // The matrix and the direct formula agree (f64 rounding of ~1e3 px values).
        for p in [
            ahead + view.up * 0.3 - view.right * 2.0,
            view.position + DVec3::new(-3.0, 1.0, -9.0),
        ] {
            let (m, _) = to_pixel(&view, near, far, p);
            let d = view.project_to_pixel(p).unwrap();
            assert!((m - d).length() < 1e-9, "{m} vs {d}");
            // pixel_ray inverts project_to_pixel.
            let ray = view.pixel_ray(d);
            let dir = (p - view.position).normalize();
            assert!((ray.normalize() - dir).length() < 1e-12);
        }
        // Depth 0 at the near plane, 1 at the far plane.
        let (_, z_near) = to_pixel(&view, near, far, view.position + view.forward * near);
        let (_, z_far) = to_pixel(&view, near, far, view.position + view.forward * far);
        assert!(z_near.abs() < 1e-12 && (z_far - 1.0).abs() < 1e-12);
        // Infinite far: depth = 1 − near / d.
        let (_, z) = to_pixel(
            &view,
            near,
            f64::INFINITY,
            view.position + view.forward * 4.0,
        );
        assert!((z - (1.0 - near / 4.0)).abs() < 1e-12);
        // Square pixels for the symmetric view: f = h / (2 tan(fov_y / 2)).
        let (fx, fy) = view.focal_lengths_px();
        let f = 240.0 / (30f64.to_radians().tan());
        assert!((fx - f).abs() < 1e-9 && (fy - f).abs() < 1e-9);
    }

    #[test]
    fn asymmetric_fov_maps_its_edges_to_the_image_edges() {
        let fov = Fov {
            left: -0.7,
            right: 0.3,
            up: 0.5,
            down: -0.2,
        };
        let view = EyeView::from_pose(
            DVec3::new(0.2, -1.0, 3.0),
            DQuat::from_rotation_y(0.4),
            fov,
            200,
            100,
        );
        let (near, far) = (0.01, 50.0);
        // A point at the left/up frustum edge lands on the image's top-left corner.
        let d = 5.0;
        let corner = view.position
            + view.forward * d
            + view.right * (d * fov.left.tan())
            + view.up * (d * fov.up.tan());
        let (px, _) = to_pixel(&view, near, far, corner);
        assert!(px.length() < 1e-9, "{px}");
        let corner = view.position
            + view.forward * d
            + view.right * (d * fov.right.tan())
            + view.up * (d * fov.down.tan());
        let (px, _) = to_pixel(&view, near, far, corner);
        assert!((px - DVec2::new(200.0, 100.0)).length() < 1e-9, "{px}");
        // The pose round-trips through orientation().
        let q = view.orientation();
        assert!(q.angle_between(DQuat::from_rotation_y(0.4)) < 1e-12);
    }

    #[test]
    fn stereo_disparity_is_ipd_f_over_d() {
        let cam = camera();
        let ipd = 0.064;
        let [left, right] = cam.stereo_views(ipd, DVec3::ZERO);
        assert!(((right.position - left.position) - left.right * ipd).length() < 1e-15);
        assert_eq!(left.forward, right.forward);
        let (f, _) = left.focal_lengths_px();
        let centre = DVec3::from(cam.eye);
        for (d, lateral) in [(0.5, 0.1), (3.0, -0.4), (40.0, 2.0)] {
            let p = centre + left.forward * d + left.right * lateral + left.up * 0.2;
            let xl = left.project_to_pixel(p).unwrap();
            let xr = right.project_to_pixel(p).unwrap();
            // Same row; the column shift is exactly ipd·f/d. 1e-6 px is far above
            // the f64 rounding of ~1e3-pixel coordinates (1e-13 px).
            assert!((xl.y - xr.y).abs() < 1e-6);
            assert!(((xl.x - xr.x) - ipd * f / d).abs() < 1e-6, "d = {d}");
        }
    }

    #[test]
    fn offset_is_subtracted_in_f64() {
        let mut cam = camera();
        let offset = DVec3::new(1e6, -2e6, 3e6);
        cam.eye = (DVec3::from(cam.eye) + offset).into();
        cam.target = (DVec3::from(cam.target) + offset).into();
        let moved = cam.mono_view(offset);
        let plain = camera().mono_view(DVec3::ZERO);
        // Eye coordinates of ~1e6 carry ~1e-10 absolute f64 rounding.
        assert!((moved.position - plain.position).length() < 1e-9);
        assert!((moved.forward - plain.forward).length() < 1e-12);
    }

    #[test]
    fn degenerate_cameras_are_reported_and_still_usable() {
        let mut cam = camera();
        cam.up = [0.0, 0.0, -1.0];
        cam.target = [1.0, 2.0, -5.0]; // straight down −z, up parallel to it
        assert!(cam.validate().is_ok());
        let (r, u, f) = cam.basis();
        assert!(r.is_finite() && u.is_finite() && (r.cross(u) + f).length() < 1e-12);
        cam.target = cam.eye;
        assert!(matches!(
            cam.validate(),
            Err(CameraError::EyeAtTarget { .. })
        ));
        assert_eq!(cam.basis().2, DVec3::NEG_Z);
        let mut cam = camera();
        cam.fov_y_deg = 180.0;
        assert!(matches!(
            cam.validate(),
            Err(CameraError::FieldOfView { .. })
        ));
        cam.fov_y_deg = f64::NAN;
        assert!(cam.validate().is_err());
        let mut cam = camera();
        cam.width = 0;
        assert!(matches!(cam.validate(), Err(CameraError::ImageSize { .. })));
        assert!(matches!(
            camera().try_stereo_views(-0.1, DVec3::ZERO),
            Err(CameraError::Ipd { .. })
        ));
        assert!(camera().try_stereo_views(f64::NAN, DVec3::ZERO).is_err());
        assert!(camera().try_stereo_views(0.064, DVec3::ZERO).is_ok());
        let mut cam = camera();
        cam.eye[1] = f64::INFINITY;
        assert!(matches!(
            cam.validate(),
            Err(CameraError::NotFinite { field: "eye", .. })
        ));
    }

    #[test]
    fn clip_planes_enclose_the_bounds() {
        let (lo, hi) = (DVec3::splat(-1.0), DVec3::splat(1.0));
        let (near, far) = clip_planes_for(DVec3::ZERO, lo, hi);
        assert!((near - 1e-3 * 12f64.sqrt()).abs() < 1e-15);
        assert!(far >= 3f64.sqrt() * 1.01);
        // Far outside: near grows with the distance, far still reaches the far corner.
        let eye = DVec3::new(0.0, 0.0, 1000.0);
        let (near, far) = clip_planes_for(eye, lo, hi);
        assert!(
            near > 400.0 && near < 999.0 && far > (eye - DVec3::new(-1.0, -1.0, -1.0)).length()
        );
        // Degenerate bounds never give a zero, negative or non-finite pair.
        for (e, a, b) in [
            (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO),
            (DVec3::ONE, DVec3::ZERO, DVec3::ZERO),
            (DVec3::ZERO, DVec3::splat(f64::NAN), DVec3::ONE),
        ] {
            let (n, f) = clip_planes_for(e, a, b);
            assert!(
                n > 0.0 && n.is_finite() && f > n && f.is_finite(),
                "{n} {f}"
            );
        }
    }
}
