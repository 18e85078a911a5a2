//! Reads an environment map file a `[sky]` with `kind = "map"` names: a
//! Radiance `.hdr` through `light::envmap::parse_hdr`, an OpenEXR `.exr`
//! through `compare::read` (its `R`, `G`, `B` channels), both with their
//! sizes checked before the texels are allocated.

use crate::light::envmap::{parse_hdr, EnvMap, MAX_TEXELS};
use std::path::Path;

/// The map at `path`, times `scale`, turned by `rotation_deg` about up; the
/// error says what is wrong with the file (the caller names it).
#[allow(clippy::disallowed_methods)] // An edge: an importer reads the map its scene names.
pub(super) fn load_envmap(path: &Path, scale: f64, rotation_deg: f64) -> Result<EnvMap, String> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let (width, height, texels) = match extension.as_deref() {
        Some("hdr") | Some("pic") => {
            let bytes = std::fs::read(path).map_err(|e| format!("cannot be read ({e})"))?;
            parse_hdr(&bytes).map_err(|e| e.to_string())?
        }
        Some("exr") => {
            let loaded = crate::compare::read::read_image(path).map_err(|e| e.to_string())?;
            let image = loaded.image;
            let (w, h) = (image.width as u64, image.height as u64);
            // `read_image` already capped the pixels at its own limit.
            if w * h > MAX_TEXELS {
                return Err(format!(
                    "the map is {w}×{h}, more than the {MAX_TEXELS}-texel limit"
                ));
            }
            let texels = image.pixels().map(|p| [p[0], p[1], p[2]]).collect();
            (image.width, image.height, texels)
        }
        _ => {
            return Err(
                "is neither a Radiance .hdr nor an OpenEXR .exr file (by its extension)".into(),
            )
        }
    };
    EnvMap::new(width, height, texels, scale, rotation_deg).map_err(|e| e.to_string())
}
