//! How big patches and the smallest elements are: size-driven (absolute lengths
//! derived from the scene's size) or flat (a patch count and an area fraction per
//! polygon, Remington 1992, §3.3 and appendix B `patch N`).
//!
//! Size-driven, a polygon's patches per side are N = ⌈longest edge / target⌉,
//! so a polygon already smaller than the target stays one patch as it is, and
//! every patch's longest side is at most about the target whatever the polygon's
//! size. (Splitting each piece N × N keeps the mesh one quadtree per patch, so
//! an elongated polygon gets square-ish patches along its long side and thin
//! ones across; anisotropic grids would fix that but need a second N per piece.)
//!
//! The reference length that the settings' fractions multiply is the diagonal
//! of the scene's bounding box: it needs no notion of rooms, is defined for
//! every scene, does not depend on how finely the input was tessellated, and is
//! what a viewer's sense of "the scene" scales with. Its weakness, a scene with
//! one far-away polygon, is the user's to fix with an absolute per-object size
//! (the TOML config, `solver/src/scene/config.rs`).

use super::MAX_PATCHES_PER_SIDE;
use crate::scene::{Polygon, Scene, PATCHES_UNSET};
use crate::settings::SolverSettings;
use glam::DVec3;

/// How a polygon whose input sets no patch count gets one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PatchRule {
    /// N × N patches whatever the polygon's size ([`Sizing::flat`]).
    PerPolygon(u32),
    /// N = ⌈longest edge / size⌉, `size` in scene units.
    Size(f64),
}

/// The meshing sizes of one solve, in scene units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sizing {
    pub patches: PatchRule,
    /// The smallest element, as its longest edge; `None` leaves the decision to
    /// the flat rule's floor (a fixed fraction of each polygon's area,
    /// `refine::FLAT_MIN_ELEMENT_AREA`).
    pub min_element_size: Option<f64>,
    /// Converts per-object sizes given in metres ([`crate::scene::Length::Metres`]).
    pub units_per_metre: f64,
}

impl Sizing {
    /// The flat rule: `patches` per side on every polygon that sets none, and
    /// the area-fraction floor.
    pub fn flat(patches: u32) -> Self {
        Sizing {
            patches: PatchRule::PerPolygon(patches.max(1)),
            min_element_size: None,
            units_per_metre: 1.0,
        }
    }

    /// The sizes `settings` ask for, scaled by `scene`'s diagonal.
    pub fn from_settings(settings: &SolverSettings, scene: &Scene) -> Self {
        let diagonal = scene_diagonal(scene);
        Sizing {
            patches: PatchRule::Size(settings.patch_size * diagonal),
            min_element_size: Some(settings.min_element_size * diagonal),
            units_per_metre: scene.units_per_metre,
        }
    }

    /// Patches per side for `polygon`, before clamping: its own `patches` if its
    /// input set one, else its own `patch_size` (a TOML per-object override),
    /// else this rule.
    pub fn requested_patches(&self, polygon: &Polygon) -> u64 {
        if polygon.patches != PATCHES_UNSET {
            return polygon.patches as u64;
        }
        let rule = match polygon.sizes.patch_size {
            Some(size) => PatchRule::Size(size.in_scene_units(self.units_per_metre)),
            None => self.patches,
        };
        match rule {
            PatchRule::PerPolygon(n) => n.max(1) as u64,
            PatchRule::Size(size) => patches_for_size(&polygon.vertices, size),
        }
    }

    /// Patches per side for `polygon`: [`Self::requested_patches`], with a
    /// size-driven count clamped to [`MAX_PATCHES_PER_SIDE`] (see
    /// [`clamped_polygons`]). An explicit count is returned as asked, for the
    /// mesh to refuse when it is too large.
    pub fn patches_per_side(&self, polygon: &Polygon) -> u32 {
        let n = self.requested_patches(polygon);
        if polygon.patches != PATCHES_UNSET {
            polygon.patches
        } else {
            n.min(MAX_PATCHES_PER_SIDE as u64) as u32
        }
    }

    /// Patches per side for a part of `polygon` cut along contact lines
    /// (`mesh::contact`) with vertices `part`: by the size rule, the part's own
    /// ⌈longest edge / size⌉; by a count (the polygon's own or the flat
    /// rule's), that count scaled by the part's longest edge over the
    /// polygon's, so that the parts' patches are about as large as the whole
    /// polygon's would be. Clamped to [`MAX_PATCHES_PER_SIDE`].
    pub fn patches_per_side_of_part(&self, polygon: &Polygon, part: &[DVec3]) -> u32 {
        let by_size = polygon.patches == PATCHES_UNSET
            && (polygon.sizes.patch_size.is_some() || matches!(self.patches, PatchRule::Size(_)));
        let n = if by_size {
            let mut whole = polygon.clone();
            whole.vertices = part.to_vec();
            self.requested_patches(&whole)
        } else {
            let whole = self.patches_per_side(polygon) as f64;
            let ratio = longest_edge(part) / longest_edge(&polygon.vertices);
            // A part whose longest edge is the polygon's keeps its count,
            // whatever the rounding of its cut corners (1e-9 relative).
            let n = (whole * ratio * (1.0 - 1e-9)).ceil();
            if n.is_finite() && n >= 1.0 {
                n.min(u32::MAX as f64) as u64
            } else {
                1
            }
        };
        n.clamp(1, MAX_PATCHES_PER_SIDE as u64) as u32
    }

    /// The smallest element of `polygon`, as a longest edge in scene units: its
    /// own override, else the solve's; `None` for the flat area-fraction floor.
    pub fn min_element_size(&self, polygon: &Polygon) -> Option<f64> {
        polygon
            .sizes
            .min_element_size
            .map(|l| l.in_scene_units(self.units_per_metre))
            .or(self.min_element_size)
    }
}

/// ⌈longest edge / size⌉ (at least 1), saturating rather than overflowing on
/// absurd ratios; non-finite input gives 1 (such polygons are skipped anyway).
pub fn patches_for_size(vertices: &[DVec3], size: f64) -> u64 {
    let longest = longest_edge(vertices);
    let ratio = (longest / size).ceil();
    if ratio.is_finite() && ratio >= 1.0 {
        ratio.min(u32::MAX as f64) as u64
    } else {
        1
    }
}

fn longest_edge(vertices: &[DVec3]) -> f64 {
    let n = vertices.len();
    (0..n)
        .map(|i| (vertices[(i + 1) % n] - vertices[i]).length())
        .fold(0.0, f64::max)
}

/// The diagonal of the bounding box of every finite vertex of `scene`, in scene
/// units (0 for an empty scene).
pub fn scene_diagonal(scene: &Scene) -> f64 {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for v in scene.polygons.iter().flat_map(|p| &p.vertices) {
        if v.is_finite() {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
    }
    if lo.x <= hi.x {
        (hi - lo).length()
    } else {
        0.0
    }
}

/// Polygons whose size-driven patch count was clamped to
/// [`MAX_PATCHES_PER_SIDE`]: (index into `Scene::polygons`, the count asked
/// for), for the command line to warn about (their patches are larger than
/// the target).
pub fn clamped_polygons(scene: &Scene, sizing: &Sizing) -> Vec<(usize, u64)> {
    scene
        .polygons
        .iter()
        .enumerate()
        .filter(|(_, p)| p.patches == PATCHES_UNSET)
        .map(|(i, p)| (i, sizing.requested_patches(p)))
        .filter(|&(_, n)| n > MAX_PATCHES_PER_SIDE as u64)
        .collect()
}
